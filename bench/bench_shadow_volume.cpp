// Shadow volumes with ED06 §3.2 culling and clamping: per scene, the casters culled and the
// shadow-volume fragments rasterized in the camera frame without culling, with culling, and with
// culling and clamping, the masks compared pixel for pixel, and the frame time of render() with
// and without culling. One run per configuration (counts are deterministic; times are one sample).
//
//   ./build/bench_shadow_volume [meshes-dir] [width height]   (configure with -DVOXFX_BUILD_BENCH=ON)
//       (defaults: data/meshes, 1280 x 720)
//
// Scenes: "field" (144 small closed casters on a 12 x 12 grid under a high point light, the camera
// looking at one corner; "field-sun" under a sun), "city" (126 closed casters: six long walls with 20 small
// boxes and spheres behind each, a point light behind the camera: many casters in a wall's shadow or throwing
// their shadow onto ground the camera does not see), "city-sun" (the same under a low sun), and the
// foliage-free demo scenes "bunny" and "cgal" (leaves = 0).
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "demo/demo_scenes.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow_volume.hpp"

namespace {

using namespace voxfx;
using namespace voxfx::demo;
using BenchClock = std::chrono::steady_clock;

double benchMs(BenchClock::time_point t0) {
    return std::chrono::duration<double, std::milli>(BenchClock::now() - t0).count();
}

void benchAppendBox(Mesh& m, const Vec3d& lo, const Vec3d& hi) {
    const auto b = uint32_t(m.positions.size());
    for (int k = 0; k < 8; ++k)
        m.positions.push_back(
            Vec3f(Vec3d{(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z}));
    const uint32_t f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                               {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (const auto& t : f) m.indices.insert(m.indices.end(), {b + t[0], b + t[1], b + t[2]});
}

Mesh benchSphere(const Vec3d& c, double r, int rings, int segments) {
    Mesh m;
    m.positions.push_back(Vec3f(c + Vec3d{0, -r, 0}));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const double th = M_PI * i / rings, ph = 2 * M_PI * j / segments;
            m.positions.push_back(Vec3f(c + Vec3d{r * std::sin(th) * std::cos(ph), -r * std::cos(th),
                                                  -r * std::sin(th) * std::sin(ph)}));
        }
    m.positions.push_back(Vec3f(c + Vec3d{0, r, 0}));
    const auto top = uint32_t(m.positions.size() - 1);
    auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j % segments)); };
    for (int j = 0; j < segments; ++j) {
        m.indices.insert(m.indices.end(), {0, ring(1, j), ring(1, j + 1)});
        m.indices.insert(m.indices.end(), {top, ring(rings - 1, j + 1), ring(rings - 1, j)});
        for (int i = 1; i + 1 < rings; ++i) {
            m.indices.insert(m.indices.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            m.indices.insert(m.indices.end(), {ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
    }
    return m;
}

// A 12 x 12 field of small closed casters (boxes and spheres) under a high light, the camera
// looking at one corner: most volumes leave the picture, the rest reach far past their shadows.
Scene fieldScene(bool sun) {
    Scene s;
    Material ground;
    ground.name = "ground";
    ground.baseColor = {0.5f, 0.5f, 0.45f};
    s.addMaterial(ground);
    Material solid;
    solid.name = "solid";
    solid.baseColor = {0.7f, 0.3f, 0.2f};
    const uint32_t mat = s.addMaterial(solid);
    SceneMesh g;
    g.name = "ground";
    benchAppendBox(g.mesh, {-14, -0.2, -14}, {14, 0, 14});
    g.castsShadow = false;
    s.meshes.push_back(g);
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) {
            SceneMesh m;
            m.name = "caster" + std::to_string(i * 12 + j);
            m.material = mat;
            const double x = -11 + 2.0 * i, z = -11 + 2.0 * j, h = 0.4 + 0.1 * ((i * 7 + j * 3) % 9);
            if ((i + j) % 2)
                benchAppendBox(m.mesh, {x - 0.4, 0, z - 0.4}, {x + 0.4, h, z + 0.4});
            else
                m.mesh = benchSphere({x, 0.2 + 0.5 * h, z}, 0.45, 12, 18);
            s.meshes.push_back(std::move(m));
        }
    Light l;
    if (sun) {
        l.type = LightType::Directional;
        l.name = "sun";
        l.direction = normalize(Vec3d{0.4, -1, 0.3});
        l.intensity = 3;
    } else {
        l.type = LightType::Point;
        l.name = "lamp";
        l.position = {-3, 9, -2};
        l.intensity = 150;
    }
    s.lights.push_back(l);
    Camera c;
    c.name = "corner";
    c.position = {-13, 6, 9};
    c.target = {-6, 0, 2};
    c.fovY = 0.8;
    s.cameras.push_back(c);
    return s;
}

// Six long walls with 20 small casters in each gap, seen from above and in front: the ground
// behind a wall is partly hidden from the camera, and the light (behind the camera, low) throws
// the walls' shadows over the casters behind them.
Scene cityScene(bool sun) {
    Scene s;
    Material ground;
    ground.name = "ground";
    ground.baseColor = {0.5f, 0.5f, 0.45f};
    s.addMaterial(ground);
    Material solid;
    solid.name = "solid";
    solid.baseColor = {0.7f, 0.3f, 0.2f};
    const uint32_t mat = s.addMaterial(solid);
    SceneMesh g;
    g.name = "ground";
    benchAppendBox(g.mesh, {-16, -0.2, -26}, {16, 0, 8});
    g.castsShadow = false;
    s.meshes.push_back(g);
    int n = 0;
    for (int j = 0; j < 6; ++j) {
        const double zw = 2.0 - 4.0 * j;
        SceneMesh w;
        w.name = "wall" + std::to_string(j);
        w.material = mat;
        benchAppendBox(w.mesh, {-12, 0, zw - 0.3}, {12, 3, zw + 0.3});
        s.meshes.push_back(std::move(w));
        for (int i = 0; i < 20; ++i) {
            SceneMesh m;
            m.name = "caster" + std::to_string(n++);
            m.material = mat;
            const double x = -11.4 + 1.2 * i, z = zw - 1.2 - 1.6 * ((i * 7) % 3) / 2.0;
            const double h = 0.4 + 0.1 * ((i * 5 + j * 3) % 7);
            if ((i + j) % 2)
                benchAppendBox(m.mesh, {x - 0.35, 0, z - 0.35}, {x + 0.35, h, z + 0.35});
            else
                m.mesh = benchSphere({x, 0.1 + 0.5 * h, z}, 0.4, 12, 18);
            s.meshes.push_back(std::move(m));
        }
    }
    Light l;
    if (sun) {
        l.type = LightType::Directional;
        l.name = "sun";
        l.direction = normalize(Vec3d{0.25, -0.55, -1});
        l.intensity = 3;
    } else {
        l.type = LightType::Point;
        l.name = "lamp";
        l.position = {-2, 7, 12};
        l.intensity = 300;
    }
    s.lights.push_back(l);
    Camera c;
    c.name = "front";
    c.position = {0, 9, 16};
    c.target = {0, 0, -5};
    c.fovY = 0.9;
    s.cameras.push_back(c);
    return s;
}

// Every culling and clamping switch on or off.
void setSwitches(ShadowVolumeOptions& o, bool on) {
    o.cullReceivers = o.cullOccluded = o.cullShadowedParts = o.dropShadowedReceivers = o.clamp = o.clampRuns =
        on;
}

struct BenchRow {
    std::string name;
    Scene scene;
};

void runScene(const BenchRow& row, int64_t width, int64_t height) {
    const Scene& scene = row.scene;
    const Camera& camera = scene.cameras.at(0);
    const SceneGeometry geometry = flattenScene(scene);
    const GBuffer gbuffer = renderGBuffer(geometry, cameraFrame(camera, width, height));
    auto t0 = BenchClock::now();
    const ShadowCasterSet casters = ShadowCasterSet::build(scene);
    const double adjacencyMs = benchMs(t0);
    for (const Light& light : scene.lights) {
        const std::vector<uint8_t> receivers =
            shadowVolumeReceivers(gbuffer, geometry, scene.materials, light);
        ShadowVolumeOptions none, cull, both;
        setSwitches(none, false);
        cull.clamp = cull.clampRuns = false;
        ShadowVolumeMask masks[3];
        double ms[3];
        const ShadowVolumeOptions* opts[3] = {&none, &cull, &both};
        for (int k = 0; k < 3; ++k) {
            t0 = BenchClock::now();
            masks[k] = computeShadowVolumes(casters, light, gbuffer, receivers, scene.bounds(), *opts[k]);
            ms[k] = benchMs(t0);
        }
        int64_t differ = 0;
        for (std::size_t i = 0; i < receivers.size(); ++i)
            differ += receivers[i] && (masks[0].shadowed[i] != masks[1].shadowed[i] ||
                                       masks[0].shadowed[i] != masks[2].shadowed[i]);
        const ShadowVolumeStats& a = masks[0].stats;
        const ShadowVolumeStats& b = masks[1].stats;
        const ShadowVolumeStats& c = masks[2].stats;
        std::printf("%-10s %-6s casters %4lld  culled %4lld + %4lld  clamped %4lld  fragments %11lld / "
                    "%11lld / %11lld  "
                    "(%.2fx / %.2fx)  volumes %.1f / %.1f / %.1f ms (cull %.1f)  differing receivers %lld  "
                    "adjacency %.1f ms\n",
                    row.name.c_str(), light.name.c_str(), (long long)a.casters, (long long)b.culledNoReceiver,
                    (long long)b.culledOccluded, (long long)c.clamped, (long long)a.fragments,
                    (long long)b.fragments, (long long)c.fragments,
                    double(a.fragments) / double(std::max<int64_t>(1, b.fragments)),
                    double(a.fragments) / double(std::max<int64_t>(1, c.fragments)), ms[0], ms[1], ms[2],
                    c.cullMs, (long long)differ, adjacencyMs);
    }
    // Each switch on its own against none (ED06 §3.2, issue 25 item 7), then the three switches of
    // issue 12 and all of them: fragments and the time of computeShadowVolumes, in one run.
    for (const Light& light : scene.lights) {
        const std::vector<uint8_t> receivers =
            shadowVolumeReceivers(gbuffer, geometry, scene.materials, light);
        ShadowVolumeOptions none;
        setSwitches(none, false);
        struct Config {
            const char* name;
            ShadowVolumeOptions o;
        };
        std::vector<Config> configs{{"none", none}};
        for (bool ShadowVolumeOptions::*flag :
             {&ShadowVolumeOptions::cullReceivers, &ShadowVolumeOptions::cullOccluded,
              &ShadowVolumeOptions::cullShadowedParts, &ShadowVolumeOptions::clamp,
              &ShadowVolumeOptions::clampRuns}) {
            ShadowVolumeOptions o = none;
            o.*flag = true;
            configs.push_back({flag == &ShadowVolumeOptions::cullReceivers       ? "cullReceivers"
                               : flag == &ShadowVolumeOptions::cullOccluded      ? "cullOccluded"
                               : flag == &ShadowVolumeOptions::cullShadowedParts ? "cullShadowedParts"
                               : flag == &ShadowVolumeOptions::clamp             ? "volumeClamping"
                                                                                 : "clampRuns",
                               o});
        }
        ShadowVolumeOptions receiversClamped = none;
        receiversClamped.cullReceivers = receiversClamped.clamp = receiversClamped.clampRuns = true;
        configs.push_back({"receivers+clamping", receiversClamped});
        receiversClamped.dropShadowedReceivers = true;
        configs.push_back({" +dropShadowedReceivers", receiversClamped});
        ShadowVolumeOptions old = none;
        old.cullReceivers = old.cullOccluded = old.clamp = true;
        configs.push_back({"issue-12 three", old});
        configs.push_back({"all", ShadowVolumeOptions{}});
        ShadowVolumeMask reference;
        for (const Config& c : configs) {
            t0 = BenchClock::now();
            const ShadowVolumeMask m =
                computeShadowVolumes(casters, light, gbuffer, receivers, scene.bounds(), c.o);
            const double ms = benchMs(t0);
            if (reference.shadowed.empty()) reference = m;
            int64_t differ = 0;
            for (std::size_t i = 0; i < receivers.size(); ++i)
                differ += receivers[i] && m.shadowed[i] != reference.shadowed[i];
            const ShadowVolumeStats& st = m.stats;
            std::printf(
                "%-10s %-6s %-24s fragments %11lld (%.2fx)  culled %lld + %lld, %lld triangles, clamped %lld "
                "(%lld near, %lld gaps), %lld receiver cells left  %.1f ms (cull %.1f)  differing %lld\n",
                row.name.c_str(), light.name.c_str(), c.name, (long long)st.fragments,
                double(reference.stats.fragments) / double(std::max<int64_t>(1, st.fragments)),
                (long long)st.culledNoReceiver, (long long)st.culledOccluded, (long long)st.culledTriangles,
                (long long)st.clamped, (long long)st.nearClamped, (long long)st.gaps,
                (long long)st.droppedReceivers, ms, st.cullMs, (long long)differ);
        }
    }
    // Whole frames: render() with shadow volumes, culling and clamping off and on.
    RenderOptions o;
    o.width = width;
    o.height = height;
    double frame[2];
    int64_t imageDiff = 0;
    Image images[2];
    for (int k = 0; k < 2; ++k) {
        o.shadow = ShadowVolumeOptions{};
        setRenderOption(o, "volumeCulling", k == 1);
        const RenderResult r = render(scene, camera, o);
        frame[k] = r.timings.totalMs;
        images[k] = r.image;
    }
    for (int64_t y = 0; y < height; ++y)
        for (int64_t x = 0; x < width; ++x) imageDiff += !(images[0].at(x, y) == images[1].at(x, y));
    std::printf(
        "%-10s frame %.1f ms without culling, %.1f ms with culling and clamping; differing pixels %lld\n",
        row.name.c_str(), frame[0], frame[1], (long long)imageDiff);
}

} // namespace

int main(int argc, char** argv) {
    const std::string meshes = argc > 1 ? argv[1] : std::string(VOXFX_DATA_DIR) + "/meshes";
    const int64_t width = argc > 3 ? std::stoll(argv[2]) : 1280,
                  height = argc > 3 ? std::stoll(argv[3]) : 720;
    std::printf("shadow volumes, %lld x %lld, fragments: no culling / culling / culling + clamping\n",
                (long long)width, (long long)height);
    std::vector<BenchRow> rows;
    rows.push_back({"field", fieldScene(false)});
    rows.push_back({"field-sun", fieldScene(true)});
    rows.push_back({"city", cityScene(false)});
    rows.push_back({"city-sun", cityScene(true)});
    try {
        rows.push_back({"bunny", makeBunnyScene(meshes, 0)});
    } catch (const std::exception& e) { std::printf("bunny: skipped (%s)\n", e.what()); }
    try {
        rows.push_back({"cgal", makeCgalScene(meshes, 0)});
    } catch (const std::exception& e) { std::printf("cgal: skipped (%s)\n", e.what()); }
    for (const BenchRow& row : rows) {
        try {
            runScene(row, width, height);
        } catch (const std::exception& e) { std::printf("%-10s failed: %s\n", row.name.c_str(), e.what()); }
    }
    return 0;
}
