// Deep shadow maps on the DSM demo scene (examples/dsm-demo: bunny, translucent knot, CT skull and
// smoke volumes, one spot light, a receiving ground), the paper's tables 1-3 (Bornik et al. 2012
// §6.2) at the paper's viewport, 720 x 480:
//
//   BM_DsmTable13/S/R/C/F   one frame; S storage (0 fixed: the paper's table 1 "3D texture",
//                           1 chunked: table 3), R the map resolution (256, 512, 1024), C clusters (0:
//                           one map; 4: four clusters at equal texels, each about (R/2)^2 as the
//                           paper's 4 x 128^2 against 256^2; d0 = 0 so every object is its own
//                           cluster), F the lookup filter (0 bilinear, 1 none)
//   BM_DsmTable2/D          one frame with the smoke volume at D^3 voxels (24, 48, 96), chunked,
//                           4 clusters at 512^2 equal texels (the paper's 4 x 256^2), bilinear
//
//   ./build/bench/bench_dsm_tables --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Counters (per frame, averaged over the iterations): gen_ms (the shadows pass: fragment lists,
// walking and compressing every texel), render_ms (the frame without it: G-buffer, shading, glass,
// volume ray casting, resolve), nodes_mean (over all texels, most see no caster) and nodes_max,
// MiB (the maps' storage), maps.
#include <map>
#include <memory>
#include <string>

#include <benchmark/benchmark.h>

#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume_scene.hpp"

namespace {

using namespace voxfx;

const Scene& dsmDemo() {
    static const Scene scene = loadScene(VOXFX_DATA_DIR "/../examples/dsm-demo/scene.json");
    return scene;
}

void dsmFrame(benchmark::State& state, const Scene& scene, const char* storage, int64_t resolution,
              int clusters, const char* filter) {
    RenderOptions o;
    o.width = 720;
    o.height = 480;
    o.shadow = shadowOptionsNamed("deep");
    setRenderOption(o, "dsmStorage", std::string(storage));
    setRenderOption(o, "dsmResolution", resolution);
    setRenderOption(o, "clusters", int64_t(clusters));
    setRenderOption(o, "clusterThreshold", 0.0);
    setRenderOption(o, "dsmFilter", std::string(filter));
    const Camera camera = sceneCamera(scene, 0, double(o.width) / double(o.height));
    double gen = 0, rest = 0;
    DeepShadowStats stats;
    for (auto _ : state) {
        const RenderResult r = render(scene, camera, o);
        benchmark::DoNotOptimize(r.image.pixels.data());
        const double shadows = r.timings.ms("shadows");
        gen += shadows;
        for (const char* pass : {"flatten", "G-buffer", "shading", "glass", "ray casting", "resolve"})
            rest += r.timings.ms(pass);
        stats = std::get<DeepShadowStats>(r.shadowStats);
    }
    const double n = double(state.iterations());
    state.counters["gen_ms"] = gen / n;
    state.counters["render_ms"] = rest / n;
    state.counters["nodes_mean"] = stats.meanNodes();
    state.counters["nodes_max"] = double(stats.maxNodes);
    state.counters["MiB"] = double(stats.bytes) / 1048576.0;
    state.counters["maps"] = double(stats.clusteredLights ? stats.clusterViews : 1);
    state.SetLabel(std::string(storage) + " " + std::to_string(resolution) + "^2" +
                   (clusters ? " clusters " + std::to_string(clusters) : "") + " filter " + filter);
}

void BM_DsmTable13(benchmark::State& state) {
    dsmFrame(state, dsmDemo(), state.range(0) ? "chunked" : "fixed", state.range(1), int(state.range(2)),
             state.range(3) ? "none" : "bilinear");
}

// The demo scene with its smoke at D^3 voxels.
const Scene& demoWithSmoke(int64_t d) {
    static std::map<int64_t, Scene> scenes;
    auto it = scenes.find(d);
    if (it != scenes.end()) return it->second;
    Scene s = dsmDemo();
    auto vs = std::make_shared<VolumeScene>(*s.volumeScene);
    for (VolumeSceneObject& o : vs->objects)
        if (o.name == "smoke") {
            SmokeParams sp;
            sp.dims = {int(d), int(d), int(d)};
            sp.box = vs->volumes[std::size_t(o.volume)]->box();
            sp.seed = 3;
            vs->volumes[std::size_t(o.volume)] = std::make_shared<Volume>(makeSmoke(sp));
        }
    s.volumeScene = vs;
    return scenes.emplace(d, std::move(s)).first->second;
}

void BM_DsmTable2(benchmark::State& state) {
    dsmFrame(state, demoWithSmoke(state.range(0)), "chunked", 512, 4, "bilinear");
}

BENCHMARK(BM_DsmTable13)
    ->ArgsProduct({{0, 1}, {256, 512, 1024}, {0, 4}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_DsmTable2)
    ->Arg(24)
    ->Arg(48)
    ->Arg(96)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

} // namespace

BENCHMARK_MAIN();
