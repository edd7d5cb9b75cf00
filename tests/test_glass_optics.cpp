// Tests of src/render/glass_optics.cpp (voxfx/glass_optics.hpp) in closed form: Snell's law and
// total internal reflection, Fresnel at normal incidence, Brewster's angle and grazing, and
// Beer–Lambert attenuation of KHR_materials_volume.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "support/glass_scenes.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {
namespace {

using test::glassDirAt;
using test::kGlassIor;

TEST(GlassTest, SnellBendsByTheSineLawAndReflectsTotallyPastTheCriticalAngle) {
    const Vec3d n{0, 0, 1}; // facing a ray that travels along -z
    for (double a = 0; a < 1.5; a += 0.1) {
        Vec3d t;
        ASSERT_TRUE(refractDirection(glassDirAt(a), n, 1 / kGlassIor, t));
        EXPECT_NEAR(length(t), 1.0, 1e-12);
        EXPECT_NEAR(t.x, std::sin(a) / kGlassIor, 1e-12); // sin(theta_t) = sin(theta_i) / n
        EXPECT_LT(t.z, 0);
        EXPECT_NEAR(t.y, 0, 1e-15);
    }
    const double critical = std::asin(1 / kGlassIor);
    Vec3d t;
    EXPECT_TRUE(refractDirection(glassDirAt(critical - 1e-6), n, kGlassIor, t));
    EXPECT_FALSE(refractDirection(glassDirAt(critical + 1e-6), n, kGlassIor, t));
    const Vec3d r = reflectDirection(glassDirAt(0.3), n);
    EXPECT_NEAR(r.x, std::sin(0.3), 1e-12);
    EXPECT_NEAR(r.z, std::cos(0.3), 1e-12);
}

TEST(GlassTest, FresnelMatchesNormalIncidenceBrewsterAndTotalReflection) {
    const double r0 = (kGlassIor - 1) / (kGlassIor + 1);
    EXPECT_NEAR(fresnelDielectric(1, 1, kGlassIor), r0 * r0, 1e-12);
    EXPECT_NEAR(fresnelDielectric(1, kGlassIor, 1), r0 * r0, 1e-12); // reciprocity at normal incidence
    // Brewster: tan(theta_B) = n, the p-polarized part vanishes: F = rs^2 / 2.
    const double b = std::atan(kGlassIor), tb = std::asin(std::sin(b) / kGlassIor);
    const double rs = std::sin(tb - b) / std::sin(tb + b);
    EXPECT_NEAR(fresnelDielectric(std::cos(b), 1, kGlassIor), rs * rs / 2, 1e-12);
    EXPECT_DOUBLE_EQ(fresnelDielectric(std::cos(1.2), kGlassIor, 1), 1.0);
    EXPECT_NEAR(fresnelDielectric(0, 1, kGlassIor), 1.0, 1e-12); // grazing
}

TEST(GlassTest, AttenuationFollowsBeerLambertOfTheVolumeExtension) {
    Material m;
    m.attenuationColor = {0.5f, 0.25f, 1.0f};
    m.attenuationDistance = 2;
    const Vec3f s = attenuationCoefficient(m);
    // After attenuationDistance the light is attenuationColor: exp(-sigma * 2) = colour.
    const Vec3f t = beerLambert(s, 2.0);
    EXPECT_NEAR(t.x, 0.5f, 1e-6f);
    EXPECT_NEAR(t.y, 0.25f, 1e-6f);
    EXPECT_NEAR(t.z, 1.0f, 1e-6f);
    EXPECT_NEAR(beerLambert(s, 4.0).x, 0.25f, 1e-6f);
    m.attenuationDistance = std::numeric_limits<float>::infinity();
    EXPECT_EQ(attenuationCoefficient(m), (Vec3f{0, 0, 0}));
}

} // namespace
} // namespace voxfx
