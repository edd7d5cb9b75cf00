// Tests of clustered deep shadow maps (voxfx/deep_shadow.hpp, DeepShadowOptions::clusters): the
// clustering of projected boxes, maps aimed at each cluster of casting objects (point lights: only
// the cube faces a cluster reaches) against the dense ray march of tests/support/volume_reference.hpp
// at equal texels, clusters that follow the camera, the statistics' invariants, and the renderer and
// its summary with clusters.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::dsmrLoadScaled;
using test::dsmrReferenceTransmittance;
using test::dsmrSpot;
using test::pointLight;

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

// The unclustered and the clustered maps of one light against the independent reference at
// `count` receivers receiver(k) (those the reference can tell): their summed errors and how many
// were compared; visit(reference, unclustered, clustered) sees each.
struct ClusterErrors {
    double single = 0, clustered = 0;
    int64_t n = 0;
};
template <class Receiver, class Visit>
ClusterErrors compareAtReceivers(const VolumeScene& s, const Light& l, const DeepShadow& single,
                                 const DeepShadow& clustered, int count, Receiver receiver, Visit visit) {
    ClusterErrors e;
    for (int k = 0; k < count; ++k) {
        const Vec3d p = receiver(k);
        const double ref = dsmrReferenceTransmittance(s, l.position, p, 1.0);
        if (ref < 0) continue;
        const double a = single.visibility(p, {0, 0, 0}, 0, 0).x,
                     b = clustered.visibility(p, {0, 0, 0}, 0, 0).x;
        e.single += std::abs(a - ref);
        e.clustered += std::abs(b - ref);
        visit(ref, a, b);
        ++e.n;
    }
    return e;
}

TEST(DeepShadowClusterTest, PointLightClustersAimFewerMapsAndAreCloserToTheReferenceAtEqualTexels) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    const VolumeScene s = dsmrTwoUnderAPointLight();
    const Light l = pointLight({0, 3, 0});
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
    int64_t differ = 0;
    const auto [errSingle, errClustered, n] = compareAtReceivers(
        s, l, single, clustered, 2000,
        [&](int k) {
            const double side = k % 2 ? 2.8 : -2.8;
            return Vec3d{side + 0.6 * u(rng), -0.5, 0.6 * u(rng)};
        },
        [&](double, double a, double b) { differ += std::abs(a - b) > 0.01; });
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
    const Light l = pointLight({0, 0, 0});
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
    int64_t wrong = 0, shadowed = 0;
    const auto [errSingle, errClustered, n] = compareAtReceivers(
        s, l, single, clustered, 3000,
        [&](int) {
            return Vec3d{3 * u(rng), 3 * u(rng), 3 * u(rng)};
        },
        [&](double ref, double, double b) {
            wrong += std::abs(b - ref) > 0.5;
            shadowed += ref < 0.5;
        });
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
    for (const Light& light : {Light{}, dsmrSpot(), pointLight({0, 4, 0})}) {
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
    s.lights.push_back(pointLight({0, 3, 0}));
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

} // namespace
} // namespace voxfx
