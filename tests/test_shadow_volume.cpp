// voxfx — shadow volumes: closed casters, closed volumes, the per-pixel count against an exact
// ray-traced hard shadow (CGAL segment-triangle tests, nothing shared with the rasterizer), and
// ED06 §3.2 culling and clamping leaving the shadow unchanged while rasterizing fewer fragments.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "demo/demo_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/error.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/shadow_volume.hpp"

namespace voxfx {
namespace {

using namespace voxfx::demo;

Light svPointLight(const Vec3d& p) {
    Light l;
    l.type = LightType::Point;
    l.name = "point";
    l.position = p;
    l.intensity = 30;
    return l;
}

Light svSpotLight(const Vec3d& p, const Vec3d& target) {
    Light l;
    l.type = LightType::Spot;
    l.name = "spot";
    l.position = p;
    l.direction = normalize(target - p);
    l.outerConeAngle = 0.7;
    l.innerConeAngle = 0.5;
    l.intensity = 30;
    return l;
}

Light svSun(const Vec3d& d) {
    Light l;
    l.type = LightType::Directional;
    l.name = "sun";
    l.direction = normalize(d);
    l.intensity = 2;
    return l;
}

void svAddCaster(Scene& s, const std::string& name, Mesh mesh) {
    SceneMesh m;
    m.name = name;
    m.mesh = std::move(mesh);
    m.material = 0;
    s.meshes.push_back(std::move(m));
}

// A receive-only ground and closed casters: some stacked (one in another's shadow), one far off
// to the side whose shadow leaves the picture, one low enough for the camera to see its shadow on
// the others.
Scene svScene() {
    Scene s;
    s.addMaterial(Material{});
    SceneMesh g;
    g.name = "ground";
    test::appendQuad(g.mesh, {0, 0, 0}, {0, 0, 5}, {5, 0, 0});
    g.castsShadow = false;
    s.meshes.push_back(g);
    svAddCaster(s, "torus", test::makeTorus({0, 1.0, 0}, 0.6, 0.2, 32, 12));
    svAddCaster(s, "sphere", test::makeUvSphere({1.5, 0.6, 0.8}, 0.45, 14, 20));
    svAddCaster(s, "box", test::makeBox({-2.0, 0.0, -0.5}, {-1.2, 0.9, 0.4}));
    svAddCaster(s, "high", test::makeOctahedron({0.1, 2.6, -0.1}, 0.35));
    svAddCaster(s, "far", test::makeBox({-40, 0.5, 30}, {-39, 1.5, 31})); // behind the camera
    // A slab with a small sphere under it, wholly in its shadow for every light of the tests.
    svAddCaster(s, "slab", test::makeBox({1.6, 1.9, -2.6}, {4.4, 2.0, 0.2}));
    svAddCaster(s, "hidden", test::makeUvSphere({3.0, 1.2, -1.2}, 0.3, 10, 14));
    // Under the ground: on screen behind it, its volume reaches no visible receiver.
    svAddCaster(s, "buried", test::makeBox({-0.8, -3.6, -0.8}, {0.8, -2.9, 0.8}));
    return s;
}

Camera svCamera(const Vec3d& eye, const Vec3d& target) {
    Camera c;
    c.position = eye;
    c.target = target;
    c.fovY = 0.9;
    return c;
}

struct SvFixture {
    Scene scene;
    SceneGeometry geometry;
    GBuffer gbuffer;
};

SvFixture svFixture(Scene scene, const Camera& camera, int64_t w, int64_t h) {
    SvFixture f{std::move(scene), {}, {}};
    f.geometry = flattenScene(f.scene);
    f.gbuffer = renderGBuffer(f.geometry, cameraFrame(camera, w, h));
    return f;
}

// The exact hard shadow at every G-buffer point: does the segment from the point to the light (for
// a directional light, far along -direction) meet a caster triangle that faces away from the light?
// For closed casters that is "occluded": a light ray through a caster leaves it through such a
// triangle; lit surfaces are never tested against themselves.
std::vector<uint8_t> svRayTraced(const SvFixture& f, const Light& light) {
    Mesh unlit;
    for (const SceneMesh& m : f.scene.meshes) {
        if (!m.castsShadow) continue;
        for (std::size_t t = 0; t < m.mesh.triangleCount(); ++t) {
            const Vec3d a(m.mesh.positions[m.mesh.indices[3 * t]]),
                b(m.mesh.positions[m.mesh.indices[3 * t + 1]]),
                c(m.mesh.positions[m.mesh.indices[3 * t + 2]]);
            const Vec3d toLight =
                light.type == LightType::Directional ? -light.direction : light.position - a;
            if (dot(cross(b - a, c - a), toLight) > 0) continue;
            const auto base = uint32_t(unlit.positions.size());
            unlit.positions.insert(unlit.positions.end(), {Vec3f(a), Vec3f(b), Vec3f(c)});
            unlit.indices.insert(unlit.indices.end(), {base, base + 1, base + 2});
        }
    }
    const Frame& cam = f.gbuffer.frame;
    std::vector<Vec3d> from, to;
    std::vector<size_t> pixel;
    const double reach = 10 * length(f.scene.bounds().extent()) + 100;
    for (int64_t y = 0; y < cam.height(); ++y)
        for (int64_t x = 0; x < cam.width(); ++x) {
            const auto i = size_t(y * cam.width() + x);
            if (f.gbuffer.triangle[i] == GBuffer::kNone) continue;
            const Vec3d p = cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, double(f.gbuffer.depth[i])});
            from.push_back(p);
            to.push_back(light.type == LightType::Directional ? p - light.direction * reach : light.position);
            pixel.push_back(i);
        }
    const std::vector<uint8_t> hit = test::oracleSegmentsHitMesh(unlit.view(), from, to);
    std::vector<uint8_t> out(f.gbuffer.triangle.size(), 0);
    for (std::size_t k = 0; k < pixel.size(); ++k) out[pixel[k]] = hit[k];
    return out;
}

struct SvComparison {
    int64_t receivers = 0, shadowed = 0, mismatches = 0, offSilhouette = 0, silhouettePixels = 0;
};

// Mismatches at receiver pixels; a mismatch is on a silhouette when the reference changes between
// the pixel and one of its 8 neighbours (a shadow boundary or a depth edge runs through it).
SvComparison svCompare(const SvFixture& f, const std::vector<uint8_t>& receivers,
                       const std::vector<uint8_t>& mask, const std::vector<uint8_t>& reference) {
    SvComparison c;
    const int64_t W = f.gbuffer.frame.width(), H = f.gbuffer.frame.height();
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const auto i = size_t(y * W + x);
            if (!receivers[i]) continue;
            ++c.receivers;
            c.shadowed += reference[i];
            bool boundary = false;
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx) {
                    const int64_t xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
                    const auto j = size_t(yy * W + xx);
                    boundary |= reference[j] != reference[i] || (f.gbuffer.triangle[j] == GBuffer::kNone) !=
                                                                    (f.gbuffer.triangle[i] == GBuffer::kNone);
                }
            c.silhouettePixels += boundary;
            if (mask[i] != reference[i]) {
                ++c.mismatches;
                c.offSilhouette += !boundary;
            }
        }
    return c;
}

ShadowVolumeOptions svOptions(bool cull, bool clamp) {
    ShadowVolumeOptions o;
    o.cullReceivers = cull;
    o.cullOccluded = cull;
    o.cullShadowedParts = cull;
    o.dropShadowedReceivers = cull;
    o.clamp = clamp;
    o.clampRuns = clamp;
    o.mapResolution = 256;
    o.receiverSlices = 64;
    return o;
}

TEST(ShadowVolumeTest, CasterSetPairsEveryEdgeAndRefusesOpenMeshes) {
    Scene s;
    s.addMaterial(Material{});
    svAddCaster(s, "torus", test::makeTorus({0, 0, 0}, 1, 0.3, 12, 8));
    const ShadowCasterSet set = ShadowCasterSet::build(s);
    ASSERT_EQ(set.casters.size(), 1u);
    const ShadowCaster& c = set.casters[0];
    // The twin of a directed edge runs backwards, and twins pair up.
    for (std::size_t e = 0; e < c.twin.size(); ++e) {
        const std::size_t t = c.twin[e];
        ASSERT_LT(t, c.twin.size());
        EXPECT_EQ(c.twin[t], e);
        EXPECT_EQ(c.indices[e], c.indices[t - t % 3 + (t % 3 + 1) % 3]);
        EXPECT_EQ(c.indices[t], c.indices[e - e % 3 + (e % 3 + 1) % 3]);
    }
    // One triangle removed: three unmatched edges, refused with the mesh's name.
    s.meshes[0].mesh.indices.resize(s.meshes[0].mesh.indices.size() - 3);
    try {
        ShadowCasterSet::build(s);
        FAIL() << "an open caster was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'torus'"), std::string::npos) << e.what();
    }
    // Receive-only meshes may be open.
    s.meshes[0].castsShadow = false;
    EXPECT_TRUE(ShadowCasterSet::build(s).casters.empty());
}

TEST(ShadowVolumeTest, VolumesAreClosedConsistentlyOrientedSurfaces) {
    const Scene scene = svScene();
    const ShadowCasterSet casters = ShadowCasterSet::build(scene);
    for (const Light& light : {svPointLight({0.5, 5, 1.5}), svSun({0.3, -1, 0.2})}) {
        SCOPED_TRACE(light.name);
        Scene volumes;
        volumes.addMaterial(Material{});
        svAddCaster(volumes, "volumes", shadowVolumeMesh(casters, light, scene.bounds()));
        EXPECT_NO_THROW(ShadowCasterSet::build(volumes));
        // Outward orientation: a closed surface's signed volume is positive.
        EXPECT_GT(test::meshVolume(volumes.meshes[0].mesh.view()), 0);
    }
}

// The count against the exact ray-traced shadow, for point, spot and directional lights, and for a
// camera far outside the volumes (depth-pass) and one inside a volume (depth-fail).
TEST(ShadowVolumeTest, ShadowEqualsRayTracedHardShadowExceptAtSilhouettePixels) {
    const Light lights[] = {svPointLight({0.5, 5, 1.5}), svSpotLight({-1.5, 5.5, 2}, {0, 0, 0}),
                            svSun({0.3, -1, 0.2})};
    const Camera cameras[] = {svCamera({0.5, 4.5, 6.5}, {0, 0.6, 0}),
                              // Under the torus (outside it), in its shadow for every light: depth-fail.
                              svCamera({0.1, 0.08, 0.05}, {2.5, 0.0, 2.5})};
    for (const Camera& camera : cameras) {
        const SvFixture f = svFixture(svScene(), camera, 80, 60);
        const ShadowCasterSet casters = ShadowCasterSet::build(f.scene);
        for (const Light& light : lights) {
            SCOPED_TRACE(light.name + (&camera == &cameras[0] ? ", outside" : ", inside"));
            const std::vector<uint8_t> receivers =
                shadowVolumeReceivers(f.gbuffer, f.geometry, f.scene.materials, light);
            const ShadowVolumeMask mask = computeShadowVolumes(casters, light, f.gbuffer, receivers,
                                                               f.scene.bounds(), svOptions(false, false));
            const SvComparison c = svCompare(f, receivers, mask.shadowed, svRayTraced(f, light));
            std::cout << "[ shadow ] " << light.name << ": " << c.receivers << " receivers, " << c.shadowed
                      << " shadowed, " << c.mismatches << " mismatches (" << c.offSilhouette
                      << " off silhouettes) among " << c.silhouettePixels << " silhouette pixels; depth-pass "
                      << mask.stats.depthPass << ", depth-fail " << mask.stats.depthFail << "\n";
            EXPECT_GT(c.shadowed, 20);
            if (&camera == &cameras[0]) { EXPECT_LT(c.shadowed, c.receivers); }
            EXPECT_EQ(c.offSilhouette, 0);
            EXPECT_LE(c.mismatches * 10, c.silhouettePixels + 10);
            if (&camera == &cameras[1]) {
                EXPECT_GT(mask.stats.depthFail, 0);
            } else {
                EXPECT_GT(mask.stats.depthPass, 0);
            }
        }
    }
}

// Culling and clamping are conservative: the same shadow at every receiver, fewer fragments.
TEST(ShadowVolumeTest, CullingAndClampingKeepTheShadowPixelForPixel) {
    const SvFixture f = svFixture(svScene(), svCamera({0.5, 4.5, 6.5}, {0, 0.6, 0}), 96, 72);
    const ShadowCasterSet casters = ShadowCasterSet::build(f.scene);
    for (const Light& light :
         {svPointLight({0.5, 5, 1.5}), svSpotLight({-1.5, 5.5, 2}, {0, 0, 0}), svSun({0.3, -1, 0.2})}) {
        SCOPED_TRACE(light.name);
        const std::vector<uint8_t> receivers =
            shadowVolumeReceivers(f.gbuffer, f.geometry, f.scene.materials, light);
        const ShadowVolumeMask plain = computeShadowVolumes(casters, light, f.gbuffer, receivers,
                                                            f.scene.bounds(), svOptions(false, false));
        const ShadowVolumeMask culled = computeShadowVolumes(casters, light, f.gbuffer, receivers,
                                                             f.scene.bounds(), svOptions(true, false));
        const ShadowVolumeMask both = computeShadowVolumes(casters, light, f.gbuffer, receivers,
                                                           f.scene.bounds(), svOptions(true, true));
        int64_t diffCulled = 0, diffBoth = 0, shadowed = 0;
        for (std::size_t i = 0; i < receivers.size(); ++i) {
            if (!receivers[i]) continue;
            shadowed += plain.shadowed[i];
            diffCulled += plain.shadowed[i] != culled.shadowed[i];
            diffBoth += plain.shadowed[i] != both.shadowed[i];
        }
        EXPECT_GT(shadowed, 20);
        EXPECT_EQ(diffCulled, 0);
        EXPECT_EQ(diffBoth, 0);
        EXPECT_TRUE(both.stats.receiversCovered);
        // The far and the buried casters reach no visible receiver; the sphere under the slab lies
        // in its shadow.
        EXPECT_GE(culled.stats.culledNoReceiver, 2);
        EXPECT_GE(culled.stats.culledOccluded, 1);
        EXPECT_GE(both.stats.clamped, 1);
        EXPECT_LT(culled.stats.fragments, plain.stats.fragments);
        EXPECT_LT(both.stats.fragments, culled.stats.fragments);
        std::cout << "[ shadow ] " << light.name << ": fragments " << plain.stats.fragments << " / "
                  << culled.stats.fragments << " / " << both.stats.fragments << ", culled "
                  << culled.stats.culledNoReceiver << " + " << culled.stats.culledOccluded << " (" <<
            [&] {
                std::string names;
                for (std::size_t i = 0; i < casters.casters.size(); ++i)
                    if (culled.culled[i])
                        names += casters.casters[i].name + (culled.culled[i] == 1 ? "/r " : "/o ");
                return names;
            }() << ")"
                  << ", clamped " << both.stats.clamped << "\n";
    }
}

// Each switch of ED06 §3.2 on its own, then all together: the shadow at every receiver is the one
// of the unculled, unclamped volumes (which equals the ray-traced shadow off silhouettes, above),
// and each switch does its part: layers starting behind their caster and gaps left out (clampRuns),
// shadowed unlit triangles dropped (cullShadowedParts), receivers left to the caster in front
// (dropShadowedReceivers), with fewer fragments than without it.
TEST(ShadowVolumeTest, EachCullingAndClampingSwitchKeepsTheShadowAndSavesFragments) {
    const SvFixture f = svFixture(svScene(), svCamera({0.5, 4.5, 6.5}, {0, 0.6, 0}), 96, 72);
    const ShadowCasterSet casters = ShadowCasterSet::build(f.scene);
    struct Switch {
        const char* name;
        bool ShadowVolumeOptions::*flag;
    };
    const Switch switches[] = {{"cullReceivers", &ShadowVolumeOptions::cullReceivers},
                               {"cullOccluded", &ShadowVolumeOptions::cullOccluded},
                               {"cullShadowedParts", &ShadowVolumeOptions::cullShadowedParts},
                               {"volumeClamping", &ShadowVolumeOptions::clamp},
                               {"clampRuns", &ShadowVolumeOptions::clampRuns}};
    const ShadowVolumeOptions none = svOptions(false, false);
    int64_t nearClamped = 0, gaps = 0, culledTriangles = 0, dropped = 0;
    for (const Light& light :
         {svPointLight({0.5, 5, 1.5}), svSpotLight({-1.5, 5.5, 2}, {0, 0, 0}), svSun({0.3, -1, 0.2})}) {
        SCOPED_TRACE(light.name);
        const std::vector<uint8_t> receivers =
            shadowVolumeReceivers(f.gbuffer, f.geometry, f.scene.materials, light);
        const ShadowVolumeMask plain =
            computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), none);
        auto differences = [&](const ShadowVolumeMask& m) {
            int64_t n = 0;
            for (std::size_t i = 0; i < receivers.size(); ++i)
                n += receivers[i] && plain.shadowed[i] != m.shadowed[i];
            return n;
        };
        std::cout << "[ shadow ] " << light.name << ": fragments none " << plain.stats.fragments;
        for (const Switch& sw : switches) {
            ShadowVolumeOptions o = none;
            o.*sw.flag = true;
            const ShadowVolumeMask m =
                computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), o);
            EXPECT_EQ(differences(m), 0) << sw.name;
            EXPECT_LE(m.stats.fragments, plain.stats.fragments) << sw.name;
            std::cout << ", " << sw.name << " " << m.stats.fragments;
            if (sw.flag == &ShadowVolumeOptions::clampRuns) {
                nearClamped += m.stats.nearClamped;
                gaps += m.stats.gaps;
                EXPECT_EQ(m.stats.clamped, 0); // the far end stays: clampRuns alone
            }
            if (sw.flag == &ShadowVolumeOptions::cullShadowedParts) {
                culledTriangles += m.stats.culledTriangles;
                EXPECT_EQ(m.stats.culledOccluded, 0);
            }
        }
        // Shadowed receivers left to the caster in front: on top of receiver culling and clamping.
        ShadowVolumeOptions before = none;
        before.cullReceivers = before.clamp = before.clampRuns = true;
        ShadowVolumeOptions withDrop = before;
        withDrop.dropShadowedReceivers = true;
        const ShadowVolumeMask b =
            computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), before);
        const ShadowVolumeMask d =
            computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), withDrop);
        EXPECT_EQ(differences(b), 0);
        EXPECT_EQ(differences(d), 0);
        EXPECT_LE(d.stats.fragments, b.stats.fragments);
        dropped += d.stats.droppedReceivers;
        // Everything together, against the three switches there were before.
        ShadowVolumeOptions old = none;
        old.cullReceivers = old.cullOccluded = old.clamp = true;
        ShadowVolumeOptions all = svOptions(true, true);
        const ShadowVolumeMask o =
            computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), old);
        const ShadowVolumeMask a =
            computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), all);
        EXPECT_EQ(differences(a), 0); // the savings are reported, not required: see BENCHMARKS.md
        std::cout << ", dropShadowedReceivers " << b.stats.fragments << " -> " << d.stats.fragments << " ("
                  << d.stats.droppedReceivers << " cells), the three old switches " << o.stats.fragments
                  << ", all " << a.stats.fragments << "\n";
    }
    EXPECT_GE(culledTriangles, 1);
    EXPECT_GE(dropped, 1);
    std::cout << "[ shadow ] clampRuns on the scene above: " << nearClamped << " near ends, " << gaps
              << " gaps\n";
}

// The unculled, unclamped volumes and the same with clampRuns alone, for one light: the shadowed
// receivers of the first and the receivers where the two differ.
struct SvRunsAgainstPlain {
    ShadowVolumeMask plain, runs;
    int64_t shadowed = 0, differ = 0;
};
SvRunsAgainstPlain svRunsAgainstPlain(const SvFixture& f, const ShadowCasterSet& casters, const Light& light,
                                      const std::vector<uint8_t>& receivers) {
    SvRunsAgainstPlain out;
    ShadowVolumeOptions runs = svOptions(false, false);
    runs.clampRuns = true;
    out.plain =
        computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), svOptions(false, false));
    out.runs = computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), runs);
    for (std::size_t i = 0; i < receivers.size(); ++i) {
        out.shadowed += receivers[i] && out.plain.shadowed[i];
        out.differ += receivers[i] && out.plain.shadowed[i] != out.runs.shadowed[i];
    }
    return out;
}

// Layers: a small ball high over a thin platform that takes half its shadow, the ground far below
// taking the rest. The ball's volume holds receivers on the ball itself, on the platform and on the
// ground: clampRuns leaves out the empty depth between them (two gaps, each longer than twice the
// volume's width), with the same shadow as the whole volume and fewer fragments.
TEST(ShadowVolumeTest, ClampRunsLeavesOutTheEmptyDepthBetweenReceivers) {
    Scene s;
    s.addMaterial(Material{});
    SceneMesh ground, platform;
    ground.name = "ground";
    test::appendQuad(ground.mesh, {0, 0, 0}, {0, 0, 5}, {5, 0, 0});
    ground.castsShadow = false;
    platform.name = "platform";
    test::appendQuad(platform.mesh, {-1.0, 2.0, 0}, {0, 0, 1.5}, {1.0, 0, 0});
    platform.castsShadow = false;
    s.meshes.push_back(ground);
    s.meshes.push_back(platform);
    svAddCaster(s, "ball", test::makeUvSphere({0, 4.5, 0}, 0.25, 16, 24));
    const SvFixture f = svFixture(s, svCamera({2.5, 6.5, 6.0}, {0, 1.2, 0}), 128, 96);
    const ShadowCasterSet casters = ShadowCasterSet::build(f.scene);
    for (const Light& light : {svPointLight({0.05, 9, 0.03}), svSun({0.02, -1, 0.01})}) {
        SCOPED_TRACE(light.name);
        const std::vector<uint8_t> receivers =
            shadowVolumeReceivers(f.gbuffer, f.geometry, f.scene.materials, light);
        ShadowVolumeOptions far = svOptions(false, false);
        far.clamp = true;
        const SvRunsAgainstPlain both = svRunsAgainstPlain(f, casters, light, receivers);
        const ShadowVolumeMask &plain = both.plain, &r = both.runs;
        const ShadowVolumeMask fa =
            computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), far);
        const int64_t shadowed = both.shadowed, differ = both.differ;
        const SvComparison c = svCompare(f, receivers, plain.shadowed, svRayTraced(f, light));
        std::cout << "[ shadow ] " << light.name << ": " << shadowed << " shadowed receivers, fragments none "
                  << plain.stats.fragments << ", clampRuns " << r.stats.fragments << " (" << r.stats.gaps
                  << " gaps, " << r.stats.nearClamped << " near ends), volumeClamping " << fa.stats.fragments
                  << "\n";
        EXPECT_EQ(c.offSilhouette, 0);
        EXPECT_GT(shadowed, 15);
        EXPECT_EQ(differ, 0);
        EXPECT_GE(r.stats.gaps, 1);
        EXPECT_LT(r.stats.fragments, plain.stats.fragments);
    }
}

// The near end (#37 item 5): a ball high over the ground (the light far above it, so that the
// empty depth between them is worth leaving out), seen only from its lit side, has no
// receiver near it, so clampRuns starts its volume just over the ground, behind the caster, and
// caps it there. Two cameras: one from the side, outside the volume (depth-pass: the piece's near
// cap must be drawn, though it is not on the caster), one under the ball looking down, inside the
// unclamped volume, whose near end (at the ball) lies behind the camera's near plane (depth-fail).
// Each time the clamped volume has a near end, the same shadow as the whole volume and the
// ray-traced one off silhouettes, and fewer fragments.
TEST(ShadowVolumeTest, NearEndClampingStartsTheVolumeAtItsReceiversAndKeepsTheShadow) {
    Scene s;
    s.addMaterial(Material{});
    SceneMesh ground;
    ground.name = "ground";
    test::appendQuad(ground.mesh, {0, 0, 0}, {0, 0, 5}, {5, 0, 0});
    ground.castsShadow = false;
    s.meshes.push_back(ground);
    svAddCaster(s, "ball", test::makeUvSphere({0, 4.5, 0}, 0.5, 16, 24));
    const Camera cameras[] = {svCamera({4.0, 5.5, 5.0}, {0, 0.5, 0}),
                              svCamera({0.05, 3.0, 0.02}, {0.4, 0, 0.3})};
    for (const Camera& camera : cameras) {
        const bool inside = &camera == &cameras[1];
        const SvFixture f = svFixture(s, camera, 96, 72);
        const ShadowCasterSet casters = ShadowCasterSet::build(f.scene);
        for (const Light& light : {svPointLight({0.05, 20, 0.03}), svSun({0.02, -1, 0.01})}) {
            SCOPED_TRACE(light.name + (inside ? ", inside" : ", outside"));
            const std::vector<uint8_t> receivers =
                shadowVolumeReceivers(f.gbuffer, f.geometry, f.scene.materials, light);
            const SvRunsAgainstPlain both = svRunsAgainstPlain(f, casters, light, receivers);
            const ShadowVolumeMask &plain = both.plain, &r = both.runs;
            const int64_t shadowed = both.shadowed, differ = both.differ;
            const SvComparison c = svCompare(f, receivers, r.shadowed, svRayTraced(f, light));
            std::cout << "[ shadow ] " << light.name << (inside ? " inside" : " outside") << ": " << shadowed
                      << " shadowed receivers, " << r.stats.nearClamped << " near ends, depth-pass "
                      << r.stats.depthPass << ", fragments " << plain.stats.fragments << " -> "
                      << r.stats.fragments << "\n";
            EXPECT_EQ(r.stats.nearClamped, 1);
            EXPECT_EQ(r.stats.depthPass, inside ? 0 : 1);
            EXPECT_GT(shadowed, 40);
            EXPECT_EQ(differ, 0);
            EXPECT_EQ(c.offSilhouette, 0);
            EXPECT_LT(r.stats.fragments, plain.stats.fragments);
        }
    }
}

TEST(ShadowVolumeTest, RendererDrawsVolumeShadowsAndCullingDoesNotChangeTheImage) {
    Scene scene = svScene();
    scene.lights = {svPointLight({0.5, 5, 1.5}), svSun({0.3, -1, 0.2})};
    scene.cameras = {svCamera({0.5, 4.5, 6.5}, {0, 0.6, 0})};
    RenderOptions o;
    o.width = 80;
    o.height = 60;
    o.shadow = ShadowVolumeOptions{};
    const RenderResult with = render(scene, scene.cameras[0], o);
    setRenderOption(o, "volumeCulling", false);
    const RenderResult without = render(scene, scene.cameras[0], o);
    o.shadow = NoShadowOptions{};
    const RenderResult none = render(scene, scene.cameras[0], o);
    int64_t differ = 0, darker = 0;
    for (int64_t y = 0; y < 60; ++y)
        for (int64_t x = 0; x < 80; ++x) {
            differ += !(with.image.at(x, y) == without.image.at(x, y));
            darker += with.image.at(x, y).x < none.image.at(x, y).x;
        }
    EXPECT_EQ(differ, 0);
    EXPECT_GT(darker, 50);
    EXPECT_GT(std::get<ShadowVolumeStats>(without.shadowStats).fragments,
              std::get<ShadowVolumeStats>(with.shadowStats).fragments);
    EXPECT_TRUE(std::holds_alternative<ShadowVolumeOptions>(shadowOptionsNamed("volumes")));
    // Built but not prepared with a G-buffer (what the renderer does), nothing is counted: lit.
    const LightShadow unprepared = buildLightShadow(scene, scene.lights[0], ShadowVolumeOptions{});
    EXPECT_EQ(shadowVisibility(unprepared, {0, 0, 0}, {0, 1, 0}), (Vec3f{1, 1, 1}));
}

// A blended (see-through) quad half in a floating box's shadow, over a ground whose own shadow lies
// elsewhere on screen: the quad's pixels must take the quad's shadow, not the ground's behind it.
// The ground and box are black, so a pixel on the quad is the quad's shading alone: equal to the
// exact tracer's wherever the visibility is.
TEST(ShadowVolumeTest, BlendedSurfacesTakeTheirOwnShadowAsTheExactTracerDoes) {
    Scene s;
    Material black;
    black.baseColor = {0, 0, 0};
    black.specular = 0;
    const uint32_t blackId = s.addMaterial(black);
    Material glassy;
    glassy.baseColor = {0.9f, 0.8f, 0.7f};
    glassy.opacity = 0.5f;
    glassy.blend = true;
    const uint32_t glassyId = s.addMaterial(glassy);
    SceneMesh ground;
    ground.name = "ground";
    test::appendQuad(ground.mesh, {0, 0, 0}, {0, 0, 4}, {4, 0, 0});
    ground.material = blackId;
    ground.castsShadow = false;
    s.meshes.push_back(ground);
    SceneMesh box;
    box.name = "box";
    box.mesh = test::makeBox({-0.5, 1.5, -0.5}, {0.5, 2.5, 0.5});
    box.material = blackId;
    s.meshes.push_back(box);
    SceneMesh quad;
    quad.name = "quad";
    test::appendQuad(quad.mesh, {-0.2, 1.0, 0}, {0, 0, 1.2}, {1.2, 0, 0});
    quad.material = glassyId;
    quad.castsShadow = false;
    s.meshes.push_back(quad);
    s.lights = {svSun({0.4, -1, 0.1})};
    s.cameras = {svCamera({0, 5, 4}, {0, 0.5, 0})};
    RenderOptions o;
    o.width = 80;
    o.height = 60;
    o.background = {0, 0, 0};
    o.exposure = 1; // fixed: the renders are compared pixel by pixel
    o.shadow = ExactShadowOptions{};
    const RenderResult exact = render(s, s.cameras[0], o);
    o.shadow = NoShadowOptions{};
    const RenderResult lit = render(s, s.cameras[0], o);
    o.shadow = ShadowVolumeOptions{};
    const RenderResult volumes = render(s, s.cameras[0], o);
    int64_t shadowedOnQuad = 0, litOnQuad = 0, differ = 0;
    for (std::size_t i = 0; i < exact.image.pixels.size(); ++i) {
        const Vec3f e = exact.image.pixels[i], v = volumes.image.pixels[i], l = lit.image.pixels[i];
        if (!(l.x > 0.05f)) continue; // not on the quad (the rest is black)
        (e.x < l.x - 0.05f ? shadowedOnQuad : litOnQuad) += 1;
        differ += std::abs(e.x - v.x) > 1e-5f || std::abs(e.y - v.y) > 1e-5f || std::abs(e.z - v.z) > 1e-5f;
    }
    EXPECT_GT(shadowedOnQuad, 50);
    EXPECT_GT(litOnQuad, 100);
    EXPECT_EQ(differ, 0);
}

// A see-through (blended) caster is not in the G-buffer: the camera sees the ground through it, and
// those eye rays enter its volume through the near cap, which depth-pass counting left out (#37 item
// 5). A blended torus over the ground, camera and light on the same side (depth-pass): the mask at
// every receiver, the ground behind the torus included, is the ray-traced hard shadow off
// silhouettes.
TEST(ShadowVolumeTest, ReceiversSeenThroughABlendedCasterTakeTheRayTracedShadow) {
    Scene s;
    s.addMaterial(Material{});
    Material see;
    see.opacity = 0.45f;
    see.blend = true;
    const uint32_t seeId = s.addMaterial(see);
    SceneMesh ground;
    ground.name = "ground";
    test::appendQuad(ground.mesh, {0, 0, 0}, {0, 0, 5}, {5, 0, 0});
    ground.castsShadow = false;
    s.meshes.push_back(ground);
    svAddCaster(s, "torus", test::makeTorus({0, 1.0, 0}, 0.6, 0.2, 32, 12));
    s.meshes.back().material = seeId;
    const SvFixture f = svFixture(s, svCamera({1.5, 4.5, 3.5}, {0, 0.3, 0}), 96, 72);
    const ShadowCasterSet casters = ShadowCasterSet::build(f.scene);
    for (const Light& light : {svPointLight({-1.0, 5, 2.0}), svSun({0.3, -1, -0.4})}) {
        SCOPED_TRACE(light.name);
        const std::vector<uint8_t> receivers =
            shadowVolumeReceivers(f.gbuffer, f.geometry, f.scene.materials, light);
        const ShadowVolumeMask mask = computeShadowVolumes(casters, light, f.gbuffer, receivers,
                                                           f.scene.bounds(), svOptions(true, true));
        const SvComparison c = svCompare(f, receivers, mask.shadowed, svRayTraced(f, light));
        std::cout << "[ shadow ] blended torus, " << light.name << ": " << c.shadowed << " shadowed of "
                  << c.receivers << ", " << c.offSilhouette << " wrong off silhouettes, depth-pass "
                  << mask.stats.depthPass << "\n";
        EXPECT_EQ(mask.stats.depthPass, 1);
        EXPECT_GT(c.shadowed, 40);
        EXPECT_EQ(c.offSilhouette, 0);
    }
}

// The DSM demo's blended knot (examples/dsm-demo/scene.json: knot1.off, opacity 0.45, under its
// spot light, over a ground that only receives), volumes against map: both draw every caster as
// opaque, so the knot's pixels (its surfaces and the ground seen through them) must agree but for
// shadow edges (PCF). Without the see-through caster's near cap a third of them came out more than
// 30 levels (of 255) darker: black patches of ground seen through the knot.
TEST(ShadowVolumeTest, BlendedKnotIsNoDarkerUnderVolumesThanUnderAShadowMap) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    // The demo's scene file less its bunny and volumes, and its render settings (flat dark sky,
    // no sky light, a little constant ambient).
    test::TempDir dir;
    const std::string meshes = test::dataPath("meshes");
    test::writeFile(dir.file("knot.json"), R"({"meshes": [
        {"file": ")" + meshes + R"(/cube.off", "name": "Ground", "scale": [3, 0.05, 3],
         "translate": [0, -0.05, 0], "material": {"baseColor": [0.6, 0.6, 0.55], "specular": 0}},
        {"file": ")" + meshes + R"(/knot1.off", "name": "knot", "scale": 0.9, "translate": [-1.0, 0.55, 0.9],
         "material": {"baseColor": [0.3, 0.6, 0.9], "opacity": 0.45}}],
      "receiversOnly": ["Ground"],
      "lights": [{"type": "spot", "position": [-2.5, 4.0, 1.5], "target": [0.2, 0.4, -0.3],
                  "intensity": 40, "innerConeDegrees": 30, "outerConeDegrees": 42}],
      "cameras": [{"position": [0.3, 3.0, 5.2], "target": [0, 0.6, -0.2], "fovYDegrees": 40}],
      "render": {"ambient": [0.08, 0.08, 0.1], "skyLight": 0, "sky": "flat", "background": [0.15, 0.16, 0.2]}})");
    const Scene s = loadScene(dir.file("knot.json"));
    auto image = [&](const Scene& scene, const char* shadows) {
        RenderOptions o = renderOptionsFor(scene, shadows);
        o.width = 160;
        o.height = 120;
        o.antiAliasing = AntiAliasing::Off;
        return render(scene, scene.cameras.at(0), o).image;
    };
    Scene bare = s;
    bare.meshes.pop_back();
    const Image unshadowed = image(s, "none"), without = image(bare, "none");
    const Image map = image(s, "map"), volumes = image(s, "volumes");
    int64_t knotPixels = 0, darker = 0;
    auto level = [](const Vec3f& c) { return 255 * (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z); };
    for (std::size_t i = 0; i < map.pixels.size(); ++i) {
        if (unshadowed.pixels[i] == without.pixels[i]) continue; // not on the knot
        ++knotPixels;
        darker += level(volumes.pixels[i]) < level(map.pixels[i]) - 30;
    }
    std::cout << "[ shadow ] blended knot: " << knotPixels << " knot pixels, " << darker
              << " more than 30 levels darker under volumes than under map\n";
    EXPECT_GT(knotPixels, 300);
    EXPECT_LE(darker, knotPixels / 50);
}

// CGAL meshes as casters over a ground plane: exact against the ray tracer, unchanged by culling.
TEST(ShadowVolumeTest, CgalMeshCastersMatchRayTracingAndCulling) {
    const std::string path = test::dataPath("meshes/elephant.off");
    if (!std::filesystem::exists(path)) {
        if (test::dataRequired()) FAIL() << test::missingData("meshes/elephant.off");
        GTEST_SKIP() << test::missingData("meshes/elephant.off");
    }
    Scene scene = svScene();
    Mesh elephant = loadMesh(path);
    const Box3d b = computeBounds(elephant.view());
    const double k = 1.2 / std::max({b.extent().x, b.extent().y, b.extent().z});
    for (Vec3f& p : elephant.positions)
        p = Vec3f((Vec3d(p) - Vec3d{b.center().x, b.lo.y, b.center().z}) * k + Vec3d{-0.6, 0.0, 1.4});
    svAddCaster(scene, "elephant", std::move(elephant));
    const SvFixture f = svFixture(std::move(scene), svCamera({0.5, 4.0, 6.5}, {0, 0.6, 0.5}), 72, 54);
    const ShadowCasterSet casters = ShadowCasterSet::build(f.scene);
    const Light light = svPointLight({-2.0, 4.5, 3.5});
    const std::vector<uint8_t> receivers =
        shadowVolumeReceivers(f.gbuffer, f.geometry, f.scene.materials, light);
    const ShadowVolumeMask plain =
        computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), svOptions(false, false));
    const ShadowVolumeMask both =
        computeShadowVolumes(casters, light, f.gbuffer, receivers, f.scene.bounds(), svOptions(true, true));
    const SvComparison c = svCompare(f, receivers, plain.shadowed, svRayTraced(f, light));
    std::cout << "[ shadow ] elephant: " << c.receivers << " receivers, " << c.shadowed << " shadowed, "
              << c.mismatches << " mismatches among " << c.silhouettePixels << " silhouette pixels\n";
    EXPECT_EQ(c.offSilhouette, 0);
    EXPECT_LE(c.mismatches * 10, c.silhouettePixels + 10);
    int64_t diff = 0;
    for (std::size_t i = 0; i < receivers.size(); ++i)
        diff += receivers[i] && plain.shadowed[i] != both.shadowed[i];
    EXPECT_EQ(diff, 0);
}

// The foliage-free demo scenes: the image with culling and clamping is the image without.
void svExpectDemoUnchangedByCulling(Scene scene) {
    const Camera camera = scene.cameras.at(0);
    RenderOptions o;
    o.width = 96;
    o.height = 54;
    o.shadow = ShadowVolumeOptions{};
    const RenderResult with = render(scene, camera, o);
    setRenderOption(o, "volumeCulling", false);
    const RenderResult without = render(scene, camera, o);
    int64_t differ = 0;
    for (int64_t y = 0; y < o.height; ++y)
        for (int64_t x = 0; x < o.width; ++x) differ += !(with.image.at(x, y) == without.image.at(x, y));
    EXPECT_EQ(differ, 0);
    const int64_t withFragments = std::get<ShadowVolumeStats>(with.shadowStats).fragments;
    const int64_t withoutFragments = std::get<ShadowVolumeStats>(without.shadowStats).fragments;
    EXPECT_GT(withoutFragments, 0);
    EXPECT_LE(withFragments, withoutFragments);
}

TEST(ShadowVolumeTest, FoliageFreeTreeDemoRendersTheSameWithAndWithoutCulling) {
    TreeOptions t;
    t.leaves = 0;
    svExpectDemoUnchangedByCulling(makeTreeScene(t));
}

TEST(ShadowVolumeTest, FoliageFreeMeshDemosRenderTheSameWithAndWithoutCullingSlow) {
    const std::string dir = test::dataPath("meshes");
    if (!std::filesystem::exists(dir + "/bunny00.off")) {
        if (test::dataRequired()) FAIL() << test::missingData("meshes/bunny00.off");
        GTEST_SKIP() << test::missingData("meshes/bunny00.off");
    }
    svExpectDemoUnchangedByCulling(makeBunnyScene(dir, 0));
    svExpectDemoUnchangedByCulling(makeCgalScene(dir, 0));
}

} // namespace
} // namespace voxfx
