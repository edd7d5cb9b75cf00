// Tests of src/render/glass_optics.cpp and glass_trace.cpp: Snell, Fresnel and Beer–Lambert in closed
// form; the exact tracer (Embree) and the voxel march on slabs and a sphere against the closed-form
// refracted rays; the material channel of the attribute voxelization; ED06 frosted glass (at the end).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/attribute_grid.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/frosted_glass.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {
namespace {

using namespace voxfx::demo;

constexpr double kGlassIor = 1.5;

Vec3d glassDirAt(double angle) { return {std::sin(angle), 0, -std::cos(angle)}; } // into -z, tilted to +x

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
    // is a slab (closed form): parallel exit, (1 - F_in)(1 - F_out), two events.
    const double h = 1.2e-5;
    const Mesh sheet = test::makeBox({-1, -1, -h / 2}, {1, 1, h / 2});
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    ExactGlass glass(sheet.view(), {}, std::vector<uint32_t>(sheet.triangleCount(), 0), {medium});
    for (const double a : {0.0, 0.3, 0.9}) {
        const Vec3d d = glassDirAt(a);
        const GlassPath p = glass.trace(Vec3d{0.1, 0.2, 0} - d * 2, d, 16);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 2) << a;
        EXPECT_NEAR(length(p.exitDir - d), 0, 1e-5) << a;
        const double tt = std::asin(std::sin(a) / kGlassIor);
        const double want = (1 - fresnelDielectric(std::cos(a), 1, kGlassIor)) *
                            (1 - fresnelDielectric(std::cos(tt), kGlassIor, 1));
        EXPECT_NEAR(p.throughput.x, want, 1e-4) << a;
        EXPECT_NEAR(p.exitPoint.z, -h / 2, 1e-6) << a;
    }
}

TEST(GlassTest, VoxelMarchThroughASlabExitsParallelLikeTheExactTracer) {
    const double h = 0.5, sigma = 0.8;
    const Mesh slab = test::makeBox({-1, -1, -h / 2}, {1, 1, h / 2});
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    medium.sigma = {float(sigma), float(sigma), float(sigma)};
    VoxelGlassOptions o;
    o.gridResolution = 64;
    for (const bool twoSurface : {false, true}) {
        const char* kind = twoSurface ? "two-surface" : "multi";
        VoxelGlass glass(slab.view(), std::vector<uint32_t>(slab.triangleCount(), 0), {medium}, o);
        const double a = 0.4;
        const Vec3d d = glassDirAt(a);
        const GlassPath p = glass.trace({0.05, 0.02, h / 2}, {0, 0, 1}, 0, d, o, twoSurface);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 2) << kind;
        EXPECT_NEAR(length(p.exitDir - d), 0, 1e-6) << kind;
        const double tt = std::asin(std::sin(a) / kGlassIor), L = h / std::cos(tt);
        const double want = (1 - fresnelDielectric(std::cos(a), 1, kGlassIor)) *
                            (1 - fresnelDielectric(std::cos(tt), kGlassIor, 1)) * std::exp(-sigma * L);
        // The exit is placed mid-voxel: the length is right to about a voxel.
        EXPECT_NEAR(p.throughput.x, want, want * sigma * 2 * glass.voxelSize()) << kind;
    }
}

// #25 item 2, the angle threshold on a thin sheet: a glass sheet a third of a voxel thick has its
// front and back faces in the same voxels, with opposite normals. Both voxel methods must take them
// as two interfaces (in and out: parallel exit, two Fresnel passes, the sheet's attenuation), not
// one surface (a single refraction that leaves the ray bent) or none.
TEST(GlassTest, VoxelMarchCrossesASheetThinnerThanAVoxelAsTwoInterfaces) {
    const double sigma = 2;
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    medium.sigma = {float(sigma), float(sigma), float(sigma)};
    VoxelGlassOptions o;
    o.gridResolution = 64;
    const double voxel = 2.0 / 64, h = voxel / 3;
    const Mesh sheet = test::makeBox({-1, -1, -h / 2}, {1, 1, h / 2});
    for (const bool twoSurface : {false, true}) {
        const char* kind = twoSurface ? "two-surface" : "multi";
        VoxelGlass glass(sheet.view(), std::vector<uint32_t>(sheet.triangleCount(), 0), {medium}, o);
        for (const double a : {0.0, 0.3, 0.7}) {
            const Vec3d d = glassDirAt(a);
            const GlassPath p = glass.trace({0.05, 0.02, h / 2}, {0, 0, 1}, 0, d, o, twoSurface);
            ASSERT_TRUE(p.hit) << kind << " at " << a;
            EXPECT_EQ(p.events, 2) << kind << " at " << a;
            EXPECT_NEAR(length(p.exitDir - d), 0, 1e-6) << kind << " at " << a;
            const double tt = std::asin(std::sin(a) / kGlassIor), L = h / std::cos(tt);
            const double fresnel = (1 - fresnelDielectric(std::cos(a), 1, kGlassIor)) *
                                   (1 - fresnelDielectric(std::cos(tt), kGlassIor, 1));
            // Through less than a voxel: the length is known to about a voxel, so the attenuation
            // lies between none and a voxel's.
            EXPECT_LE(p.throughput.x, fresnel * 1.0001) << kind << " at " << a;
            EXPECT_GE(p.throughput.x, fresnel * std::exp(-sigma * (L + 2 * glass.voxelSize())))
                << kind << " at " << a;
        }
    }
}

// Snell in closed form for the tests below (unit d, unit n facing d, eta = n_from / n_to).
Vec3d snell(const Vec3d& d, const Vec3d& n, double eta) {
    const double c = -dot(d, n);
    return d * eta + n * (eta * c - std::sqrt(1 - eta * eta * (1 - c * c)));
}

// The mean angle between the voxel march's exit direction and the closed-form one through a glass
// sphere (radius 1 at the origin, a fine UV mesh), over parallel rays along -z entering at up to 60
// degrees of incidence: in at p, along the refracted ray to the sphere's far side q, out with the
// normal q. Each ray crosses two interfaces.
double sphereExitError(int64_t res, bool twoSurface) {
    const Mesh sphere = test::makeUvSphere({0, 0, 0}, 1, 64, 128);
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    VoxelGlassOptions o;
    o.gridResolution = res;
    VoxelGlass glass(sphere.view(), std::vector<uint32_t>(sphere.triangleCount(), 0), {medium}, o);
    double sum = 0;
    int n = 0;
    for (double x = -0.85; x <= 0.85; x += 0.05)
        for (double y = -0.85; y <= 0.85; y += 0.05) {
            if (x * x + y * y > 0.85 * 0.85) continue;
            const Vec3d d{0, 0, -1};
            const Vec3d p{x, y, std::sqrt(1 - x * x - y * y)};
            const Vec3d t = snell(d, p, 1 / kGlassIor);
            const Vec3d q = p - t * (2 * dot(p, t)); // the chord's far end: |p + s t| = 1, s = -2 p.t
            const Vec3d want = snell(t, -q, kGlassIor);
            const GlassPath path = glass.trace(p, p, 0, d, o, twoSurface);
            sum += std::acos(std::clamp(dot(path.exitDir, want), -1.0, 1.0));
            ++n;
        }
    return sum / n;
}

TEST(GlassTest, VoxelMarchBendsThroughASphereCloseToTheClosedFormAtTheSubVoxelCrossing) {
    // #26 item 4, the voxel staircase. Refracting with the voxel's own averaged normal (the faces
    // touching it) put the exit direction 0.0226 / 0.0105 rad off the closed form on average at
    // 32³ / 64³ (multi and two-surface alike: one back surface); the normal interpolated at the
    // crossing over the surface's neighbouring voxels: 0.0055 / 0.0048.
    for (const bool twoSurface : {false, true})
        for (const int64_t res : {32, 64}) {
            const double e = sphereExitError(res, twoSurface);
            EXPECT_LT(e, 0.0075) << (twoSurface ? "two-surface " : "multi ") << res << "³";
        }
}

TEST(GlassTest, VoxelMarchRefractsOutOfASphereJustBelowTheCriticalAngle) {
    // #25 item 2. A ray entering a sphere meets its far side at the angle it was refracted to on
    // entry (the chord is symmetric): parallel rays entering at 74.6 / 77.1 degrees leave at 40 /
    // 40.5, 1.8 / 1.3 degrees below the critical angle (41.8 for n = 1.5), so they refract out, as
    // the exact tracer has them. With the normal taken at the first voxel of the far side that the
    // ray meets (inside the surface, where a convex surface's normal is tilted further from the
    // ray) 32 / 16 of these 72 rays each were totally reflected at 32³ (none at 64³); with the
    // normal at the middle of the run of the surface's voxels along the ray, none.
    //
    // Rays oblique to the grid, on coarser grids (the sphere 9 to 11 voxels in radius), leaving at
    // 38 and 40 degrees: before the event moved past voxels the surface touches only at a corner
    // the ray does not pass (the ray going on into unwritten voxels, then the same surface again),
    // 5 / 8 rays of 72 were reflected at 20³, 7 / 14 at 24³, 1 / 1 at 32³.
    const Mesh sphere = test::makeUvSphere({0, 0, 0}, 1, 64, 128);
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    struct Case {
        Vec3d dir;
        std::vector<int64_t> resolutions;
        std::vector<double> degrees;
    };
    const Case cases[] = {{{0, 0, -1}, {32, 64}, {40.0, 40.5}},
                          {normalize(Vec3d{0.37, 0.21, -1}), {20, 24, 32}, {38.0, 40.0}}};
    for (const Case& c : cases)
        for (const int64_t res : c.resolutions) {
            VoxelGlassOptions o;
            o.gridResolution = res;
            VoxelGlass glass(sphere.view(), std::vector<uint32_t>(sphere.triangleCount(), 0), {medium}, o);
            const Vec3d d = c.dir;
            const Vec3d u = normalize(cross(d, std::abs(d.y) < 0.9 ? Vec3d{0, 1, 0} : Vec3d{1, 0, 0}));
            const Vec3d v = cross(d, u);
            for (const double degrees : c.degrees) {
                const double out = degrees * M_PI / 180, in = std::asin(kGlassIor * std::sin(out));
                for (const bool twoSurface : {false, true}) {
                    int reflected = 0;
                    for (int k = 0; k < 72; ++k) {
                        const double phi = (k + 0.5) * 2 * M_PI / 72;
                        // Where the ray enters: at `in` degrees from the sphere's normal there.
                        const Vec3d p =
                            (u * std::cos(phi) + v * std::sin(phi)) * std::sin(in) - d * std::cos(in);
                        const Vec3d t = snell(d, p, 1 / kGlassIor);
                        const Vec3d q = p - t * (2 * dot(p, t)); // where the ray leaves (as sphereExitError)
                        const GlassPath path = glass.trace(p, p, 0, d, o, twoSurface);
                        // Refracted out: two events, leaving away from the sphere (a total reflection
                        // turns it back inside; two-surface stops there with two events).
                        reflected += path.events != 2 || dot(path.exitDir, q) <= 0;
                    }
                    EXPECT_EQ(reflected, 0)
                        << (twoSurface ? "two-surface " : "multi ") << res << "³, direction (" << d.x << " "
                        << d.y << " " << d.z << "), leaving at " << degrees << " degrees: of 72 rays";
                }
            }
        }
}

// The right-angle prism of ExactTracerReflectsTotallyInsideAPrism (45-45-90, extruded along y), 2 long.
Mesh rightPrism() {
    Mesh prism;
    const float L = 1;
    for (const float y : {-L, L})
        for (const Vec3f p : {Vec3f{-1, y, 0}, Vec3f{1, y, 0}, Vec3f{0, y, 1}}) prism.positions.push_back(p);
    prism.indices = {0, 1, 2, 3, 5, 4, 0, 3, 4, 0, 4, 1, 1, 4, 5, 1, 5, 2, 2, 5, 3, 2, 3, 0};
    return prism;
}

TEST(GlassTest, MultiReflectsTotallyInsideAPrismAtTheCriticalAngle) {
    // CHANG §4.1.1 on the voxel path. Snell: a ray inside glass of index n meeting a face at more
    // than asin(1 / n) is totally reflected. Lit normally through the prism's hypotenuse, the ray
    // meets each leg at 45 degrees: above the critical angle for n = 1.5 (41.8), so it is reflected
    // at both legs and leaves back through the hypotenuse reversed, at -x (closed form, as the exact
    // tracer); below it for n = 1.3 (50.3), so it leaves through the first leg, bent away from
    // the normal by asin(1.3 sin 45) - 45 degrees.
    const Mesh prism = rightPrism();
    VoxelGlassOptions o;
    o.gridResolution = 64; // 2 / 62 per voxel
    for (const double ior : {1.5, 1.3}) {
        GlassMedium medium;
        medium.ior = float(ior);
        const bool tir = std::asin(1 / ior) < M_PI / 4;
        VoxelGlass glass(prism.view(), std::vector<uint32_t>(prism.triangleCount(), 0), {medium}, o);
        const GlassPath p = glass.trace({0.3, 0.1, 0}, {0, 0, -1}, 0, {0, 0, 1}, o, false);
        ASSERT_TRUE(p.hit);
        if (tir) {
            EXPECT_EQ(p.events, 4) << ior; // enter, two total reflections, exit
            EXPECT_NEAR(length(p.exitDir - Vec3d{0, 0, -1}), 0, 1e-3) << ior;
            EXPECT_NEAR(p.exitPoint.x, -0.3, 2 * glass.voxelSize()) << ior;
        } else {
            EXPECT_EQ(p.events, 2) << ior;
            const double out = std::asin(ior * std::sin(M_PI / 4)); // from the leg's normal (1, 0, 1)/sqrt2
            const Vec3d nLeg = normalize(Vec3d{1, 0, 1}), tLeg = normalize(Vec3d{1, 0, -1});
            const Vec3d want = nLeg * std::cos(out) - tLeg * std::sin(out);
            EXPECT_NEAR(length(p.exitDir - want), 0, 1e-3) << ior;
        }
        // The exact tracer agrees.
        ExactGlass exact(prism.view(), {}, std::vector<uint32_t>(prism.triangleCount(), 0), {medium});
        const GlassPath e = exact.trace({0.3, 0.1, -2}, {0, 0, 1}, 16);
        EXPECT_EQ(e.events, p.events) << ior;
        EXPECT_NEAR(length(e.exitDir - p.exitDir), 0, 1e-3) << ior;
    }
}

TEST(GlassTest, MultipleRefractionSeesThroughTwoSlabsWhereTwoSurfaceStopsAfterOne) {
    // Two parallel slabs, one behind the other: the refracted ray crosses both. Multi follows four
    // refractions and exits parallel; two-surface stops after the first slab's back face (also parallel
    // here, but with two events and the first slab's attenuation only).
    Mesh two = test::makeBox({-1, -1, 0.5}, {1, 1, 0.8});
    test::appendBox(two, {-1, -1, -0.8}, {1, 1, -0.5});
    GlassMedium medium;
    medium.ior = float(kGlassIor);
    medium.sigma = {1, 1, 1};
    VoxelGlassOptions o;
    o.gridResolution = 64;
    const Vec3d d = glassDirAt(0.3);
    VoxelGlass glass(two.view(), std::vector<uint32_t>(two.triangleCount(), 0), {medium}, o);
    const GlassPath multi = glass.trace({0, 0, 0.8}, {0, 0, 1}, 0, d, o, false);
    EXPECT_EQ(multi.events, 4);
    EXPECT_NEAR(length(multi.exitDir - d), 0, 1e-6);
    EXPECT_LT(multi.exitPoint.z, -0.5);
    const GlassPath two2 = glass.trace({0, 0, 0.8}, {0, 0, 1}, 0, d, o, true);
    EXPECT_EQ(two2.events, 2);
    EXPECT_GT(two2.exitPoint.z, 0.4);
    EXPECT_GT(two2.throughput.x, multi.throughput.x);
    // The exact tracer agrees with multi on the exit direction and number of events.
    ExactGlass exact(two.view(), {}, std::vector<uint32_t>(two.triangleCount(), 0), {medium});
    const GlassPath e = exact.trace(Vec3d{0, 0, 0.8} - d, d, 16);
    EXPECT_EQ(e.events, 4);
    EXPECT_NEAR(length(e.exitDir - d), 0, 1e-5);
    EXPECT_NEAR(e.throughput.x, multi.throughput.x, 0.05);
}

TEST(GlassTest, AttributeMaterialChannelHoldsTheFirstWritersMaterialWhereverSomethingWasWritten) {
    Mesh m = test::makeBox({0.1, 0.1, 0.1}, {0.45, 0.9, 0.9});
    test::appendBox(m, {0.55, 0.1, 0.1}, {0.9, 0.9, 0.9});
    std::vector<uint32_t> mat(m.triangleCount());
    for (size_t t = 12; t < mat.size(); ++t) mat[t] = 7;
    AttributeOptions o;
    o.coverage = Coverage::Conservative;
    o.triangleMaterial = mat;
    const Frame f = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 20, 20, 20);
    const AttributeGrid g = voxelizeAttributes(m.view(), f, {}, o);
    ASSERT_EQ(g.material.size(), g.count.size());
    int64_t written = 0;
    for (int64_t y = 0; y < 20; ++y)
        for (int64_t x = 0; x < 20; ++x)
            for (int64_t s = 0; s < 20; ++s) {
                const int64_t i = g.index(x, y, s);
                if (g.count[size_t(i)] == 0) {
                    EXPECT_EQ(g.material[size_t(i)], AttributeGrid::kNoMaterial);
                    continue;
                }
                ++written;
                // The boxes are apart by two voxels: a voxel's x says whose it is.
                EXPECT_EQ(g.material[size_t(i)], x < 10 ? 0u : 7u) << x << " " << y << " " << s;
            }
    EXPECT_GT(written, 100);
    o.triangleMaterial = std::span<const uint32_t>(mat.data(), 3);
    EXPECT_THROW(voxelizeAttributes(m.view(), f, {}, o), Error);
}

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

Scene glassTestScene() {
    Scene s;
    Material ground;
    ground.baseColor = {0.6f, 0.6f, 0.6f};
    ground.specular = 0;
    Material glass;
    glass.transmission = 1;
    glass.ior = 1.5f;
    glass.attenuationColor = {0.5f, 0.9f, 0.6f};
    glass.attenuationDistance = 1;
    const uint32_t g = s.addMaterial(ground), c = s.addMaterial(glass);
    SceneMesh floor;
    test::appendQuad(floor.mesh, {0, 0, 0}, {0, 0, 3}, {3, 0, 0});
    floor.material = g;
    floor.castsShadow = false;
    s.meshes.push_back(floor);
    SceneMesh ball;
    ball.mesh = test::makeUvSphere({0, 0.8, 0}, 0.7, 48, 96);
    ball.material = c;
    s.meshes.push_back(ball);
    Camera cam;
    cam.position = {0, 1.5, 4};
    cam.target = {0, 0.6, 0};
    cam.fovY = 0.6;
    s.cameras.push_back(cam);
    return s;
}

// CHANG's absorption constant (#25 item 2): a constant k on the method is the material's
// attenuation coefficient times k, for the exact tracer and the voxel march alike: k = 2 renders
// as the same glass with half the attenuation distance, k = 0 as glass without attenuation, and
// more absorption never brightens a glass pixel.
TEST(GlassTest, AbsorptionConstantScalesEveryMediumsAttenuation) {
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.shadow = NoShadowOptions{};
    o.antiAliasing = AntiAliasing::Off;
    MultiGlassOptions multi;
    multi.gridResolution = 48;
    for (const GlassOptions base : {GlassOptions(ExactGlassOptions{}), GlassOptions(multi)}) {
        const auto withConstant = [&](double k) {
            GlassOptions g = base;
            std::visit(
                [&](auto& m) {
                    if constexpr (requires { m.absorptionConstant; }) m.absorptionConstant = k;
                },
                g);
            return g;
        };
        const Scene s = glassTestScene();
        o.glass = withConstant(2);
        const RenderResult doubled = render(s, s.cameras[0], o);
        Scene half = s;
        half.materials[1].attenuationDistance = 0.5f;
        o.glass = base;
        const RenderResult byMaterial = render(half, half.cameras[0], o);
        o.glass = withConstant(0);
        const RenderResult none = render(s, s.cameras[0], o);
        Scene clear = s;
        clear.materials[1].attenuationDistance = std::numeric_limits<float>::infinity();
        o.glass = base;
        const RenderResult clearGlass = render(clear, clear.cameras[0], o);
        const RenderResult plain = render(s, s.cameras[0], o);
        int64_t glassPixels = 0, darker = 0;
        for (size_t i = 0; i < plain.image.pixels.size(); ++i) {
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(doubled.image.pixels[i][c], byMaterial.image.pixels[i][c], 1e-5f) << i;
                EXPECT_NEAR(none.image.pixels[i][c], clearGlass.image.pixels[i][c], 1e-5f) << i;
                EXPECT_LE(doubled.image.pixels[i][c], plain.image.pixels[i][c] + 1e-6f) << i;
                EXPECT_LE(plain.image.pixels[i][c], none.image.pixels[i][c] + 1e-6f) << i;
            }
            if (plain.glassMask.empty() || !plain.glassMask[i]) continue;
            ++glassPixels;
            darker += doubled.image.pixels[i].x < plain.image.pixels[i].x - 1e-3f;
        }
        EXPECT_GT(glassPixels, 300);
        EXPECT_GT(darker, glassPixels / 2); // the constant does act
    }
    GlassOptions bad = ExactGlassOptions{};
    std::get<ExactGlassOptions>(bad).absorptionConstant = std::nan("");
    o.glass = bad;
    const Scene s = glassTestScene();
    EXPECT_THROW(render(s, s.cameras[0], o), Error);
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

TEST(GlassTest, CrossingCountingShadowsPassWhatExactShadowsPassThroughGlass) {
    // The ball of glassTestScene under the sun (a thicknessFactor of its diameter, which the
    // methods no longer use): transmittance, absorption and deep shadow maps multiply two
    // crossings of sqrt(tint) (1 - F0) and Beer–Lambert over the chord between them, which must
    // agree with the exact tracer's Fresnel x tint x Beer–Lambert under the ball's centre in every
    // channel, and not pass the tint twice with no Fresnel (what every crossing passed before).
    Scene s = glassTestScene();
    s.materials[1].thickness = 1.4f;
    s.materials[1].attenuationColor = {0.3f, 0.5f, 0.4f}; // far from the tint alone
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0, -1, 0};
    auto luminance = [](const Vec3f& v) { return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z; };
    const Vec3d under{0.05, 0, 0.03};
    const Vec3f exact = shadowVisibility(buildLightShadow(s, sun, ExactShadowOptions{}), under, {0, 1, 0});
    const Vec3f tint = s.materials[1].crossingTransmittance();
    for (const std::string_view kind : {"transmittance", "absorption", "deep"}) {
        RenderOptions o;
        setRenderOption(o, "shadows", std::string(kind));
        for (const char* name : {"gridResolution", "gridDepth", "dsmResolution"})
            setRenderOption(o, name, int64_t(64));
        setRenderOption(o, "epsilon", 0.0);
        const Vec3f v = shadowVisibility(buildLightShadow(s, sun, o.shadow), under, {0, 1, 0});
        EXPECT_NEAR(luminance(v), luminance(exact), 0.03) << kind;
        EXPECT_GT(std::abs(luminance(v) - luminance(tint * tint)), 0.1) << kind;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], exact[c], 0.03) << kind << " channel " << c;
    }
    // A leaf's transmission (opacity < 1) is a sheet, not glass: the tree renders without glass.
    TreeOptions t;
    t.leaves = 50;
    const Scene tree = makeTreeScene(t);
    EXPECT_TRUE(std::holds_alternative<NoGlassOptions>(defaultGlass(tree)));
    for (const Material& m : tree.materials)
        if (m.transmission > 0) {
            EXPECT_FALSE(m.isGlass()) << m.name;
            EXPECT_EQ(m.shadowCrossingTransmittance(), m.crossingTransmittance()) << m.name;
        }
}

// The glass shadow of a scene's casters on its ground (y = 0, normal up) under `sun`, sampled on a
// grid of points over [-half, half]^2: the mean absolute error per channel of `kind` against the
// exact tracer (the reference: Fresnel at each crossing, the tint, Beer–Lambert over the true chord),
// over the points that either shadows darkens, with no shadow's error over the same points.
struct GlassShadowError {
    double method = 0, none = 0;
    int64_t points = 0;
};
GlassShadowError glassShadowError(const Scene& s, const Light& sun, std::string_view kind, double half) {
    const LightShadow exact = buildLightShadow(s, sun, ExactShadowOptions{});
    const LightShadow method = buildLightShadow(s, sun, shadowOptionsNamed(kind));
    GlassShadowError e;
    const int n = 100;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const Vec3d p{-half + 2 * half * (i + 0.5) / n, 0, -half + 2 * half * (j + 0.5) / n};
            const Vec3f r = shadowVisibility(exact, p, {0, 1, 0}), v = shadowVisibility(method, p, {0, 1, 0});
            if (std::min({r.x, r.y, r.z, v.x, v.y, v.z}) > 0.999f) continue;
            ++e.points;
            for (int c = 0; c < 3; ++c) {
                e.method += std::abs(double(v[c]) - double(r[c]));
                e.none += std::abs(1.0 - double(r[c]));
            }
        }
    e.method /= double(3 * std::max<int64_t>(e.points, 1));
    e.none /= double(3 * std::max<int64_t>(e.points, 1));
    return e;
}

// A green glass box and an amber glass ball (white tint: all their colour from KHR_materials_volume
// attenuation, no thicknessFactor) over the ground of glassTestScene, under a tilted sun.
Scene tintedGlassScene() {
    Scene s = glassTestScene();
    s.meshes.resize(1); // the ground
    s.meshes[0].mesh = Mesh{};
    test::appendQuad(s.meshes[0].mesh, {0, 0, 0}, {0, 0, 3}, {3, 0, 0});
    Material green = s.materials[1], amber = s.materials[1];
    green.attenuationColor = {0.3f, 0.8f, 0.4f};
    green.attenuationDistance = 0.5f;
    amber.attenuationColor = {0.95f, 0.6f, 0.15f};
    amber.attenuationDistance = 0.6f;
    SceneMesh box, ball;
    box.mesh = test::makeBox({-1.4, 0.2, -0.5}, {-0.4, 1.0, 0.5});
    box.material = s.addMaterial(green);
    ball.mesh = test::makeUvSphere({0.9, 0.8, 0}, 0.6, 48, 96);
    ball.material = s.addMaterial(amber);
    s.meshes.push_back(box);
    s.meshes.push_back(ball);
    return s;
}

Light tiltedSun() {
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = normalize(Vec3d{0.3, -1, 0.2});
    return sun;
}

TEST(GlassTest, CrossingMethodsShadowTintedGlassByTheChordAsExactDoes) {
    // Transmittance, absorption and deep shadow maps against the exact tracer on the ground under a
    // green glass box and an amber glass ball with no thicknessFactor (mean absolute error per
    // channel over the 725 points either shadow darkens). Each crossing passing only Fresnel left
    // the shadow grey at 0.92 (before: transmittance 0.423, absorption 0.423, deep 0.419 against no
    // shadow's 0.681); with Beer–Lambert over the chord between paired crossings (cells of the
    // light grid, fragments of the deep shadow map) the error is a fraction of it (after:
    // transmittance 0.060, absorption 0.060, deep 0.074).
    const Scene s = tintedGlassScene();
    for (const std::string_view kind : {"transmittance", "absorption", "deep"}) {
        const GlassShadowError e = glassShadowError(s, tiltedSun(), kind, 3);
        RecordProperty(std::string(kind) + "Error", std::to_string(e.method));
        RecordProperty(std::string(kind) + "NoShadowError", std::to_string(e.none));
        EXPECT_GT(e.points, 500) << kind;
        EXPECT_GT(e.none, 0.3) << kind;
        EXPECT_LT(e.method, 0.25 * e.none) << kind << ": " << e.method << " against no shadow's " << e.none;
    }
}

TEST(GlassTest, CrossingMethodsShadowTheGlassDemoNearExactShadows) {
    // The glass demo (glass bunny, green torus knot, amber and blue block; white tints, colour from
    // the attenuation) under its default sun: the ground's shadow error against exact shadows
    // (before: transmittance 0.319, absorption 0.314, deep 0.324 against no shadow's 0.397; after:
    // transmittance 0.085, absorption 0.085, deep 0.092).
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Scene s = makeDemoScene("glass", test::dataPath("meshes"));
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = -normalize(SkyOptions{}.sunDirection);
    for (const std::string_view kind : {"transmittance", "absorption", "deep"}) {
        const GlassShadowError e = glassShadowError(s, sun, kind, 4);
        RecordProperty(std::string(kind) + "Error", std::to_string(e.method));
        RecordProperty(std::string(kind) + "NoShadowError", std::to_string(e.none));
        EXPECT_GT(e.points, 500) << kind;
        EXPECT_LT(e.method, 0.3 * e.none) << kind << ": " << e.method << " against no shadow's " << e.none;
    }
}

TEST(GlassTest, AbsorptionAndDeepShadowsAreColouredUnderTintedLeavesAndGlass) {
    // A green leaf (a sheet: gaps plus tissue of its base colour) and the green glass box of
    // tintedGlassScene: exact shadows under each are green; absorption and deep shadows, grey
    // before (one visibility for all channels), must be green too and near exact per channel.
    Scene s = tintedGlassScene();
    s.meshes.resize(2); // ground and box
    Material leaf;
    leaf.baseColor = {0.2f, 0.8f, 0.15f};
    leaf.opacity = 0.7f;
    leaf.transmission = 0.7f;
    SceneMesh quad;
    test::appendQuad(quad.mesh, {1.2, 1.0, 0}, {0, 0, 0.5}, {0.5, 0, 0}); // centre (1.2, 1, 0)
    quad.material = s.addMaterial(leaf);
    s.meshes.push_back(quad);
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0, -1, 0};
    const LightShadow exact = buildLightShadow(s, sun, ExactShadowOptions{});
    for (const Vec3d under : {Vec3d{1.2, 0, 0.02}, Vec3d{-0.9, 0, 0.02}}) {
        const Vec3f r = shadowVisibility(exact, under, {0, 1, 0});
        ASSERT_GT(r.y, r.x + 0.1f);
        ASSERT_GT(r.y, r.z + 0.1f);
        for (const std::string_view kind : {"absorption", "deep"}) {
            const Vec3f v =
                shadowVisibility(buildLightShadow(s, sun, shadowOptionsNamed(kind)), under, {0, 1, 0});
            EXPECT_GT(v.y, v.x + 0.1f) << kind << " at x " << under.x;
            EXPECT_GT(v.y, v.z + 0.1f) << kind << " at x " << under.x;
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], r[c], 0.05) << kind << " channel " << c;
        }
    }
}

// The top pixels of a green glass cube standing on the ground in a magenta environment, and how
// many of them show the environment (magenta over green) through the glass.
struct TopPixels {
    int64_t top = 0, sky = 0;
};
TopPixels glassCubeOnTheGround(const GlassOptions& method) {
    Scene s = glassTestScene(); // the ground, and the ball (mesh 1) made a cube
    s.meshes[1].mesh = test::makeBox({-0.5, 0, -0.5}, {0.5, 1, 0.5});
    Light sun;
    sun.direction = normalize(Vec3d{0.2, -1, 0.1});
    s.lights.push_back(sun);
    Camera cam = s.cameras[0]; // from higher up: the top fills the view
    cam.position = {0.3, 3, 2};
    cam.target = {0, 0.4, 0};
    RenderOptions o;
    o.width = 96;
    o.height = 72;
    o.shadow = shadowOptionsNamed("none");
    o.glass = method;
    Image magenta(4, 2);
    for (Vec3f& p : magenta.pixels) p = {1, 0, 1};
    o.environment = std::make_shared<const Environment>(magenta);
    o.skyLight = 0; // what the glass sees, not the magenta ambient on its surface
    const RenderResult r = render(s, cam, o);
    const SceneGeometry geo = flattenScene(s);
    const GBuffer g = renderGBuffer(geo, cameraFrame(cam, o.width, o.height));
    TopPixels out;
    for (int64_t y = 0; y < o.height; ++y)
        for (int64_t x = 0; x < o.width; ++x) {
            const uint32_t t = g.triangle[size_t(y * o.width + x)];
            if (t == GBuffer::kNone || geo.triangleMesh[t] != 1) continue;
            bool onTop = true;
            for (int k = 0; k < 3; ++k)
                onTop = onTop && geo.mesh.positions[geo.mesh.indices[3 * t + k]].y == 1;
            if (!onTop) continue;
            ++out.top;
            const Vec3f& p = r.image.at(x, o.height - 1 - y);
            out.sky += p.y < 0.5f * p.x;
        }
    return out;
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

TEST(GlassTest, VoxelGlassStandingOnTheGroundShowsTheGroundNotTheSky) {
    // The cube above with the voxel methods. Multi marched on after the exit to the grid's edge, a
    // voxel below the ground, and the scene cast from there met only the environment: 1,232 /
    // 1,236 / 1,236 of the 1,236 top pixels at 16³ / 32³ / 64³. The exact tracer sees no
    // environment through the top; the voxel methods now look the scene up from where the ray left
    // glass: two-surface none, multi 86 / 17 / 7 (rays bent by averaged normals at the cube's
    // edges and corners, a voxel's worth of the top, shrinking with the grid); 94 / 20 / 7 since
    // the normal is interpolated at the event (#26 item 4), 97 / 17 / 7 since it is taken at the
    // middle of the surface's run of voxels (#25 item 2). Those were rays reflected by a side
    // towards the bottom edge, whose voxels hold the 45-degree mean of the side's and the bottom's
    // normals: a second, false total reflection there sent them up through the far side. Since a
    // crease voxel is passed where the ray goes on into a voxel of one surface (and otherwise takes
    // the normal of the face the ray heads into): 7 / 0 / 0, bounded here by 16 / 2 / 2.
    for (const int64_t res : {16, 32, 64}) {
        MultiGlassOptions multi;
        multi.gridResolution = res;
        const TopPixels m = glassCubeOnTheGround(multi);
        EXPECT_GT(m.top, 600);
        EXPECT_LE(m.sky, res == 16 ? 16 : 2) << "multi " << res << "³: of " << m.top << " pixels of the top";
        TwoSurfaceGlassOptions two;
        two.gridResolution = res;
        const TopPixels t = glassCubeOnTheGround(two);
        EXPECT_EQ(t.sky, 0) << "two-surface " << res << "³: of " << t.top << " pixels of the top";
    }
}

TEST(GlassTest, VoxelGlassRendersCloseToTheExactTracerAndDeterministically) {
    const Scene s = glassTestScene();
    RenderOptions o;
    o.width = 96;
    o.height = 72;
    o.shadow = NoShadowOptions{};
    o.glass = ExactGlassOptions{};
    const RenderResult exact = render(s, s.cameras[0], o);
    int64_t glassPixels = 0;
    for (const uint8_t m : exact.glassMask) glassPixels += m;
    EXPECT_GT(glassPixels, 500);
    MultiGlassOptions multiOptions;
    multiOptions.gridResolution = 64;
    o.glass = multiOptions;
    const RenderResult multi = render(s, s.cameras[0], o);
    const ImageError e = imageError(multi.image, exact.image, exact.glassMask);
    EXPECT_LT(e.mae, 0.06);
    EXPECT_GT(e.psnr, 18);
    o.threads = 1;
    EXPECT_EQ(render(s, s.cameras[0], o).image.pixels, multi.image.pixels);
    // Glass off: the mask is empty, and the sphere is shaded like a surface.
    o.glass = NoGlassOptions{};
    EXPECT_TRUE(render(s, s.cameras[0], o).glassMask.empty());
}

// #25 item 2: multi's extra error after the last exit. Measured at 120x68, 64³: multi 0.0388,
// two-surface 0.0338 (before the exit-point fix: larger still). Diagnosed per pixel against the
// exact tracer's paths: nearly all of the excess was on paths the exact tracer takes through two
// interfaces where multi took 3 to 16 events (101 pixels at maxEvents): a false total reflection
// at the back surface near the critical angle, after which multi bounces inside the tube or ball
// (two-surface stops at the first back surface). The interpolated normal (#26 item 4) brought it
// to multi 0.0263, two-surface 0.0236; the normal taken where the surface crosses the ray (the
// middle of the run of its voxels along the ray, not the first voxel met, the event left there)
// to 0.0153 / 0.0153 (moving the event itself to the run's middle gave 0.0174 / 0.0160 but
// showed more sky through a glass cube's top: VoxelGlassStandingOnTheGround).
TEST(GlassTest, MultiIsNoFurtherFromExactThanTwoSurfaceWhereMostPathsCrossTwoInterfaces) {
    // A standing clear torus and a tinted ball, both on the ground: most paths enter and leave once,
    // where multi and two-surface refract alike; multi must then be no further from the exact image
    // than two-surface.
    Scene s;
    Material ground;
    ground.baseColor = {0.6f, 0.6f, 0.6f};
    ground.specular = 0;
    Material clear;
    clear.transmission = 1;
    clear.ior = 1.5f;
    Material tinted = clear;
    tinted.baseColor = {0.7f, 0.9f, 1.0f};
    SceneMesh floor;
    test::appendQuad(floor.mesh, {0, 0, 0}, {0, 0, 4}, {4, 0, 0});
    floor.material = s.addMaterial(ground);
    s.meshes.push_back(floor);
    SceneMesh torus;
    torus.mesh = test::makeTorus({-0.8, 0.95, 0}, 0.7, 0.25, 48, 24);
    torus.material = s.addMaterial(clear);
    s.meshes.push_back(torus);
    SceneMesh ball;
    ball.mesh = test::makeUvSphere({0.9, 0.6, 0.2}, 0.6, 24, 48);
    ball.material = s.addMaterial(tinted);
    s.meshes.push_back(ball);
    Camera cam;
    cam.position = {0, 1.4, 4.5};
    cam.target = {0, 0.8, 0};
    cam.fovY = 45 * M_PI / 180;
    RenderOptions o;
    o.width = 120;
    o.height = 68;
    o.shadow = NoShadowOptions{};
    o.antiAliasing = AntiAliasing::Off;
    o.glass = ExactGlassOptions{};
    const RenderResult exact = render(s, cam, o);
    int64_t glassPixels = 0;
    for (const uint8_t m : exact.glassMask) glassPixels += m;
    ASSERT_GT(glassPixels, 1000);
    MultiGlassOptions multi;
    multi.gridResolution = 64;
    o.glass = multi;
    const ImageError m = imageError(render(s, cam, o).image, exact.image, exact.glassMask);
    TwoSurfaceGlassOptions two;
    two.gridResolution = 64;
    o.glass = two;
    const ImageError t = imageError(render(s, cam, o).image, exact.image, exact.glassMask);
    // Measured at 64³: multi 0.0103, two-surface 0.0110 (with face normals and events at corner
    // voxels, 0.0153 and 0.0153; at 96³ 0.0146 and 0.0128).
    EXPECT_LE(m.mae, t.mae) << "multi " << m.mae << ", two-surface " << t.mae;
}

TEST(GlassTest, ASceneWithoutLightsIsLitByTheDefaultSunAndSkyAmbient) {
    Scene s = glassTestScene();
    s.materials[1].transmission = 0; // opaque: plain shading
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.ambient = {0, 0, 0};
    o.sky = SkyKind::Flat; // black
    o.background = {0, 0, 0};
    o.shadow = NoShadowOptions{};
    o.defaultLights = false;
    o.toneMap = ToneMap::Clamp;
    o.antiAliasing = AntiAliasing::Off;
    const RenderResult dark = render(s, s.cameras[0], o);
    for (const Vec3f& p : dark.image.pixels) EXPECT_EQ(p, (Vec3f{0, 0, 0}));
    o.defaultLights = true;
    o.sky = SkyKind::Procedural;
    const RenderResult lit = render(s, s.cameras[0], o);
    // A ground pixel: albedo / pi * the sky's irradiance on an upward face (ambient) + albedo / pi
    // * E * cos(sun), hand-derived with the default sun (intensity 3, colour (1, 0.96, 0.9), towards
    // SkyOptions' sun direction).
    const Vec3d p{1.2, 0, 0.3}; // beside the ball, in view
    const Vec3d g = cameraFrame(s.cameras[0], 64, 48).gridFromWorld(p);
    const int64_t x = int64_t(std::floor(g.x)), y = 47 - int64_t(std::floor(g.y));
    ASSERT_TRUE(x >= 0 && x < 64 && y >= 0 && y < 48) << x << " " << y;
    const Vec3d sun = normalize(SkyOptions{}.sunDirection);
    const Vec3f avg = Environment::sky().irradiance({0, 1, 0}) * float(1 / M_PI);
    const float albedo = 0.6f;
    const Vec3f colour{1.0f, 0.96f, 0.9f};
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(lit.image.at(x, y)[c], albedo * avg[c] + albedo / M_PI * 3 * colour[c] * sun.y, 1e-3)
            << c;
}

// An octahedron of blue glass over a ground quad, in a JSON scene without lights: DIR/scene.json.
void writeGemScene(const test::TempDir& dir) {
    test::writeFile(dir.file("gem.off"),
                    "OFF\n6 8 0\n1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
                    "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n");
    test::writeFile(dir.file("ground.off"),
                    "OFF\n4 2 0\n-4 -1.2 -4\n4 -1.2 -4\n4 -1.2 4\n-4 -1.2 4\n3 0 2 1\n3 0 3 2\n");
    test::writeFile(dir.file("scene.json"),
                    R"({ "meshes": [ { "file": "gem.off", "material": { "transmission": 1, "ior": 1.5,
                                                                         "baseColor": [0.6, 0.8, 1] } },
                                     { "file": "ground.off" } ],
                         "cameras": [ { "position": [0, 1, 4], "target": [0, 0, 0], "fovYDegrees": 50 } ] })");
}

TEST(GlassTest, CommandLineRendersGlassAndComparesTheVoxelMethodsWithTheExactTracer) {
    test::TempDir dir;
    writeGemScene(dir);
    const auto r =
        test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("a.png") +
                                " --width 64 --height 48 --glass multi --glass-grid 32 --shadows exact");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("glass multi (glass-grid 32"), std::string::npos) << r.out;
    const Image img = readPng(dir.file("a.png"));
    EXPECT_EQ(img.width, 64);
    const auto e =
        test::runVoxfx(dir, "glass-error " + dir.file("scene.json") +
                                " --width 64 --height 48 --resolutions 16,32 --methods multi,two-surface");
    ASSERT_EQ(e.exitCode, 0) << e.err;
    EXPECT_NE(e.out.find("| multi | 32³ |"), std::string::npos) << e.out;
    EXPECT_NE(e.out.find("| two-surface | 16³ |"), std::string::npos) << e.out;
    const auto bad = test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("b.png") +
                                             " --glass frosty");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("exact, multi, two-surface"), std::string::npos) << bad.err;
}

TEST(GlassTest, CommandLineGlassKnobsChangeTheImageAndBadValuesSayWhich) {
    // CHANG's knobs on the render command line (--glass-grid, --glass-coverage, --angle-threshold,
    // --slab-overlap, --max-events, --no-scene-behind: CHANG's environment-only lookup after the last exit):
    // each is parsed, most change the multi image of a glass octahedron over a ground quad, and a bad value
    // exits non-zero naming the flag, with no image written.
    test::TempDir dir;
    writeGemScene(dir);
    const std::string base =
        "render " + dir.file("scene.json") + " --width 48 --height 36 --shadows none --glass multi ";
    auto renderWith = [&](const std::string& flags, const std::string& png) {
        const auto r = test::runVoxfx(dir, base + flags + " -o " + dir.file(png));
        EXPECT_EQ(r.exitCode, 0) << flags << ": " << r.err;
        return readPng(dir.file(png));
    };
    const Image plain = renderWith("--glass-grid 24", "plain.png");
    for (const char* flags :
         {"--glass-grid 12", "--glass-grid 24 --glass-coverage center", "--glass-grid 24 --max-events 1",
          "--glass-grid 24 --no-scene-behind", "--glass-grid 24 --glass-coverage center --slab-overlap 1"}) {
        const Image other = renderWith(flags, "other.png");
        EXPECT_NE(other.pixels, plain.pixels) << flags << " changed nothing";
    }
    // The defaults, given. (The angle threshold changes nothing on this gem: with the media stack a
    // voxel of the surface just crossed is no new event whatever the threshold.)
    EXPECT_EQ(
        renderWith("--glass-grid 24 --angle-threshold 0.35 --slab-overlap 0 --max-events 16 --scene-behind",
                   "same.png")
            .pixels,
        plain.pixels);
    for (const auto& [flags, says] :
         std::vector<std::pair<std::string, std::string>>{{"--angle-threshold abc", "--angle-threshold"},
                                                          {"--angle-threshold 4", "angle"},
                                                          {"--max-events 0", "max"},
                                                          {"--slab-overlap -1", "slab"},
                                                          {"--glass-grid 1", "glass"},
                                                          {"--glass-coverage most", "conservative"}}) {
        const auto r = test::runVoxfx(dir, base + flags + " -o " + dir.file("bad.png"));
        EXPECT_NE(r.exitCode, 0) << flags << ": " << r.err;
        EXPECT_EQ(r.err.find("terminate called"), std::string::npos) << flags << ": " << r.err; // "abc" did
        EXPECT_NE(r.err.find(says), std::string::npos) << flags << ": " << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("bad.png"))) << flags;
    }
}

TEST(GlassTest, ImageErrorIsTheMeanAbsoluteAndPsnrOverTheMask) {
    Image a(2, 1), b(2, 1);
    a.at(0, 0) = {0.5f, 0.5f, 0.5f};
    b.at(0, 0) = {0.6f, 0.4f, 0.5f};
    a.at(1, 0) = {9, 9, 9}; // masked out
    const ImageError e = imageError(a, b, {1, 0});
    EXPECT_EQ(e.pixels, 1);
    EXPECT_NEAR(e.mae, 0.2 / 3, 1e-6);
    EXPECT_NEAR(e.psnr, 10 * std::log10(1 / (0.02 / 3)), 1e-4);
    EXPECT_THROW(imageError(a, b, {1}), Error);
    EXPECT_TRUE(std::holds_alternative<TwoSurfaceGlassOptions>(glassOptionsNamed("two-surface")));
    EXPECT_THROW(glassOptionsNamed("frosty"), Error);
}

// ---- ED06 §3.3 frosted glass -------------------------------------------------------------------------
// The column walk's rules on hand-made columns (ED06 fig. 9), and the thickness at pixels of thick
// and thin parts, silhouettes and folds against the exact chord of the eye ray (Embree,
// voxfx/triangle_tracer.hpp), its smoothness across columns, and the refraction it bends.

constexpr double kFrostedIor = 1.5;

// Rotates the mesh's positions by `angle` around the y axis through `c`.
void frostedRotateY(Mesh& m, double angle, const Vec3d& c) {
    const double cs = std::cos(angle), sn = std::sin(angle);
    for (Vec3f& p : m.positions) {
        const Vec3d q = Vec3d(p) - c;
        p = Vec3f(c + Vec3d{cs * q.x + sn * q.z, q.y, -sn * q.x + cs * q.z});
    }
}

void frostedAppend(Mesh& m, const Mesh& o) {
    const auto base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), o.positions.begin(), o.positions.end());
    for (const uint32_t i : o.indices) m.indices.push_back(base + i);
}

// A frosted glass of `mesh` seen by a camera, with the exact reference along the camera's rays.
struct FrostedScene {
    Mesh mesh;
    Frame camera;
    FrostedGlass glass;
    TriangleTracer tracer;

    FrostedScene(Mesh m, const Vec3d& eye, const Vec3d& target, int64_t w, int64_t h, int64_t grid)
        : mesh(std::move(m)), camera(Frame::perspective(eye, target, {0, 1, 0}, 0.7, w, h, 0.1, 100, 1)),
          glass(mesh.view(), std::vector<uint32_t>(mesh.triangleCount(), 0), {medium()}, camera,
                options(grid)),
          tracer(mesh.view()) {}
    static GlassMedium medium() {
        GlassMedium g;
        g.ior = float(kFrostedIor);
        g.sigma = {0.5f, 0.5f, 0.5f};
        return g;
    }
    static FrostedGlassOptions options(int64_t grid) {
        FrostedGlassOptions o;
        o.gridResolution = grid;
        return o;
    }
    // The uniform slice length of the slicemaps' frame (local slices are shorter).
    double slice() const {
        return (glass.frame().farDepth() - glass.frame().nearDepth()) / double(glass.frame().depth());
    }
    Vec3d pixelRay(double px, double py) const {
        return normalize(camera.worldFromGrid({px, py, 1.0}) - camera.eye());
    }
    // The exact length of the ray from the eye along `dir` inside the glass (winding count of the
    // faces it crosses), and its first hit (t, geometric normal).
    struct Chord {
        bool hit = false;
        double t = 0, length = 0;
        Vec3d normal;
    };
    Chord exact(const Vec3d& dir) const {
        Chord c;
        int winding = 0;
        double tPrev = 0, t = 0;
        for (int guard = 0; guard < 1000; ++guard) {
            const TriangleTracer::Hit h = tracer.intersect(camera.eye(), dir, t, 1e30);
            if (!h.hit) break;
            const MeshView v = tracer.mesh().view();
            const Vec3d a = v.vertex(v.index(h.triangle, 0)), b = v.vertex(v.index(h.triangle, 1)),
                        cc = v.vertex(v.index(h.triangle, 2));
            const Vec3d n = normalize(cross(b - a, cc - a));
            if (!c.hit) {
                c.hit = true;
                c.t = h.t;
                c.normal = n;
            }
            if (winding > 0) c.length += h.t - tPrev;
            winding += dot(n, dir) < 0 ? 1 : -1;
            tPrev = h.t;
            t = h.t + tracer.epsilon();
        }
        return c;
    }
    // The frosted thickness at the pixel's surface point (with its normal) and the exact chord.
    struct Sample {
        bool hit = false;
        double estimate = 0, exact = 0, lo = 0, hi = 0;
    };
    // lo, hi: the least and greatest exact chord of the rays within one column of the pixel's (the
    // four columns the estimate interpolates lie there).
    Sample sample(double px, double py, bool neighbourhood) const {
        Sample s;
        const Vec3d d = pixelRay(px, py);
        const Chord c = exact(d);
        if (!c.hit) return s;
        s.hit = true;
        const Vec3d p = camera.eye() + d * c.t;
        s.estimate = glass.thickness(p, c.normal);
        s.exact = s.lo = s.hi = c.length;
        if (!neighbourhood) return s;
        const Vec3d g = glass.frame().gridFromWorld(p);
        for (double dy = -1; dy <= 1; dy += 0.25)
            for (double dx = -1; dx <= 1; dx += 0.25) {
                const Vec3d q = glass.frame().worldFromGrid({g.x + dx, g.y + dy, 1.0});
                const double l = exact(normalize(q - camera.eye())).length;
                s.lo = std::min(s.lo, l);
                s.hi = std::max(s.hi, l);
            }
        return s;
    }
};

// Counts the pixels (a stride over the image) whose estimate leaves [lo - tol, hi + tol] and
// returns the mean absolute error against the pixel's own chord where the neighbourhood is flat
// (hi - lo below tol: away from silhouettes and edges).
struct FrostedReport {
    int glassPixels = 0, outside = 0, flatPixels = 0;
    double flatMeanError = 0, flatMaxError = 0;
};
FrostedReport frostedCheckImage(const FrostedScene& s, int stride, double tol) {
    FrostedReport r;
    for (int64_t y = 0; y < s.camera.height(); y += stride)
        for (int64_t x = 0; x < s.camera.width(); x += stride) {
            const FrostedScene::Sample a = s.sample(double(x) + 0.5, double(y) + 0.5, true);
            if (!a.hit) continue;
            ++r.glassPixels;
            if (a.estimate < a.lo - tol || a.estimate > a.hi + tol) {
                ++r.outside;
                if (r.outside <= 5)
                    ADD_FAILURE() << "pixel (" << x << ", " << y << "): thickness " << a.estimate
                                  << ", exact chords around it " << a.lo << " .. " << a.hi << " (own "
                                  << a.exact << "), tolerance " << tol;
            }
            if (a.hi - a.lo < tol) {
                ++r.flatPixels;
                r.flatMeanError += std::abs(a.estimate - a.exact);
                r.flatMaxError = std::max(r.flatMaxError, std::abs(a.estimate - a.exact));
            }
        }
    if (r.flatPixels) r.flatMeanError /= r.flatPixels;
    return r;
}

// ED06 fig. 9 on hand-made columns: f front only, b back only, a both, . empty.
std::vector<double> frostedWalk(const char* cells) {
    const auto D = int64_t(std::char_traits<char>::length(cells));
    std::vector<uint64_t> f(size_t((D + 63) / 64)), b(f.size());
    for (int64_t s = 0; s < D; ++s) {
        if (cells[s] == 'f' || cells[s] == 'a') f[size_t(s >> 6)] |= uint64_t(1) << (s & 63);
        if (cells[s] == 'b' || cells[s] == 'a') b[size_t(s >> 6)] |= uint64_t(1) << (s & 63);
    }
    std::vector<double> out;
    detail::frostedColumnIntervals(f.data(), b.data(), int64_t(f.size()), D, out);
    return out;
}

TEST(FrostedGlassTest, ColumnWalkResolvesAmbiguousCellsByTheNextUnambiguousOne) {
    using V = std::vector<double>;
    // Unambiguous: enter at the front cell's middle, leave at the back cell's middle; the column's
    // first and last fragments lie on its ends (local slicing).
    EXPECT_EQ(frostedWalk(".f...b.."), (V{1.5, 5.5}));
    EXPECT_EQ(frostedWalk("f......b"), (V{0, 8}));
    // An ambiguous cell followed by a back-only cell: inside after it (a fold entered and left
    // within the cell, then the ray is inside up to the back face).
    EXPECT_EQ(frostedWalk(".f..a..b."), (V{1.5, 7.5}));
    EXPECT_EQ(frostedWalk("..a..b..."), (V{2.5, 5.5}));
    // Followed by a front-only cell: outside after it.
    EXPECT_EQ(frostedWalk(".f..a..f.b."), (V{1.5, 4.5, 7.5, 9.5}));
    // Two ambiguous cells in a row: the cells between count as inside.
    EXPECT_EQ(frostedWalk("..a...a..f.b."), (V{2.5, 6.5, 9.5, 11.5}));
    // An ambiguous cell from outside with nothing behind: a sliver (a third of the cell).
    EXPECT_EQ(frostedWalk("...a...."), (V{3 + 1.0 / 3, 3 + 2.0 / 3}));
    // A front face met inside and a back face met outside are ignored.
    EXPECT_EQ(frostedWalk(".f.f.b.b."), (V{1.5, 5.5}));
    // A missed back face: inside to the column's end.
    EXPECT_EQ(frostedWalk(".f......"), (V{1.5, 8}));
    EXPECT_TRUE(frostedWalk("........").empty());
    // Across words.
    std::string longColumn(150, '.');
    longColumn[10] = 'f';
    longColumn[100] = 'b';
    EXPECT_EQ(frostedWalk(longColumn.c_str()), (V{10.5, 100.5}));
}

TEST(FrostedGlassTest, ThicknessOfThickAndThinPartsIsTheExactChord) {
    // A slab 0.6 thick and beside it a sheet 0.001 thick (its faces share a cell of the uniform
    // slicing), seen at a slant.
    Mesh m = test::makeBox({-1, -1, -0.3}, {1, 1, 0.3});
    test::appendBox(m, {1.3, -1, 0}, {2.5, 1, 0.001});
    const FrostedScene s(std::move(m), {0.75, 0.5, 6}, {0.75, 0, 0}, 160, 120, 128);
    const double tol = 0.25 * s.slice();
    const FrostedReport r = frostedCheckImage(s, 3, tol);
    EXPECT_GT(r.glassPixels, 500);
    EXPECT_EQ(r.outside, 0) << "of " << r.glassPixels;
    EXPECT_GT(r.flatPixels, r.glassPixels / 2);
    EXPECT_LT(r.flatMaxError, tol) << "mean " << r.flatMeanError << ", slice " << s.slice();
    // The sheet alone: its own chord, far below one slice.
    const FrostedScene::Sample sheet = s.sample(120, 60, false);
    ASSERT_TRUE(sheet.hit);
    EXPECT_LT(sheet.exact, 0.002);
    EXPECT_NEAR(sheet.estimate, sheet.exact, 0.05 * s.slice());
}

TEST(FrostedGlassTest, ThicknessAtSilhouettesStaysWithinTheExactChordsOfItsColumns) {
    // A sphere: the chord falls to zero at the silhouette, where the nearest columns differ most.
    const FrostedScene s(test::makeUvSphere({0, 0, 0}, 1, 48, 96), {0.2, 0.3, 4}, {0, 0, 0}, 160, 120, 64);
    const double tol = 0.25 * s.slice();
    const FrostedReport r = frostedCheckImage(s, 2, tol);
    EXPECT_GT(r.glassPixels, 1000);
    EXPECT_EQ(r.outside, 0) << "of " << r.glassPixels;
}

TEST(FrostedGlassTest, ThicknessThroughFoldsCountsEveryPartTheRayCrosses) {
    // Two slabs 0.3 thick with a gap of 0.002 between them (the back of the first and the front of
    // the second in one cell: a fold), and a torus at a slant (rays through both sides of the tube).
    Mesh m = test::makeBox({-2, -1, 0.001}, {0, 1, 0.301});
    test::appendBox(m, {-2, -1, -0.301}, {0, 1, -0.001});
    Mesh torus = test::makeTorus({0, 0, 0}, 0.9, 0.35, 64, 32);
    frostedRotateY(torus, 1.2, {0, 0, 0});
    for (Vec3f& p : torus.positions) p = p + Vec3f(1.4f, 0, 0);
    frostedAppend(m, torus);
    const FrostedScene s(std::move(m), {0, 0.4, 6}, {0, 0, 0}, 160, 120, 128);
    const double tol = 0.25 * s.slice();
    const FrostedReport r = frostedCheckImage(s, 2, tol);
    EXPECT_GT(r.glassPixels, 1000);
    EXPECT_EQ(r.outside, 0) << "of " << r.glassPixels;
    // Through the two slabs: both counted (0.6 of glass along the ray, the gap within a cell).
    const FrostedScene::Sample slabs = s.sample(40, 60, false);
    ASSERT_TRUE(slabs.hit);
    EXPECT_GT(slabs.exact, 0.6);
    EXPECT_NEAR(slabs.estimate, slabs.exact, tol + 0.002);
}

// Largest change of (estimate - exact) between neighbouring pixels along row y, over [x0, x1), in
// slices: the staircase the column and slice structure leaves in the thickness.
double frostedRowRoughness(const FrostedScene& s, int64_t y, int64_t x0, int64_t x1) {
    double worst = 0, prev = 0;
    for (int64_t x = x0; x < x1; ++x) {
        const FrostedScene::Sample a = s.sample(double(x) + 0.5, double(y) + 0.5, false);
        EXPECT_TRUE(a.hit) << x;
        const double e = a.estimate - a.exact;
        if (x > x0) worst = std::max(worst, std::abs(e - prev));
        prev = e;
    }
    return worst / s.slice();
}

TEST(FrostedGlassTest, ThicknessIsSmoothAcrossColumnsOfAFlatSlabAndASphere) {
    // A wide slab turned 35 degrees and a sphere, 640 pixels across 64 columns: the thickness may
    // not step from column to column or slice to slice (streaks). The row stops short of where the
    // eye rays start leaving through the slab's side (a kink of the exact chord).
    Mesh slab = test::makeBox({-3, -3, -0.3}, {3, 3, 0.3});
    frostedRotateY(slab, 0.6, {0, 0, 0});
    const FrostedScene a(std::move(slab), {0, 0, 6}, {0, 0, 0}, 640, 480, 64);
    const double slabSteps = frostedRowRoughness(a, 240, 100, 480);
    EXPECT_LT(slabSteps, 0.02) << "slice " << a.slice();
    const FrostedScene b(test::makeUvSphere({0, 0, 0}, 1, 96, 192), {0, 0, 4}, {0, 0, 0}, 640, 480, 64);
    const double sphereSteps = frostedRowRoughness(b, 240, 220, 420); // the middle of the disc
    EXPECT_LT(sphereSteps, 0.1) << "slice " << b.slice();
}

TEST(FrostedGlassTest, RefractionBendsWithTheThicknessCrossed) {
    Mesh m = test::makeBox({-1, -1, -0.3}, {1, 1, 0.3});
    test::appendBox(m, {1.3, -1, 0}, {2.5, 1, 0.001});
    const FrostedScene s(std::move(m), {0.75, 0.5, 6}, {0.75, 0, 0}, 160, 120, 128);
    const double diagonal = length(computeBounds(s.mesh.view()).extent());
    for (const auto& [px, py] : {std::pair{40.0, 60.0}, std::pair{120.0, 60.0}}) {
        const Vec3d d = s.pixelRay(px, py);
        const FrostedScene::Chord c = s.exact(d);
        ASSERT_TRUE(c.hit);
        const Vec3d entry = s.camera.eye() + d * c.t;
        const GlassPath p = s.glass.trace(entry, c.normal, 0, d);
        Vec3d t;
        ASSERT_TRUE(refractDirection(d, c.normal, 1 / kFrostedIor, t));
        // ED06: the environment lookup is perturbed by the refraction scaled with the volume
        // crossed, here the exact chord.
        const Vec3d want = normalize(d + (t - d) * (c.length / diagonal));
        const double bend = std::acos(std::clamp(dot(t, d), -1.0, 1.0));
        EXPECT_LT(std::acos(std::clamp(dot(p.exitDir, want), -1.0, 1.0)), 0.02 * bend) << px;
        const double F = fresnelDielectric(-dot(d, c.normal), 1, kFrostedIor);
        EXPECT_NEAR(p.throughput.x, (1 - F) * (1 - F) * std::exp(-0.5 * c.length), 0.01) << px;
        EXPECT_NEAR(p.blurAngle, 0.6 * c.length / diagonal, 0.01) << px;
    }
}

} // namespace
} // namespace voxfx
