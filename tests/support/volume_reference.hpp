// voxfx tests — the volume scene's reference (voxfx/volume_scene.hpp): brute-force ray-triangle
// crossings, the Boolean shapes evaluated on leaf flags (apart from VolumeScene::evalShape), and a
// dense ray march from the light (dsmrReferenceTransmittance) that shares no code with the deep
// shadow map or the exact tracer; the scenes the deep shadow, exact shadow, fragment list and volume
// tests build on (the elephant, the knot and smoke, smoke over a ground, a homogeneous slab) and the
// render options of the volume pass's closed forms.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "support/ground_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx::test {

// Ray-triangle crossing (Möller-Trumbore, double): the ray parameter and the smallest barycentric
// coordinate (how far from an edge the hit is); false when the ray misses or is parallel.
inline bool dsmrRayTriangle(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                            double& t, double& edge) {
    const Vec3d e1 = b - a, e2 = c - a, p = cross(d, e2);
    const double det = dot(e1, p);
    if (std::abs(det) < 1e-300) return false;
    const Vec3d s = o - a;
    const double u = dot(s, p) / det;
    const Vec3d q = cross(s, e1);
    const double v = dot(d, q) / det;
    t = dot(e2, q) / det;
    edge = std::min({u, v, 1 - u - v});
    return edge >= -1e-12;
}

struct DsmrHit {
    double t;
    int leaf;
};

// Crossings of the ray o + t d (t in (0, tMax)) with every leaf of the scene; `nearEdge` is set
// when a hit lies within 1e-7 (barycentric) of an edge, where the rasterizer's tie rule decides.
inline std::vector<DsmrHit> dsmrCrossings(const VolumeScene& s, const Vec3d& o, const Vec3d& d, double tMax,
                                          bool& nearEdge) {
    std::vector<DsmrHit> hits;
    for (std::size_t l = 0; l < s.leaves.size(); ++l) {
        const MeshView m = s.leaves[l].view();
        for (std::size_t tr = 0; tr < m.triangleCount; ++tr) {
            double t = 0, edge = 0;
            if (!dsmrRayTriangle(o, d, m.vertex(m.index(tr, 0)), m.vertex(m.index(tr, 1)),
                                 m.vertex(m.index(tr, 2)), t, edge))
                continue;
            if (edge < 1e-7) nearEdge = true;
            if (t > 0 && t < tMax) hits.push_back({t, int(l)});
        }
    }
    std::sort(hits.begin(), hits.end(), [](const DsmrHit& a, const DsmrHit& b) { return a.t < b.t; });
    return hits;
}

// Whether a point is inside the Boolean shape of node `n`, from whether it is inside each leaf
// (inside[leaf] > 0; written apart from VolumeScene::evalShape).
inline bool shapeInside(const VolumeScene& s, int32_t n, const std::vector<int>& inside) {
    const ShapeNode& node = s.nodes[std::size_t(n)];
    if (node.op == ShapeOp::Leaf) return inside[std::size_t(node.leaf)] > 0;
    const bool a = shapeInside(s, node.a, inside), b = shapeInside(s, node.b, inside);
    if (node.op == ShapeOp::Union) return a || b;
    if (node.op == ShapeOp::Intersection) return a && b;
    return a && !b;
}

// Reference transmittance from `from` to `to` through the scene's casting objects: exact crossings
// (parity per leaf), surfaces where an object's flag flips, volumes sampled every `step` world
// units (midpoints). Returns -1 when a crossing lies on a triangle edge (ambiguous ray).
inline double dsmrReferenceTransmittance(const VolumeScene& s, const Vec3d& from, const Vec3d& to,
                                         double step) {
    const Vec3d d = to - from;
    bool nearEdge = false;
    const std::vector<DsmrHit> hits = dsmrCrossings(s, from, d, 1.0, nearEdge);
    if (nearEdge) return -1;
    const double len = length(d);
    std::vector<int> inside(s.leaves.size(), 0);
    std::vector<int> objIn(s.objects.size(), 0);
    double v = 1;
    double t = 0;
    std::size_t h = 0;
    while (true) {
        const double tNext = h < hits.size() ? hits[h].t : 1.0;
        // Volume objects inside over (t, tNext).
        bool anyVolume = false;
        for (std::size_t o = 0; o < s.objects.size(); ++o)
            anyVolume |= objIn[o] && s.objects[o].kind == ObjectKind::Volume && s.objects[o].castsShadow;
        if (anyVolume && tNext > t) {
            const double segLen = (tNext - t) * len;
            const int64_t n = std::max<int64_t>(1, int64_t(std::ceil(segLen / step)));
            for (int64_t k = 0; k < n; ++k) {
                const Vec3d p = from + d * (t + (tNext - t) * (double(k) + 0.5) / double(n));
                double sigma = 0;
                for (std::size_t o = 0; o < s.objects.size(); ++o) {
                    const VolumeSceneObject& obj = s.objects[o];
                    if (!objIn[o] || obj.kind != ObjectKind::Volume || !obj.castsShadow) continue;
                    const double a = std::min(
                        obj.transfer.opacity(s.volumes[std::size_t(obj.volume)]->sample(p)), 1.0 - 1e-7);
                    sigma += -std::log(1 - a) / obj.opacityLength;
                }
                v *= std::exp(-sigma * segLen / double(n));
            }
        }
        if (h >= hits.size()) break;
        // Apply every crossing at this parameter (coincident hits flip together).
        const double tc = hits[h].t;
        for (; h < hits.size() && hits[h].t == tc; ++h) inside[std::size_t(hits[h].leaf)] ^= 1;
        for (std::size_t o = 0; o < s.objects.size(); ++o) {
            const int now = shapeInside(s, s.objects[o].shape, inside) ? 1 : 0;
            const VolumeSceneObject& obj = s.objects[o];
            if (now != objIn[o] && obj.castsShadow && obj.kind != ObjectKind::Volume)
                v *= obj.kind == ObjectKind::Opaque ? 0.0 : 1.0 - double(obj.opacity);
            objIn[o] = now;
        }
        t = tc;
    }
    return v;
}

// ---- Scenes -------------------------------------------------------------------------------------

/// The fetched mesh data/meshes/NAME.off, scaled uniformly and centred to fit `into`.
inline Mesh dsmrLoadScaled(const std::string& name, const Box3d& into) {
    Mesh m = loadMesh(dataPath("meshes/" + name + ".off"));
    const Box3d b = computeBounds(m.view());
    const double scale = std::min(
        {into.extent().x / b.extent().x, into.extent().y / b.extent().y, into.extent().z / b.extent().z});
    for (Vec3f& p : m.positions) p = Vec3f((Vec3d(p) - b.center()) * scale + into.center());
    return m;
}

/// White smoke: transparent up to 0.1, then opacity rising to 0.6 at 1.
inline TransferFunction dsmrSmokeTransfer() {
    return TransferFunction({{0, {1, 1, 1}}, {1, {1, 1, 1}}}, {{0, 0}, {0.1, 0}, {1, 0.6}});
}

// A real mixed scene: the elephant opaque, the knot translucent, a smoke volume bounded by its box
// minus a sphere (a Boolean volume object).
inline VolumeScene dsmrMixedScene() {
    VolumeScene s;
    VolumeSceneObject elephant;
    elephant.name = "elephant";
    elephant.shape = s.addLeaf(dsmrLoadScaled("elephant", {{-1.0, -1.0, -1.2}, {0.0, 0.0, -0.4}}));
    s.addObject(elephant);
    VolumeSceneObject knot;
    knot.name = "knot";
    knot.kind = ObjectKind::Translucent;
    knot.opacity = 0.4f;
    knot.shape = s.addLeaf(dsmrLoadScaled("knot1", {{0.1, -0.9, -1.0}, {0.9, -0.1, -0.2}}));
    s.addObject(knot);
    SmokeParams sp;
    sp.dims = {24, 24, 24};
    sp.box = {{-0.8, -0.6, 0.0}, {0.8, 1.0, 1.0}};
    auto smoke = std::make_shared<Volume>(makeSmoke(sp));
    VolumeSceneObject cloud;
    cloud.name = "smoke";
    cloud.kind = ObjectKind::Volume;
    const int32_t box = s.addLeaf(boxMesh(smoke->box()));
    const int32_t ball = s.addLeaf(makeUvSphere({0.3, 0.5, 0.6}, 0.35, 12, 16));
    cloud.shape = s.addNode(ShapeOp::Difference, box, ball);
    s.volumes.push_back(smoke);
    cloud.volume = 0;
    cloud.transfer = dsmrSmokeTransfer();
    cloud.opacityLength = 0.1;
    s.addObject(cloud);
    return s;
}

/// The spot light over the mixed scene, from +z.
inline Light dsmrSpot() {
    Light l;
    l.type = LightType::Spot;
    l.position = {0.3, 0.2, 4.0};
    l.direction = normalize(Vec3d{-0.1, -0.1, -1});
    l.outerConeAngle = 0.7;
    return l;
}

/// A point light at `at` (default intensity and colour).
inline Light pointLight(const Vec3d& at) {
    Light l;
    l.type = LightType::Point;
    l.position = at;
    return l;
}

/// The sunlit ground (sunlitGroundScene), with a smoke volume over it in [-1, 1] x [0.5, 1.5] x
/// [-1, 1] when `withVolume`.
inline Scene dsmrGroundAndSmoke(bool withVolume) {
    Scene s = sunlitGroundScene();
    if (withVolume) {
        auto vs = std::make_shared<VolumeScene>();
        SmokeParams sp;
        sp.dims = {20, 20, 20};
        sp.box = {{-1, 0.5, -1}, {1, 1.5, 1}};
        vs->addVolumeBox(std::make_shared<Volume>(makeSmoke(sp)), dsmrSmokeTransfer(), 0.05, "smoke");
        s.volumeScene = vs;
    }
    return s;
}

// ---- The volume pass's closed forms ---------------------------------------------------------------

/// The linear one-sample image over black, without ambient or sky light, tone map, anti-aliasing or
/// shadows: what the closed forms of the volume pass describe.
inline RenderOptions linearBlackOptions(int64_t width, int64_t height) {
    RenderOptions o;
    o.width = width;
    o.height = height;
    o.ambient = {0, 0, 0};
    o.skyLight = 0;
    o.sky = SkyKind::Flat;
    o.background = {0, 0, 0};
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    o.exposure = 1; // fixed: the closed forms describe radiance
    o.shadow = NoShadowOptions{};
    return o;
}

/// A homogeneous slab: every voxel 1 (white, opacity `opacity` per `opacityLength` world units) in
/// the volume's own box [-1, 1] x [0, 0.5] x [-1, 1] (32 x 8 x 32 voxels of 1/16), under a sun of
/// intensity `sun` slanted along (0.5, -1, 0.3), seen from above (from (0, 5, 2.5) towards
/// (0, 0.25, 0), fovY 0.3). `zeroCorner`: voxel (0, 0, 0) holds 0 (same colour and opacity).
inline Scene homogeneousSlabScene(double opacity, double opacityLength, double sun, bool zeroCorner = false) {
    Scene s;
    Light light;
    light.direction = normalize(Vec3d{0.5, -1, 0.3});
    light.intensity = float(sun);
    s.lights.push_back(light);
    Camera c;
    c.position = {0, 5, 2.5};
    c.target = {0, 0.25, 0};
    c.fovY = 0.3;
    s.cameras.push_back(c);
    const double h = 1.0 / 16;
    auto v = std::make_shared<Volume>(Vec3i{32, 8, 32}, Vec3d{-1, 0, -1}, Vec3d{h, h, h});
    std::fill(v->values().begin(), v->values().end(), 1.0f);
    if (zeroCorner) v->at(0, 0, 0) = 0;
    const TransferFunction tf({{0, {1, 1, 1}}, {2, {1, 1, 1}}}, {{0, opacity}, {2, opacity}});
    auto vs = std::make_shared<VolumeScene>();
    vs->addVolumeBox(v, tf, opacityLength, "slab");
    s.volumeScene = vs;
    return s;
}

} // namespace voxfx::test
