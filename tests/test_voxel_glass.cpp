// Tests of the voxel glass methods (CHANG §4: src/render/voxel_glass.cpp, voxfx/voxel_glass.hpp,
// glass methods "multi" and "two-surface"): the voxel march through slabs, thin sheets, a sphere
// and a prism against closed-form refracted rays and the exact tracer; the material channel of the
// attribute voxelization they march in; and renders against the exact tracer's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "support/glass_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/attribute_grid.hpp"
#include "voxfx/exact_glass.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/render.hpp"
#include "voxfx/voxel_glass.hpp"

namespace voxfx {
namespace {

using test::glassCubeOnTheGround;
using test::glassDirAt;
using test::glassTestScene;
using test::kGlassIor;
using test::TopPixels;

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

// #37: the angle threshold changes paths. Multi renders the glass demo (160x90, its first camera,
// 128^3) with the threshold at its default and at 0 (the media stack alone): some glass pixels
// differ (rays that leave a curved surface grazing it, along voxels of that surface whose normals
// face the ray again, re-enter it without the guard), and the default is no further from the exact
// tracer over the glass pixels. (On a ball or a cube at 96x72 no pixel differs: few rays leave
// grazing.) Slow: three renders of the demo.
TEST(GlassSlowTest, TheAngleThresholdChangesGrazingPathsOfTheGlassDemo) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Scene s = demo::makeGlassScene(test::dataPath("meshes"));
    RenderOptions o;
    o.width = 160;
    o.height = 90;
    o.shadow = NoShadowOptions{};
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    o.glass = ExactGlassOptions{};
    const RenderResult exact = render(s, s.cameras[0], o);
    double error[2] = {0, 0};
    Image images[2];
    for (int k = 0; k < 2; ++k) {
        MultiGlassOptions multi;
        multi.gridResolution = 128;
        if (k == 1) multi.angleThreshold = 0;
        o.glass = multi;
        images[k] = render(s, s.cameras[0], o).image;
        error[k] = imageError(images[k], exact.image, exact.glassMask).mae;
    }
    int64_t differing = 0;
    for (size_t i = 0; i < images[0].pixels.size(); ++i)
        differing += exact.glassMask[i] && images[0].pixels[i] != images[1].pixels[i];
    std::printf("glass demo: glass pixels differing %lld; error against exact: threshold %.2f %.5f, 0 %.5f\n",
                (long long)differing, MultiGlassOptions{}.angleThreshold, error[0], error[1]);
    EXPECT_GT(differing, 20);
    EXPECT_LE(error[0], error[1]);
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

} // namespace
} // namespace voxfx
