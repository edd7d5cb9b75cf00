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

void frame(benchmark::State& state, ShadowKind kind) {
    const Scene& scene = treeScene();
    RenderOptions o;
    o.width = 1280;
    o.height = 720;
    o.shadow.kind = kind;
    warmUp(o);
    RenderTimings sum;
    for (auto _ : state) {
        const RenderResult r = render(scene, scene.cameras[0], o);
        benchmark::DoNotOptimize(r.image.pixels.data());
        sum.gbufferMs += r.timings.gbufferMs;
        sum.shadowMapMs += r.timings.shadowMapMs;
        sum.lightVoxelizeMs += r.timings.lightVoxelizeMs;
        sum.shadingMs += r.timings.shadingMs;
    }
    const double n = double(state.iterations());
    state.counters["gbuffer_ms"] = sum.gbufferMs / n;
    state.counters["shadowmap_ms"] = sum.shadowMapMs / n;
    state.counters["voxelize_ms"] = sum.lightVoxelizeMs / n;
    state.counters["shading_ms"] = sum.shadingMs / n;
    state.SetLabel(std::to_string(scene.triangleCount()) + " triangles, 1280x720, " + toString(kind));
}

void BM_FrameNone(benchmark::State& s) { frame(s, ShadowKind::None); }
void BM_FrameMap(benchmark::State& s) { frame(s, ShadowKind::Map); }
void BM_FrameTransmittance(benchmark::State& s) { frame(s, ShadowKind::Transmittance); }
void BM_FrameAbsorption(benchmark::State& s) { frame(s, ShadowKind::Absorption); }
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
    map.shadow.kind = ShadowKind::Map;
    tr.shadow.kind = ShadowKind::Transmittance;
    warmUp(map);
    RenderTimings sm, st;
    bool mapFirst = true;
    auto add = [](RenderTimings& to, const RenderTimings& t) {
        to.totalMs += t.totalMs;
        to.gbufferMs += t.gbufferMs;
        to.shadowMapMs += t.shadowMapMs;
        to.lightVoxelizeMs += t.lightVoxelizeMs;
        to.shadingMs += t.shadingMs;
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
    state.counters["map_ms"] = sm.totalMs / n;
    state.counters["tr_ms"] = st.totalMs / n;
    state.counters["tr/map"] = st.totalMs / sm.totalMs;
    state.counters["map_shadow_ms"] = sm.shadowMapMs / n;
    state.counters["map_shading_ms"] = sm.shadingMs / n;
    state.counters["tr_voxelize_ms"] = st.lightVoxelizeMs / n;
    state.counters["tr_trunkmap_ms"] = st.shadowMapMs / n;
    state.counters["tr_shading_ms"] = st.shadingMs / n;
    state.SetLabel(std::to_string(scene.triangleCount()) + " triangles, 1280x720, transmittance / map");
}
BENCHMARK(BM_FrameRatioTransmittanceOverMap)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// One light's shadow data alone, grid (or map) resolution N.
void build(benchmark::State& state, ShadowKind kind) {
    const Scene& scene = treeScene();
    ShadowOptions o;
    o.kind = kind;
    o.gridResolution = o.gridDepth = o.mapResolution = state.range(0);
    for (auto _ : state) {
        const LightShadow shadow = LightShadow::build(scene, scene.lights[0], o);
        benchmark::DoNotOptimize(&shadow);
    }
    state.counters["tri/s"] = benchmark::Counter(double(scene.triangleCount()) * double(state.iterations()),
                                                 benchmark::Counter::kIsRate);
}

void BM_BuildMap(benchmark::State& s) { build(s, ShadowKind::Map); }
void BM_BuildTransmittance(benchmark::State& s) { build(s, ShadowKind::Transmittance); }
void BM_BuildAbsorption(benchmark::State& s) { build(s, ShadowKind::Absorption); }
BENCHMARK(BM_BuildMap)->Arg(1024)->Arg(2048)->Arg(4096)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BuildTransmittance)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_BuildAbsorption)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

BENCHMARK_MAIN();
