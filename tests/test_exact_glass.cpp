// Tests of the exact glass tracer (Embree: src/render/exact_glass.cpp, voxfx/exact_glass.hpp, glass
// method "exact") against closed-form refracted rays: parallel slabs, a flattened cube, a sphere, a
// prism's total internal reflection, a sheet thinner than the tracer's epsilon; and a glass cube
// standing on the ground that must show the ground, not the sky, through its top.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "support/glass_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/exact_glass.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/render.hpp"

namespace voxfx {
namespace {

using test::glassCubeOnTheGround;
using test::glassDirAt;
using test::kGlassIor;
using test::TopPixels;

// A slab |z| <= h/2, wide in x and y.
Mesh glassSlab(double h, double z0 = 0) {
    return test::makeBox({-20, -20, z0 - h / 2}, {20, 20, z0 + h / 2});
}

// Closed form: a ray at angle a crosses a slab of thickness h: inside length h / cos(theta_t),
// exits parallel to its entry, with throughput (1 - F_in)(1 - F_out) exp(-sigma L).
TEST(GlassTest, ExactTracerExitsAParallelSlabParallelAndAttenuatedByTheTrueLength) {
    const double h = 0.5, sigma = 0.8;
    const Mesh slab = glassSlab(h);
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    medium.sigma = {float(sigma), float(sigma), float(sigma)};
    ExactGlass glass(slab.view(), {}, std::vector<uint32_t>(slab.triangleCount(), 0), {medium});
    for (const double a : {0.0, 0.3, 0.7, 1.2}) {
        const Vec3d d = glassDirAt(a);
        const Vec3d origin = Vec3d{0.123, 0.05, 3} - d * 0.0;
        const GlassPath p = glass.trace(origin, d, 16);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 2);
        EXPECT_NEAR(length(p.exitDir - d), 0, 1e-5) << a;
        const double tt = std::asin(std::sin(a) / kGlassIor);
        const double L = h / std::cos(tt);
        const double F = fresnelDielectric(std::cos(a), 1, kGlassIor);
        const double Fout = fresnelDielectric(std::cos(tt), kGlassIor, 1);
        EXPECT_NEAR(p.reflectance, F, 1e-5);
        EXPECT_NEAR(p.throughput.x, (1 - F) * (1 - Fout) * std::exp(-sigma * L), 1e-4) << a;
        // Lateral shift of the exit point against the straight line: h sin(a - tt) / cos(tt).
        const double tIn = (origin.z - h / 2) / -d.z;
        const Vec3d entry = origin + d * tIn;
        const Vec3d exitPoint = entry + Vec3d{std::sin(tt), 0, -std::cos(tt)} * L;
        EXPECT_NEAR(length(p.exitPoint - exitPoint), 0, 1e-4) << a;
    }
}

// A cube whose corners are shared by three faces (8 vertices, as the demos' boxes are), flattened as
// the renderer does: its normals are split at the 90-degree creases, so the exact tracer sees flat
// faces and the cube acts on a straight view ray as a slab (closed form above): parallel exit,
// lateral shift h sin(a - tt) / cos(tt). Averaged corner normals bent it like a lens.
TEST(GlassTest, ExactTracerSeesAFlattenedCubeWithSharedCornersAsASlab) {
    Scene s;
    Material glass;
    glass.transmission = 1;
    glass.ior = float(kGlassIor);
    SceneMesh cube;
    cube.mesh = test::makeBox({-1, -1, -1}, {1, 1, 1});
    ASSERT_EQ(cube.mesh.positions.size(), 8u);
    cube.material = s.addMaterial(glass);
    s.meshes.push_back(cube);
    const SceneGeometry geo = flattenScene(s);
    ExactGlass exact(geo.mesh.view(), geo.normals, std::vector<uint32_t>(geo.mesh.triangleCount(), 0),
                     {glassMedium(glass)});
    const double h = 2;
    for (const double a : {0.2, 0.5}) {
        for (const Vec3d entry : {Vec3d{-0.3, 0.2, 1}, Vec3d{-0.7, -0.6, 1}, Vec3d{0.1, 0.55, 1}}) {
            const Vec3d d = glassDirAt(a);
            const GlassPath p = exact.trace(entry - d * 2, d, 16);
            ASSERT_TRUE(p.hit);
            EXPECT_EQ(p.events, 2);
            EXPECT_NEAR(length(p.exitDir - d), 0, 1e-5) << a;
            const double tt = std::asin(std::sin(a) / kGlassIor);
            const Vec3d exitPoint = entry + Vec3d{std::sin(tt), 0, -std::cos(tt)} * (h / std::cos(tt));
            EXPECT_NEAR(length(p.exitPoint - exitPoint), 0, 1e-4) << a << " " << entry.x << " " << entry.y;
        }
    }
}

TEST(GlassTest, ExactTracerMatchesTheClosedFormRayThroughASphere) {
    // A finely tessellated unit sphere with its exact normals per vertex.
    const double R = 1;
    const Mesh sphere = test::makeUvSphere({0, 0, 0}, R, 255, 512); // odd: no ring on the equator
    std::vector<Vec3f> normals;
    for (const Vec3f& p : sphere.positions) normals.push_back(Vec3f(normalize(Vec3d(p))));
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    medium.sigma = {0.5f, 0.5f, 0.5f};
    ExactGlass glass(sphere.view(), normals, std::vector<uint32_t>(sphere.triangleCount(), 0), {medium});
    for (const double b : {0.0, 0.2, 0.5, 0.8, 0.95}) {
        // Along -x at height b in the y direction (away from the poles on the z axis).
        const Vec3d d{-1, 0, 0};
        const GlassPath p = glass.trace({5, b, 0}, d, 16);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 2) << b;
        const double ti = std::asin(b / R), tt = std::asin(std::sin(ti) / kGlassIor);
        const double deviation = 2 * (ti - tt); // turned towards the centre (-y for b > 0)
        const Vec3d want{-std::cos(deviation), -std::sin(deviation), 0};
        EXPECT_NEAR(length(p.exitDir - want), 0, 3e-3) << b;
        const double chord = 2 * R * std::cos(tt);
        const double F = fresnelDielectric(std::cos(ti), 1, kGlassIor);
        const double Fout = fresnelDielectric(std::cos(tt), kGlassIor, 1);
        EXPECT_NEAR(p.throughput.x, (1 - F) * (1 - Fout) * std::exp(-0.5 * chord), 3e-3) << b;
        EXPECT_NEAR(length(p.exitPoint), R, 1e-3);
    }
}

TEST(GlassTest, ExactTracerReflectsTotallyInsideAPrism) {
    // A right-angle prism (45-45-90) lit normally through its hypotenuse face: the ray hits each leg
    // at 45 degrees > the critical angle (41.8) twice and leaves back through the hypotenuse reversed.
    Mesh prism;
    const float L = 10;
    // Cross-section in x-z: (-1, 0), (1, 0), (0, 1); extruded along y.
    for (const float y : {-L, L})
        for (const Vec3f p : {Vec3f{-1, y, 0}, Vec3f{1, y, 0}, Vec3f{0, y, 1}}) prism.positions.push_back(p);
    prism.indices = {0, 1, 2, 3, 5, 4, 0, 3, 4, 0, 4, 1, 1, 4, 5, 1, 5, 2, 2, 5, 3, 2, 3, 0};
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    ExactGlass glass(prism.view(), {}, std::vector<uint32_t>(prism.triangleCount(), 0), {medium});
    const GlassPath p = glass.trace({0.3, 0.1, -2}, {0, 0, 1}, 16);
    ASSERT_TRUE(p.hit);
    EXPECT_EQ(p.events, 4); // enter, two total reflections, exit
    EXPECT_NEAR(length(p.exitDir - Vec3d{0, 0, -1}), 0, 1e-5);
    EXPECT_NEAR(p.exitPoint.x, -0.3, 1e-4);
}

TEST(GlassTest, ExactTracerCrossesASheetThinnerThanItsEpsilonAsAParallelSlab) {
    // A sheet 2 x 2 and 1.2e-5 thick: the tracer's epsilon (1e-5 of the diagonal, 2.8e-5) is more
    // than the sheet's thickness. Skipping every hit within epsilon of the front face missed the back
    // face: the ray stayed bent inside. Only the surface just crossed is skipped now, so the sheet
    // is a slab (closed form): parallel exit, (1 - F_in)(1 - F_out), two events. The search for the
    // next face starts 1/100 of epsilon past the surface, below the 1/10 of epsilon within which a
    // parallel face counts as the surface itself: a sheet 4e-6 thick (1/7 of epsilon) is a slab too.
    for (const double h : {1.2e-5, 4e-6}) {
        const Mesh sheet = test::makeBox({-1, -1, -h / 2}, {1, 1, h / 2});
        GlassMedium medium;
        medium.ior = float(kGlassIor);
        ExactGlass glass(sheet.view(), {}, std::vector<uint32_t>(sheet.triangleCount(), 0), {medium});
        for (const double a : {0.0, 0.3, 0.9}) {
            const Vec3d d = glassDirAt(a);
            const GlassPath p = glass.trace(Vec3d{0.1, 0.2, 0} - d * 2, d, 16);
            ASSERT_TRUE(p.hit);
            EXPECT_EQ(p.events, 2) << a << " " << h;
            EXPECT_NEAR(length(p.exitDir - d), 0, 1e-5) << a;
            const double tt = std::asin(std::sin(a) / kGlassIor);
            const double want = (1 - fresnelDielectric(std::cos(a), 1, kGlassIor)) *
                                (1 - fresnelDielectric(std::cos(tt), kGlassIor, 1));
            EXPECT_NEAR(p.throughput.x, want, 1e-4) << a;
            EXPECT_NEAR(p.exitPoint.z, -h / 2, 1e-7) << a << " " << h;
        }
    }
}

TEST(GlassTest, ExactGlassStandingOnTheGroundShowsTheGroundNotTheSky) {
    // A glass cube (green tint) standing on a grey ground, seen from above, in a magenta environment. A ray
    // entering the top is within the critical angle of the vertical, so it is totally reflected at
    // the sides and leaves through the bottom into the ground: no pixel of the top sees the
    // environment through the glass, only its Fresnel reflection (a few per cent of magenta over
    // the ground's grey seen through green). (Rays entering a side can be totally reflected at the bottom and
    // leave upwards: those rightly see the sky.) Skipping every opaque hit within epsilon of the exit (the
    // ground under the bottom face) showed the environment below the ground through the top.
    const TopPixels exact = glassCubeOnTheGround(glassOptionsNamed("exact"));
    EXPECT_GT(exact.top, 600);
    EXPECT_EQ(exact.sky, 0) << "of " << exact.top << " pixels of the top";
}

} // namespace
} // namespace voxfx
