// Tests of deep shadow maps from lights (voxfx/deep_shadow.hpp, technique "deep"; the clustered
// maps are tested in test_deep_shadow_cluster.cpp). Oracles: the standard shadow map, and the dense
// ray march from the light of tests/support/volume_reference.hpp (dsmrReferenceTransmittance),
// which shares no code with the deep shadow map. Also the filtered lookups against a closed-form
// shadow edge, the renderer's "deep" shadows of scene volumes, the command line's DSM flags, and the
// error table of BENCHMARKS.md as the Slow case.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/shadow_map.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::dsmrGroundAndSmoke;
using test::dsmrLoadScaled;
using test::dsmrMixedScene;
using test::dsmrReferenceTransmittance;
using test::dsmrSpot;

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

// ---- the renderer and the command line ----------------------------------------------------------

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
