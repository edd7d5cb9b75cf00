// Interactive frames (issue #34): the default voxfx frame against a yardstick, a minimal Embree ray
// tracer of the same scene, measured side by side in one run; and, on a forest of 10^4..10^6 leaf
// triangles, the voxel shadow techniques against the exact reference that traces every leaf.
//
// The yardstick (class Yardstick) is what a real-time ray tracer does per frame and no more: an
// Embree 3 BVH over every triangle of the scene's meshes, built each frame
// (RTC_BUILD_QUALITY_MEDIUM, Embree's default; the copy of the vertices and indices into Embree's
// buffers included), one primary ray per pixel through the pixel's centre of the same camera
// frame, at a hit one opaque shadow ray (rtcOccluded1) towards the scene's first light (the
// renderer's default sun where the scene has none), Lambert shading of the material's base colour
// (double-sided, no transmission), an image buffer written. Every frame runs under
// withThreads(kThreads), the same thread count the voxfx frame gets; the Embree device is made once
// per process, as an application keeps it. It traces triangles only: the volume objects of the DSM
// demo (its CT skull and smoke) are not in it.
//
//   BM_Frame/<scene>             the default frame (renderOptionsFor(scene): AA, ambient occlusion,
//                                sky, the scene's shadows; 1280x720, 2 threads) and the yardstick,
//                                alternating which goes first per iteration, after one untimed
//                                frame of each. Counters (ms per frame): frame_ms, one per pass
//                                (flatten_ms, gbuffer_ms, occlusion_ms, shadows_ms, shading_ms,
//                                translucency_ms, glass_ms, ray_casting_ms, resolve_ms), yard_ms
//                                (yard_build_ms: the BVH, yard_trace_ms: the rays and shading) and
//                                frame/yard, the ratio (target <= 2); frame_cpu_ms,
//                                yard_cpu_ms and frame/yard_cpu: the same in process CPU time (all
//                                threads), which a shared machine's load does not inflate.
//   BM_Frame/<scene>_cached      the same as an interactive frame: a RenderCache kept across frames
//                                and the camera orbiting a degree per frame (the view-dependent
//                                passes made anew, the scene's builds reused).
//   BM_FrameCost/<scene>         cached frames with every default, with --aa off and with --ao off,
//                                interleaved: aa_ratio (target <= 1.3), ao_share (target <= 0.15);
//                                take --benchmark_min_time=6 (the default gives one or two frames).
//   BM_ForestShadows/<kind>/leavesPerTree:<L>
//                                the forest of 64 trees of L leaf quads (2L triangles) each: the
//                                default frame with shadows <kind>, with exact shadows and with
//                                none, in turn (<kind>_cached: interactive frames, each with a cache
//                                of its own, the camera orbiting). kind_ms, exact_ms, none_ms, exact/kind
//                                (the target: >= 1.5 for transmittance and absorption), kind_cost_ms
//                                and exact_cost_ms (each frame less the unshadowed one: what the
//                                shadows cost), the same in process CPU time (*_cpu_ms,
//                                exact/kind_cpu), the passes where they cost (kind_shadows_ms: the
//                                build; *_shading_ms, *_ray_casting_ms: the lookups or shadow rays);
//                                the error of the linear image (tone map clamp) against the exact
//                                one: mae over every channel of every pixel, mae_shadowed over the
//                                pixels the exact shadows change (`shadowed`: their fraction), and
//                                exact_mean (the exact image's mean) for scale.
//   BM_ForestShadowLookups/<kind>/leavesPerTree:1000
//                                the shadow lookups alone: shadowVisibility of the built shadow at
//                                the points of the forest's frame that ask the sun, 2 threads;
//                                cpu_ns (process CPU ns per lookup), ns (wall), lit (mean
//                                visibility: unchanged by a change that keeps the answers).
//   BM_DsmDeepVsExact/epsilon_x1000:<1000 eps>
//                                the DSM demo (examples/dsm-demo/scene.json) at 1280x720: deep
//                                shadows at compression tolerance eps against exact shadows, which
//                                march the skull and the smoke (voxfx/exact_shadow.hpp); the same
//                                counters as the forest's.
//   BM_GlassLattice              the glass demo's interactive frame with the glass lattice (the
//                                default) against every cell traced (--glass-refinement 0),
//                                interleaved: lattice_ratio(_cpu), glass_ms, paths, interpolated.
//   BM_GlassSamples/0, /1, /2    the same against fewer N-rooks samples inside glass
//                                (--glass-sample-contrast 1/4, 1), or more (1/32, the default before
//                                frames-glass8): sample_ratio(_cpu).
//   BM_GlassPaths                where a glass path's CPU goes: the glass demo's exact paths (one per
//                                pixel centre on glass) and each query kind alone, one thread
//                                (path_ms, eye_ms, reflect_ms, exit_ms, events_per_path).
//
//   build/bench_frame --benchmark_filter='BM_Frame/' --benchmark_repetitions=3
//   build/bench_frame --benchmark_filter=BM_FrameCost
//   build/bench_frame --benchmark_filter='BM_ForestShadows/.*:(100|1000)/'
//   build/bench_frame --benchmark_filter=BM_DsmDeepVsExact
//
// The machine is shared: compare ratios taken within one run (each iteration renders both sides),
// not times across runs.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <sys/resource.h>

#include "demo/demo_scenes.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/environment_io.hpp"
#include "voxfx/error.hpp"
#include "voxfx/exact_glass.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/triangle_tracer.hpp"
#include "voxfx/view.hpp"

namespace {

using namespace voxfx;

constexpr int kThreads = 2; // the issue's: both sides get the same two threads
constexpr int64_t kWidth = 1280, kHeight = 720;

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// CPU time of the whole process (every thread: the renderer's and Embree's workers), user and
// system, in milliseconds: on a shared machine it measures the work, which waiting for a core does
// not inflate.
double processCpuMs() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e3 +
           double(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-3;
}

// ---- The yardstick: a minimal Embree ray tracer -------------------------------------------------

class Yardstick {
public:
    struct Frame {
        Image image;
        double buildMs = 0, traceMs = 0, totalMs = 0;
    };

    Yardstick() : device_(rtcNewDevice(nullptr)) {
        if (!device_) fail("yardstick: Embree could not create a device");
    }
    ~Yardstick() { rtcReleaseDevice(device_); }
    Yardstick(const Yardstick&) = delete;
    Yardstick& operator=(const Yardstick&) = delete;

    Frame render(const Scene& scene, const Camera& camera, int64_t width, int64_t height) const {
        Frame out;
        const auto t0 = std::chrono::steady_clock::now();
        withThreads(kThreads, [&] {
            // The BVH over every mesh, one geometry each (its ID the mesh's index).
            RTCScene rs = rtcNewScene(device_);
            rtcSetSceneBuildQuality(rs, RTC_BUILD_QUALITY_MEDIUM);
            Box3d bounds;
            for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
                const Mesh& mesh = scene.meshes[m].mesh;
                if (mesh.indices.empty()) continue;
                RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
                void* v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                  3 * sizeof(float), mesh.positions.size());
                void* t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                  3 * sizeof(uint32_t), mesh.triangleCount());
                static_assert(sizeof(Vec3f) == 3 * sizeof(float));
                std::memcpy(v, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3f));
                std::memcpy(t, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
                rtcCommitGeometry(g);
                rtcAttachGeometryByID(rs, g, unsigned(m));
                rtcReleaseGeometry(g);
                bounds.extend(computeBounds(mesh.view()));
            }
            rtcCommitScene(rs);
            if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) fail("yardstick: Embree failed to build");
            out.buildMs = msSince(t0);

            // The light: the first, else the renderer's default sun.
            Light light;
            if (!scene.lights.empty()) {
                light = scene.lights[0];
            } else {
                static const Environment sky = Environment::sky();
                light.direction = -normalize(sky.sunDirection());
                light.color = {1.0f, 0.96f, 0.9f};
                light.intensity = 3;
            }
            const float offset = float(1e-4 * length(bounds.extent()));
            const voxfx::Frame frame = cameraFrame(camera, width, height);
            const Vec3d eye = frame.eye();
            out.image = Image(width, height);
            const auto t1 = std::chrono::steady_clock::now();
            parallelFor(0, height, 4, [&](int64_t y0, int64_t y1) {
                RTCIntersectContext context;
                rtcInitIntersectContext(&context);
                for (int64_t y = y0; y < y1; ++y)
                    for (int64_t x = 0; x < width; ++x) {
                        const Vec3d d =
                            normalize(frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
                        RTCRayHit rh{};
                        rh.ray.org_x = float(eye.x), rh.ray.org_y = float(eye.y), rh.ray.org_z = float(eye.z);
                        rh.ray.dir_x = float(d.x), rh.ray.dir_y = float(d.y), rh.ray.dir_z = float(d.z);
                        rh.ray.tnear = 0;
                        rh.ray.tfar = std::numeric_limits<float>::infinity();
                        rh.ray.mask = 0xffffffffu;
                        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                        rtcIntersect1(rs, &context, &rh);
                        Vec3f c{0.6f, 0.72f, 0.9f}; // a flat sky
                        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
                            const SceneMesh& sm = scene.meshes[rh.hit.geomID];
                            const Vec3f albedo = scene.materials[sm.material].baseColor;
                            Vec3d n = normalize(Vec3d{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
                            if (dot(n, d) > 0) n = -n; // double-sided: the side facing the eye
                            const Vec3d p = eye + d * double(rh.ray.tfar);
                            Vec3d l = -light.direction;
                            float far = std::numeric_limits<float>::infinity();
                            double irradiance = light.intensity;
                            if (light.type != LightType::Directional) {
                                l = light.position - p;
                                const double dist = length(l);
                                l = l / dist;
                                far = float(dist) - offset;
                                irradiance /= dist * dist;
                            }
                            const double cosine = dot(n, l);
                            c = albedo * 0.1f; // ambient
                            if (cosine > 0) {
                                const Vec3d o = p + n * double(offset);
                                RTCRay shadow{};
                                shadow.org_x = float(o.x), shadow.org_y = float(o.y),
                                shadow.org_z = float(o.z);
                                shadow.dir_x = float(l.x), shadow.dir_y = float(l.y),
                                shadow.dir_z = float(l.z);
                                shadow.tnear = 0;
                                shadow.tfar = far;
                                shadow.mask = 0xffffffffu;
                                rtcOccluded1(rs, &context, &shadow);
                                // rtcOccluded1 sets tfar to -inf when something blocks the ray.
                                if (shadow.tfar >= 0)
                                    c += albedo * light.color * float(irradiance * cosine / M_PI);
                            }
                        }
                        out.image.at(x, height - 1 - y) = c;
                    }
            });
            out.traceMs = msSince(t1);
            rtcReleaseScene(rs);
        });
        out.totalMs = msSince(t0);
        return out;
    }

private:
    RTCDevice device_;
};

const Yardstick& yardstick() {
    static const Yardstick y;
    return y;
}

// ---- Scenes and their default frames -----------------------------------------------------------

struct BenchScene {
    Scene scene;
    Camera camera;
    std::string label;
};

// The renderer's defaults for the scene, at 1280x720 on kThreads threads (shadows: the scene's, or
// `shadows` where given).
RenderOptions frameOptions(const Scene& scene, std::string_view shadows = {}) {
    RenderOptions o = renderOptionsFor(scene, shadows);
    o.width = kWidth;
    o.height = kHeight;
    o.threads = kThreads;
    o.environment = loadSceneEnvironment(scene, o);
    return o;
}

BenchScene makeBenchScene(Scene scene) {
    BenchScene b;
    b.camera = sceneCamera(scene, 0, double(kWidth) / double(kHeight));
    b.label = std::to_string(scene.triangleCount()) + " triangles (" +
              std::to_string(demo::leafTriangleCount(scene)) + " partial occluders)";
    b.scene = std::move(scene);
    return b;
}

const BenchScene& benchScene(const std::string& name) {
    static std::map<std::string, BenchScene> scenes;
    auto it = scenes.find(name);
    if (it != scenes.end()) return it->second;
    Scene s = name == "dsm-demo" ? loadScene(VOXFX_DATA_DIR "/../examples/dsm-demo/scene.json")
                                 : demo::makeDemoScene(name, VOXFX_DATA_DIR "/meshes");
    return scenes.emplace(name, makeBenchScene(std::move(s))).first->second;
}

const BenchScene& forest(int leavesPerTree) {
    static std::map<int, BenchScene> forests;
    auto it = forests.find(leavesPerTree);
    if (it != forests.end()) return it->second;
    demo::ForestOptions fo;
    fo.leavesPerTree = leavesPerTree;
    return forests.emplace(leavesPerTree, makeBenchScene(demo::makeForestScene(fo))).first->second;
}

// How the loop gets a frame: from nothing (render(scene, camera, options): every build made
// again, a first frame), or as an interactive frame (a RenderCache kept across the frames, filled by
// the untimed warm-up, and the camera orbiting a degree further about its target each frame, so
// that the G-buffer, occlusion, shading and everything fitted to the view are made anew while the
// scene's builds are reused, as in a viewer).
using FrameFn = std::function<RenderResult()>;
FrameFn firstFrames(const BenchScene& b, RenderOptions o) {
    return [&b, o] { return render(b.scene, b.camera, o); };
}
FrameFn cachedFrames(const BenchScene& b, RenderOptions o) {
    auto cache = std::make_shared<RenderCache>();
    auto frame = std::make_shared<int>(0);
    return [&b, o, cache, frame] {
        const double yaw = (M_PI / 180) * double((*frame)++ % 10);
        return render(b.scene, orbitCamera(b.camera, yaw, 0), o, *cache);
    };
}

// Per-pass sums of a series of frames, and their process CPU time.
struct PassSums {
    double total = 0, cpu = 0;
    std::map<std::string, double> passes;
    void add(const RenderResult& r, double cpuMs) {
        total += r.timings.totalMs;
        cpu += cpuMs;
        for (const PassTime& p : r.timings.passes) passes[std::string(p.name)] += p.ms;
    }
    double pass(const char* name) const {
        const auto it = passes.find(name);
        return it == passes.end() ? 0 : it->second;
    }
};

// Calls every one of `frames` (frame(timed)) in each iteration, starting one further along each
// time (two: alternating which goes first) so that load changes hit them alike, after one untimed
// call of each where `warmUp` (the process's first large allocations fault their pages in; a cache
// would fill).
void interleaved(benchmark::State& state, const std::vector<std::function<void(bool)>>& frames,
                 bool warmUp = true) {
    if (warmUp)
        for (const auto& f : frames) f(false);
    std::size_t first = 0;
    for (auto _ : state) {
        for (std::size_t i = 0; i < frames.size(); ++i) frames[(first + i) % frames.size()](true);
        first = (first + 1) % frames.size();
    }
}

// "shadows_ms" from "shadows", "gbuffer_ms" from "G-buffer".
std::string counterName(std::string_view pass, std::string_view prefix = {}) {
    std::string s(prefix);
    for (const char c : pass)
        if (c != '-') s += c == ' ' ? '_' : char(std::tolower(static_cast<unsigned char>(c)));
    return s + "_ms";
}

// Mean absolute difference of two images over every channel of every pixel.
double meanAbsDifference(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height) fail("images of different sizes");
    double sum = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) sum += std::abs(double(a.pixels[i][c]) - double(b.pixels[i][c]));
    return sum / (3.0 * double(a.pixels.size()));
}

double meanValue(const Image& a) {
    double sum = 0;
    for (const Vec3f& p : a.pixels) sum += double(p.x) + double(p.y) + double(p.z);
    return sum / (3.0 * double(a.pixels.size()));
}

void BM_Frame(benchmark::State& state, const std::string& name, bool cached) {
    const BenchScene& b = benchScene(name);
    const RenderOptions options = frameOptions(b.scene);
    const FrameFn frame = cached ? cachedFrames(b, options) : firstFrames(b, options);
    PassSums sums;
    double yard = 0, yardBuild = 0, yardTrace = 0, yardCpu = 0;
    interleaved(state, {[&](bool timed) {
                            const double cpu0 = processCpuMs();
                            const RenderResult r = frame();
                            benchmark::DoNotOptimize(r.image.pixels.data());
                            if (timed) sums.add(r, processCpuMs() - cpu0);
                        },
                        [&](bool timed) {
                            const double cpu0 = processCpuMs();
                            const Yardstick::Frame y = yardstick().render(b.scene, b.camera, kWidth, kHeight);
                            benchmark::DoNotOptimize(y.image.pixels.data());
                            if (!timed) return;
                            yardCpu += processCpuMs() - cpu0;
                            yard += y.totalMs;
                            yardBuild += y.buildMs;
                            yardTrace += y.traceMs;
                        }});
    const double n = double(state.iterations());
    state.counters["frame_ms"] = sums.total / n;
    for (const auto& [pass, ms] : sums.passes) state.counters[counterName(pass)] = ms / n;
    state.counters["yard_ms"] = yard / n;
    state.counters["yard_build_ms"] = yardBuild / n;
    state.counters["yard_trace_ms"] = yardTrace / n;
    state.counters["frame/yard"] = sums.total / yard;
    state.counters["frame_cpu_ms"] = sums.cpu / n;
    state.counters["yard_cpu_ms"] = yardCpu / n;
    state.counters["frame/yard_cpu"] = sums.cpu / yardCpu;
    state.SetLabel(name + ": " + b.label + ", 1280x720, shadows " + std::string(shadowName(options.shadow)) +
                   (cached ? ", cached" : ", first frame"));
}
// BM_Frame/<scene>: first frames (every build made per frame); BM_Frame/<scene>_cached: interactive
// frames (a RenderCache, the camera orbiting).
#define VOXFX_FRAME_SCENE(id, name)                                                                          \
    BENCHMARK_CAPTURE(BM_Frame, id, std::string(name), false)->Unit(benchmark::kMillisecond)->UseRealTime(); \
    BENCHMARK_CAPTURE(BM_Frame, id##_cached, std::string(name), true)                                        \
        ->Unit(benchmark::kMillisecond)                                                                      \
        ->UseRealTime()
VOXFX_FRAME_SCENE(tree, "tree");
VOXFX_FRAME_SCENE(bunny, "bunny");
VOXFX_FRAME_SCENE(cgal, "cgal");
VOXFX_FRAME_SCENE(glass, "glass");
VOXFX_FRAME_SCENE(dsm_demo, "dsm-demo");
VOXFX_FRAME_SCENE(forest, "forest");

// What anti-aliasing and ambient occlusion cost in an interactive frame: the default frame, the
// same with --aa off and with --ao off, each with a RenderCache of its own and the camera orbiting,
// interleaved. aa_ratio = frame / aa_off (the target: <= 1.3), ao_share = (frame - ao_off) /
// frame (target: <= 0.15; the occlusion pass and what the shading spends reading it), and
// occlusion_share: the occlusion pass alone over the frame.
void BM_FrameCost(benchmark::State& state, const std::string& name) {
    const BenchScene& b = benchScene(name);
    const RenderOptions options = frameOptions(b.scene);
    RenderOptions aaOff = options, aoOff = options;
    aaOff.antiAliasing = AntiAliasing::Off;
    aoOff.ambientOcclusion = Occlusion::Off;
    PassSums full, noAa, noAo;
    auto into = [&](const RenderOptions& o, PassSums& sums) {
        FrameFn frame = cachedFrames(b, o);
        return [&sums, frame](bool timed) {
            const double cpu0 = processCpuMs();
            const RenderResult r = frame();
            benchmark::DoNotOptimize(r.image.pixels.data());
            if (timed) sums.add(r, processCpuMs() - cpu0);
        };
    };
    interleaved(state, {into(options, full), into(aaOff, noAa), into(aoOff, noAo)});
    const double n = double(state.iterations());
    state.counters["frame_ms"] = full.total / n;
    state.counters["aa_off_ms"] = noAa.total / n;
    state.counters["ao_off_ms"] = noAo.total / n;
    state.counters["occlusion_ms"] = full.pass("occlusion") / n;
    state.counters["aa_ratio"] = full.total / noAa.total;
    state.counters["aa_ratio_cpu"] = full.cpu / noAa.cpu;
    state.counters["ao_share"] = (full.total - noAo.total) / full.total;
    state.counters["ao_share_cpu"] = (full.cpu - noAo.cpu) / full.cpu;
    state.counters["occlusion_share"] = full.pass("occlusion") / full.total;
    // Where anti-aliasing costs: the passes it makes dearer (ms per frame, with AA and without).
    for (const char* pass : {"G-buffer", "shading", "resolve"}) {
        state.counters[counterName(pass)] = full.pass(pass) / n;
        state.counters[counterName(pass, "aa_off_")] = noAa.pass(pass) / n;
    }
    state.SetLabel(name + ": default, --aa off, --ao off; 1280x720, cached, orbiting");
}
BENCHMARK_CAPTURE(BM_FrameCost, tree, std::string("tree"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_FrameCost, bunny, std::string("bunny"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_FrameCost, cgal, std::string("cgal"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_FrameCost, glass, std::string("glass"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_FrameCost, forest, std::string("forest"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_FrameCost, dsm_demo, std::string("dsm-demo"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The glass demo's interactive frames with the default options against `other`, each with a
// RenderCache of its own and the camera orbiting, interleaved: <ratio> = frame / other_ms (wall;
// <ratio>_cpu: process CPU), glass_ms and other_glass_ms the glass pass, paths and other_paths the
// glass paths traced per frame, interpolated the cells whose light through the glass was
// interpolated (default frame).
void glassAgainst(benchmark::State& state, const RenderOptions& other, const std::string& ratio,
                  const std::string& label) {
    const BenchScene& b = benchScene("glass");
    const RenderOptions options = frameOptions(b.scene);
    RenderOptions o2 = options;
    o2.glassRefinement = other.glassRefinement;
    o2.glassSampleContrast = other.glassSampleContrast;
    PassSums mine, theirs;
    double paths = 0, otherPaths = 0, interpolated = 0;
    auto into = [&](const RenderOptions& o, PassSums& sums, double& pathSum, bool counts) {
        FrameFn frame = cachedFrames(b, o);
        return [&sums, &pathSum, &interpolated, frame, counts](bool timed) {
            const double cpu0 = processCpuMs();
            const RenderResult r = frame();
            benchmark::DoNotOptimize(r.image.pixels.data());
            if (!timed) return;
            sums.add(r, processCpuMs() - cpu0);
            pathSum += double(r.glass.paths);
            if (counts) interpolated += double(r.glass.interpolated);
        };
    };
    interleaved(state, {into(options, mine, paths, true), into(o2, theirs, otherPaths, false)});
    const double n = double(state.iterations());
    state.counters["frame_ms"] = mine.total / n;
    state.counters["other_ms"] = theirs.total / n;
    state.counters["glass_ms"] = mine.pass("glass") / n;
    state.counters["other_glass_ms"] = theirs.pass("glass") / n;
    state.counters[ratio] = mine.total / theirs.total;
    state.counters[ratio + "_cpu"] = mine.cpu / theirs.cpu;
    state.counters["paths"] = paths / n;
    state.counters["other_paths"] = otherPaths / n;
    state.counters["interpolated"] = interpolated / n;
    state.SetLabel("glass: default against " + label + "; 1280x720, cached, orbiting");
}

// The glass lattice (RenderOptions::glassRefinement): the default frame against every cell and
// every anti-aliasing sample traced (glassRefinement 0, the image before the lattice).
void BM_GlassLattice(benchmark::State& state) {
    RenderOptions every;
    every.glassRefinement = 0;
    glassAgainst(state, every, "lattice_ratio", "--glass-refinement 0");
}
BENCHMARK(BM_GlassLattice)->Unit(benchmark::kMillisecond)->UseRealTime();

// Anti-aliasing inside glass (RenderOptions::glassSampleContrast): the default frame (N-rooks samples
// where the glass's light bends by more than 1/16) against fewer samples, where it bends by more than
// 1/4 or 1 (none), or more, by more than 1/32 (the default before frames-glass8): what the option buys
// (the image's error against a supersampled reference: BENCHMARKS.md, "N-rooks samples inside glass
// against a supersampled reference" and frames-glass8).
void BM_GlassSamples(benchmark::State& state) {
    static constexpr double kContrast[3] = {1.0 / 4, 1.0, 1.0 / 32};
    static const char* const kLabel[3] = {"--glass-sample-contrast 1/4", "--glass-sample-contrast 1",
                                          "--glass-sample-contrast 1/32"};
    RenderOptions other;
    other.glassSampleContrast = kContrast[state.range(0)];
    glassAgainst(state, other, "sample_ratio", kLabel[state.range(0)]);
}
BENCHMARK(BM_GlassSamples)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Where a glass path's CPU goes, on the glass demo's camera paths (one per pixel centre at 1280x720
// that meets glass, the demo's first camera), each query kind timed alone, one at a time, on one
// thread (process CPU ms per pass over the paths): path_ms, the whole ExactGlass::trace of each (its
// first query from the eye, then the next-face queries inside the glass and the touching-glass
// queries); eye_ms, the eye rays' first query alone (Embree over the glass triangles);
// reflect_ms and exit_ms, the glass pass's two queries into the opaque scene per path (the
// reflection at the first surface, the light leaving the glass); events_per_path. The shading of
// what those queries find is not in it (the frame's glass_ms has it).
void BM_GlassPaths(benchmark::State& state) {
    const BenchScene& b = benchScene("glass");
    const SceneGeometry g = flattenScene(b.scene);
    Mesh glass, opaque;
    glass.positions = opaque.positions = g.mesh.positions;
    std::vector<uint32_t> medium;
    std::vector<GlassMedium> media;
    for (const Material& m : b.scene.materials) media.push_back(glassMedium(m));
    for (size_t t = 0; t < g.mesh.triangleCount(); ++t) {
        const bool isGlass = b.scene.materials[g.triangleMaterial[t]].isGlass();
        for (int k = 0; k < 3; ++k)
            (isGlass ? glass : opaque).indices.push_back(g.mesh.indices[3 * t + size_t(k)]);
        if (isGlass) medium.push_back(g.triangleMaterial[t]);
    }
    const ExactGlass exact(glass.view(), g.normals, medium, media);
    const TriangleTracer glassTracer(glass.view()), behind(opaque.view());
    const voxfx::Frame frame = cameraFrame(b.camera, kWidth, kHeight);
    const Vec3d eye = frame.eye();
    struct Ray {
        Vec3d origin, dir;
    };
    std::vector<Ray> eyeRays, reflections, exits;
    double events = 0;
    for (int64_t y = 0; y < kHeight; ++y)
        for (int64_t x = 0; x < kWidth; ++x) {
            const Vec3d d = normalize(frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
            const GlassPath p = exact.trace(eye, d, ExactGlassOptions{}.maxEvents);
            const TriangleTracer::Hit first = glassTracer.intersect(eye, d, 0, 1e30);
            if (!p.hit || !first.hit) continue;
            eyeRays.push_back({eye, d});
            events += p.events;
            reflections.push_back({eye + d * first.t, p.reflectDir});
            exits.push_back({p.exitPoint, p.exitDir});
        }
    const auto queries = [](const TriangleTracer& tracer, const std::vector<Ray>& rays) {
        const double c0 = processCpuMs();
        int hits = 0;
        for (const Ray& r : rays) hits += tracer.intersect(r.origin, r.dir, 0, 1e30).hit;
        benchmark::DoNotOptimize(hits);
        return processCpuMs() - c0;
    };
    double pathMs = 0, eyeMs = 0, reflectMs = 0, exitMs = 0;
    int64_t n = 0;
    for (auto _ : state) {
        const double c0 = processCpuMs();
        for (const Ray& r : eyeRays)
            benchmark::DoNotOptimize(exact.trace(r.origin, r.dir, ExactGlassOptions{}.maxEvents));
        pathMs += processCpuMs() - c0;
        eyeMs += queries(glassTracer, eyeRays);
        reflectMs += queries(behind, reflections);
        exitMs += queries(behind, exits);
        ++n;
    }
    state.counters["paths"] = double(eyeRays.size());
    state.counters["events_per_path"] = events / double(eyeRays.size());
    state.counters["path_ms"] = pathMs / double(n);
    state.counters["eye_ms"] = eyeMs / double(n);
    state.counters["reflect_ms"] = reflectMs / double(n);
    state.counters["exit_ms"] = exitMs / double(n);
    state.SetLabel("glass demo, 1280x720 pixel centres on glass, 1 thread, process CPU");
}
BENCHMARK(BM_GlassPaths)->Unit(benchmark::kMillisecond)->UseRealTime();

// For counting rather than timing (the machine is shared: `perf stat -e cycles:u,instructions:u`
// counts the process's own work whatever the load): one warm-up frame, then VOXFX_BENCH_FRAMES
// (default 8) cached frames of one variant (default, --aa off, --ao off), the camera orbiting as in
// BM_FrameCost; run it with 0 frames too and take the difference for the frames' own cost.
void BM_FrameVariant(benchmark::State& state, const std::string& name, int variant) {
    const BenchScene& b = benchScene(name);
    RenderOptions o = frameOptions(b.scene);
    if (variant == 1) o.antiAliasing = AntiAliasing::Off;
    if (variant == 2) o.ambientOcclusion = Occlusion::Off;
    const char* env = std::getenv("VOXFX_BENCH_FRAMES");
    const int frames = env ? std::atoi(env) : 8;
    const FrameFn frame = cachedFrames(b, o);
    benchmark::DoNotOptimize(frame().image.pixels.data());
    for (auto _ : state)
        for (int i = 0; i < frames; ++i) benchmark::DoNotOptimize(frame().image.pixels.data());
    state.SetLabel(name + (variant == 0 ? ": default" : variant == 1 ? ": --aa off" : ": --ao off"));
}
#define VOXFX_FRAME_VARIANTS(id, scene)                                                                      \
    BENCHMARK_CAPTURE(BM_FrameVariant, id##_default, std::string(scene), 0)->Iterations(1);                  \
    BENCHMARK_CAPTURE(BM_FrameVariant, id##_aa_off, std::string(scene), 1)->Iterations(1);                   \
    BENCHMARK_CAPTURE(BM_FrameVariant, id##_ao_off, std::string(scene), 2)->Iterations(1)
VOXFX_FRAME_VARIANTS(tree, "tree");
VOXFX_FRAME_VARIANTS(bunny, "bunny");
VOXFX_FRAME_VARIANTS(cgal, "cgal");
VOXFX_FRAME_VARIANTS(forest, "forest");

// The linear (tone map clamp) frames of a scene with exact shadows and with none, made once.
struct LinearReferences {
    Image exact, none;
};
const LinearReferences& linearReferences(const BenchScene& b, RenderOptions exact, RenderOptions none) {
    static std::map<const BenchScene*, LinearReferences> made;
    auto it = made.find(&b);
    if (it != made.end()) return it->second;
    exact.toneMap = none.toneMap = ToneMap::Clamp;
    LinearReferences r;
    r.exact = render(b.scene, b.camera, exact).image;
    r.none = render(b.scene, b.camera, none).image;
    return made.emplace(&b, std::move(r)).first->second;
}

// One technique against the exact reference on one scene: its frame, the exact one and one without
// shadows, interleaved (the differences to the last are what each technique's shadows cost). The
// error of the technique's linear image (tone map clamp) against the exact one, over every channel
// of every pixel (mae) and over the pixels the exact shadows change (mae_shadowed: where the exact
// and the unshadowed images differ by more than 1e-3 summed over the channels; `shadowed` the
// fraction of such pixels), from untimed frames that also serve as the warm-up.
void againstExact(benchmark::State& state, const BenchScene& b, const RenderOptions& kind,
                  const RenderOptions& exact, bool cached = false) {
    RenderOptions none = exact;
    none.shadow = NoShadowOptions{};
    const LinearReferences& ref = linearReferences(b, exact, none);
    RenderOptions linearKind = kind;
    linearKind.toneMap = ToneMap::Clamp;
    const Image got = render(b.scene, b.camera, linearKind).image;
    double shadowedSum = 0;
    int64_t shadowed = 0;
    for (std::size_t i = 0; i < got.pixels.size(); ++i) {
        double touched = 0, err = 0;
        for (int c = 0; c < 3; ++c) {
            touched += std::abs(double(ref.exact.pixels[i][c]) - double(ref.none.pixels[i][c]));
            err += std::abs(double(got.pixels[i][c]) - double(ref.exact.pixels[i][c]));
        }
        if (touched <= 1e-3) continue;
        shadowedSum += err / 3;
        ++shadowed;
    }
    PassSums k, e, o;
    // Each its own frames: first frames, or interactive ones with a cache of its own.
    auto frameInto = [&](const RenderOptions& options, PassSums& sums) {
        FrameFn frame = cached ? cachedFrames(b, options) : firstFrames(b, options);
        return [&sums, frame](bool timed) {
            const double cpu0 = processCpuMs();
            const RenderResult r = frame();
            benchmark::DoNotOptimize(r.image.pixels.data());
            if (timed) sums.add(r, processCpuMs() - cpu0);
        };
    };
    interleaved(state, {frameInto(kind, k), frameInto(exact, e), frameInto(none, o)}, cached);
    const double n = double(state.iterations());
    state.counters["kind_ms"] = k.total / n;
    state.counters["exact_ms"] = e.total / n;
    state.counters["none_ms"] = o.total / n;
    state.counters["exact/kind"] = e.total / k.total;
    state.counters["kind_cost_ms"] = (k.total - o.total) / n;
    state.counters["exact_cost_ms"] = (e.total - o.total) / n;
    state.counters["kind_cpu_ms"] = k.cpu / n;
    state.counters["exact_cpu_ms"] = e.cpu / n;
    state.counters["none_cpu_ms"] = o.cpu / n;
    state.counters["exact/kind_cpu"] = e.cpu / k.cpu;
    state.counters["kind_cost_cpu_ms"] = (k.cpu - o.cpu) / n;
    state.counters["exact_cost_cpu_ms"] = (e.cpu - o.cpu) / n;
    state.counters["kind_shadows_ms"] = k.pass("shadows") / n;
    state.counters["kind_shading_ms"] = k.pass("shading") / n;
    state.counters["kind_ray_casting_ms"] = k.pass("ray casting") / n;
    state.counters["exact_shading_ms"] = e.pass("shading") / n;
    state.counters["exact_ray_casting_ms"] = e.pass("ray casting") / n;
    state.counters["none_shading_ms"] = o.pass("shading") / n;
    state.counters["none_ray_casting_ms"] = o.pass("ray casting") / n;
    state.counters["mae"] = meanAbsDifference(got, ref.exact);
    state.counters["mae_shadowed"] = shadowed ? shadowedSum / double(shadowed) : 0;
    state.counters["shadowed"] = double(shadowed) / double(got.pixels.size());
    state.counters["exact_mean"] = meanValue(ref.exact);
}

void BM_ForestShadows(benchmark::State& state, const std::string& kind, bool cached) {
    const BenchScene& b = forest(int(state.range(0)));
    againstExact(state, b, frameOptions(b.scene, kind), frameOptions(b.scene, "exact"), cached);
    state.SetLabel(kind + " against exact, forest of " + b.label + ", 1280x720" +
                   (cached ? ", cached" : ", first frames"));
}
// BM_ForestShadows/<kind>: first frames; BM_ForestShadows/<kind>_cached: interactive frames (each
// technique's builds and exact's BVH kept in a cache of their own, the camera orbiting).
#define VOXFX_FOREST_ARGS                                                                                    \
    ->Arg(100)->Arg(1000)->Arg(10000)->ArgName("leavesPerTree")->Unit(benchmark::kMillisecond)->UseRealTime()
#define VOXFX_FOREST_KIND(kind)                                                                              \
    BENCHMARK_CAPTURE(BM_ForestShadows, kind, std::string(#kind), false) VOXFX_FOREST_ARGS;                  \
    BENCHMARK_CAPTURE(BM_ForestShadows, kind##_cached, std::string(#kind), true) VOXFX_FOREST_ARGS
VOXFX_FOREST_KIND(transmittance);
VOXFX_FOREST_KIND(absorption);
VOXFX_FOREST_KIND(map);
VOXFX_FOREST_KIND(deep);

// The shading points of the forest's first frame that ask the sun for its shadow, as the shading
// pass asks (surfaces facing the light, and leaves lit from behind: the normal turned to the
// light's side), made once per forest.
struct LookupPoints {
    std::vector<Vec3d> position, normal;
};
const LookupPoints& forestLookupPoints(const BenchScene& b) {
    static std::map<const BenchScene*, LookupPoints> made;
    auto it = made.find(&b);
    if (it != made.end()) return it->second;
    const SceneGeometry geometry = flattenScene(b.scene);
    const GBuffer gbuffer = renderGBuffer(geometry, cameraFrame(b.camera, kWidth, kHeight));
    const Vec3d toLight = -normalize(b.scene.lights.at(0).direction);
    LookupPoints out;
    for (int64_t y = 0; y < kHeight; ++y)
        for (int64_t x = 0; x < kWidth; ++x) {
            SurfacePoint s;
            if (!surfaceAt(gbuffer, geometry, x, y, s)) continue;
            const bool front = dot(s.geometricNormal, toLight) > 0;
            if ((front ? 1.0 : -1.0) * dot(s.normal, toLight) <= 0) continue;
            out.position.push_back(s.position);
            out.normal.push_back(front ? s.geometricNormal : -s.geometricNormal);
        }
    return made.emplace(&b, std::move(out)).first->second;
}

// BM_ForestShadowLookups/<kind>: the shadow lookups alone (shadowVisibility of the built shadow at
// each of the frame's points above, on kThreads threads), in process CPU ns per lookup (cpu_ns) and
// wall ns per lookup (ns); `lit` is the mean visibility (the same for any change that keeps the
// answers).
void BM_ForestShadowLookups(benchmark::State& state, const std::string& kind) {
    const BenchScene& b = forest(int(state.range(0)));
    const LookupPoints& points = forestLookupPoints(b);
    const RenderOptions o = frameOptions(b.scene, kind);
    const LightShadow shadow = buildLightShadow(b.scene, b.scene.lights.at(0), o.shadow);
    const auto n = int64_t(points.position.size());
    std::vector<float> lit(static_cast<std::size_t>(n));
    double cpu = 0, wall = 0;
    for (auto _ : state) {
        const double cpu0 = processCpuMs();
        const auto t0 = std::chrono::steady_clock::now();
        withThreads(kThreads, [&] {
            parallelFor(0, n, 4096, [&](int64_t i0, int64_t i1) {
                for (int64_t i = i0; i < i1; ++i) {
                    const Vec3f v =
                        shadowVisibility(shadow, points.position[size_t(i)], points.normal[size_t(i)]);
                    lit[size_t(i)] = (v.x + v.y + v.z) / 3;
                }
            });
        });
        wall += msSince(t0);
        cpu += processCpuMs() - cpu0;
        benchmark::DoNotOptimize(lit.data());
    }
    const double lookups = double(n) * double(state.iterations());
    state.counters["ns"] = wall * 1e6 / lookups;
    state.counters["cpu_ns"] = cpu * 1e6 / lookups;
    state.counters["lookups"] = double(n);
    double sum = 0;
    for (const float v : lit) sum += double(v);
    state.counters["lit"] = sum / double(n);
    state.SetLabel(kind + " lookups, forest of " + b.label);
}
BENCHMARK_CAPTURE(BM_ForestShadowLookups, transmittance, std::string("transmittance"))
    ->Arg(1000)
    ->ArgName("leavesPerTree")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_ForestShadowLookups, absorption, std::string("absorption"))
    ->Arg(1000)
    ->ArgName("leavesPerTree")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_ForestShadowLookups, map, std::string("map"))
    ->Arg(1000)
    ->ArgName("leavesPerTree")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_ForestShadowLookups, exact, std::string("exact"))
    ->Arg(1000)
    ->ArgName("leavesPerTree")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_DsmDeepVsExact(benchmark::State& state) {
    const BenchScene& b = benchScene("dsm-demo");
    RenderOptions deep = frameOptions(b.scene, "deep");
    setRenderOption(deep, "epsilon", double(state.range(0)) / 1000.0);
    againstExact(state, b, deep, frameOptions(b.scene, "exact"));
    state.SetLabel("deep (epsilon " + std::to_string(double(state.range(0)) / 1000.0) +
                   ") against exact through the volumes, DSM demo, " + b.label + ", 1280x720");
}
BENCHMARK(BM_DsmDeepVsExact)
    ->Arg(0)
    ->Arg(10)
    ->Arg(50)
    ->Arg(200)
    ->ArgName("epsilon_x1000")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

} // namespace

BENCHMARK_MAIN();
