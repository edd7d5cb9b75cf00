// voxfx — exact point occupancy (voxfx/contains.hpp) against CGAL.
//
// Oracles:
//   - off the surface: CGAL::Side_of_triangle_mesh (exact predicates) on closed real meshes;
//   - on the surface (vertices, edge midpoints, points inside faces, exactly on the mesh as
//     CGAL confirms with ON_BOUNDARY): the documented rule says the answer is the inside test at
//     p + (eps, eps^2, -delta), 0 < eps << delta; CGAL decides that point exactly with rational
//     coordinates (Epeck) and eps, delta far below the mesh's feature size;
//   - the voxelizer itself as a property: at voxel centres contains() must give the solid
//     voxelization's bits (the same tie rule), including centres exactly on faces, edges, vertices;
//   - the exact predicates against CGAL::orientation on nearly degenerate inputs.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

/// Random points in the mesh's bounds grown by 10% on every side.
std::vector<Vec3d> containsRandomPoints(const MeshView& mesh, std::size_t n, uint64_t seed) {
    Box3d b = computeBounds(mesh);
    const Vec3d grow = b.extent() * 0.1;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Vec3d> pts(n);
    for (Vec3d& p : pts)
        for (int k = 0; k < 3; ++k) p[k] = b.lo[k] - grow[k] + u(rng) * (b.extent()[k] + 2 * grow[k]);
    return pts;
}

/// The closed real meshes the tests use (small, so the CGAL oracles stay fast).
const char* const kContainsMeshes[] = {"meshes/elephant.off", "meshes/knot.off", "meshes/cube-meshed.off",
                                       "meshes/cross.off", "meshes/pinion.off"};

TEST(Contains, ParityMatchesCgalSideOfMeshOnRandomPoints) {
    for (const char* name : kContainsMeshes) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const std::vector<Vec3d> pts = containsRandomPoints(mesh.view(), 20000, 7);
        const std::vector<int> side = test::sideOfClosedMesh(mesh.view(), pts);
        ASSERT_EQ(side.size(), pts.size()) << name << " is not a closed manifold";
        for (const int64_t resolution : {int64_t(0), int64_t(16), int64_t(97)}) {
            ContainsOptions o;
            o.resolution = resolution;
            const PointClassifier classifier(mesh.view(), o);
            std::vector<uint8_t> got(pts.size());
            ContainsStats stats;
            classifier.classify(pts, got, &stats);
            int64_t wrong = 0, inside = 0;
            for (std::size_t i = 0; i < pts.size(); ++i) {
                if (side[i] == 0) continue; // on the boundary
                const bool expected = side[i] > 0;
                inside += expected;
                if (bool(got[i]) != expected && wrong++ < 5)
                    ADD_FAILURE() << name << " resolution " << resolution << ": point (" << pts[i].x << ", "
                                  << pts[i].y << ", " << pts[i].z << ") expected " << expected;
            }
            EXPECT_EQ(wrong, 0) << name;
            EXPECT_GT(inside, 0) << name;
            // Both paths were taken: cells away from the surface and exact decisions.
            EXPECT_GT(stats.fromCells, 0) << name;
            EXPECT_GT(stats.exact, 0) << name;
            EXPECT_EQ(stats.fromCells + stats.exact, int64_t(pts.size()));
        }
    }
}

/// Points exactly on the mesh: vertices, edge midpoints and points inside faces, kept when CGAL
/// says ON_BOUNDARY (exactly on the surface).
std::vector<Vec3d> containsSurfacePoints(const Mesh& mesh, std::size_t maxTriangles) {
    std::vector<Vec3d> pts;
    const MeshView v = mesh.view();
    const std::size_t step = std::max<std::size_t>(1, v.triangleCount / maxTriangles);
    for (std::size_t t = 0; t < v.triangleCount; t += step) {
        const Vec3d a = v.vertex(v.index(t, 0)), b = v.vertex(v.index(t, 1)), c = v.vertex(v.index(t, 2));
        pts.push_back(a);
        pts.push_back(a + (b - a) * 0.5);
        pts.push_back(b + (c - b) * 0.5);
        pts.push_back(a + (b - a) * 0.25 + (c - a) * 0.25);
        pts.push_back(a + (b - a) * 0.5 + (c - a) * 0.25);
    }
    return pts;
}

TEST(Contains, ParityOnVerticesEdgesAndFacesFollowsTheTieRule) {
    // Exact constructions are slow: the smaller meshes, ~150 triangles' points each.
    for (const char* name : {"meshes/cube-meshed.off", "meshes/cross.off", "meshes/pinion.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const std::vector<Vec3d> candidates = containsSurfacePoints(mesh, 150);
        const std::vector<int> side = test::sideOfClosedMesh(mesh.view(), candidates);
        ASSERT_EQ(side.size(), candidates.size()) << name << " is not a closed manifold";
        std::vector<Vec3d> pts;
        for (std::size_t i = 0; i < candidates.size(); ++i)
            if (side[i] == 0) pts.push_back(candidates[i]); // exactly on the surface
        ASSERT_GT(pts.size(), 200u) << name;
        const std::vector<uint8_t> got = contains(mesh.view(), pts);
        // The exact side of each point moved off the surface by the tie rule's perturbation.
        const std::vector<int> perturbed = test::sideOfClosedMeshPerturbed(mesh.view(), pts);
        ASSERT_EQ(perturbed.size(), pts.size()) << name;
        int64_t wrong = 0, inside = 0;
        for (std::size_t i = 0; i < pts.size(); ++i) {
            ASSERT_NE(perturbed[i], 0) << name << ": the perturbation is too small";
            const bool expected = perturbed[i] > 0;
            inside += expected;
            if (bool(got[i]) != expected && wrong++ < 5)
                ADD_FAILURE() << name << ": surface point (" << pts[i].x << ", " << pts[i].y << ", "
                              << pts[i].z << ") expected " << expected;
        }
        EXPECT_EQ(wrong, 0) << name << " (" << pts.size() << " points on the surface)";
        // Both answers occur on the surface (points on top faces are inside, on bottom ones outside).
        EXPECT_GT(inside, 0) << name;
        EXPECT_LT(inside, int64_t(pts.size())) << name;
    }
}

/// contains() at every voxel centre of a solid voxelization gives the voxelizer's bits.
void expectContainsEqualsVoxelCentres(const Mesh& mesh, const Frame& frame, const std::string& what) {
    VoxelizeOptions vo;
    vo.fill = Fill::Parity;
    const VoxelGrid solid = voxelize(mesh.view(), frame, vo);
    const test::CellGeometry g = test::CellGeometry::of(solid);
    std::vector<Vec3d> centres;
    for (int64_t k = 0; k < g.dims.z; ++k)
        for (int64_t j = 0; j < g.dims.y; ++j)
            for (int64_t i = 0; i < g.dims.x; ++i) centres.push_back(frame.cellCenter(i, j, k));
    const std::vector<uint8_t> got = contains(mesh.view(), centres);
    int64_t wrong = 0, filled = 0;
    std::size_t n = 0;
    for (int64_t k = 0; k < g.dims.z; ++k)
        for (int64_t j = 0; j < g.dims.y; ++j)
            for (int64_t i = 0; i < g.dims.x; ++i, ++n) {
                const bool expected = solid.atWorldIndex(i, j, k);
                filled += expected;
                if (bool(got[n]) != expected && wrong++ < 5)
                    ADD_FAILURE() << what << ": centre of voxel (" << i << ", " << j << ", " << k
                                  << ") expected " << expected;
            }
    EXPECT_EQ(wrong, 0) << what;
    EXPECT_GT(filled, 0) << what;
}

TEST(Contains, AtVoxelCentresEqualsTheSolidVoxelization) {
    // Centres exactly on faces, edges and vertices: boxes and an octahedron on the half-integer
    // lattice of a unit-cell grid.
    Mesh boxes;
    test::appendBox(boxes, {0.5, 0.5, 0.5}, {3.5, 2.5, 4.5});
    test::appendBox(boxes, {4.5, 1.5, 1.0}, {6.5, 5.5, 3.5});
    const Mesh octa = test::makeOctahedron({3.5, 3.5, 3.5}, 2.0);
    Box3d box;
    box.lo = {0, 0, 0};
    box.hi = {8, 8, 8};
    expectContainsEqualsVoxelCentres(boxes, Frame::orthographic(box, Axis::Z, 8, 8, 8), "boxes");
    expectContainsEqualsVoxelCentres(octa, Frame::orthographic(box, Axis::Z, 8, 8, 8), "octahedron");
    for (const char* name : {"meshes/cube-meshed.off", "meshes/elephant.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        FitOptions fo;
        fo.resolution = 24;
        expectContainsEqualsVoxelCentres(mesh, fitFrame(computeBounds(mesh.view()), fo), name);
    }
}

TEST(Contains, WindingAndFloodOnAClosedMeshAgreeWithCgal) {
    const char* name = "meshes/knot.off";
    VOXFX_REQUIRE_DATA(name);
    const Mesh mesh = loadMesh(test::dataPath(name));
    const std::vector<Vec3d> pts = containsRandomPoints(mesh.view(), 2000, 11);
    const std::vector<int> side = test::sideOfClosedMesh(mesh.view(), pts);
    ASSERT_EQ(side.size(), pts.size()) << name << " is not a closed manifold";
    ContainsOptions wo;
    wo.method = ContainsMethod::Winding;
    const std::vector<uint8_t> winding = contains(mesh.view(), pts, wo);
    ContainsOptions fo;
    fo.method = ContainsMethod::Flood;
    fo.resolution = 64;
    const std::vector<uint8_t> flood = contains(mesh.view(), pts, fo);
    int64_t windingWrong = 0, floodMissing = 0, floodExtra = 0, inside = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const bool expected = side[i] > 0;
        inside += expected;
        windingWrong += bool(winding[i]) != expected;
        floodMissing += expected && !flood[i];
        floodExtra += !expected && flood[i];
    }
    EXPECT_GT(inside, 50);
    // The winding number of a closed mesh is exactly 1 or 0 away from the surface; the summation
    // is accurate to far better than 0.5.
    EXPECT_EQ(windingWrong, 0);
    // Flood includes the surface cells: every inside point is inside, and the extra ones lie in
    // cells the surface touches (a thin shell, well under a tenth of the points here).
    EXPECT_EQ(floodMissing, 0);
    EXPECT_LT(floodExtra, int64_t(pts.size()) / 10);
}

// Three of CGAL's closed meshes are oriented inward throughout (negative signed volume), and a
// flipped bunny is too: the winding number is -1 inside them, which |w| >= 0.5 takes as inside.
// Oracle: CGAL::Side_of_triangle_mesh, which counts ray crossings and ignores orientation.
TEST(Contains, WindingFindsTheInsideOfMeshesOrientedInward) {
    for (const char* name :
         {"meshes/beam.off", "meshes/tetrahedron.off", "meshes/ellipe0.003.off", "meshes/bunny00.off"}) {
        VOXFX_REQUIRE_DATA(name);
        Mesh mesh = loadMesh(test::dataPath(name));
        if (test::meshVolume(mesh.view()) > 0) mesh = test::flippedMesh(mesh);
        ASSERT_LT(test::meshVolume(mesh.view()), 0) << name;
        const std::vector<Vec3d> pts = containsRandomPoints(mesh.view(), 2000, 13);
        const std::vector<int> side = test::sideOfClosedMesh(mesh.view(), pts);
        ASSERT_EQ(side.size(), pts.size()) << name << " is not a closed manifold";
        ContainsOptions o;
        o.method = ContainsMethod::Winding;
        const std::vector<uint8_t> got = contains(mesh.view(), pts, o);
        const PointClassifier classifier(mesh.view(), o);
        int64_t inside = 0, wrong = 0, wrongOne = 0;
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (side[i] == 0) continue;
            inside += side[i] > 0;
            wrong += bool(got[i]) != (side[i] > 0);
            wrongOne += classifier.inside(pts[i]) != (side[i] > 0);
        }
        EXPECT_GT(inside, 100) << name;
        EXPECT_EQ(wrong, 0) << name;
        EXPECT_EQ(wrongOne, 0) << name;
    }
}

TEST(Contains, WindingNumberOfAnOpenMeshIsFractionalNearItsHole) {
    // A unit box with its top face removed: the winding number at the centre is 1 minus the top
    // face's share (1/6 of the full sphere, by symmetry), so still inside at 0.5.
    Mesh box;
    test::appendBox(box, {0, 0, 0}, {1, 1, 1});
    Mesh open;
    open.positions = box.positions;
    const MeshView v = box.view();
    for (std::size_t t = 0; t < v.triangleCount; ++t) {
        bool top = true;
        for (int c = 0; c < 3; ++c) top = top && v.vertex(v.index(t, c)).z == 1.0;
        if (!top)
            for (int c = 0; c < 3; ++c) open.indices.push_back(v.index(t, c));
    }
    ASSERT_EQ(open.triangleCount(), 10u);
    EXPECT_NEAR(windingNumber(box.view(), {0.5, 0.5, 0.5}), 1.0, 1e-12);
    EXPECT_NEAR(windingNumber(open.view(), {0.5, 0.5, 0.5}), 5.0 / 6.0, 1e-12);
    ContainsOptions o;
    o.method = ContainsMethod::Winding;
    const std::vector<Vec3d> pts = {{0.5, 0.5, 0.5}, {0.5, 0.5, 1.5}, {2, 2, 2}};
    const std::vector<uint8_t> got = contains(open.view(), pts, o);
    EXPECT_EQ(got, (std::vector<uint8_t>{1, 0, 0}));
}

TEST(Contains, FastWindingNumbersStayCloseToTheExactSum) {
    // Barill et al.'s approximation (first order: dipoles) against the exact sum over every
    // triangle, on an open mesh (holes: fractional winding numbers) and a closed one, at random
    // points around them. The error falls as the clusters kept exact grow (beta).
    for (const char* name : {"meshes/elephant-with-holes.off", "meshes/knot.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const std::vector<Vec3d> pts = containsRandomPoints(mesh.view(), 600, 21);
        std::vector<double> exactSum(pts.size());
        windingNumbers(mesh.view(), pts, exactSum, 0.0);
        int64_t fractional = 0;
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (i < 50) { EXPECT_NEAR(exactSum[i], windingNumber(mesh.view(), pts[i]), 1e-9); }
            fractional += std::abs(exactSum[i] - std::round(exactSum[i])) > 0.05;
        }
        if (std::string(name).find("holes") != std::string::npos) { EXPECT_GT(fractional, 10) << name; }
        double previous = 1;
        for (const double beta : {2.0, 3.0, 4.0}) {
            std::vector<double> fast(pts.size());
            windingNumbers(mesh.view(), pts, fast, beta);
            double worst = 0;
            for (std::size_t i = 0; i < pts.size(); ++i)
                worst = std::max(worst, std::abs(fast[i] - exactSum[i]));
            std::cout << name << ": beta " << beta << ", largest error " << worst << "\n";
            EXPECT_LT(worst, 0.25 / (beta * beta)) << name << " beta " << beta;
            EXPECT_LE(worst, previous) << name << " beta " << beta;
            previous = worst;
        }
    }
}

// ContainsOptions::progress and classify()'s: polled between chunks of points and while the
// classifier is built; false cancels with an Error, true changes nothing.
TEST(Contains, ProgressIsPolledAndCancels) {
    const Mesh mesh = test::makeTorus({0, 0, 0}, 3, 1, 24, 12);
    const std::vector<Vec3d> pts = containsRandomPoints(mesh.view(), (1 << 20) + 5000, 3);
    struct Count final : Progress {
        int64_t calls = 0, allow = 0;
        bool update(double) override { return ++calls <= allow; }
    };
    for (const ContainsMethod method : {ContainsMethod::Parity, ContainsMethod::Winding}) {
        ContainsOptions o;
        o.method = method;
        o.resolution = 32;
        const std::vector<uint8_t> plain = contains(mesh.view(), pts, o);
        Count yes;
        yes.allow = 1000000;
        o.progress = &yes;
        EXPECT_EQ(contains(mesh.view(), pts, o), plain);
        EXPECT_GE(yes.calls, 2); // two chunks of points at least
        Count no;
        o.progress = &no;
        EXPECT_THROW(contains(mesh.view(), pts, o), Error);
        EXPECT_EQ(no.calls, 1);
        o.progress = nullptr;
        const PointClassifier classifier(mesh.view(), o);
        std::vector<uint8_t> out(pts.size());
        Count second;
        second.allow = 1;
        EXPECT_THROW(classifier.classify(pts, out, nullptr, &second), Error);
        EXPECT_EQ(second.calls, 2);
    }
}

TEST(Contains, ResultsDoNotDependOnTheThreadCount) {
    const Mesh mesh = test::makeTorus({0.1, 0.2, 0.3}, 1.0, 0.4, 48, 24);
    const std::vector<Vec3d> pts = containsRandomPoints(mesh.view(), 50000, 3);
    ContainsOptions one;
    one.threads = 1;
    EXPECT_EQ(contains(mesh.view(), pts, one), contains(mesh.view(), pts));
}

TEST(Contains, ErrorsAndEdgeCases) {
    Mesh bad = test::makeOctahedron({0, 0, 0}, 1);
    bad.indices[4] = 99;
    const std::vector<Vec3d> pts = {{0, 0, 0}};
    EXPECT_THROW(contains(bad.view(), pts), Error);
    const Mesh octa = test::makeOctahedron({0, 0, 0}, 1);
    std::vector<uint8_t> small(0);
    EXPECT_THROW(contains(octa.view(), pts, small), Error);
    EXPECT_THROW(parseContainsMethod("majority"), Error);
    EXPECT_EQ(parseContainsMethod(toString(ContainsMethod::Winding)), ContainsMethod::Winding);
    // NaN and far points are outside; an empty mesh contains nothing.
    const std::vector<Vec3d> odd = {{NAN, 0, 0}, {1e300, 0, 0}, {0, 0, 0}};
    EXPECT_EQ(contains(octa.view(), odd), (std::vector<uint8_t>{0, 0, 1}));
    EXPECT_EQ(contains(Mesh{}.view(), odd), (std::vector<uint8_t>{0, 0, 0}));
}

TEST(ContainsExact, OrientationsMatchCgalOnNearlyDegenerateInputs) {
    // Points on a line (and a plane) moved by a few ulps: the floating point filter fails and
    // the exact path decides; CGAL's orientation is the oracle.
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_int_distribution<int> ulps(-3, 3);
    const auto nudge = [&](double x) {
        for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1) x = std::nextafter(x, k > 0 ? 2.0 : -2.0);
        return x;
    };
    // Every fourth case on a dyadic lattice, where collinear and coplanar points are exact.
    std::uniform_int_distribution<int> lattice(-1024, 1024);
    bool dyadic = false;
    const auto coord = [&] { return dyadic ? std::ldexp(double(lattice(rng)), -10) : u(rng); };
    const auto weight = [&] { return dyadic ? std::ldexp(double(lattice(rng) / 64), -4) : u(rng); };
    int zeros2 = 0, zeros3 = 0;
    for (int n = 0; n < 20000; ++n) {
        dyadic = n % 4 == 0;
        const double ax = coord(), ay = coord(), bx = coord(), by = coord(), t = weight();
        const double cx = nudge(ax + t * (bx - ax)), cy = nudge(ay + t * (by - ay));
        const int got = exact::orient2d(ax, ay, bx, by, cx, cy);
        ASSERT_EQ(got, test::oracleOrient2d(ax, ay, bx, by, cx, cy));
        zeros2 += got == 0;

        const Vec3d a{coord(), coord(), coord()}, b{coord(), coord(), coord()}, c{coord(), coord(), coord()};
        const double s = weight(), r = weight();
        Vec3d d = a + (b - a) * s + (c - a) * r;
        d.z = nudge(d.z);
        const int got3 = exact::orient3d(a, b, c, d);
        ASSERT_EQ(got3, test::oracleOrient3d(a, b, c, d)) << n;
        zeros3 += got3 == 0;
    }
    // Products that underflow: a subnormal coordinate next to ordinary ones (found by this test).
    const double tiny = std::ldexp(1.0, -1074), ax = -0x1.66p-3, bx = -0x1.29p-1, by = 0x1.048p-1;
    EXPECT_EQ(exact::orient2d(ax, 0.0, bx, by, ax, -tiny), test::oracleOrient2d(ax, 0.0, bx, by, ax, -tiny));
    EXPECT_EQ(exact::orient3d({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.5, tiny}), 1);
    EXPECT_EQ(exact::orient3d({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.5, -tiny}), -1);
    EXPECT_EQ(exact::orient3d({0, 0, 0}, {1e300, 0, 0}, {0, 1e300, 0}, {1e299, 1e299, 0}), 0);
    // Some inputs were exactly degenerate (the exact path returned 0).
    EXPECT_GT(zeros2, 100);
    EXPECT_GT(zeros3, 100);
}

} // namespace
} // namespace voxfx
