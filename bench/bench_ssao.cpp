// Ambient occlusion at 1280 x 720 on the tree demo's G-buffer (921,600 samples): the screen-space
// method (render/screen_space_ao.hpp, GTAO) at half and full resolution next to the field method
// (voxfx/ambient_occlusion.hpp: the field's build, and one visibility lookup per covered sample, as
// the shading pass does), in one run; and the gathering of the surface buffers the screen-space
// method reads (surfaceAt per sample, which the shading pass computes anyway).
//
//   ./build/bench_ssao --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// ScreenSpace*/D/S: D directions, S steps (2/4 the default since 2026-12-08, 2/5 before it, and
// cheaper and dearer settings);
// *Reused: the buffers kept from call to call (ScreenSpaceOcclusionScratch); */D/S/V: V 1 the horizon
// search in SIMD lanes (the default), 0 one side at a time. Times are process CPU
// time (all threads) next to wall time. Counters: samples/s (items processed), covered (samples
// showing geometry).
#include <string>

#include <benchmark/benchmark.h>

#include "demo/demo_scenes.hpp"
#include "render/screen_space_ao.hpp"
#include "voxfx/ambient_occlusion.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"

namespace {

using namespace voxfx;

constexpr int64_t kWidth = 1280, kHeight = 720;

// The tree scene's G-buffer and surfaces, and the field method's set-up as the renderer makes it.
struct Tree {
    Scene scene = demo::makeTreeScene();
    SceneGeometry geometry = flattenScene(scene);
    Frame frame = cameraFrame(scene.cameras[0], kWidth, kHeight);
    GBuffer gbuffer = renderGBuffer(geometry, frame);
    detail::SurfaceBuffers surfaces = detail::gatherSurfaces(gbuffer, geometry, scene.materials);
    detail::FieldOcclusionSetup setup = detail::fieldOcclusionSetup(
        geometry, scene.materials, scene.meshes.size(), 0, RenderOptions{}.occlusionResolution);
    int64_t covered = 0;
    Tree() {
        for (const uint8_t c : surfaces.covered) covered += c;
    }
    MeshView occluders() const {
        MeshView v;
        v.positions = &geometry.mesh.positions[0].x;
        v.vertexCount = geometry.mesh.positions.size();
        v.indices = setup.indices.data();
        v.triangleCount = setup.indices.size() / 3;
        return v;
    }
    AmbientOcclusionOptions fieldOptions() const {
        AmbientOcclusionOptions o;
        o.radius = setup.radius;
        o.resolution = setup.resolution;
        return o;
    }
};

const Tree& tree() {
    static const Tree t;
    return t;
}

void label(benchmark::State& state) {
    const Tree& t = tree();
    state.SetItemsProcessed(state.iterations() * kWidth * kHeight);
    state.counters["covered"] = double(t.covered);
    state.SetLabel("tree, 1280x720, radius " + std::to_string(t.setup.radius));
}

// Arguments: directions, steps (the defaults, and a cheaper and a dearer setting).
void screenSpace(benchmark::State& state, bool half) {
    const Tree& t = tree();
    detail::ScreenSpaceOcclusionOptions o;
    o.radius = t.setup.radius;
    o.halfResolution = half;
    o.directions = int(state.range(0));
    o.steps = int(state.range(1));
    for (auto _ : state) {
        const std::vector<float> v =
            detail::screenSpaceOcclusion(t.frame, kWidth, kHeight, t.surfaces.position, t.surfaces.normal,
                                         t.surfaces.covered, o, t.surfaces.occluder);
        benchmark::DoNotOptimize(v.data());
    }
    label(state);
}

// The same with the buffers kept from call to call (ScreenSpaceOcclusionScratch and the output), as a
// renderer that keeps them across frames would: no page faults, no zero fill. Third argument: the
// horizon search in SIMD lanes (1, the default) or one side at a time (0, the scalar reference).
void screenSpaceReused(benchmark::State& state, bool half) {
    const Tree& t = tree();
    detail::ScreenSpaceOcclusionOptions o;
    o.radius = t.setup.radius;
    o.halfResolution = half;
    o.directions = int(state.range(0));
    o.steps = int(state.range(1));
    o.vectorWalk = state.range(2) != 0;
    detail::ScreenSpaceOcclusionScratch scratch;
    std::vector<float> v(std::size_t(kWidth * kHeight));
    for (auto _ : state) {
        detail::screenSpaceOcclusion(t.frame, kWidth, kHeight, t.surfaces.position, t.surfaces.normal,
                                     t.surfaces.covered, o, t.surfaces.occluder, v, scratch);
        benchmark::DoNotOptimize(v.data());
    }
    label(state);
}

void BM_ScreenSpaceHalf(benchmark::State& s) { screenSpace(s, true); }
void BM_ScreenSpaceHalfReused(benchmark::State& s) { screenSpaceReused(s, true); }
void BM_ScreenSpaceFullReused(benchmark::State& s) { screenSpaceReused(s, false); }
void BM_ScreenSpaceFull(benchmark::State& s) { screenSpace(s, false); }

void BM_GatherSurfaces(benchmark::State& state) {
    const Tree& t = tree();
    for (auto _ : state) {
        const detail::SurfaceBuffers s = detail::gatherSurfaces(t.gbuffer, t.geometry, t.scene.materials);
        benchmark::DoNotOptimize(s.position.data());
    }
    label(state);
}

void BM_FieldBuild(benchmark::State& state) {
    const Tree& t = tree();
    for (auto _ : state) {
        const AmbientOcclusion ao(t.occluders(), t.setup.region, t.fieldOptions());
        benchmark::DoNotOptimize(&ao);
    }
    label(state);
}

// One lookup per covered sample, rows in parallel (as the shading pass calls it).
void BM_FieldLookups(benchmark::State& state) {
    const Tree& t = tree();
    const AmbientOcclusion ao(t.occluders(), t.setup.region, t.fieldOptions());
    std::vector<float> out(std::size_t(kWidth * kHeight), 1.0f);
    for (auto _ : state) {
        parallelFor(0, kHeight, 16, [&](int64_t y0, int64_t y1) {
            for (auto i = std::size_t(y0 * kWidth); i < std::size_t(y1 * kWidth); ++i)
                if (t.surfaces.covered[i])
                    out[i] = float(ao.visibility(Vec3d(t.surfaces.position[i]), Vec3d(t.surfaces.normal[i])));
        });
        benchmark::DoNotOptimize(out.data());
    }
    label(state);
}

BENCHMARK(BM_ScreenSpaceHalf)
    ->Args({2, 4})
    ->Args({2, 5})
    ->Args({2, 6})
    ->Args({1, 8})
    ->Args({3, 4})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_ScreenSpaceHalfReused)
    ->Args({2, 5, 1})
    ->Args({2, 5, 0})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_ScreenSpaceFullReused)
    ->Args({2, 5, 1})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_ScreenSpaceFull)
    ->Args({2, 5})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK(BM_GatherSurfaces)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_FieldBuild)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_FieldLookups)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

} // namespace

BENCHMARK_MAIN();
