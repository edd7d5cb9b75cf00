// Tests of exact shadows (src/render/exact_shadow.cpp, voxfx/exact_shadow.hpp, technique "exact"):
// the transmittances of every crossing multiplied; glass as Fresnel times the tint times
// Beer–Lambert (closed form), a glass ball's coloured shadow; volumes in closed form (a uniform
// volume, and a Boolean hole in it) and against the independent dense march of
// tests/support/volume_reference.hpp on a mixed Boolean scene.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "support/glass_scenes.hpp"
#include "support/shadow_reference.hpp"
#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::dsmrMixedScene;
using test::dsmrReferenceTransmittance;
using test::dsmrSpot;
using test::glassTestScene;
using test::pointLight;

TEST(GlassTest, ExactShadowMultipliesTheTransmittancesOfEveryCrossing) {
    // Two leaves above the origin (z = 1 and z = 2) and an opaque one off to the side.
    Mesh m;
    test::appendQuad(m, {0, 0, 1}, {1, 0, 0}, {0, 1, 0});
    test::appendQuad(m, {0, 0, 2}, {1, 0, 0}, {0, 1, 0});
    test::appendQuad(m, {5, 0, 1}, {1, 0, 0}, {0, 1, 0});
    const Vec3f a{0.5f, 0.4f, 0.3f}, b{0.5f, 0.5f, 1.0f};
    ExactShadow shadow(m.view(), {a, a, b, b, {0, 0, 0}, {0, 0, 0}});
    const Vec3f both =
        shadow.transmittance({0.1, 0.2, 0}, {0, 0, 1}, std::numeric_limits<double>::infinity());
    EXPECT_NEAR(both.x, 0.25f, 1e-6f);
    EXPECT_NEAR(both.y, 0.2f, 1e-6f);
    EXPECT_NEAR(both.z, 0.3f, 1e-6f);
    EXPECT_EQ(shadow.transmittance({0.1, 0.2, 0}, {0, 0, 1}, 1.5), a); // a point light between the leaves
    EXPECT_EQ(shadow.transmittance({5, 0, 0}, {0, 0, 1}, 10), (Vec3f{0, 0, 0}));
    EXPECT_EQ(shadow.transmittance({9, 9, 0}, {0, 0, 1}, 10), (Vec3f{1, 1, 1}));
}

TEST(GlassTest, ExactShadowThroughGlassIsFresnelTimesBeerLambert) {
    // A glass slab z in [1, 1.4] (a closed box, outward faces) between the origin and the light
    // along +z, from a material: transmission 1, ior 1.5, half the red light left after 0.5 units.
    // Closed form: per crossing the Fresnel transmittance 1 - F (Fresnel's equations for the angle
    // in air), once the tint (base colour), and exp(-sigma * L / cos) inside.
    const Mesh slab = test::makeBox({-5, -5, 1}, {5, 5, 1.4});
    Material glass;
    glass.transmission = 1;
    glass.ior = 1.5f;
    glass.baseColor = {1.0f, 0.8f, 1.0f};
    glass.attenuationColor = {0.5f, 1.0f, 1.0f};
    glass.attenuationDistance = 0.5f;
    const std::vector<Material> materials{glass};
    const std::vector<uint32_t> triangleMaterial(slab.triangleCount(), 0);
    const ExactShadow shadow = ExactShadow::fromMaterials(slab.view(), triangleMaterial, materials);
    const double n = 1.5, sigmaRed = std::log(2.0) / 0.5;
    for (const double thetaDeg : {0.0, 30.0, 60.0}) {
        const double th = thetaDeg * M_PI / 180, ci = std::cos(th), st = std::sin(th) / n;
        const double ct = std::sqrt(1 - st * st);
        const double rs = (ci - n * ct) / (ci + n * ct), rp = (n * ci - ct) / (n * ci + ct);
        const double T = 1 - 0.5 * (rs * rs + rp * rp);
        const Vec3d dir{std::sin(th), 0, ci};
        const Vec3f v = shadow.transmittance({0.1, 0.2, 0}, dir, std::numeric_limits<double>::infinity());
        EXPECT_NEAR(v.x, T * T * std::exp(-sigmaRed * 0.4 / ci), 1e-5) << thetaDeg;
        EXPECT_NEAR(v.y, T * T * 0.8, 1e-5) << thetaDeg;
        EXPECT_NEAR(v.z, T * T, 1e-5) << thetaDeg;
        // From inside the slab (0.1 below its top): one crossing and the length up to it.
        const Vec3f in = shadow.transmittance({0.1, 0.2, 1.3}, dir, std::numeric_limits<double>::infinity());
        EXPECT_NEAR(in.x, T * std::exp(-sigmaRed * 0.1 / ci), 1e-5) << thetaDeg;
        EXPECT_NEAR(in.z, T, 1e-5) << thetaDeg;
    }
    // Normal incidence: (1 - R0)^2 with R0 = ((n - 1) / (n + 1))^2 = 0.04, the classic 92 %.
    const Vec3f straight = shadow.transmittance({0, 0, 0}, {0, 0, 1}, 10);
    EXPECT_NEAR(straight.z, 0.96 * 0.96, 1e-6);
    // A light inside the glass: attenuated up to the light only.
    const Vec3f toInside = shadow.transmittance({0, 0, 0}, {0, 0, 1}, 1.2);
    EXPECT_NEAR(toInside.x, 0.96 * std::exp(-sigmaRed * 0.2), 1e-5);
    // Leaves (no transmission) keep their per-crossing transmittance.
    Material leaf;
    leaf.opacity = 0.5f;
    const std::vector<Material> leaves{leaf};
    const ExactShadow sheet = ExactShadow::fromMaterials(slab.view(), triangleMaterial, leaves);
    EXPECT_NEAR(sheet.transmittance({0, 0, 0}, {0, 0, 1}, 10).x, 0.25, 1e-6);
}

TEST(GlassTest, GlassBallCastsAColouredShadowUnderExactShadows) {
    // The sun straight above the glass ball of glassTestScene (radius 0.7): the ground point under
    // its centre sees the light through a diameter (1.4 units) at nearly normal incidence, so the
    // light left is tint (1 - 0.04)^2 exp(-sigma * 1.4), sigma = -ln(attenuationColor) (distance 1). Off to
    // the side the light is not dimmed. defaultGlass renders such a scene as glass.
    const Scene s = glassTestScene();
    EXPECT_TRUE(std::holds_alternative<ExactGlassOptions>(defaultGlass(s)));
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0, -1, 0};
    const LightShadow shadow = buildLightShadow(s, sun, ExactShadowOptions{});
    // Just off the axis (a UV sphere's pole is a vertex): chord 2 sqrt(0.49 - 0.0034), incidence 3
    // degrees from normal (F changes by under 1e-4).
    const Vec3f under = shadowVisibility(shadow, {0.05, 0, 0.03}, {0, 1, 0});
    // The tint (the base colour, 0.8 by default) once where the light enters.
    const Vec3f tint = s.materials[1].baseColor;
    const double fresnel = 0.96 * 0.96, chord = 2 * std::sqrt(0.49 - 0.0034);
    EXPECT_NEAR(under.x, tint.x * fresnel * std::exp(std::log(0.5) * chord), 0.005);
    EXPECT_NEAR(under.y, tint.y * fresnel * std::exp(std::log(0.9) * chord), 0.005);
    EXPECT_NEAR(under.z, tint.z * fresnel * std::exp(std::log(0.6) * chord), 0.005);
    const Vec3f beside = shadowVisibility(shadow, {1.2, 0, 0}, {0, 1, 0});
    EXPECT_EQ(beside, (Vec3f{1, 1, 1}));
    Scene plain = s;
    plain.materials[1].transmission = 0;
    EXPECT_TRUE(std::holds_alternative<NoGlassOptions>(defaultGlass(plain)));
}

// ---- Through the volume scene --------------------------------------------------------------------

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
    const ExactShadow sun = ExactShadow::build(box, test::sun(slant), {});
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
    const ExactShadow point = ExactShadow::build(box, pointLight(lamp), {});
    for (const Vec3d p : {Vec3d{0, 0, 0}, Vec3d{0.6, 0, -0.4}, Vec3d{-0.9, 0, 0.9}})
        EXPECT_NEAR(point.visibility(p, {0, 1, 0}).z, std::exp(-sigma * length(lamp - p) / 3), tol);
    // A light inside the volume: the chord from the bottom face up to the light.
    const Vec3d inside{0, 1.0, 0};
    const ExactShadow buried = ExactShadow::build(box, pointLight(inside), {});
    for (const Vec3d p : {Vec3d{0.2, 0, 0.1}, Vec3d{-0.3, 0, 0.3}})
        EXPECT_NEAR(buried.visibility(p, {0, 1, 0}).x, std::exp(-sigma * length(inside - p) / 2), tol);
    // The Boolean: straight down through the hole the chord is 1 - 0.6, beside it 1.
    const ExactShadow holed = ExactShadow::build(exvUniformBox(true), test::sun({0, -1, 0}), {});
    for (const double x : {-0.9, -0.6, -0.4, -0.2, 0.0, 0.2, 0.4, 0.6, 0.9}) {
        const bool underHole = std::abs(x) < 0.3;
        EXPECT_NEAR(holed.visibility({x, 0, 0.05}, {0, 1, 0}).x, std::exp(-sigma * (underHole ? 0.4 : 1.0)),
                    tol)
            << x;
    }
    // The step is checked where it is given.
    ExactShadowOptions bad;
    bad.volumeStep = 0;
    EXPECT_THROW(ExactShadow::build(box, test::sun(slant), bad), Error);
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

} // namespace
} // namespace voxfx
