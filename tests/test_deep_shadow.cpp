// Tests of fragment lists, the Boolean volume scene and deep shadow maps from lights
// (voxfx/fragment_list.hpp, voxfx/volume_scene.hpp, voxfx/deep_shadow.hpp). Oracles: brute-force
// ray-triangle crossings, CGAL::Side_of_triangle_mesh, the standard shadow map, and a dense ray
// march from the light written here (dsmrRef*) that shares no code with the deep shadow map.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

// ---- independent helpers --------------------------------------------------------------------

// Ray-triangle crossing (Möller-Trumbore, double): the ray parameter and the smallest barycentric
// coordinate (how far from an edge the hit is); false when the ray misses or is parallel.
bool dsmrRayTriangle(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c,
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
std::vector<DsmrHit> dsmrCrossings(const VolumeScene& s, const Vec3d& o, const Vec3d& d, double tMax,
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

// The Boolean shape of node `n`, evaluated on leaf flags (written apart from VolumeScene::evalShape).
bool dsmrShape(const VolumeScene& s, int32_t n, const std::vector<int>& inside) {
    const ShapeNode& node = s.nodes[std::size_t(n)];
    if (node.op == ShapeOp::Leaf) return inside[std::size_t(node.leaf)] != 0;
    const bool a = dsmrShape(s, node.a, inside), b = dsmrShape(s, node.b, inside);
    if (node.op == ShapeOp::Union) return a || b;
    if (node.op == ShapeOp::Intersection) return a && b;
    return a && !b;
}

// Reference transmittance from `from` to `to` through the scene's casting objects: exact crossings
// (parity per leaf), surfaces where an object's flag flips, volumes sampled every `step` world
// units (midpoints). Returns -1 when a crossing lies on a triangle edge (ambiguous ray).
double dsmrReferenceTransmittance(const VolumeScene& s, const Vec3d& from, const Vec3d& to, double step) {
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
            const int now = dsmrShape(s, s.objects[o].shape, inside) ? 1 : 0;
            const VolumeSceneObject& obj = s.objects[o];
            if (now != objIn[o] && obj.castsShadow && obj.kind != ObjectKind::Volume)
                v *= obj.kind == ObjectKind::Opaque ? 0.0 : 1.0 - double(obj.opacity);
            objIn[o] = now;
        }
        t = tc;
    }
    return v;
}

Mesh dsmrLoadScaled(const std::string& name, const Box3d& into) {
    Mesh m = loadMesh(test::dataPath("meshes/" + name + ".off"));
    const Box3d b = computeBounds(m.view());
    const double scale = std::min(
        {into.extent().x / b.extent().x, into.extent().y / b.extent().y, into.extent().z / b.extent().z});
    for (Vec3f& p : m.positions) p = Vec3f((Vec3d(p) - b.center()) * scale + into.center());
    return m;
}

TransferFunction dsmrSmokeTransfer() {
    return TransferFunction({{0, {1, 1, 1}}, {1, {1, 1, 1}}}, {{0, 0}, {0.1, 0}, {1, 0.6}});
}

// A real mixed scene: the elephant opaque, the knot translucent, a smoke volume bounded by its box
// minus a sphere (a Boolean volume object).
VolumeScene dsmrMixedScene() {
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
    const int32_t ball = s.addLeaf(test::makeUvSphere({0.3, 0.5, 0.6}, 0.35, 12, 16));
    cloud.shape = s.addNode(ShapeOp::Difference, box, ball);
    s.volumes.push_back(smoke);
    cloud.volume = 0;
    cloud.transfer = dsmrSmokeTransfer();
    cloud.opacityLength = 0.1;
    s.addObject(cloud);
    return s;
}

Light dsmrSpot() {
    Light l;
    l.type = LightType::Spot;
    l.position = {0.3, 0.2, 4.0};
    l.direction = normalize(Vec3d{-0.1, -0.1, -1});
    l.outerConeAngle = 0.7;
    return l;
}

// ---- fragment lists ---------------------------------------------------------------------------

TEST(FragmentListTest, KeepsEveryCrossingOfEachColumnSortedAndAlternatingOnAClosedMesh) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    const Mesh mesh = dsmrLoadScaled("knot1", {{-1, -1, -1}, {1, 1, 1}});
    const Frame frame = Frame::orthographic({{-1.1, -1.1, -1.1}, {1.1, 1.1, 1.1}}, Axis::Z, 40, 40, 64);
    const FragmentLists lists = FragmentLists::build(frame, mesh.view());
    VolumeScene scene;
    scene.addLeaf(mesh);
    int64_t checked = 0;
    for (int64_t y = 0; y < 40; ++y)
        for (int64_t x = 0; x < 40; ++x) {
            const auto col = lists.column(x, y);
            for (std::size_t i = 0; i + 1 < col.size(); ++i) ASSERT_LE(col[i].depth, col[i + 1].depth);
            // A ray along the column from below the box: brute-force crossings.
            const Vec3d a = frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, -1.0});
            const Vec3d b = frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 65.0});
            bool nearEdge = false;
            const auto hits = dsmrCrossings(scene, a, b - a, 1.0, nearEdge);
            if (nearEdge) continue;
            ASSERT_EQ(col.size(), hits.size()) << "column " << x << ", " << y;
            for (std::size_t i = 0; i < col.size(); ++i) {
                EXPECT_EQ(col[i].front, i % 2 == 0); // enters, leaves, enters ...
                const double depth = -1.0 + hits[i].t * 66.0;
                EXPECT_NEAR(col[i].depth, depth, 1e-6);
            }
            ++checked;
        }
    EXPECT_GT(checked, 1000);
    EXPECT_GT(lists.maxPerColumn(), 2);
}

TEST(FragmentListTest, ListsDoNotDependOnTheThreadCount) {
    const Mesh mesh = test::makeTorus({0, 0, 0}, 0.6, 0.25, 24, 12);
    const Frame frame = Frame::perspective({0.3, 0.2, 3}, {0, 0, 0}, {0, 1, 0}, 0.8, 37, 29, 0.5, 6, 1);
    FragmentLists one, all;
    withThreads(1, [&] { one = FragmentLists::build(frame, mesh.view()); });
    withThreads(0, [&] { all = FragmentLists::build(frame, mesh.view()); });
    ASSERT_EQ(one.fragmentCount(), all.fragmentCount());
    ASSERT_GT(one.fragmentCount(), 0);
    for (int64_t y = 0; y < 29; ++y)
        for (int64_t x = 0; x < 37; ++x) {
            const auto a = one.column(x, y), b = all.column(x, y);
            ASSERT_EQ(a.size(), b.size());
            for (std::size_t i = 0; i < a.size(); ++i) {
                EXPECT_EQ(a[i].depth, b[i].depth);
                EXPECT_EQ(a[i].triangle, b[i].triangle);
                EXPECT_EQ(a[i].front, b[i].front);
            }
        }
}

// ---- Boolean scene graph --------------------------------------------------------------------

TEST(VolumeSceneTest, BooleanNodesAgreeWithCgalInsideTestsAlongFragmentSegments) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    VolumeScene s;
    const int32_t a = s.addLeaf(dsmrLoadScaled("elephant", {{-1, -1, -1}, {0.6, 0.6, 0.6}}));
    const int32_t b = s.addLeaf(dsmrLoadScaled("knot1", {{-0.5, -0.6, -0.7}, {1, 0.9, 0.8}}));
    const int32_t u = s.addNode(ShapeOp::Union, a, b), i = s.addNode(ShapeOp::Intersection, a, b),
                  d = s.addNode(ShapeOp::Difference, a, b), e = s.addNode(ShapeOp::Difference, b, u);
    for (int32_t n : {u, i, d, e}) {
        VolumeSceneObject o;
        o.shape = n;
        o.name = toString(s.nodes[std::size_t(n)].op);
        s.addObject(o);
    }
    s.validate();
    const FlatLeaves flat = flattenLeaves(s, false);
    const Frame frame = Frame::perspective({1.5, 1.1, 1.8}, {0, 0, 0}, {0, 1, 0}, 1.0, 64, 64, 0.5, 8, 1);
    const FragmentLists lists = FragmentLists::build(frame, flat.mesh.view());
    // Midpoints of every segment, with the walker's flags.
    std::vector<Vec3d> points;
    std::vector<std::vector<uint8_t>> flags;
    SegmentWalker walker(s, flat.triangleLeaf);
    for (int64_t y = 0; y < 64; ++y)
        for (int64_t x = 0; x < 64; ++x)
            walker.walk(
                lists.column(x, y), [](double, std::size_t, bool) { return true; },
                [&](double z0, double z1, std::span<const uint8_t> inside) {
                    if (z1 - z0 > 1e-5) {
                        points.push_back(
                            frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 0.5 * (z0 + z1)}));
                        flags.emplace_back(inside.begin(), inside.end());
                    }
                    return true;
                },
                true);
    ASSERT_GT(points.size(), 700u);
    const std::vector<int> inA = test::sideOfClosedMesh(s.leaves[0].view(), points);
    const std::vector<int> inB = test::sideOfClosedMesh(s.leaves[1].view(), points);
    ASSERT_EQ(inA.size(), points.size());
    ASSERT_EQ(inB.size(), points.size());
    int64_t wrong = 0, insideSome = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
        if (inA[k] == 0 || inB[k] == 0) continue;
        const std::vector<int> leaf{inA[k] > 0, inB[k] > 0};
        for (std::size_t o = 0; o < s.objects.size(); ++o) {
            const bool expected = dsmrShape(s, s.objects[o].shape, leaf);
            wrong += expected != (flags[k][o] != 0);
            insideSome += expected;
        }
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(insideSome, 500);
}

// ---- deep shadow maps -------------------------------------------------------------------------

TEST(DeepShadowTest, OpaqueSurfacesOnlyGiveTheStandardShadowMap) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    VolumeScene s;
    VolumeSceneObject o;
    o.shape = s.addLeaf(dsmrLoadScaled("elephant", {{-1, -1, -1}, {1, 1, 1}}));
    s.addObject(o);
    Mesh ground;
    test::appendQuad(ground, {0, 0, -1.2}, {1.5, 0, 0}, {0, 1.5, 0});
    o.shape = s.addLeaf(ground);
    s.addObject(o);
    const FlatLeaves flat = flattenLeaves(s, true);
    for (const Light& light : {dsmrSpot(), Light{}}) { // spot and directional
        const std::vector<LightView> views = makeLightViews(light, s.bounds(true), 48, 1);
        DeepShadowOptions opt;
        opt.epsilon = 0.1;
        const DeepShadow deep = DeepShadow::build(s, views, opt);
        for (std::size_t vi = 0; vi < views.size(); ++vi) {
            const ShadowMap map = ShadowMap::build(flat.mesh.view(), views[vi]);
            const DsmView dv = deep.maps()[vi].view();
            int64_t shadowed = 0;
            for (int64_t y = 0; y < views[vi].frame.height(); ++y)
                for (int64_t x = 0; x < views[vi].frame.width(); ++x) {
                    const float depth = map.depthAt(x, y);
                    const float zs[] = {0.0f,         depth,        std::nextafter(depth, 1e30f),
                                        depth * 0.5f, depth * 1.5f, 1e30f};
                    for (float z : zs) {
                        const float expected = std::isfinite(depth) && z > depth ? 0.0f : 1.0f;
                        ASSERT_EQ(dv.visibility(x, y, z), expected) << x << ", " << y << " at " << z;
                        shadowed += expected == 0;
                    }
                }
            EXPECT_GT(shadowed, 500);
        }
    }
}

TEST(DeepShadowTest, CompressedStaysWithinEpsilonOfExactAndNeverIncreasesOverEveryTexel) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    const VolumeScene s = dsmrMixedScene();
    const std::vector<LightView> views = makeLightViews(dsmrSpot(), s.bounds(true), 40, 1);
    DeepShadowOptions exactOpt;
    exactOpt.epsilon = 0;
    exactOpt.termination = 0;
    const DeepShadow exact = DeepShadow::build(s, views, exactOpt);
    int64_t volumeTexels = 0;
    for (const double eps : {0.01, 0.05, 0.2}) {
        for (const DsmStorage storage : {DsmStorage::Chunked, DsmStorage::Fixed}) {
            DeepShadowOptions opt = exactOpt;
            opt.epsilon = eps;
            opt.storage = storage;
            const DeepShadow comp = DeepShadow::build(s, views, opt);
            const DsmView e = exact.maps()[0].view(), c = comp.maps()[0].view();
            EXPECT_EQ(comp.maps()[0].stats().overflowTexels, 0);
            EXPECT_LT(comp.stats().nodes, exact.stats().nodes);
            for (int64_t y = 0; y < views[0].frame.height(); ++y)
                for (int64_t x = 0; x < views[0].frame.width(); ++x) {
                    std::vector<DsmNode> ne = exact.maps()[0].texel(x, y), nc = comp.maps()[0].texel(x, y);
                    volumeTexels += ne.size() > 8;
                    for (const auto* nodes : {&ne, &nc})
                        for (std::size_t k = 1; k < nodes->size(); ++k) {
                            ASSERT_LE((*nodes)[k].v, (*nodes)[k - 1].v) << x << ", " << y;
                            ASSERT_GE((*nodes)[k].z, (*nodes)[k - 1].z);
                        }
                    // Both functions are linear between the union of their depths: check both
                    // one-sided limits there and the midpoints.
                    std::vector<float> zs;
                    for (const auto* nodes : {&ne, &nc})
                        for (const DsmNode& n : *nodes) zs.push_back(n.z);
                    std::sort(zs.begin(), zs.end());
                    const std::size_t count = zs.size();
                    for (std::size_t k = 0; k + 1 < count; ++k) zs.push_back(0.5f * (zs[k] + zs[k + 1]));
                    for (std::size_t k = 0; k < count; ++k) zs.push_back(std::nextafter(zs[k], 1e30f));
                    for (const float z : zs)
                        ASSERT_NEAR(c.visibility(x, y, z), e.visibility(x, y, z), eps + 1e-5)
                            << "texel " << x << ", " << y << " depth " << z << " epsilon " << eps;
                }
        }
    }
    EXPECT_GT(volumeTexels, 50);
}

TEST(DeepShadowTest, LookupsAgreeWithADenseRayMarchFromTheLight) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    const VolumeScene s = dsmrMixedScene();
    const Light light = dsmrSpot();
    const std::vector<LightView> views = makeLightViews(light, s.bounds(true), 48, 1);
    DeepShadowOptions opt;
    opt.epsilon = 0.02;
    const DeepShadow deep = DeepShadow::build(s, views, opt);
    const double voxel = s.volumes[0]->spacing().x;
    // Points on texel-centre rays (no bilinear blur), at depths through and behind everything.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    const Frame& f = views[0].frame;
    double maxErr = 0, sumErr = 0;
    int64_t n = 0, dark = 0, partial = 0;
    for (int k = 0; k < 1500; ++k) {
        const int64_t x = int64_t(unit(rng) * double(f.width())), y = int64_t(unit(rng) * double(f.height()));
        const double z = f.nearDepth() + unit(rng) * (f.farDepth() - f.nearDepth());
        const Vec3d p = f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, z});
        const double ref = dsmrReferenceTransmittance(s, light.position, p, voxel / 4);
        if (ref < 0) continue;
        const double got = deep.maps()[0].view().visibility(x, y, float(f.gridFromWorld(p).z));
        // A point within a float ulp of a surface may see either side.
        const double err = std::abs(got - ref);
        maxErr = std::max(maxErr, err);
        sumErr += err;
        ++n;
        dark += ref < 0.01;
        partial += ref > 0.05 && ref < 0.95;
    }
    ASSERT_GT(n, 1200);
    EXPECT_GT(dark, 5);
    EXPECT_GT(partial, 50);
    // ε plus the volume sampling (one voxel steps against an eighth).
    EXPECT_LT(sumErr / double(n), 0.01);
    EXPECT_LT(maxErr, opt.epsilon + 0.05);
}

TEST(DeepShadowTest, PointLightsUseSixFacesAndLookupsFollowThem) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    VolumeScene s;
    VolumeSceneObject o;
    o.kind = ObjectKind::Translucent;
    o.opacity = 0.5f;
    o.shape = s.addLeaf(dsmrLoadScaled("knot1", {{-1, -1, -1}, {1, 1, 1}}));
    s.addObject(o);
    Light l;
    l.type = LightType::Point;
    l.position = {0, 0, 0.05};
    DeepShadowOptions opt;
    opt.resolution = 64;
    opt.epsilon = 0.01;
    const DeepShadow deep = DeepShadow::build(s, l, opt);
    ASSERT_EQ(deep.views().size(), 6u);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    int64_t n = 0, wrong = 0;
    for (int k = 0; k < 2000; ++k) {
        const Vec3d p{1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng)};
        const double ref = dsmrReferenceTransmittance(s, l.position, p, 1.0);
        if (ref < 0) continue;
        ++n;
        // Bilinear lookups blur one texel: count the points whose value is off by more than a step.
        wrong += std::abs(deep.visibility(p, {0, 0, 0}, 0, 0).x - ref) > 0.26;
    }
    ASSERT_GT(n, 1500);
    EXPECT_LT(double(wrong) / double(n), 0.05);
}

// Two small objects far apart below a point light (both in its -y cube face), the knot
// translucent and the elephant opaque; the ground at y = -0.5 receives only.
VolumeScene dsmrTwoUnderAPointLight() {
    VolumeScene s;
    VolumeSceneObject o;
    o.kind = ObjectKind::Translucent;
    o.opacity = 0.6f;
    o.shape = s.addLeaf(dsmrLoadScaled("knot1", {{-2.3, 0.2, -0.3}, {-1.7, 0.8, 0.3}}));
    s.addObject(o);
    o.kind = ObjectKind::Opaque;
    o.shape = s.addLeaf(dsmrLoadScaled("elephant", {{1.7, 0.2, -0.3}, {2.3, 0.8, 0.3}}));
    s.addObject(o);
    return s;
}

Light dsmrPoint(const Vec3d& at) {
    Light l;
    l.type = LightType::Point;
    l.position = at;
    return l;
}

TEST(DeepShadowClusterTest, PointLightClustersAimFewerMapsAndAreCloserToTheReferenceAtEqualTexels) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    const VolumeScene s = dsmrTwoUnderAPointLight();
    const Light l = dsmrPoint({0, 3, 0});
    DeepShadowOptions opt;
    opt.resolution = 64;
    opt.epsilon = 0.01;
    const DeepShadow single = DeepShadow::build(s, l, opt);
    opt.clusters = 4;
    const DeepShadow clustered = DeepShadow::build(s, l, opt);
    ASSERT_EQ(single.views().size(), 6u);
    // Two clusters, one aimed map each: fewer than the six cube faces.
    ASSERT_EQ(clustered.groupBegin().size(), 3u);
    EXPECT_EQ(clustered.views().size(), 2u);
    EXPECT_NE(clustered.objectClusters()[0], clustered.objectClusters()[1]);
    // Equal memory: the two maps share the six faces' texels (and use most of them).
    const DeepShadowStats st = clustered.stats();
    EXPECT_EQ(st.unclusteredViewTexels, 6 * 64 * 64);
    EXPECT_LE(st.clusteredViewTexels, st.unclusteredViewTexels);
    EXPECT_GT(st.clusteredViewTexels, st.unclusteredViewTexels * 9 / 10);
    EXPECT_LE(st.texels, single.stats().texels);
    EXPECT_NE(st.summary().find("2 clusters in 2 maps"), std::string::npos) << st.summary();
    // Receivers on the ground around both shadows, against the independent reference.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    double errSingle = 0, errClustered = 0;
    int64_t n = 0, differ = 0;
    for (int k = 0; k < 2000; ++k) {
        const double side = k % 2 ? 2.8 : -2.8;
        const Vec3d p{side + 0.6 * u(rng), -0.5, 0.6 * u(rng)};
        const double ref = dsmrReferenceTransmittance(s, l.position, p, 1.0);
        if (ref < 0) continue;
        const double a = single.visibility(p, {0, 0, 0}, 0, 0).x,
                     b = clustered.visibility(p, {0, 0, 0}, 0, 0).x;
        errSingle += std::abs(a - ref);
        errClustered += std::abs(b - ref);
        differ += std::abs(a - b) > 0.01;
        ++n;
    }
    ASSERT_GT(n, 1800);
    std::printf("point light, mean error single %.4f clustered %.4f, %lld of %lld differ\n",
                errSingle / double(n), errClustered / double(n), (long long)differ, (long long)n);
    EXPECT_GT(differ, n / 20); // not the unclustered maps again
    EXPECT_LT(errClustered, 0.7 * errSingle);
}

TEST(DeepShadowClusterTest, APointLightClusterWiderThanAConeKeepsOnlyTheCubeFacesItReaches) {
    // A long box just below the light spans more than 60 degrees from its centre's direction: its
    // cluster takes the cube faces it reaches (+x, -x, -y), not all six, and loses no shadow.
    VolumeScene s;
    VolumeSceneObject o;
    o.shape = s.addLeaf(test::makeBox({-1.5, -1.2, -0.3}, {1.5, -0.8, 0.3}));
    s.addObject(o);
    o.shape = s.addLeaf(test::makeBox({-0.2, 1.5, -0.2}, {0.2, 1.9, 0.2}));
    s.addObject(o);
    const Light l = dsmrPoint({0, 0, 0});
    DeepShadowOptions opt;
    opt.resolution = 48;
    opt.epsilon = 0.01;
    const DeepShadow single = DeepShadow::build(s, l, opt);
    opt.clusters = 2;
    const DeepShadow clustered = DeepShadow::build(s, l, opt);
    ASSERT_EQ(clustered.groupBegin().size(), 3u);
    // The small box above: one aimed map; the long box: three faces.
    EXPECT_EQ(clustered.views().size(), 4u);
    EXPECT_LE(clustered.stats().clusteredViewTexels, clustered.stats().unclusteredViewTexels);
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-1, 1);
    double errSingle = 0, errClustered = 0;
    int64_t n = 0, wrong = 0, shadowed = 0;
    for (int k = 0; k < 3000; ++k) {
        const Vec3d p{3 * u(rng), 3 * u(rng), 3 * u(rng)};
        const double ref = dsmrReferenceTransmittance(s, l.position, p, 1.0);
        if (ref < 0) continue;
        const double a = single.visibility(p, {0, 0, 0}, 0, 0).x,
                     b = clustered.visibility(p, {0, 0, 0}, 0, 0).x;
        errSingle += std::abs(a - ref);
        errClustered += std::abs(b - ref);
        wrong += std::abs(b - ref) > 0.5;
        shadowed += ref < 0.5;
        ++n;
    }
    ASSERT_GT(n, 2800);
    EXPECT_GT(shadowed, 200);
    std::printf("wide cluster, mean error single %.4f clustered %.4f, %lld wrong\n", errSingle / double(n),
                errClustered / double(n), (long long)wrong);
    EXPECT_LT(double(wrong) / double(n), 0.01);
    EXPECT_LE(errClustered, errSingle * 1.05);
}

// Three boxes in a row under a directional light; the ground at y = 0 receives. Their exact shadows
// are the boxes' footprints.
VolumeScene dsmrThreeInARow() {
    VolumeScene s;
    VolumeSceneObject o;
    for (const double x : {-3.0, 0.0, 3.0}) {
        o.shape = s.addLeaf(test::makeBox({x - 0.25, 1, -0.25}, {x + 0.25, 1.5, 0.25}));
        s.addObject(o);
    }
    return s;
}

TEST(DeepShadowClusterTest, ClustersFollowTheCameraAndSharpenTheShadowsNearIt) {
    const VolumeScene s = dsmrThreeInARow();
    Light sun;
    sun.direction = {0, -1, 0};
    DeepShadowOptions opt;
    opt.resolution = 64;
    opt.clusters = 3;
    opt.clusterThreshold = 0.5;
    BuildContext context;
    context.camera = Camera{};
    context.camera->position = Vec3d{-3, 2.5, 3}; // near the left box
    const DeepShadow nearLeft = DeepShadow::build(s, sun, opt, context);
    context.camera->position = Vec3d{3, 2.5, 3}; // near the right box
    const DeepShadow nearRight = DeepShadow::build(s, sun, opt, context);
    const std::vector<int>& l = nearLeft.objectClusters();
    const std::vector<int>& r = nearRight.objectClusters();
    EXPECT_NE(l[0], l[1]);
    EXPECT_EQ(l[1], l[2]);
    EXPECT_NE(r[2], r[1]);
    EXPECT_EQ(r[0], r[1]);
    // At equal texels, the left box's shadow is closer to its exact footprint when the camera is near it.
    double errNear = 0, errFar = 0;
    int64_t n = 0;
    for (double x = -3.6; x <= -2.4; x += 0.01)
        for (double z = -0.6; z <= 0.6; z += 0.01) {
            const double ref = std::abs(x + 3) <= 0.25 && std::abs(z) <= 0.25 ? 0.0 : 1.0;
            errNear += std::abs(nearLeft.visibility({x, 0, z}, {0, 0, 0}, 0, 0).x - ref);
            errFar += std::abs(nearRight.visibility({x, 0, z}, {0, 0, 0}, 0, 0).x - ref);
            ++n;
        }
    std::printf("left box, mean error camera near %.4f far %.4f\n", errNear / double(n), errFar / double(n));
    EXPECT_LT(errNear, 0.5 * errFar);
}

TEST(DeepShadowClusterTest, ClusterCountTexelsAndTheSummaryKeepTheirInvariants) {
    const VolumeScene s = dsmrThreeInARow();
    for (const Light& light : {Light{}, dsmrSpot(), dsmrPoint({0, 4, 0})}) {
        DeepShadowOptions opt;
        opt.resolution = 40;
        const DeepShadow single = DeepShadow::build(s, light, opt);
        for (const int m : {2, 3, 8}) {
            for (const double d0 : {0.0, 0.3, 10.0}) {
                opt.clusters = m;
                opt.clusterThreshold = d0;
                opt.clusterEqualTexels = true;
                const DeepShadow c = DeepShadow::build(s, light, opt);
                const DeepShadowStats st = c.stats();
                const int64_t groups = int64_t(c.groupBegin().size()) - 1;
                EXPECT_GE(groups, 1);
                EXPECT_LE(groups, std::min(m, 3));
                EXPECT_EQ(st.clusterGroups, groups);
                EXPECT_EQ(st.clusterViews, int64_t(c.views().size()));
                if (d0 == 10.0) { EXPECT_EQ(groups, 1); } // every pair within d0: one cluster
                if (d0 == 0.0) { EXPECT_EQ(groups, std::min(m, 3)); }
                // Every casting object in exactly one cluster, numbered 0..groups-1.
                for (const int k : c.objectClusters()) {
                    EXPECT_GE(k, 0);
                    EXPECT_LT(k, groups);
                }
                EXPECT_EQ(st.unclusteredViewTexels, single.stats().texels);
                EXPECT_LE(st.clusteredViewTexels, st.unclusteredViewTexels);
                EXPECT_LE(c.views().size(),
                          light.type == LightType::Point ? 6u * std::size_t(groups) : std::size_t(groups));
                // Without the equal-texel budget every map has the full resolution.
                opt.clusterEqualTexels = false;
                const DeepShadow full = DeepShadow::build(s, light, opt);
                for (const LightView& v : full.views())
                    EXPECT_EQ(std::max(v.frame.width(), v.frame.height()), 40);
            }
        }
    }
}

TEST(DeepShadowClusterTest, ClustersAreNeverSilentlyIgnored) {
    // A point light clusters (the summary counts its maps); a light over a single casting object
    // says it has one cluster.
    Scene s;
    SceneMesh box;
    box.mesh = test::makeBox({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
    box.material = s.addMaterial(Material{});
    s.meshes.push_back(box);
    box.mesh = test::makeBox({2, -0.5, -0.5}, {3, 0.5, 0.5});
    s.meshes.push_back(box);
    Light point;
    point.type = LightType::Point;
    point.position = {1, 3, 0};
    RenderOptions r;
    r.shadow = shadowOptionsNamed("deep");
    setRenderOption(r, "dsmResolution", int64_t(32));
    setRenderOption(r, "clusters", int64_t(4));
    const ShadowOptions o = r.shadow;
    const std::string said = summary(shadowStats(buildLightShadow(s, point, o)));
    EXPECT_NE(said.find("2 clusters in 2 maps"), std::string::npos) << said;
    EXPECT_EQ(said.find("one casting object"), std::string::npos) << said;
    s.meshes.pop_back();
    const std::string one = summary(shadowStats(buildLightShadow(s, point, o)));
    EXPECT_NE(one.find("1 light(s) have one casting object"), std::string::npos) << one;
}

TEST(DeepShadowClusterTest, APointLightRenderChangesWithClusters) {
    // The bug this replaces: --clusters with a point light gave a byte-identical image.
    Scene s;
    Material m;
    const uint32_t mat = s.addMaterial(m);
    SceneMesh g;
    test::appendQuad(g.mesh, {0, 0, 0}, {0, 0, 4}, {4, 0, 0});
    g.material = mat;
    g.castsShadow = false;
    s.meshes.push_back(g);
    for (const double x : {-1.5, 1.5}) {
        SceneMesh b;
        b.mesh = test::makeBox({x - 0.2, 0.4, -0.2}, {x + 0.2, 0.8, 0.2});
        b.material = mat;
        s.meshes.push_back(b);
    }
    s.lights.push_back(dsmrPoint({0, 3, 0}));
    Camera c;
    c.position = {0, 4, 5};
    c.fovY = 0.8;
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.shadow = shadowOptionsNamed("deep");
    setRenderOption(o, "dsmResolution", int64_t(32));
    const RenderResult without = render(s, c, o);
    setRenderOption(o, "clusters", int64_t(4));
    const RenderResult with = render(s, c, o);
    int64_t differ = 0;
    for (int64_t y = 0; y < o.height; ++y)
        for (int64_t x = 0; x < o.width; ++x) differ += !(with.image.at(x, y) == without.image.at(x, y));
    EXPECT_GT(differ, 10);
    EXPECT_NE(summary(with.shadowStats).find("clusters in"), std::string::npos) << summary(with.shadowStats);
}

// ---- filtering ---------------------------------------------------------------------------------

// A square box turned 30 degrees about the vertical, floating over the ground at y = 0 under a sun
// straight above: its exact shadow is the turned square |x'|, |z'| <= 0.5 (closed form).
struct DsmrTurnedSquare {
    double c = std::cos(0.5235987755982988), s = std::sin(0.5235987755982988);
    Vec3d world(double lx, double lz) const { return {c * lx - s * lz, 0, s * lx + c * lz}; }
    double exact(const Vec3d& p) const {
        const double lx = c * p.x + s * p.z, lz = -s * p.x + c * p.z;
        return std::abs(lx) <= 0.5 && std::abs(lz) <= 0.5 ? 0.0 : 1.0;
    }
};

TEST(DeepShadowFilterTest, BilinearLookupsCutTheStairStepsOfAShadowEdge) {
    const DsmrTurnedSquare sq;
    Mesh box = test::makeBox({-0.5, 1, -0.5}, {0.5, 1.5, 0.5});
    for (Vec3f& p : box.positions) {
        const Vec3d w = sq.world(p.x, p.z);
        p = Vec3f(Vec3d{w.x, double(p.y), w.z});
    }
    VolumeScene s;
    VolumeSceneObject o;
    o.shape = s.addLeaf(box);
    s.addObject(o);
    Light sun;
    sun.direction = {0, -1, 0};
    DeepShadowOptions opt;
    opt.resolution = 32;
    EXPECT_EQ(opt.filter, DsmFilter::Bilinear); // filtered by default
    const DeepShadow bilinear = DeepShadow::build(s, sun, opt);
    opt.filter = DsmFilter::None;
    const DeepShadow none = DeepShadow::build(s, sun, opt);
    const double texel = bilinear.views()[0].columnWorldSize({0, 0, 0});
    // Lines parallel to each edge, at fixed distances from it (up to a texel either side): the exact
    // shadow is constant along each, so its total variation there is the stair-stepping; and the
    // RMS error against the exact shadow over the same points.
    double tv[2] = {0, 0}, sq2[2] = {0, 0};
    int64_t n = 0;
    for (int edge = 0; edge < 4; ++edge)
        for (const double off : {-1.0, -0.6, -0.3, 0.3, 0.6, 1.0}) {
            float prev[2] = {-1, -1};
            for (double t = -0.4; t <= 0.4; t += 0.002) {
                const double a = 0.5 + off * texel, lx = edge < 2 ? (edge ? -a : a) : t,
                             lz = edge < 2 ? t : (edge == 2 ? a : -a);
                const Vec3d p = sq.world(lx, lz);
                const double ref = sq.exact(p);
                const DeepShadow* maps[2] = {&bilinear, &none};
                for (int k = 0; k < 2; ++k) {
                    const float v = maps[k]->visibility(p, {0, 0, 0}, 0, 0).x;
                    if (prev[k] >= 0) tv[k] += std::abs(v - prev[k]);
                    prev[k] = v;
                    sq2[k] += (v - ref) * (v - ref);
                }
                ++n;
            }
        }
    const double rms[2] = {std::sqrt(sq2[0] / double(n)), std::sqrt(sq2[1] / double(n))};
    std::printf(
        "edge: total variation along the edge bilinear %.1f none %.1f; RMS error bilinear %.4f none %.4f\n",
        tv[0], tv[1], rms[0], rms[1]);
    EXPECT_LT(tv[0], 0.6 * tv[1]);
    EXPECT_LT(rms[0], rms[1]);
    // Unfiltered: the visibility function of the one texel the point falls in; filtered: the
    // bilinear lookup (the behaviour before the option existed).
    const LightView& v = none.views()[0];
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int k = 0; k < 500; ++k) {
        const Vec3d p{u(rng), 0, u(rng)};
        const Vec3d g = v.gridFromWorld(p);
        const int64_t x = std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, v.frame.width() - 1);
        const int64_t y = std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, v.frame.height() - 1);
        const std::vector<DsmNode> nodes = none.maps()[0].texel(x, y);
        ASSERT_EQ(none.visibility(p, {0, 0, 0}, 0, 0).x,
                  evalVisibility(nodes.data(), int64_t(nodes.size()), float(g.z)));
        ASSERT_EQ(bilinear.visibility(p, {0, 0, 0}, 0, 0).x,
                  bilinear.maps()[0].view().visibilityBilinear(float(g.x), float(g.y), float(g.z)));
    }
}

TEST(DeepShadowTest, InvalidScenesAndOptionsThrow) {
    VolumeScene s;
    VolumeSceneObject o;
    o.shape = s.addLeaf(test::makeBox({0, 0, 0}, {1, 1, 1}));
    o.kind = ObjectKind::Volume; // without a volume
    s.addObject(o);
    EXPECT_THROW(s.validate(), Error);
    s.objects[0].kind = ObjectKind::Opaque;
    s.validate();
    s.nodes.push_back({ShapeOp::Union, -1, 0, 5});
    EXPECT_THROW(s.validate(), Error);
    s.nodes.pop_back();
    DeepShadowOptions opt;
    opt.resolution = 0;
    EXPECT_THROW(DeepShadow::build(s, dsmrSpot(), opt), Error);
}

// ---- clustering -------------------------------------------------------------------------------

TEST(DeepShadowClusterTest, NearBoxesShareAClusterAndTheCountIsCapped) {
    std::vector<ProjectedBox> boxes;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> jitter(0, 0.05);
    for (int g = 0; g < 3; ++g)
        for (int k = 0; k < 4; ++k) {
            const double x = 0.3 * g + jitter(rng), y = 0.1 + jitter(rng);
            boxes.push_back({{x, y}, {x + 0.1 + jitter(rng), y + 0.1 + jitter(rng)}});
        }
    const std::vector<int> c = clusterBoxes(boxes, 8, 0.12);
    // Every pair within a cluster is within d0 (brute force), and the three groups are apart.
    auto dist = [&](std::size_t a, std::size_t b) {
        double d = 0;
        for (int k = 0; k < 2; ++k)
            d = std::max(
                {d, std::abs(boxes[a].lo[k] - boxes[b].lo[k]), std::abs(boxes[a].hi[k] - boxes[b].hi[k])});
        return d;
    };
    for (std::size_t a = 0; a < boxes.size(); ++a)
        for (std::size_t b = 0; b < boxes.size(); ++b) {
            if (c[a] == c[b]) { EXPECT_LE(dist(a, b), 0.12); }
            if (a / 4 == b / 4) {
                EXPECT_EQ(c[a], c[b]);
            } else {
                EXPECT_NE(c[a], c[b]);
            }
        }
    const std::vector<int> capped = clusterBoxes(boxes, 2, 0.12);
    EXPECT_EQ(*std::max_element(capped.begin(), capped.end()), 1);
    const std::vector<int> one = clusterBoxes(boxes, 1, 0.12);
    EXPECT_EQ(*std::max_element(one.begin(), one.end()), 0);
}

TEST(DeepShadowClusterTest, ClusteredMapsAgreeWithTheReferenceOnASparseScene) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    // Two small objects far apart under one spot light, and a ground that receives only.
    VolumeScene s;
    VolumeSceneObject o;
    o.kind = ObjectKind::Translucent;
    o.opacity = 0.6f;
    o.shape = s.addLeaf(dsmrLoadScaled("knot1", {{-2.2, -0.3, -0.3}, {-1.6, 0.3, 0.3}}));
    s.addObject(o);
    o.kind = ObjectKind::Opaque;
    o.shape = s.addLeaf(dsmrLoadScaled("elephant", {{1.6, -0.3, -0.3}, {2.2, 0.3, 0.3}}));
    s.addObject(o);
    Light l;
    l.type = LightType::Spot;
    l.position = {0, 0, 3};
    l.direction = {0, 0, -1};
    l.outerConeAngle = 1.0;
    DeepShadowOptions opt;
    opt.resolution = 64;
    opt.epsilon = 0.01;
    const DeepShadow single = DeepShadow::build(s, l, opt);
    opt.clusters = 4;
    opt.clusterThreshold = 0.2;
    const DeepShadow clustered = DeepShadow::build(s, l, opt);
    ASSERT_EQ(single.groupBegin().size(), 2u);
    ASSERT_EQ(clustered.groupBegin().size(), 3u); // two clusters, one map each
    // Points on a plane behind both objects: the clustered maps put more texels on each object.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    double errSingle = 0, errClustered = 0;
    int64_t n = 0;
    for (int k = 0; k < 1600; ++k) {
        const double side = k % 2 ? 1.9 : -1.9;
        const Vec3d p{side + 0.45 * u(rng), 0.45 * u(rng), -0.8};
        const double ref = dsmrReferenceTransmittance(s, l.position, p, 1.0);
        if (ref < 0) continue;
        errSingle += std::abs(single.visibility(p, {0, 0, 0}, 0, 0).x - ref);
        errClustered += std::abs(clustered.visibility(p, {0, 0, 0}, 0, 0).x - ref);
        ++n;
    }
    ASSERT_GT(n, 1400);
    EXPECT_LT(errClustered / double(n), 0.08);
    EXPECT_LT(errClustered, errSingle);
}

// ---- the renderer: shadows "deep", volumes in the scene, ray casting, the scene file ----------

Scene dsmrGroundAndSmoke(bool withVolume) {
    Scene s;
    Material ground;
    ground.baseColor = {0.5f, 0.5f, 0.5f};
    ground.specular = 0;
    SceneMesh g;
    g.name = "Ground";
    test::appendQuad(g.mesh, {0, 0, 0}, {0, 0, 4}, {4, 0, 0});
    g.material = s.addMaterial(ground);
    g.castsShadow = false;
    s.meshes.push_back(g);
    Light sun;
    sun.direction = {0, -1, 0};
    sun.intensity = 2;
    s.lights.push_back(sun);
    Camera c;
    c.position = {0, 5, 5};
    c.target = {0, 0, 0};
    c.fovY = 0.7;
    s.cameras.push_back(c);
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

TEST(DeepShadowRenderTest, LightShadowDeepSeesSceneVolumesAndMatchesTheReference) {
    const Scene s = dsmrGroundAndSmoke(true);
    DeepShadowOptions so;
    so.resolution = 64;
    so.epsilon = 0.01;
    const LightShadow ls = buildLightShadow(s, s.lights[0], so);
    ASSERT_FALSE(std::get<DeepShadow>(ls).maps().empty());
    const VolumeScene vs = volumeSceneOf(s);
    int64_t n = 0, shadowed = 0;
    double err = 0;
    for (double x = -1.5; x <= 1.5; x += 0.1)
        for (double z = -1.5; z <= 1.5; z += 0.1) {
            const Vec3d p{x, 0, z};
            const double ref = dsmrReferenceTransmittance(vs, p + Vec3d{0, 10, 0}, p, 0.01);
            if (ref < 0) continue;
            err += std::abs(double(shadowVisibility(ls, p, {0, 0, 0}).x) - ref);
            shadowed += ref < 0.9;
            ++n;
        }
    ASSERT_GT(n, 700);
    EXPECT_GT(shadowed, 100);
    EXPECT_LT(err / double(n), 0.03);
    EXPECT_EQ(shadowVisibility(ls, {3.5, 0, 3.5}, {0, 1, 0}).x, 1.0f);
}

// ---- exact shadows through the volume scene (voxfx/exact_shadow.hpp) ------------------------------

// A volume whose every voxel is 1 filling [-1, 1] x [0.5, 1.5] x [-1, 1] (8 x 4 x 8 voxels of 0.25),
// seen through a transfer function of constant opacity 0.3 per 0.2 world units; with `hole`, the
// object's shape is that box minus the box [-0.3, 0.3] x [0.7, 1.3] x [-0.3, 0.3] (a Boolean).
Scene exvUniformBox(bool hole) {
    auto vs = std::make_shared<VolumeScene>();
    auto volume = std::make_shared<Volume>(Vec3i{8, 4, 8}, Vec3d{-1, 0.5, -1}, Vec3d{0.25, 0.25, 0.25});
    std::fill(volume->values().begin(), volume->values().end(), 1.0f);
    const TransferFunction tf({{0, {1, 1, 1}}, {2, {1, 1, 1}}}, {{0, 0.3}, {2, 0.3}});
    if (!hole) {
        vs->addVolumeBox(volume, tf, 0.2, "uniform");
    } else {
        VolumeSceneObject o;
        o.name = "uniform minus a box";
        o.kind = ObjectKind::Volume;
        o.shape = vs->addNode(ShapeOp::Difference, vs->addLeaf(boxMesh(volume->box())),
                              vs->addLeaf(boxMesh({{-0.3, 0.7, -0.3}, {0.3, 1.3, 0.3}})));
        vs->volumes.push_back(volume);
        o.volume = 0;
        o.transfer = tf;
        o.opacityLength = 0.2;
        vs->addObject(o);
    }
    Scene s;
    s.volumeScene = vs;
    return s;
}

Light exvSun(const Vec3d& direction) {
    Light l;
    l.direction = normalize(direction);
    return l;
}

Light exvPoint(const Vec3d& position) {
    Light l;
    l.type = LightType::Point;
    l.position = position;
    return l;
}

// The closed form: a chord of length d through the uniform volume passes (1 - 0.3)^(d / 0.2) =
// exp(-sigma d) with sigma = -ln(1 - alpha) / opacityLength (voxfx/volume_scene.hpp). The field is
// constant, so the march's midpoints are exact; what is left is float arithmetic (ray parameters
// from Embree in float, the product of about 30 float factors): 1e-4 covers it with room.
TEST(ExactShadowVolumeTest, AUniformVolumePassesExpMinusSigmaTimesTheChord) {
    const double sigma = -std::log(0.7) / 0.2;
    const double tol = 1e-4;
    const Scene box = exvUniformBox(false);
    // A sun at a slant: from the ground under the box the chord crosses the slab of height 1
    // (y in [0.5, 1.5]) through its top and bottom faces, length 1 / |dir.y|.
    const Vec3d slant = normalize(Vec3d{0.3, -1, 0.2});
    const ExactShadow sun = ExactShadow::build(box, exvSun(slant), {});
    int64_t n = 0;
    for (double x = -0.5; x <= 0.5; x += 0.25)
        for (double z = -0.5; z <= 0.5; z += 0.25) {
            EXPECT_NEAR(sun.visibility({x, 0, z}, {0, 1, 0}).x, std::exp(-sigma / std::abs(slant.y)), tol);
            // From inside the volume (y = 1) the chord runs to the top face only.
            EXPECT_NEAR(sun.transmittance({x, 1.0, z}, -slant, std::numeric_limits<double>::infinity()).y,
                        std::exp(-sigma * 0.5 / std::abs(slant.y)), tol);
            ++n;
        }
    EXPECT_EQ(n, 25);
    // Beside the box the light is whole.
    EXPECT_EQ(sun.visibility({3, 0, 3}, {0, 1, 0}).x, 1.0f);
    // A point light above: a third of the way from the ground to the light lies in the slab.
    const Vec3d lamp{0, 3, 0};
    const ExactShadow point = ExactShadow::build(box, exvPoint(lamp), {});
    for (const Vec3d p : {Vec3d{0, 0, 0}, Vec3d{0.6, 0, -0.4}, Vec3d{-0.9, 0, 0.9}})
        EXPECT_NEAR(point.visibility(p, {0, 1, 0}).z, std::exp(-sigma * length(lamp - p) / 3), tol);
    // A light inside the volume: the chord from the bottom face up to the light.
    const Vec3d inside{0, 1.0, 0};
    const ExactShadow buried = ExactShadow::build(box, exvPoint(inside), {});
    for (const Vec3d p : {Vec3d{0.2, 0, 0.1}, Vec3d{-0.3, 0, 0.3}})
        EXPECT_NEAR(buried.visibility(p, {0, 1, 0}).x, std::exp(-sigma * length(inside - p) / 2), tol);
    // The Boolean: straight down through the hole the chord is 1 - 0.6, beside it 1.
    const ExactShadow holed = ExactShadow::build(exvUniformBox(true), exvSun({0, -1, 0}), {});
    for (const double x : {-0.9, -0.6, -0.4, -0.2, 0.0, 0.2, 0.4, 0.6, 0.9}) {
        const bool underHole = std::abs(x) < 0.3;
        EXPECT_NEAR(holed.visibility({x, 0, 0.05}, {0, 1, 0}).x, std::exp(-sigma * (underHole ? 0.4 : 1.0)),
                    tol)
            << x;
    }
    // The step is checked where it is given.
    ExactShadowOptions bad;
    bad.volumeStep = 0;
    EXPECT_THROW(ExactShadow::build(box, exvSun(slant), bad), Error);
}

// The mixed scene (the elephant opaque, the knot translucent, smoke in a box minus a sphere) under
// the spot: exact shadows against the dense march written above (brute-force crossings, its own
// Boolean evaluation, midpoints from the light). Both march at an eighth of a voxel; what separates
// them is where their midpoints fall in a field that is trilinear between voxel centres (a
// midpoint rule's error, h^2 / 24 times the second derivative) and float ray parameters next to
// surfaces: measured 7e-6 mean and 1.3e-4 at most over these points, bounded here at 5e-5 and 1e-3.
TEST(ExactShadowVolumeTest, AgreesWithTheIndependentDenseMarchOnAMixedBooleanScene) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    Scene scene;
    scene.volumeScene = std::make_shared<VolumeScene>(dsmrMixedScene());
    const VolumeScene& s = *scene.volumeScene;
    const Light light = dsmrSpot();
    ExactShadowOptions o;
    o.volumeStep = 0.125;
    const ExactShadow exact = ExactShadow::build(scene, light, o);
    EXPECT_GT(exact.stats().volumeObjects, 2);
    const double voxel = s.volumes[0]->spacing().x;
    const Box3d b = s.bounds(true);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0, 1);
    double maxErr = 0, sumErr = 0;
    int64_t n = 0, dark = 0, partial = 0;
    for (int k = 0; k < 600; ++k) {
        // Points in the casters' bounds and behind them (away from the light, which is at +z).
        const Vec3d p{b.lo.x + unit(rng) * b.extent().x, b.lo.y + unit(rng) * b.extent().y,
                      b.lo.z - 0.5 + unit(rng) * (b.extent().z + 0.5)};
        const double ref = dsmrReferenceTransmittance(s, light.position, p, voxel / 8);
        if (ref < 0) continue; // the ray grazes an edge: either side is right
        const Vec3d d = light.position - p;
        const double got = double(exact.transmittance(p, normalize(d), length(d)).x);
        maxErr = std::max(maxErr, std::abs(got - ref));
        sumErr += std::abs(got - ref);
        ++n;
        dark += ref < 0.01;
        partial += ref > 0.05 && ref < 0.95;
    }
    std::printf("exact against the dense march: %lld points (%lld dark, %lld partly lit), mean error %.2e, "
                "max %.2e\n",
                static_cast<long long>(n), static_cast<long long>(dark), static_cast<long long>(partial),
                sumErr / double(n), maxErr);
    ASSERT_GT(n, 500);
    EXPECT_GT(dark, 10);
    EXPECT_GT(partial, 100);
    EXPECT_LT(maxErr, 1e-3);
    EXPECT_LT(sumErr / double(n), 5e-5);
}

// Deep shadows of the smoke over the ground against the exact reference through the volume: the
// compression adds at most epsilon per texel (DeepShadowTest above), so the mean error at epsilon
// stays within epsilon of the uncompressed map's, and shrinks with epsilon towards that floor (the
// bilinear filter across texels and the pre-integrated one-voxel steps: about 0.001 on this smooth
// smoke at 64^2 and 256^2 alike).
TEST(ExactShadowVolumeTest, DeepShadowsConvergeToTheExactReferenceAsEpsilonShrinks) {
    const Scene s = dsmrGroundAndSmoke(true);
    const LightShadow exact = buildLightShadow(s, s.lights[0], ExactShadowOptions{});
    ASSERT_GT(std::get<ExactShadow>(exact).stats().volumeObjects, 0);
    std::vector<Vec3d> points;
    for (double x = -1.5; x <= 1.5; x += 0.1)
        for (double z = -1.5; z <= 1.5; z += 0.1) points.push_back({x, 0, z});
    std::vector<float> ref;
    int64_t shadowed = 0;
    for (const Vec3d& p : points) {
        ref.push_back(shadowVisibility(exact, p, {0, 1, 0}).x);
        shadowed += ref.back() < 0.9f;
    }
    EXPECT_GT(shadowed, 100);
    auto error = [&](int64_t resolution, double epsilon) {
        DeepShadowOptions so;
        so.resolution = resolution;
        so.epsilon = epsilon;
        const LightShadow deep = buildLightShadow(s, s.lights[0], so);
        double sum = 0;
        for (std::size_t i = 0; i < points.size(); ++i)
            sum += std::abs(double(shadowVisibility(deep, points[i], {0, 0, 0}).x) - double(ref[i]));
        return sum / double(points.size());
    };
    const double floor64 = error(64, 0), floor256 = error(256, 0);
    std::printf("mean |deep - exact|: uncompressed 64^2 %.4f, 256^2 %.4f\n", floor64, floor256);
    EXPECT_LT(floor64, 0.005);
    EXPECT_LT(floor256, 0.005);
    double previous = 1;
    for (const double epsilon : {0.2, 0.1, 0.05, 0.01}) {
        const double e = error(256, epsilon);
        std::printf("  epsilon %.2f: %.4f\n", epsilon, e);
        EXPECT_LE(e, floor256 + epsilon) << epsilon;
        EXPECT_LE(e, previous + 1e-3) << epsilon; // no worse than at the larger epsilon
        previous = e;
    }
    EXPECT_LT(error(256, 0.01), error(256, 0.2));
}

TEST(DeepShadowRenderTest, RayCastingCompositesVolumesOverTheImageAndOnlyThere) {
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.shadow = NoShadowOptions{}; // the smoke's shadow on the ground is tested above
    o.background = {0, 0, 0};
    o.antiAliasing = AntiAliasing::Off; // one sample per pixel with and without the volume pass
    const RenderResult with = render(dsmrGroundAndSmoke(true), dsmrGroundAndSmoke(true).cameras[0], o);
    const RenderResult without = render(dsmrGroundAndSmoke(false), dsmrGroundAndSmoke(false).cameras[0], o);
    EXPECT_GT(with.volumeSamples, 1000);
    EXPECT_EQ(without.volumeSamples, 0);
    // Pixels whose camera ray misses the smoke's box are identical; some through it differ.
    const Frame cam = cameraFrame(dsmrGroundAndSmoke(true).cameras[0], 64, 48);
    const Box3d box{{-1, 0.5, -1}, {1, 1.5, 1}};
    int64_t differ = 0, same = 0;
    for (int64_t y = 0; y < 48; ++y)
        for (int64_t x = 0; x < 64; ++x) {
            const Vec3d eye = cam.eye(), p = cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0});
            const Vec3d d = p - eye;
            double t0 = 0, t1 = 1e30;
            for (int a = 0; a < 3; ++a) {
                double ta = (box.lo[a] - eye[a]) / d[a], tb = (box.hi[a] - eye[a]) / d[a];
                if (ta > tb) std::swap(ta, tb);
                t0 = std::max(t0, ta);
                t1 = std::min(t1, tb);
            }
            const Vec3f a = with.image.at(x, 47 - y), b = without.image.at(x, 47 - y);
            const bool diff = a.x != b.x || a.y != b.y || a.z != b.z;
            if (t0 > t1 + 1e-3) {
                same += !diff;
                EXPECT_FALSE(diff) << x << ", " << y;
            } else {
                differ += diff;
            }
        }
    EXPECT_GT(differ, 50);
    EXPECT_GT(same, 500);
}

// ---- volume sampling: no wood grain (#26 item 2) -------------------------------------------------

// A homogeneous volume (every voxel 1; white, opacity 0.3 per 0.1 world units) filling the slab
// [-1, 1] x [0, 0.5] x [-1, 1], or a ball of radius 0.9 about (0, 0.25, 0), under a slanted sun,
// seen from above; the images are composited over black without ambient light.
constexpr double kUniformOpacity = 0.3, kUniformSun = 3;

Scene dsmrUniformScene(bool ball, double opacityLength) {
    Scene s;
    Light sun;
    sun.direction = normalize(Vec3d{0.5, -1, 0.3});
    sun.intensity = float(kUniformSun);
    s.lights.push_back(sun);
    Camera c;
    c.position = {0, 5, 2.5};
    c.target = {0, 0.25, 0};
    c.fovY = ball ? 0.45 : 0.3;
    s.cameras.push_back(c);
    auto vs = std::make_shared<VolumeScene>();
    const double h = 1.0 / 16;
    auto v = ball ? std::make_shared<Volume>(Vec3i{32, 32, 32}, Vec3d{-1, -0.75, -1}, Vec3d{h, h, h})
                  : std::make_shared<Volume>(Vec3i{32, 8, 32}, Vec3d{-1, 0, -1}, Vec3d{h, h, h});
    std::fill(v->values().begin(), v->values().end(), 1.0f);
    const TransferFunction tf({{0, {1, 1, 1}}, {2, {1, 1, 1}}}, {{0, kUniformOpacity}, {2, kUniformOpacity}});
    if (ball) {
        VolumeSceneObject o;
        o.name = "ball";
        o.kind = ObjectKind::Volume;
        o.shape = vs->addLeaf(test::makeUvSphere({0, 0.25, 0}, 0.9, 48, 96));
        vs->volumes.push_back(v);
        o.volume = 0;
        o.transfer = tf;
        o.opacityLength = opacityLength;
        vs->addObject(o);
    } else {
        vs->addVolumeBox(v, tf, opacityLength, "slab");
    }
    s.volumeScene = vs;
    return s;
}

RenderOptions dsmrUniformOptions(bool deep) {
    RenderOptions o;
    o.width = 96;
    o.height = 72;
    // The linear image without sky light, tone map or anti-aliasing: what the closed form describes.
    o.ambient = {0, 0, 0};
    o.skyLight = 0;
    o.sky = SkyKind::Flat;
    o.background = {0, 0, 0};
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    if (deep) {
        DeepShadowOptions d;
        d.resolution = 96;
        o.shadow = d;
    } else {
        o.shadow = NoShadowOptions{};
    }
    return o;
}

// The slab's pixels whose ray enters through the top well inside and leaves through the bottom,
// with Beer-Lambert's closed form for each: through the slab (no shadows), and with the light
// itself attenuated on its way down from the top face (deep shadows). Returns (image value, closed
// form, closed form without shadows) per pixel.
struct DsmrSlabPixel {
    double value, deep, unshadowed;
};
std::vector<DsmrSlabPixel> dsmrSlabPixels(const Scene& s, const Image& image, double opacityLength) {
    const Frame cam = cameraFrame(s.cameras[0], image.width, image.height);
    const double sigma = -std::log(1 - kUniformOpacity) / opacityLength;
    const double cosL = std::abs(normalize(s.lights[0].direction).y);
    std::vector<DsmrSlabPixel> out;
    for (int64_t y = 0; y < image.height; ++y)
        for (int64_t x = 0; x < image.width; ++x) {
            const Vec3d eye = cam.eye();
            const Vec3d d = normalize(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
            const double tTop = (0.5 - eye.y) / d.y, tBottom = (0.0 - eye.y) / d.y;
            const Vec3d top = eye + d * tTop, bottom = eye + d * tBottom;
            if (std::max(std::abs(top.x), std::abs(top.z)) > 0.55 ||
                std::max(std::abs(bottom.x), std::abs(bottom.z)) > 0.55)
                continue;
            const double len = tBottom - tTop, cosC = std::abs(d.y), k = 1 + cosC / cosL;
            const double e = kUniformSun / M_PI;
            out.push_back({double(image.at(x, image.height - 1 - y).x),
                           e / k * (1 - std::exp(-sigma * k * len)), e * (1 - std::exp(-sigma * len))});
        }
    return out;
}

TEST(VolumeSamplingTest, AHomogeneousSlabMatchesBeerLambertsClosedForm) {
    const double len = 0.5; // optical depth 0.36 straight down
    const Scene s = dsmrUniformScene(false, len);
    const RenderResult lit = render(s, s.cameras[0], dsmrUniformOptions(false));
    const std::vector<DsmrSlabPixel> px = dsmrSlabPixels(s, lit.image, len);
    ASSERT_GT(px.size(), 1000u);
    double worst = 0;
    for (const DsmrSlabPixel& p : px) worst = std::max(worst, std::abs(p.value - p.unshadowed));
    EXPECT_LT(worst, 1e-4); // the pre-integrated intervals compose to Beer-Lambert exactly
    const RenderResult deep = render(s, s.cameras[0], dsmrUniformOptions(true));
    double meanErr = 0, worstDeep = 0;
    for (const DsmrSlabPixel& p : dsmrSlabPixels(s, deep.image, len)) {
        meanErr += std::abs(p.value - p.deep) / p.deep;
        worstDeep = std::max(worstDeep, std::abs(p.value - p.deep) / p.deep);
    }
    meanErr /= double(px.size());
    std::printf("slab: unshadowed worst %.3g, deep mean relative error %.4f, worst %.4f\n", worst, meanErr,
                worstDeep);
    // Under deep shadows the volume's light is looked up a step and a texel towards the light (so
    // a dense layer does not shadow its own front: see the ring test below), which brightens a
    // homogeneous medium by about exp(sigma * that offset): 8.9 % here (3.4 % before the bias).
    EXPECT_LT(meanErr, 0.10);
    EXPECT_LT(worstDeep, 0.10);
}

// Rings are a pattern from pixel to pixel: the residual of each pixel against the mean of its
// eight neighbours, its root mean square over the pixels of `keep` (all neighbours kept too),
// relative to their mean value.
double dsmrRingContrast(const Image& image, const std::vector<uint8_t>& keep) {
    const int64_t W = image.width, H = image.height;
    double sum = 0, sum2 = 0;
    int64_t n = 0;
    for (int64_t y = 1; y + 1 < H; ++y)
        for (int64_t x = 1; x + 1 < W; ++x) {
            bool all = true;
            double mean = 0;
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx) {
                    all = all && keep[std::size_t((y + dy) * W + x + dx)];
                    if (dx || dy) mean += double(image.at(x + dx, y + dy).x) / 8;
                }
            if (!all) continue;
            const double v = image.at(x, y).x;
            sum += v;
            sum2 += (v - mean) * (v - mean);
            ++n;
        }
    EXPECT_GT(n, 500);
    return std::sqrt(sum2 / double(n)) / (sum / double(n));
}

// A dense medium (opacity 0.3 per 0.01 units: a step of 1/16 stops 89 %), where the light falls
// fast across the visible layer: samples at equal steps from each ray's entry drew its fall as
// rings.
TEST(VolumeSamplingTest, AUniformSlabAndBallShowNoRingsUnderDeepShadows) {
    for (const bool ball : {false, true}) {
        const Scene s = dsmrUniformScene(ball, 0.01);
        const RenderOptions o = dsmrUniformOptions(true);
        const RenderResult r = render(s, s.cameras[0], o);
        std::vector<uint8_t> keep(std::size_t(o.width * o.height), 0);
        const Frame cam = cameraFrame(s.cameras[0], o.width, o.height);
        for (int64_t y = 0; y < o.height; ++y)
            for (int64_t x = 0; x < o.width; ++x) {
                const Vec3d eye = cam.eye();
                const Vec3d d = normalize(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
                bool in = false;
                if (ball) { // rays passing well inside the ball
                    const Vec3d c{0, 0.25, 0};
                    in = length(c - (eye + d * dot(c - eye, d))) < 0.6;
                } else {
                    const Vec3d top = eye + d * ((0.5 - eye.y) / d.y), bottom = eye + d * (-eye.y / d.y);
                    in = std::max({std::abs(top.x), std::abs(top.z), std::abs(bottom.x),
                                   std::abs(bottom.z)}) < 0.55;
                }
                keep[std::size_t((o.height - 1 - y) * o.width + x)] = in;
            }
        const double contrast = dsmrRingContrast(r.image, keep);
        std::printf("%s: ring contrast %.5f\n", ball ? "ball" : "slab", contrast);
        // Equal unjittered steps gave 0.020 (slab) and 0.055 (ball); now 0.0003 and 0.011.
        EXPECT_LT(contrast, ball ? 0.025 : 0.005) << (ball ? "ball" : "slab");
    }
}

TEST(VolumeSamplingTest, JitteredImagesAreTheSameForOneAndAllThreads) {
    const Scene s = dsmrUniformScene(true, 0.05);
    RenderOptions o = dsmrUniformOptions(true);
    o.threads = 1;
    const RenderResult one = render(s, s.cameras[0], o);
    o.threads = 0;
    const RenderResult all = render(s, s.cameras[0], o);
    EXPECT_GT(one.volumeSamples, 1000);
    EXPECT_EQ(one.volumeSamples, all.volumeSamples);
    EXPECT_EQ(one.image.pixels, all.image.pixels);
}

TEST(DeepShadowEmptySpaceTest, SkippedSamplesAreTransparentAndSkippingChangesNoPixel) {
    // maxOpacity against the opacity sampled densely over random intervals (an upper bound that
    // the curve reaches).
    const TransferFunction tf = dsmrSmokeTransfer();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-0.3, 1.3);
    for (int i = 0; i < 200; ++i) {
        double a = u(rng), b = u(rng);
        if (a > b) std::swap(a, b);
        double dense = 0;
        for (int k = 0; k <= 400; ++k)
            dense = std::max(dense, tf.opacity(std::min(b, a + (b - a) * k / 400.0)));
        EXPECT_GE(tf.maxOpacity(a, b), dense);
        EXPECT_LE(tf.maxOpacity(a, b), dense + 0.6 * (b - a) / 400.0 / 0.9 + 1e-12);
    }
    // Every point the brick map calls empty samples to opacity 0 (random points, and points on
    // brick and voxel boundaries); the map is not trivially "never".
    SmokeParams sp;
    sp.dims = {21, 18, 20};
    sp.box = {{-1, 0.5, -1}, {1, 1.5, 1}};
    const Volume smoke = makeSmoke(sp);
    Volume turned = smoke; // and the same turned 40 degrees about z (about its lo corner)
    const double c = std::cos(0.7), n = std::sin(0.7);
    turned.setAxes({c, n, 0}, {-n, c, 0}, {0, 0, 1});
    for (const Volume* v : {&smoke, static_cast<const Volume*>(&turned)}) {
        const EmptySpace es(*v, tf);
        EXPECT_GT(es.emptyFraction(), 0.2);
        const Box3d box = v->box();
        std::uniform_real_distribution<double> x(box.lo.x, box.hi.x), y(box.lo.y, box.hi.y),
            fz(box.lo.z, box.hi.z);
        int64_t empty = 0;
        for (int i = 0; i < 20000; ++i) {
            Vec3d p{x(rng), y(rng), fz(rng)};
            if (i % 2) { // snap one voxel coordinate to a voxel boundary (every brick boundary is one)
                const int a = (i / 2) % 3;
                const double w = v->view().voxelCoordinate(p, a);
                p = p + v->axis(a) * ((std::round(w) - w) * v->spacing()[a]);
            }
            if (!es.empty(p)) continue;
            ++empty;
            ASSERT_EQ(tf.opacity(v->sample(p)), 0.0) << p.x << ", " << p.y << ", " << p.z;
        }
        EXPECT_GT(empty, 2000);
    }
    // Rendering and deep shadows with and without skipping: the same pixels, fewer samples.
    const Scene scene = dsmrGroundAndSmoke(true);
    RenderOptions o;
    o.width = 48;
    o.height = 36;
    DeepShadowOptions deep;
    deep.resolution = 48;
    o.shadow = deep;
    const RenderResult skipping = render(scene, scene.cameras[0], o);
    setRenderOption(o, "emptySpaceSkipping", false); // the camera's ray casting and the deep shadows
    const RenderResult sampling = render(scene, scene.cameras[0], o);
    EXPECT_LT(skipping.volumeSamples, sampling.volumeSamples);
    EXPECT_EQ(std::get<DeepShadowStats>(skipping.shadowStats).nodes,
              std::get<DeepShadowStats>(sampling.shadowStats).nodes);
    EXPECT_EQ(skipping.image.pixels, sampling.image.pixels);
}

TEST(DeepShadowSceneFileTest, VolumeObjectsTurnWithRotateAndKeepTheirSamples) {
    // The same smoke placed plainly and scaled, turned 90 degrees about z and moved: every sample
    // of the plain one is found at its turned place, and the default shape is the turned box.
    test::TempDir dir;
    auto load = [&](const std::string& placement) {
        test::writeFile(dir.file("s.json"), R"({"objects": [{"name": "smoke", "kind": "volume",
            "volume": {"smoke": {"dims": [6, 7, 8], "box": [[0, 0, 0], [1, 2, 1]]}},
            "transfer": {"opacity": [[0, 0], [1, 1]], "color": [[0, 1, 1, 1]]})" +
                                                placement + "}]}");
        return loadScene(dir.file("s.json"));
    };
    const Scene plain = load(R"(, "scale": 2)");
    const Scene turned = load(R"(, "scale": 2, "rotate": [0, 0, 1, 90], "translate": [5, 0, 0])");
    const Volume& a = *plain.volumeScene->volumes[0];
    const Volume& b = *turned.volumeScene->volumes[0];
    auto place = [](const Vec3d& p) { return Vec3d{5 - p.y, p.x, p.z}; };
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.2, 4.2);
    for (int i = 0; i < 2000; ++i) {
        const Vec3d p{u(rng) / 2, u(rng), u(rng) / 2};
        ASSERT_NEAR(b.sample(place(p), -1.0f), a.sample(p, -1.0f), 1e-5) << p.x << ", " << p.y << ", " << p.z;
    }
    const Mesh& box = turned.volumeScene->leaves[0];
    ASSERT_EQ(box.positions.size(), 8u);
    double volume6 = 0; // six times the signed volume: positive when the faces point out
    for (std::size_t t = 0; t < box.indices.size(); t += 3) {
        const Vec3d p0(box.positions[box.indices[t]]), p1(box.positions[box.indices[t + 1]]),
            p2(box.positions[box.indices[t + 2]]);
        volume6 += dot(p0, cross(p1, p2));
    }
    EXPECT_NEAR(volume6 / 6, 2.0 * 4.0 * 2.0, 1e-4);
    for (const Vec3f& q : box.positions) { // each corner is a turned corner of the plain box
        bool found = false;
        for (const Vec3f& r : plain.volumeScene->leaves[0].positions)
            found = found || length(Vec3d(q) - place(Vec3d(r))) < 1e-5;
        EXPECT_TRUE(found) << q.x << ", " << q.y << ", " << q.z;
    }
}

TEST(DeepShadowSceneFileTest, ObjectsWithVolumesTransferFunctionsAndBooleanShapesLoad) {
    test::TempDir dir;
    test::writeFile(dir.file("cube.off"),
                    "OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                    "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
    test::writeFile(dir.file("tf.json"), R"({"opacity": [[0, 0], [1, 0.5]], "color": [[0, 1, 1, 1]]})");
    test::writeFile(dir.file("scene.json"), R"({
      "meshes": [{"file": "cube.off", "name": "floor", "scale": [4, 0.1, 4], "translate": [-2, -0.1, -2]}],
      "lights": [{"type": "spot", "position": [0, 5, 0], "direction": [0, -1, 0], "outerConeDegrees": 40}],
      "objects": [
        {"name": "smoke", "kind": "volume", "volume": {"smoke": {"dims": [8, 8, 8], "box": [[-1, 0, -1], [1, 2, 1]]}},
         "transfer": "tf.json", "opacityLength": 0.2,
         "shape": {"difference": [{"volumeBox": true}, {"mesh": "cube.off", "translate": [-0.5, 0.5, -0.5]}]}},
        {"name": "glass", "kind": "translucent", "opacity": 0.3, "shape": {"box": [[1, 0, 1], [1.5, 0.5, 1.5]]}},
        {"name": "lens", "kind": "opaque", "shape": {"intersection": [{"box": [[-2, 0, -2], [-1, 1, -1]]},
                                                                      {"mesh": "cube.off", "translate": [-1.5, 0.5, -1.5]}]}}
      ],
      "render": {"shadows": "deep"}
    })");
    const Scene s = loadScene(dir.file("scene.json"));
    ASSERT_TRUE(s.volumeScene);
    const VolumeScene& vs = *s.volumeScene;
    ASSERT_EQ(vs.objects.size(), 2u); // the plain translucent box became a scene mesh
    EXPECT_EQ(vs.objects[0].kind, ObjectKind::Volume);
    EXPECT_EQ(vs.nodes[std::size_t(vs.objects[0].shape)].op, ShapeOp::Difference);
    EXPECT_EQ(vs.nodes[std::size_t(vs.objects[1].shape)].op, ShapeOp::Intersection);
    EXPECT_EQ(vs.volumes[0]->dims(), (Vec3i{8, 8, 8}));
    EXPECT_DOUBLE_EQ(vs.objects[0].transfer.opacity(1.0), 0.5);
    ASSERT_EQ(s.meshes.size(), 2u);
    EXPECT_FLOAT_EQ(s.materials[s.meshes[1].material].opacity, 0.3f);
    EXPECT_TRUE(s.materials[s.meshes[1].material].blend); // the camera sees through it

    // Bad objects: a clear error naming the object, no scene.
    const std::pair<const char*, const char*> bad[] = {
        {R"({"name": "a", "kind": "fog", "shape": {"box": [[0,0,0],[1,1,1]]}})", "unknown kind"},
        {R"({"name": "b", "kind": "volume", "volume": {"smoke": {}}})", "needs \"transfer\""},
        {R"({"name": "c", "kind": "volume", "volume": {"smoke": {}}, "transfer": {"opacity": [[0, 2]], "color": [[0, 1, 1, 1]]}})",
         "opacity"},
        {R"({"name": "d", "kind": "volume", "volume": "missing.inr", "transfer": "tf.json"})", "missing.inr"},
        {R"({"name": "e", "kind": "opaque", "shape": {"difference": [{"box": [[0,0,0],[1,1,1]]}]}})",
         "two shapes"},
        {R"({"name": "f", "kind": "translucent", "opacity": 1.5, "shape": {"box": [[0,0,0],[1,1,1]]}})",
         "opacity"},
        {R"({"name": "g", "kind": "volume", "volume": {"smoke": {"frequency": -1}}, "transfer": "tf.json"})",
         "objects[0] 'g'.volume.smoke: smoke frequency"},
        {R"({"name": "h", "kind": "opaque", "shape": {"mesh": "gone.off"}})", "gone.off"}};
    for (const auto& [object, message] : bad) {
        test::writeFile(dir.file("bad.json"), std::string(R"({"objects": [)") + object + "]}");
        try {
            loadScene(dir.file("bad.json"));
            ADD_FAILURE() << "accepted " << object;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
            // Files it names and generators it calls fail with the scene file's name too.
            EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
        }
    }
}

TEST(DeepShadowCliTest, RenderWithDeepShadowsEveryStorageAndClusters) {
    test::TempDir dir;
    test::writeFile(dir.file("cube.off"),
                    "OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                    "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
    test::writeFile(dir.file("scene.json"), R"({
      "meshes": [{"file": "cube.off", "name": "floor", "scale": [4, 0.1, 4], "translate": [-2, -0.1, -2]},
                 {"file": "cube.off", "name": "box", "scale": 0.5, "translate": [0.5, 0.5, 0]}],
      "receiversOnly": ["floor"],
      "lights": [{"type": "spot", "position": [0, 5, 0.5], "direction": [0, -1, 0], "outerConeDegrees": 50}],
      "objects": [{"name": "smoke", "kind": "volume", "volume": {"smoke": {"dims": [8, 8, 8], "box": [[-1, 0, -1], [0, 1, 0]]}},
                   "transfer": {"opacity": [[0, 0], [1, 0.5]], "color": [[0, 1, 1, 1]]}}]
    })");
    for (const char* flags : {"--dsm-storage fixed --epsilon 0.1", "--dsm-storage chunked --clusters 2"}) {
        const test::CommandRun r =
            test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("out.png") +
                                    " --shadows deep --dsm-resolution 64 --width 40 --height 30 " + flags);
        EXPECT_EQ(r.exitCode, 0) << r.err;
        EXPECT_NE(r.out.find("shadows deep"), std::string::npos) << r.out;
        EXPECT_NE(r.out.find("ray casting"), std::string::npos) << r.out;
        EXPECT_TRUE(std::filesystem::exists(dir.file("out.png")));
        std::filesystem::remove(dir.file("out.png"));
    }
    const test::CommandRun bad =
        test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("out.png") +
                                " --shadows deep --dsm-storage linked");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("linked"), std::string::npos) << bad.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.png")));
}

TEST(DeepShadowCliTest, TheDsmKnobsAreFlagsWithHelpAndBadValuesFailNamingThem) {
    test::TempDir dir;
    const test::CommandRun help = test::runVoxfx(dir, "render --help");
    ASSERT_EQ(help.exitCode, 0) << help.err;
    for (const char* flag : {"--fixed-nodes", "--dsm-step", "--termination", "--clusters",
                             "--cluster-threshold", "--cluster-equal-texels", "--dsm-filter"})
        EXPECT_NE(help.out.find(flag), std::string::npos) << flag;
    EXPECT_NE(help.out.find("bilinear | none"), std::string::npos);
    test::writeFile(dir.file("cube.off"),
                    "OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                    "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
    test::writeFile(dir.file("scene.json"), R"({
      "meshes": [{"file": "cube.off", "name": "floor", "scale": [4, 0.1, 4], "translate": [-2, -0.1, -2]},
                 {"file": "cube.off", "name": "a", "scale": 0.5, "translate": [-1.5, 0.5, 0]},
                 {"file": "cube.off", "name": "b", "scale": 0.5, "translate": [1.0, 0.5, 0]}],
      "receiversOnly": ["floor"],
      "lights": [{"type": "point", "position": [0, 3, 0.2]}]
    })");
    const std::string base = "render " + dir.file("scene.json") + " -o " + dir.file("out.png") +
                             " --shadows deep --dsm-resolution 32 --width 40 --height 30 ";
    const test::CommandRun good =
        test::runVoxfx(dir, base + "--fixed-nodes 4 --dsm-storage fixed --dsm-step 0.5 --termination 0.01 "
                                   "--clusters 3 --cluster-threshold 0.1 --dsm-filter none");
    EXPECT_EQ(good.exitCode, 0) << good.err;
    EXPECT_NE(good.out.find("clusters in"), std::string::npos) << good.out;
    std::filesystem::remove(dir.file("out.png"));
    // Each bad value: a non-zero exit, the flag (or the option) named, no image.
    for (const auto& [flags, named] :
         std::vector<std::pair<std::string, std::string>>{{"--fixed-nodes 1", "--fixed-nodes"},
                                                          {"--fixed-nodes -3", "--fixed-nodes"},
                                                          {"--dsm-step 0", "--dsm-step"},
                                                          {"--dsm-step abc", "--dsm-step"},
                                                          {"--termination 1", "--termination"},
                                                          {"--cluster-threshold -1", "--cluster-threshold"},
                                                          {"--clusters -2", "--clusters"},
                                                          {"--dsm-filter blurry", "blurry"}}) {
        const test::CommandRun bad = test::runVoxfx(dir, base + flags);
        EXPECT_NE(bad.exitCode, 0) << flags;
        EXPECT_NE(bad.err.find(named), std::string::npos) << flags << ": " << bad.err;
        EXPECT_EQ(bad.err.find("terminate called"), std::string::npos) << flags << ": " << bad.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("out.png"))) << flags;
    }
}

// The table of BENCHMARKS.md: DSM lookups (bilinear, at random points of the mixed scene) against the
// dense reference as ε and the resolution vary. Slow: the reference marches at an eighth of a voxel.
TEST(DeepShadowSlowTest, ErrorAgainstTheDenseReferenceAsEpsilonAndResolutionVary) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    const VolumeScene s = dsmrMixedScene();
    const Light light = dsmrSpot();
    const double voxel = s.volumes[0]->spacing().x;
    // Points in the lit volume below the light: inside the smoke, on and behind the objects.
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(0, 1);
    const Box3d b = s.bounds(true);
    std::vector<Vec3d> points;
    std::vector<double> refs;
    while (points.size() < 4000) {
        const Vec3d p = b.lo + b.extent() * Vec3d{u(rng), u(rng), u(rng)};
        const double ref = dsmrReferenceTransmittance(s, light.position, p, voxel / 8);
        if (ref < 0) continue;
        points.push_back(p);
        refs.push_back(ref);
    }
    std::printf("| resolution | epsilon | mean abs error | max abs error | nodes/texel mean | max |\n");
    for (const int64_t res : {64, 128, 256, 512})
        for (const double eps : {0.0, 0.01, 0.05, 0.1, 0.2}) {
            DeepShadowOptions opt;
            opt.resolution = res;
            opt.epsilon = eps;
            const DeepShadow d = DeepShadow::build(s, light, opt);
            double sum = 0, worst = 0;
            for (std::size_t i = 0; i < points.size(); ++i) {
                const double e = std::abs(d.visibility(points[i], {0, 0, 0}, 0, 0).x - refs[i]);
                sum += e;
                worst = std::max(worst, e);
            }
            std::printf("| %lld | %.2f | %.4f | %.3f | %.2f | %lld |\n", static_cast<long long>(res), eps,
                        sum / double(points.size()), worst, d.stats().meanNodes(),
                        static_cast<long long>(d.stats().maxNodes));
            if (res == 512 && eps <= 0.05) { EXPECT_LT(sum / double(points.size()), 0.03); }
        }
}

} // namespace
} // namespace voxfx
