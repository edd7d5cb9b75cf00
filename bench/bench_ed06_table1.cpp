// ED06 table 1 on the CPU: the procedural tree (3,000 leaf quads in 3 colour groups, an opaque
// trunk, a sun) at 1280 x 720, rendered with a standard shadow map against transmittance shadow
// maps with uniform and with local slicing (ED06 §2, fig. 2), at several grid resolutions; the
// shadow data alone (the light's grids, with local slicing's near/far pass), and each frame's error
// against the exact shadows (Embree, the `exact` kind: every leaf crossed counted).
//
//   ./build/bench/bench_ed06_table1 --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Frame counters: frame_ms, shadows_ms (building the light's map or grids), shading_ms, and
// mae (the mean absolute error of the frame's pixels against the exact-shadow frame, 0..1 per
// channel, over the pixels either frame shows shadowed or lit differently from no shadow at all)
// with mae_none (the same for no shadow: the error a method must stay below).
#include <cmath>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "demo/demo_scenes.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace {

using namespace voxfx;
using namespace voxfx::demo;

const Scene& treeScene() {
    static const Scene scene = makeTreeScene();
    return scene;
}

RenderOptions frameOptions(const ShadowOptions& shadow) {
    RenderOptions o;
    o.width = 1280;
    o.height = 720;
    o.shadow = shadow;
    return o;
}

const Image& frameWith(const char* kind) {
    static std::vector<std::pair<std::string, Image>> cache;
    for (const auto& [k, img] : cache)
        if (k == kind) return img;
    const Scene& scene = treeScene();
    cache.emplace_back(kind, render(scene, scene.cameras[0], frameOptions(shadowOptionsNamed(kind))).image);
    return cache.back().second;
}

// Mean absolute error per channel against the exact-shadow frame over the pixels where the exact
// frame differs from the unshadowed one (the shadowed receivers) or the frame does.
double shadowError(const Image& img) {
    const Image& exact = frameWith("exact");
    const Image& none = frameWith("none");
    double sum = 0;
    int64_t n = 0;
    for (size_t i = 0; i < img.pixels.size(); ++i) {
        const Vec3f a = img.pixels[i], e = exact.pixels[i], z = none.pixels[i];
        auto differs = [](const Vec3f& p, const Vec3f& q) {
            return std::abs(p.x - q.x) + std::abs(p.y - q.y) + std::abs(p.z - q.z) > 1e-4f;
        };
        if (!differs(e, z) && !differs(a, z)) continue;
        sum += (std::abs(a.x - e.x) + std::abs(a.y - e.y) + std::abs(a.z - e.z)) / 3;
        ++n;
    }
    return n ? sum / double(n) : 0;
}

RenderOptions optionsFor(int kind, int64_t n) {
    RenderOptions o = frameOptions(shadowOptionsNamed(kind == 0 ? "map" : "transmittance"));
    if (kind == 0) {
        setRenderOption(o, "mapResolution", n);
    } else {
        setRenderOption(o, "gridResolution", n);
        setRenderOption(o, "gridDepth", n);
        setRenderOption(o, "slicing", std::string(kind == 1 ? "uniform" : "local"));
    }
    return o;
}

const char* kindName(int kind) { return kind == 0 ? "map" : kind == 1 ? "uniform" : "local"; }

// Arguments: kind (0 standard map, 1 transmittance uniform, 2 transmittance local), resolution (the
// map's side; the grid's columns across and slices).
void BM_ED06Frame(benchmark::State& state) {
    const Scene& scene = treeScene();
    const int kind = int(state.range(0));
    const RenderOptions o = optionsFor(kind, state.range(1));
    const RenderResult first = render(scene, scene.cameras[0], o); // untimed: pages faulted in, error
    const double mae = shadowError(first.image), maeNone = shadowError(frameWith("none"));
    double frameMs = 0, shadows = 0, shading = 0;
    for (auto _ : state) {
        const RenderResult r = render(scene, scene.cameras[0], o);
        benchmark::DoNotOptimize(r.image.pixels.data());
        frameMs += r.timings.totalMs;
        shadows += r.timings.ms("shadows");
        shading += r.timings.ms("shading");
    }
    const double n = double(state.iterations());
    state.counters["frame_ms"] = frameMs / n;
    state.counters["shadows_ms"] = shadows / n;
    state.counters["shading_ms"] = shading / n;
    state.counters["mae"] = mae;
    state.counters["mae_none"] = maeNone;
    state.SetLabel(std::string(kindName(kind)) + " " + std::to_string(state.range(1)) + ", " +
                   std::to_string(scene.triangleCount()) + " triangles, 1280x720");
}
BENCHMARK(BM_ED06Frame)
    ->Args({0, 2048})
    ->Args({1, 128})
    ->Args({2, 128})
    ->Args({1, 256})
    ->Args({2, 256})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The light's shadow data alone: the map, or the grids (local: with the near/far pass).
void BM_ED06Build(benchmark::State& state) {
    const Scene& scene = treeScene();
    const int kind = int(state.range(0));
    const ShadowOptions o = optionsFor(kind, state.range(1)).shadow;
    for (auto _ : state) {
        const LightShadow shadow = buildLightShadow(scene, scene.lights[0], o);
        benchmark::DoNotOptimize(&shadow);
    }
    state.SetLabel(std::string(kindName(kind)) + " " + std::to_string(state.range(1)));
}
BENCHMARK(BM_ED06Build)
    ->Args({0, 2048})
    ->Args({1, 128})
    ->Args({2, 128})
    ->Args({1, 256})
    ->Args({2, 256})
    ->Args({1, 512})
    ->Args({2, 512})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

} // namespace

BENCHMARK_MAIN();
