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
#include "test_util.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::glassTestScene;

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

} // namespace
} // namespace voxfx
