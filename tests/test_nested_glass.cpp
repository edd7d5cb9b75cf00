// Tests of glass of several materials (CHANG §4.2, fig. 3: an object inside a glass object): the
// exact tracer (src/render/exact_glass.cpp) against closed forms (concentric spheres, a slab inside
// a slab, two slabs touching), then the voxel march (src/render/voxel_glass.cpp) against the exact
// tracer on a nested scene.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "support/ground_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {
namespace {

using test::greyGroundScene;

// A glass medium of index n, absorption sigma (grey) and tint.
GlassMedium nestedMedium(double n, double sigma, float tint = 1) {
    GlassMedium m;
    m.ior = float(n);
    m.sigma = {float(sigma), float(sigma), float(sigma)};
    m.tint = {tint, tint, tint};
    return m;
}

// `inner` appended to `outer`: one mesh, the media per triangle.
struct TwoMedia {
    Mesh mesh;
    std::vector<uint32_t> medium;
    std::vector<Vec3f> normals; // exact sphere normals when asked for
};
TwoMedia nest(const Mesh& outer, const Mesh& inner) {
    TwoMedia t;
    t.mesh = outer;
    const auto base = uint32_t(outer.positions.size());
    t.mesh.positions.insert(t.mesh.positions.end(), inner.positions.begin(), inner.positions.end());
    for (const uint32_t i : inner.indices) t.mesh.indices.push_back(base + i);
    t.medium.assign(outer.triangleCount(), 0);
    t.medium.resize(t.mesh.triangleCount(), 1);
    return t;
}

// Concentric spheres, radii R > r, centred at the origin, with their exact normals per vertex.
TwoMedia concentricSpheres(double R, double r) {
    TwoMedia t = nest(test::makeUvSphere({0, 0, 0}, R, 255, 512), test::makeUvSphere({0, 0, 0}, r, 255, 512));
    for (const Vec3f& p : t.mesh.positions) t.normals.push_back(Vec3f(normalize(Vec3d(p))));
    return t;
}

// Closed form of a ray through concentric spheres (outer R of index nA, inner r of index nB, in air):
// n * |p| * sin(angle to the radius) is the same in every shell (Snell at each sphere), so a ray of
// impact parameter b in air has impact parameter b / nA in A and b / nB in B. Each crossing turns the
// ray towards the centre by (incidence - refraction) angle; lengths are chords of those impact
// parameters.
struct SpherePath {
    int events;
    double deviation, throughput;
};
SpherePath concentricClosedForm(double b, double R, double r, const GlassMedium& A, const GlassMedium& B) {
    const double nA = A.ior, nB = B.ior, sA = A.sigma.x, sB = B.sigma.x;
    const double t1 = std::asin(b / R), t2 = std::asin(b / (nA * R));
    const double pA = b / nA;
    SpherePath s;
    double fresnel =
        (1 - fresnelDielectric(std::cos(t1), 1, nA)) * (1 - fresnelDielectric(std::cos(t2), nA, 1));
    s.deviation = 2 * (t1 - t2);
    if (pA >= r) { // misses the inner sphere
        s.events = 2;
        s.throughput = A.tint.x * fresnel * std::exp(-sA * 2 * std::sqrt(R * R - pA * pA));
        return s;
    }
    const double phi = std::asin(pA / r), phiB = std::asin(b / (nB * r)), pB = b / nB;
    fresnel *=
        (1 - fresnelDielectric(std::cos(phi), nA, nB)) * (1 - fresnelDielectric(std::cos(phiB), nB, nA));
    s.events = 4;
    s.deviation += 2 * (phi - phiB);
    const double inA = 2 * (std::sqrt(R * R - pA * pA) - std::sqrt(r * r - pA * pA));
    const double inB = 2 * std::sqrt(r * r - pB * pB);
    s.throughput = A.tint.x * B.tint.x * fresnel * std::exp(-sA * inA - sB * inB);
    return s;
}

TEST(NestedGlassTest, ExactTracerCrossesConcentricSpheresWithTheRatiosOfTheMediaOnEachSide) {
    const double R = 1, r = 0.5;
    const TwoMedia s = concentricSpheres(R, r);
    const GlassMedium A = nestedMedium(1.5, 0.4, 0.9f);
    // A denser core, and a lighter one (a bubble of index 1.2: Snell from A into B bends away).
    for (const GlassMedium& B : {nestedMedium(2.0, 1.5, 0.8f), nestedMedium(1.2, 0.1, 0.7f)}) {
        const ExactGlass glass(s.mesh.view(), s.normals, s.medium, {A, B});
        // Through the centre: undeviated, attenuated by exp(-sA 2 (R - r) - sB 2 r) times the four
        // normal-incidence Fresnel factors of the pairs air/A, A/B, B/A, A/air, and both tints.
        const Vec3d toCentre = normalize(Vec3d{-0.8, -0.5, -0.3});
        const GlassPath c = glass.trace(toCentre * -5.0, toCentre, 16);
        ASSERT_TRUE(c.hit);
        EXPECT_EQ(c.events, 4);
        EXPECT_NEAR(length(c.exitDir - toCentre), 0, 1e-5);
        const double nA = A.ior, nB = B.ior;
        const double fresnel = (1 - fresnelDielectric(1, 1, nA)) * (1 - fresnelDielectric(1, nA, nB)) *
                               (1 - fresnelDielectric(1, nB, nA)) * (1 - fresnelDielectric(1, nA, 1));
        const double want = 0.9 * B.tint.x * fresnel * std::exp(-0.4 * 2 * (R - r) - B.sigma.x * 2 * r);
        EXPECT_NEAR(c.throughput.x, want, 1e-4) << nB;
        EXPECT_NEAR(c.reflectance, fresnelDielectric(1, 1, nA), 1e-6);
        // Off the centre: along -x at height b (y), away from the poles on z.
        for (const double b : {0.15, 0.35, 0.55, 0.9}) {
            const SpherePath want2 = concentricClosedForm(b, R, r, A, B);
            const GlassPath p = glass.trace({5, b, 0}, {-1, 0, 0}, 16);
            ASSERT_TRUE(p.hit);
            EXPECT_EQ(p.events, want2.events) << nB << " " << b;
            const Vec3d dir{-std::cos(want2.deviation), -std::sin(want2.deviation), 0};
            EXPECT_NEAR(length(p.exitDir - dir), 0, 3e-3) << nB << " " << b;
            EXPECT_NEAR(p.throughput.x, want2.throughput, 3e-3) << nB << " " << b;
            EXPECT_NEAR(length(p.exitPoint), R, 1e-3);
        }
    }
}

// A ray at angle a (from the z axis, tilted to +x) travelling along -z.
Vec3d nestedDirAt(double a) { return {std::sin(a), 0, -std::cos(a)}; }

TEST(NestedGlassTest, ExactTracerShiftsARayThroughASlabInsideASlabByTheClosedForm) {
    // Outer slab |z| <= H/2 (index nA), inner slab |z| <= h/2 (index nB) inside it; both wide in x, y.
    // n sin(theta) is the same in every layer; the ray leaves parallel, shifted along x by
    // (H - h) tan(tA) + h tan(tB) from its entry point, attenuated by each layer's length / cos.
    const double H = 0.8, h = 0.3, sA = 0.5, sB = 2.0;
    const TwoMedia s = nest(test::makeBox({-20, -20, -H / 2}, {20, 20, H / 2}),
                            test::makeBox({-10, -10, -h / 2}, {10, 10, h / 2}));
    const GlassMedium A = nestedMedium(1.5, sA), B = nestedMedium(2.2, sB);
    const ExactGlass glass(s.mesh.view(), {}, s.medium, {A, B});
    for (const double a : {0.0, 0.3, 0.7, 1.2}) {
        const Vec3d d = nestedDirAt(a);
        const Vec3d entry{0.1, 0.05, H / 2};
        const GlassPath p = glass.trace(entry - d * 2.0, d, 16);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 4) << a;
        EXPECT_NEAR(length(p.exitDir - d), 0, 1e-5) << a;
        const double tA = std::asin(std::sin(a) / 1.5), tB = std::asin(std::sin(a) / 2.2);
        const Vec3d exitPoint = entry + Vec3d{(H - h) * std::tan(tA) + h * std::tan(tB), 0, -H};
        EXPECT_NEAR(length(p.exitPoint - exitPoint), 0, 1e-4) << a;
        const double fresnel =
            (1 - fresnelDielectric(std::cos(a), 1, 1.5)) * (1 - fresnelDielectric(std::cos(tA), 1.5, 2.2)) *
            (1 - fresnelDielectric(std::cos(tB), 2.2, 1.5)) * (1 - fresnelDielectric(std::cos(tA), 1.5, 1));
        const double want = fresnel * std::exp(-sA * (H - h) / std::cos(tA) - sB * h / std::cos(tB));
        EXPECT_NEAR(p.throughput.x, want, 1e-4) << a;
    }
}

TEST(NestedGlassTest, ExactTracerCrossesTwoTouchingSlabsAtOneInterface) {
    // Two boxes of different glass stacked face to face (the glass demo's block): their coincident
    // faces at z = 0 are one interface, from B (above) into A (below), with one Fresnel factor; the
    // ray leaves parallel, shifted by hB tan(tB) + hA tan(tA).
    const double hA = 0.4, hB = 0.5;
    const TwoMedia s = nest(test::makeBox({-5, -5, -hA}, {5, 5, 0}), test::makeBox({-5, -5, 0}, {5, 5, hB}));
    const GlassMedium A = nestedMedium(1.5, 0.3), B = nestedMedium(1.9, 1.0);
    for (const bool swapped : {false, true}) { // the face met first along the ray must not matter
        TwoMedia t = s;
        if (swapped)
            t = nest(test::makeBox({-5, -5, 0}, {5, 5, hB}), test::makeBox({-5, -5, -hA}, {5, 5, 0}));
        const std::vector<GlassMedium> media = swapped ? std::vector{B, A} : std::vector{A, B};
        const ExactGlass glass(t.mesh.view(), {}, t.medium, media);
        for (const double a : {0.0, 0.4, 0.9}) {
            const Vec3d d = nestedDirAt(a);
            const Vec3d entry{0.2, -0.1, hB};
            const GlassPath p = glass.trace(entry - d * 2.0, d, 16);
            ASSERT_TRUE(p.hit);
            EXPECT_EQ(p.events, 3) << a;
            EXPECT_NEAR(length(p.exitDir - d), 0, 1e-5) << a;
            const double tA = std::asin(std::sin(a) / 1.5), tB = std::asin(std::sin(a) / 1.9);
            const Vec3d exitPoint = entry + Vec3d{hB * std::tan(tB) + hA * std::tan(tA), 0, -hA - hB};
            EXPECT_NEAR(length(p.exitPoint - exitPoint), 0, 1e-4) << a << " " << swapped;
            const double fresnel = (1 - fresnelDielectric(std::cos(a), 1, 1.9)) *
                                   (1 - fresnelDielectric(std::cos(tB), 1.9, 1.5)) *
                                   (1 - fresnelDielectric(std::cos(tA), 1.5, 1));
            const double want = fresnel * std::exp(-1.0 * hB / std::cos(tB) - 0.3 * hA / std::cos(tA));
            EXPECT_NEAR(p.throughput.x, want, 1e-4) << a << " " << swapped;
        }
    }
}

TEST(NestedGlassTest, ExactTracerCrossesIntoATouchingGlassAtTheRimOfItsBounds) {
    // A small block B (|x|, |y| <= 1, 0 <= z <= hB) standing on a wide slab A (-hA <= z <= 0), and a
    // third glass C far off. The tracer looks for the touching faces of other media only where the
    // crossing lies within a medium's bounds (grown by twice its epsilon), and these crossings lie
    // on B's bounds (its bottom plane z = 0, as rounded along the ray), in its middle and near its
    // rim, in both orders of the meshes: they must still be one interface from B into A (the closed
    // form of the touching slabs above), and a ray that misses B crosses A alone.
    const double hA = 0.4, hB = 0.5;
    const Mesh a = test::makeBox({-5, -5, -hA}, {5, 5, 0}), b = test::makeBox({-1, -1, 0}, {1, 1, hB});
    const Mesh c = test::makeBox({20, 20, -1}, {21, 21, 1});
    const GlassMedium A = nestedMedium(1.5, 0.3), B = nestedMedium(1.9, 1.0), C = nestedMedium(1.3, 0.1);
    for (const bool swapped : {false, true}) {
        TwoMedia t = swapped ? nest(b, a) : nest(a, b); // B is medium 0 when swapped
        const auto base = uint32_t(t.mesh.positions.size());
        t.mesh.positions.insert(t.mesh.positions.end(), c.positions.begin(), c.positions.end());
        for (const uint32_t i : c.indices) t.mesh.indices.push_back(base + i);
        t.medium.resize(t.mesh.triangleCount(), 2);
        const std::vector<GlassMedium> media = swapped ? std::vector{B, A, C} : std::vector{A, B, C};
        const ExactGlass glass(t.mesh.view(), {}, t.medium, media);
        for (const double angle : {0.3, 0.7}) {
            const Vec3d d = nestedDirAt(angle);
            const double tA = std::asin(std::sin(angle) / 1.5), tB = std::asin(std::sin(angle) / 1.9);
            // Where the ray crosses z = 0: B's middle, and near its rim.
            for (const double cross : {0.0, 1 - 1e-3}) {
                const Vec3d entry{cross - hB * std::tan(tB), 0.3, hB};
                const GlassPath p = glass.trace(entry - d * 2.0, d, 16);
                ASSERT_TRUE(p.hit);
                EXPECT_EQ(p.events, 3) << angle << " " << cross << " " << swapped;
                EXPECT_NEAR(length(p.exitDir - d), 0, 1e-5) << angle << " " << cross;
                const Vec3d exitPoint{cross + hA * std::tan(tA), 0.3, -hA};
                EXPECT_NEAR(length(p.exitPoint - exitPoint), 0, 1e-4)
                    << angle << " " << cross << " " << swapped;
                const double fresnel = (1 - fresnelDielectric(std::cos(angle), 1, 1.9)) *
                                       (1 - fresnelDielectric(std::cos(tB), 1.9, 1.5)) *
                                       (1 - fresnelDielectric(std::cos(tA), 1.5, 1));
                const double want = fresnel * std::exp(-1.0 * hB / std::cos(tB) - 0.3 * hA / std::cos(tA));
                EXPECT_NEAR(p.throughput.x, want, 1e-4) << angle << " " << cross << " " << swapped;
            }
            // Past B's side: A alone (two events, A's Fresnel and absorption).
            const Vec3d entry{2.5, 0.3, 0};
            const GlassPath p = glass.trace(entry - d * 2.0, d, 16);
            ASSERT_TRUE(p.hit);
            EXPECT_EQ(p.events, 2) << angle << " " << swapped;
            const double want = (1 - fresnelDielectric(std::cos(angle), 1, 1.5)) *
                                (1 - fresnelDielectric(std::cos(tA), 1.5, 1)) *
                                std::exp(-0.3 * hA / std::cos(tA));
            EXPECT_NEAR(p.throughput.x, want, 1e-4) << angle << " " << swapped;
        }
    }
}

TEST(NestedGlassTest, ExactTracerFindsATouchingFaceWhereverItLiesInTheMediumsCoarseGrid) {
    // The tracer queries another medium's faces at a crossing only where that medium's coarse
    // occupancy grid (64 cells along its bounds' longest side) holds one of its triangles. Medium B is
    // a block (|x|, |y| <= 1, 0 <= z <= hB) whose bottom is 16 x 16 squares of 2 triangles each,
    // standing on a wide slab A (-hA <= z <= 0), and a far block of B (20..21, 5..6, -1..1) that
    // stretches B's grid unevenly along x, y and z (cells of about 0.34, most of them clear). Crossings
    // of z = 0 at 84 points over the block's bottom (across its triangles and the grid's cells) must
    // each be one interface from B into A (the touching slabs' closed form); crossings of A's top in
    // B's bounds but clear cells cross A alone.
    const double hA = 0.4, hB = 0.5;
    const Mesh a = test::makeBox({-5, -5, -hA}, {5, 5, 0});
    Mesh b = test::makeBox({-1, -1, 0}, {1, 1, hB});
    {
        std::vector<uint32_t> kept; // the box's walls and top; its bottom tessellated below
        for (size_t t = 0; t < b.triangleCount(); ++t) {
            bool bottom = true;
            for (int k = 0; k < 3; ++k) bottom = bottom && b.positions[b.indices[3 * t + size_t(k)]].z == 0;
            if (bottom) continue;
            for (int k = 0; k < 3; ++k) kept.push_back(b.indices[3 * t + size_t(k)]);
        }
        b.indices = kept;
        constexpr int n = 16;
        const auto base = uint32_t(b.positions.size());
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i)
                b.positions.push_back({float(-1 + 2.0 * i / n), float(-1 + 2.0 * j / n), 0.0f});
        const auto at = [&](int i, int j) { return base + uint32_t(j * (n + 1) + i); };
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) // facing -z (outward, counter-clockwise seen from below)
                for (const uint32_t v :
                     {at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i + 1, j)})
                    b.indices.push_back(v);
    }
    const Mesh far = test::makeBox({20, 5, -1}, {21, 6, 1});
    TwoMedia t = nest(a, b);
    const auto base = uint32_t(t.mesh.positions.size());
    t.mesh.positions.insert(t.mesh.positions.end(), far.positions.begin(), far.positions.end());
    for (const uint32_t i : far.indices) t.mesh.indices.push_back(base + i);
    t.medium.resize(t.mesh.triangleCount(), 1);
    const GlassMedium A = nestedMedium(1.5, 0.3), B = nestedMedium(1.9, 1.0);
    const ExactGlass glass(t.mesh.view(), {}, t.medium, {A, B});
    const double angle = 0.5;
    const Vec3d d = nestedDirAt(angle);
    const double tA = std::asin(std::sin(angle) / 1.5), tB = std::asin(std::sin(angle) / 1.9);
    const double fresnel = (1 - fresnelDielectric(std::cos(angle), 1, 1.9)) *
                           (1 - fresnelDielectric(std::cos(tB), 1.9, 1.5)) *
                           (1 - fresnelDielectric(std::cos(tA), 1.5, 1));
    const double want = fresnel * std::exp(-1.0 * hB / std::cos(tB) - 0.3 * hA / std::cos(tA));
    int crossings = 0;
    for (int k = 0; k <= 20; ++k)
        for (const double y : {-0.93, -0.31, 0.3, 0.77}) {
            const double cross = -0.85 + 0.09 * k; // where the ray crosses z = 0 (entering B's top)
            const Vec3d entry{cross - hB * std::tan(tB), y, hB};
            const GlassPath p = glass.trace(entry - d * 2.0, d, 16);
            ASSERT_TRUE(p.hit);
            EXPECT_EQ(p.events, 3) << cross << " " << y;
            const Vec3d exitPoint{cross + hA * std::tan(tA), y, -hA};
            EXPECT_NEAR(length(p.exitPoint - exitPoint), 0, 1e-4) << cross << " " << y;
            EXPECT_NEAR(p.throughput.x, want, 1e-4) << cross << " " << y;
            ++crossings;
        }
    EXPECT_EQ(crossings, 84);
    for (const Vec3d entry : {Vec3d{3, 3, 0}, Vec3d{4, 4.5, 0}, Vec3d{2.5, -0.5, 0}}) {
        const GlassPath p = glass.trace(entry - d * 2.0, d, 16);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 2) << entry.x << " " << entry.y;
        const double alone = (1 - fresnelDielectric(std::cos(angle), 1, 1.5)) *
                             (1 - fresnelDielectric(std::cos(tA), 1.5, 1)) *
                             std::exp(-0.3 * hA / std::cos(tA));
        EXPECT_NEAR(p.throughput.x, alone, 1e-4) << entry.x << " " << entry.y;
    }
}

// The exit direction of a ray along -x at height b through concentric spheres as a tracer that
// treats every interface as glass against air would give it (what both tracers did before media
// were tracked): into B with 1 / nB, out of B into "air", A's far side then passed as a back face
// seen from outside.
double glassAgainstAirDeviation(double b, double R, double r, double nA, double nB) {
    const double t1 = std::asin(b / R), t2 = std::asin(b / (nA * R));
    const double phi = std::asin(b / (nA * r)), phiB = std::asin(std::sin(phi) / nB);
    return (t1 - t2) + 2 * (phi - phiB);
}

TEST(NestedGlassTest, VoxelMarchFollowsTheMediaThroughConcentricSpheres) {
    // The voxel march (multi) through concentric spheres against the closed form: the exit direction
    // within 0.05 rad and within a quarter of the way to what glass against air (the march before
    // material-id transitions) gives, the attenuation within 5 %.
    const double R = 1, r = 0.5;
    TwoMedia s = nest(test::makeUvSphere({0, 0, 0}, R, 96, 192), test::makeUvSphere({0, 0, 0}, r, 64, 128));
    const GlassMedium A = nestedMedium(1.5, 0.4), B = nestedMedium(2.0, 1.5);
    VoxelGlassOptions o;
    o.gridResolution = 128;
    const VoxelGlass glass(s.mesh.view(), s.medium, {A, B}, o);
    for (const double b : {0.1, 0.3, 0.5, 0.65}) {
        const SpherePath want = concentricClosedForm(b, R, r, A, B);
        const Vec3d entry{std::sqrt(R * R - b * b), b, 0};
        const GlassPath p = glass.trace(entry, entry / R, 0, {-1, 0, 0}, o, false);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 4) << b;
        const double deviation = std::atan2(-p.exitDir.y, -p.exitDir.x);
        EXPECT_NEAR(deviation, want.deviation, 0.05) << b;
        const double air = glassAgainstAirDeviation(b, R, r, 1.5, 2.0);
        EXPECT_LT(std::abs(deviation - want.deviation), 0.25 * std::abs(air - want.deviation)) << b;
        EXPECT_NEAR(p.exitDir.z, 0, 0.01) << b;
        EXPECT_NEAR(p.throughput.x, want.throughput, 0.05 * want.throughput) << b;
    }
}

// Concentric spheres made as touching objects: a shell of A (the outer sphere, and the inner one
// facing inwards) and a core of B whose sphere lies on the shell's inner one, face on face. The
// optics are those of the nested spheres (the closed form above); the inner sphere is now a curved
// face between two touching media, which the voxel march sees only through the material ids of the
// voxels both wrote (their normals cancel). Tints 1: a medium re-entered across a touching face
// applies its tint again, where a nested one is never left.
TEST(NestedGlassTest, BothTracersCrossACoreTouchingItsShellAsTheConcentricClosedForm) {
    const double R = 1, r = 0.5;
    const GlassMedium A = nestedMedium(1.5, 0.4), B = nestedMedium(2.0, 1.5);
    auto shellAndCore = [&](int rings, int segments) {
        const Mesh outer = test::makeUvSphere({0, 0, 0}, R, rings, segments);
        Mesh inner = test::makeUvSphere({0, 0, 0}, r, rings, segments);
        TwoMedia t = nest(outer, inner); // A: outer and inner faces; B below gets its own inner
        for (std::size_t k = outer.indices.size(); k < t.mesh.indices.size(); k += 3)
            std::swap(t.mesh.indices[k + 1], t.mesh.indices[k + 2]); // the shell's inner sphere faces inwards
        t.medium.assign(t.mesh.triangleCount(), 0);
        const auto base = uint32_t(t.mesh.positions.size());
        t.mesh.positions.insert(t.mesh.positions.end(), inner.positions.begin(), inner.positions.end());
        for (const uint32_t i : inner.indices) t.mesh.indices.push_back(base + i);
        t.medium.resize(t.mesh.triangleCount(), 1);
        for (const Vec3f& p : t.mesh.positions) t.normals.push_back(Vec3f(normalize(Vec3d(p))));
        return t;
    };
    const TwoMedia fine = shellAndCore(128, 256);
    const ExactGlass exact(fine.mesh.view(), fine.normals, fine.medium, {A, B});
    const TwoMedia s = shellAndCore(64, 128);
    VoxelGlassOptions o;
    o.gridResolution = 128;
    const VoxelGlass glass(s.mesh.view(), s.medium, {A, B}, o);
    for (const double b : {0.1, 0.3, 0.5, 0.65}) {
        const SpherePath want = concentricClosedForm(b, R, r, A, B);
        const GlassPath e = exact.trace({5, b, 0}, {-1, 0, 0}, 16);
        ASSERT_TRUE(e.hit);
        EXPECT_EQ(e.events, 4) << b;
        EXPECT_NEAR(std::atan2(-e.exitDir.y, -e.exitDir.x), want.deviation, 3e-3) << b;
        EXPECT_NEAR(e.throughput.x, want.throughput, 3e-3) << b;
        const Vec3d entry{std::sqrt(R * R - b * b), b, 0};
        const GlassPath p = glass.trace(entry, entry / R, 0, {-1, 0, 0}, o, false);
        ASSERT_TRUE(p.hit);
        EXPECT_EQ(p.events, 4) << b;
        const double deviation = std::atan2(-p.exitDir.y, -p.exitDir.x);
        EXPECT_NEAR(deviation, want.deviation, 0.05) << b;
        EXPECT_NEAR(p.exitDir.z, 0, 0.01) << b;
        EXPECT_NEAR(p.throughput.x, want.throughput, 0.05 * want.throughput) << b;
    }
}

// The two touching slabs with the voxel march, against the closed form (as the exact tracer's test
// above). The coincident faces write the same voxels and their normals cancel, as a sheet thinner
// than a voxel does, but they are one face between two media, not a sheet of either: the march must
// cross it from one medium into the other, bending by n_from / n_to and attenuating each slab with
// its own coefficient, from above and from below, for either order of the two meshes (which
// material a shared voxel records first must not matter). Before the march saw that face it kept
// the first medium through both slabs: 2 events, the exit 0.06 units (4 voxels at 128) off along x
// at 0.9 rad, and the throughput off by the lower slab's coefficient.
TEST(NestedGlassTest, VoxelMarchCrossesTouchingGlassesAtTheClosedFormInterface) {
    const double hA = 0.4, hB = 0.5, sA = 0.3, sB = 1.0;
    const GlassMedium A = nestedMedium(1.5, sA), B = nestedMedium(1.9, sB);
    const Mesh boxA = test::makeBox({-1, -1, -hA}, {1, 1, 0}), boxB = test::makeBox({-1, -1, 0}, {1, 1, hB});
    for (const bool swapped : {false, true}) {
        const TwoMedia s = swapped ? nest(boxB, boxA) : nest(boxA, boxB);
        const std::vector<GlassMedium> media = swapped ? std::vector{B, A} : std::vector{A, B};
        const uint32_t idA = swapped ? 1 : 0, idB = swapped ? 0 : 1;
        for (const int64_t res : {32, 64, 128}) {
            VoxelGlassOptions o;
            o.gridResolution = res;
            const VoxelGlass glass(s.mesh.view(), s.medium, media, o);
            for (const bool down : {true, false}) {
                // Down: into B from above, out of A below; up: the mirror image.
                const double h1 = down ? hB : hA, h2 = down ? hA : hB, n1 = down ? 1.9 : 1.5,
                             n2 = down ? 1.5 : 1.9, s1 = down ? sB : sA, s2 = down ? sA : sB;
                for (const double a : {0.0, 0.4, 0.9}) {
                    const Vec3d d = down ? nestedDirAt(a) : Vec3d{std::sin(a), 0, std::cos(a)};
                    const Vec3d entry{0.2 - 0.3 * std::sin(a), -0.1, down ? hB : -hA};
                    const GlassPath p =
                        glass.trace(entry, {0, 0, down ? 1.0 : -1.0}, down ? idB : idA, d, o, false);
                    const std::string at = std::to_string(res) + (swapped ? " swapped " : " ") +
                                           (down ? "down " : "up ") + std::to_string(a);
                    ASSERT_TRUE(p.hit) << at;
                    EXPECT_EQ(p.events, 3) << at;
                    EXPECT_NEAR(length(p.exitDir - d), 0, 0.02) << at;
                    const double t1 = std::asin(std::sin(a) / n1), t2 = std::asin(std::sin(a) / n2);
                    // Where the ray leaves the far face (the march reports the start of its exit
                    // voxel: within about a voxel of it along the ray).
                    const double shift = h1 * std::tan(t1) + h2 * std::tan(t2);
                    const Vec3d exitPoint = entry + Vec3d{shift, 0, (down ? -1 : 1) * (h1 + h2)};
                    EXPECT_NEAR(p.exitPoint.x, exitPoint.x, 1.5 * glass.voxelSize()) << at;
                    EXPECT_NEAR(p.exitPoint.z, exitPoint.z, 1.5 * glass.voxelSize()) << at;
                    const double fresnel = (1 - fresnelDielectric(std::cos(a), 1, n1)) *
                                           (1 - fresnelDielectric(std::cos(t1), n1, n2)) *
                                           (1 - fresnelDielectric(std::cos(t2), n2, 1));
                    const double want = fresnel * std::exp(-s1 * h1 / std::cos(t1) - s2 * h2 / std::cos(t2));
                    EXPECT_NEAR(p.throughput.x, want, 0.05 * want) << at;
                }
            }
        }
    }
}

// The glass pixels of `s` from `cam` (96x72, no shadows): multi at 128³ against the exact tracer.
ImageError multiAgainstExact(const Scene& s, const Camera& cam, const char* what) {
    RenderOptions o;
    o.width = 96;
    o.height = 72;
    o.shadow = NoShadowOptions{};
    o.glass = ExactGlassOptions{};
    const RenderResult exact = render(s, cam, o);
    int64_t glassPixels = 0;
    for (const uint8_t m : exact.glassMask) glassPixels += m;
    EXPECT_GT(glassPixels, 1000) << what;
    MultiGlassOptions multi;
    multi.gridResolution = 128;
    o.glass = multi;
    const ImageError e = imageError(render(s, cam, o).image, exact.image, exact.glassMask);
    std::printf("%s, multi 128 against exact: MAE %.4f, PSNR %.2f dB over %lld pixels\n", what, e.mae, e.psnr,
                (long long)e.pixels);
    return e;
}

// A glass ball with a core of another glass (CHANG fig. 3's angel in a ball, as spheres) over a
// ground, the camera looking at it.
Scene nestedBallScene() {
    Scene s = greyGroundScene();
    Material ball;
    ball.transmission = 1;
    ball.ior = 1.5f;
    ball.attenuationColor = {0.9f, 0.95f, 0.9f};
    ball.attenuationDistance = 1;
    Material core = ball;
    core.ior = 2.2f;
    core.attenuationColor = {0.9f, 0.4f, 0.1f};
    core.attenuationDistance = 0.3f;
    const uint32_t b = s.addMaterial(ball), c = s.addMaterial(core);
    SceneMesh outer;
    outer.mesh = test::makeUvSphere({0, 0.8, 0}, 0.7, 48, 96);
    outer.material = b;
    s.meshes.push_back(outer);
    SceneMesh inner;
    inner.mesh = test::makeUvSphere({0.05, 0.8, 0}, 0.35, 32, 64);
    inner.material = c;
    s.meshes.push_back(inner);
    Camera cam;
    cam.position = {0, 1.5, 4};
    cam.target = {0, 0.7, 0};
    cam.fovY = 0.5;
    s.cameras.push_back(cam);
    return s;
}

TEST(NestedGlassTest, VoxelGlassRendersANestedBallCloseToTheExactTracer) {
    const Scene s = nestedBallScene();
    const ImageError e = multiAgainstExact(s, s.cameras[0], "nested ball");
    EXPECT_LT(e.mae, 0.035);
    EXPECT_GT(e.psnr, 19);
}

// Two boxes of different glass stacked face to face (the glass demo's block, with indices 1.5 and
// 1.9 so that rays bend at the shared face) over a ground, seen from above at an angle: multi against
// the exact tracer over the glass pixels. Multi measured MAE 0.0020 / PSNR 37.6 dB; before it saw the
// shared face, MAE 0.0256 / PSNR 23.8 dB.
TEST(NestedGlassTest, VoxelGlassRendersTouchingGlassesCloseToTheExactTracer) {
    Scene s = greyGroundScene();
    Material lower;
    lower.transmission = 1;
    lower.ior = 1.5f;
    lower.attenuationColor = {0.95f, 0.7f, 0.3f};
    lower.attenuationDistance = 0.5f;
    Material upper = lower;
    upper.ior = 1.9f;
    upper.attenuationColor = {0.3f, 0.6f, 0.95f};
    const uint32_t a = s.addMaterial(lower), b = s.addMaterial(upper);
    SceneMesh bottom, top;
    bottom.mesh = test::makeBox({-0.6, 0, -0.4}, {0.6, 0.5, 0.4});
    bottom.material = a;
    top.mesh = test::makeBox({-0.6, 0.5, -0.4}, {0.6, 1.1, 0.4});
    top.material = b;
    s.meshes.push_back(bottom);
    s.meshes.push_back(top);
    Camera cam;
    cam.position = {1.6, 2.2, 3};
    cam.target = {0, 0.5, 0};
    cam.fovY = 0.5;
    const ImageError e = multiAgainstExact(s, cam, "touching boxes");
    EXPECT_LT(e.mae, 0.008);
    EXPECT_GT(e.psnr, 30);
}

// #37: an object of the ball's own material inside it, or the ball made of two parts, is no
// interface: the light crosses the same medium on both sides of those faces. The exact tracer and
// multi must render the scene as the ball alone (multi showed the inner object's outline as noisy
// rings, 0.018 mean difference in linear radiance). Cases: a nested sphere of the same material;
// a sphere of it overlapping the ball's inside; a box made of two boxes of one glass touching face to
// face, against the one box. Mean absolute difference over the glass pixels, linear (clamp).
double sameMediumDifference(const Scene& with, const Scene& without, const GlassOptions& method) {
    RenderOptions o;
    o.width = 96;
    o.height = 72;
    o.shadow = NoShadowOptions{};
    o.toneMap = ToneMap::Clamp;
    o.antiAliasing = AntiAliasing::Off;
    o.glass = method;
    const RenderResult a = render(with, with.cameras[0], o), b = render(without, without.cameras[0], o);
    double sum = 0;
    int64_t n = 0;
    for (size_t i = 0; i < a.image.pixels.size(); ++i) {
        if (!(a.glassMask[i] || b.glassMask[i])) continue;
        for (int c = 0; c < 3; ++c)
            sum += std::abs(double(a.image.pixels[i][c]) - double(b.image.pixels[i][c]));
        ++n;
    }
    EXPECT_GT(n, 800);
    return sum / double(3 * n);
}

TEST(NestedGlassTest, AnObjectOfTheBallsOwnGlassInsideItIsNoInterface) {
    const Scene nested = nestedBallScene();
    Scene ballAlone = nested;
    ballAlone.meshes.pop_back();
    Scene sameCore = nested;
    sameCore.meshes.back().material = sameCore.meshes[1].material; // the core of the ball's glass
    Scene overlapping = sameCore; // a sphere of the ball's glass inside it, touching nothing
    overlapping.meshes.back().mesh = test::makeUvSphere({0.2, 0.9, 0.1}, 0.3, 32, 64);
    // A box of one glass, and the same box as two boxes of it stacked face to face.
    Scene box = ballAlone;
    box.meshes.back().mesh = test::makeBox({-0.5, 0, -0.4}, {0.5, 1.1, 0.4});
    Scene twoBoxes = box;
    twoBoxes.meshes.back().mesh = test::makeBox({-0.5, 0, -0.4}, {0.5, 0.5, 0.4});
    twoBoxes.meshes.push_back(twoBoxes.meshes.back());
    twoBoxes.meshes.back().mesh = test::makeBox({-0.5, 0.5, -0.4}, {0.5, 1.1, 0.4});
    MultiGlassOptions multi;
    multi.gridResolution = 128;
    for (const GlassOptions method : {GlassOptions(ExactGlassOptions{}), GlassOptions(multi)}) {
        const std::string name(glassName(method));
        const double dNested = sameMediumDifference(sameCore, ballAlone, method);
        const double dOverlap = sameMediumDifference(overlapping, ballAlone, method);
        const double dBoxes = sameMediumDifference(twoBoxes, box, method);
        std::printf("%s: same-medium difference nested %.4f, inside %.4f, two boxes %.4f\n", name.c_str(),
                    dNested, dOverlap, dBoxes);
        EXPECT_LT(dNested, 0.002) << name;
        EXPECT_LT(dOverlap, 0.002) << name;
        EXPECT_LT(dBoxes, 0.002) << name;
    }
    // The core of another glass does show (the test can tell).
    EXPECT_GT(sameMediumDifference(nested, ballAlone, multi), 0.01);
}

TEST(NestedGlassTest, GlassDemoHoldsAnObjectOfOneGlassInsideAnother) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Scene s = demo::makeGlassScene(test::dataPath("meshes"));
    const SceneMesh *ball = nullptr, *inside = nullptr;
    for (const SceneMesh& m : s.meshes) {
        if (m.name == "Ball") ball = &m;
        if (m.name == "Bunny-in-ball") inside = &m;
    }
    ASSERT_TRUE(ball && inside);
    const Material &outer = s.materials[ball->material], &inner = s.materials[inside->material];
    EXPECT_TRUE(outer.isGlass() && inner.isGlass());
    EXPECT_NE(outer.ior, inner.ior);
    // Every vertex of the inner object strictly inside the ball (its centre and radius from its bounds).
    const Box3d b = computeBounds(ball->mesh.view());
    const double radius = 0.5 * b.extent().y;
    for (const Vec3f& p : inside->mesh.positions) ASSERT_LT(length(Vec3d(p) - b.center()), 0.9 * radius);
    ASSERT_GE(s.cameras.size(), 2u); // the second camera looks at the ball
}

} // namespace
} // namespace voxfx
