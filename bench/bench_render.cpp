// Frame time of the renderer on the procedural tree scene (3,000 leaf quads in 3 colour groups, an
// opaque trunk, a sun) at 1280 x 720 for every shadow kind, split into passes, plus the shadow
// builds alone at several resolutions (ED06 transmittance grid, CHANG attribute grid, shadow map).
//
//   ./build/bench/bench_render --benchmark_filter=Frame --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true     (one command line)
//   ./build/bench/bench_render --benchmark_filter=FrameRatio --benchmark_repetitions=5
//       (the target: transmittance frame / shadow-mapped frame, interleaved in one loop)
//
// Frame counters (milliseconds per frame, averaged over the iterations): gbuffer_ms, shadowmap_ms
// (standard maps), voxelize_ms (grids from the light), shading_ms. Build benchmarks: tri/s.
#include <string>

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

// One untimed frame before timing: the process's first large allocations fault their pages in
// (glibc raises its mmap threshold after the first large free), which would otherwise be charged to
// whichever benchmark runs first (the G-buffer pass of BM_FrameNone looked 5x slower).
void warmUp(const RenderOptions& o) {
    static bool done = false;
    if (done) return;
    done = true;
    const RenderResult r = render(treeScene(), treeScene().cameras[0], o);
    benchmark::DoNotOptimize(r.image.pixels.data());
}

void frame(benchmark::State& state, const char* kind) {
    const Scene& scene = treeScene();
    RenderOptions o;
    o.width = 1280;
    o.height = 720;
    o.shadow = shadowOptionsNamed(kind);
    warmUp(o);
    double gbuffer = 0, shadows = 0, shading = 0;
    for (auto _ : state) {
        const RenderResult r = render(scene, scene.cameras[0], o);
        benchmark::DoNotOptimize(r.image.pixels.data());
        gbuffer += r.timings.ms("G-buffer");
        shadows += r.timings.ms("shadows");
        shading += r.timings.ms("shading");
    }
    const double n = double(state.iterations());
    state.counters["gbuffer_ms"] = gbuffer / n;
    state.counters["shadows_ms"] = shadows / n;
    state.counters["shading_ms"] = shading / n;
    state.SetLabel(std::to_string(scene.triangleCount()) + " triangles, 1280x720, " + kind);
}

void BM_FrameNone(benchmark::State& s) { frame(s, "none"); }
void BM_FrameMap(benchmark::State& s) { frame(s, "map"); }
void BM_FrameTransmittance(benchmark::State& s) { frame(s, "transmittance"); }
void BM_FrameAbsorption(benchmark::State& s) { frame(s, "absorption"); }
BENCHMARK(BM_FrameNone)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FrameMap)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FrameTransmittance)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FrameAbsorption)->Unit(benchmark::kMillisecond)->UseRealTime();

// The target, measured so that load changes on a shared machine hit both sides alike: each
// iteration renders a standard-shadow-mapped frame and a transmittance-shadowed frame back to back
// (alternating which goes first). Counters: the per-frame wall times of both and their ratio
// (transmittance / map; target <= 1.5), and the passes of each.
void BM_FrameRatioTransmittanceOverMap(benchmark::State& state) {
    const Scene& scene = treeScene();
    RenderOptions o;
    o.width = 1280;
    o.height = 720;
    RenderOptions map = o, tr = o;
    map.shadow = ShadowMapOptions{};
    tr.shadow = TransmittanceShadowOptions{};
    warmUp(map);
    struct Sum {
        double total = 0, shadows = 0, shading = 0;
    } sm, st;
    bool mapFirst = true;
    auto add = [](Sum& to, const RenderTimings& t) {
        to.total += t.totalMs;
        to.shadows += t.ms("shadows");
        to.shading += t.ms("shading");
    };
    for (auto _ : state) {
        for (int k = 0; k < 2; ++k) {
            const bool doMap = (k == 0) == mapFirst;
            const RenderResult r = render(scene, scene.cameras[0], doMap ? map : tr);
            benchmark::DoNotOptimize(r.image.pixels.data());
            add(doMap ? sm : st, r.timings);
        }
        mapFirst = !mapFirst;
    }
    const double n = double(state.iterations());
    state.counters["map_ms"] = sm.total / n;
    state.counters["tr_ms"] = st.total / n;
    state.counters["tr/map"] = st.total / sm.total;
    state.counters["map_shadow_ms"] = sm.shadows / n;
    state.counters["map_shading_ms"] = sm.shading / n;
    state.counters["tr_shadow_ms"] = st.shadows / n; // the trunk's map and the leaves' grids
    state.counters["tr_shading_ms"] = st.shading / n;
    state.SetLabel(std::to_string(scene.triangleCount()) + " triangles, 1280x720, transmittance / map");
}
BENCHMARK(BM_FrameRatioTransmittanceOverMap)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// One light's shadow data alone, grid (or map) resolution N.
void build(benchmark::State& state, const char* kind) {
    const Scene& scene = treeScene();
    RenderOptions o;
    o.shadow = shadowOptionsNamed(kind);
    for (const char* name : {"gridResolution", "gridDepth", "mapResolution"})
        setRenderOption(o, name, int64_t(state.range(0)));
    for (auto _ : state) {
        const LightShadow shadow = buildLightShadow(scene, scene.lights[0], o.shadow);
        benchmark::DoNotOptimize(&shadow);
    }
    state.counters["tri/s"] = benchmark::Counter(double(scene.triangleCount()) * double(state.iterations()),
                                                 benchmark::Counter::kIsRate);
}

void BM_BuildMap(benchmark::State& s) { build(s, "map"); }
void BM_BuildTransmittance(benchmark::State& s) { build(s, "transmittance"); }
void BM_BuildAbsorption(benchmark::State& s) { build(s, "absorption"); }
BENCHMARK(BM_BuildMap)->Arg(1024)->Arg(2048)->Arg(4096)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BuildTransmittance)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BuildAbsorption)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

BENCHMARK_MAIN();
