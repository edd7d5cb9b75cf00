// Tests of src/grid/intersection_volume.cpp and the CSG bounds behind it (GI08 §7, intersection
// volumes for collision and haptics): estimates against closed forms (boxes, two balls, a ball
// cut by a half-space grid) and against CGAL's exact volume of the intersection of two closed
// polyhedra, always within the stated bound, and the bound never vacuous; `voxfx csg --volume`.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/intersection_volume.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

Mat4d translation(const Vec3d& t) {
    Mat4d m;
    m.m[0][3] = t.x;
    m.m[1][3] = t.y;
    m.m[2][3] = t.z;
    return m;
}

// Turn by `degrees` about world z, then shift by t.
Mat4d turnAboutZ(double degrees, const Vec3d& t) {
    const double c = std::cos(degrees * M_PI / 180), s = std::sin(degrees * M_PI / 180);
    Mat4d m = translation(t);
    m.m[0][0] = c;
    m.m[0][1] = -s;
    m.m[1][0] = s;
    m.m[1][1] = c;
    return m;
}

// The closed-form volume of the intersection of two balls of radii r1, r2 whose centres are d apart.
double lensVolume(double r1, double r2, double d) {
    if (d >= r1 + r2) return 0;
    if (d <= std::abs(r1 - r2)) return 4.0 / 3.0 * M_PI * std::pow(std::min(r1, r2), 3);
    return M_PI * (r1 + r2 - d) * (r1 + r2 - d) * (d * d + 2 * d * (r1 + r2) - 3 * (r1 - r2) * (r1 - r2)) /
           (12 * d);
}

// |estimate - exact| <= bound, the exact value within [lower, upper], and the bound not vacuous:
// below `maxRelative` of the exact value.
void expectWithinBound(const VolumeEstimate& e, double exact, double maxRelative, const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_LE(std::abs(e.volume - exact), e.errorBound) << "volume " << e.volume << ", exact " << exact;
    EXPECT_LE(e.lowerVolume, exact * (1 + 1e-12));
    EXPECT_GE(e.upperVolume, exact * (1 - 1e-12));
    EXPECT_LT(e.errorBound, maxRelative * exact) << "bound " << e.errorBound << " for " << exact;
    EXPECT_GT(e.uncertainCells, 0);
    std::cout << "[ volume   ] " << what << ": " << e.volume << " +- " << e.errorBound << ", exact " << exact
              << " (off by " << std::abs(e.volume - exact) / e.errorBound << " of the bound)\n";
}

TEST(IntersectionVolumeTest, BoxesMatchTheProductOfTheirOverlapsWithinTheBound) {
    // [0, 3] x [0, 2] x [0, 1.5] against a box of 2.2 x 1.1 x 0.9 placed by a quarter turn
    // about z and a shift: in world it is [1.9, 3.0] x [0.7, 2.9] x [0.4, 1.3], so the overlap is
    // 1.1 x 1.3 x 0.9. Cells from the overlap's fitted grid at 32 and 128 along its longest side.
    const Mesh a = test::makeBox({0, 0, 0}, {3, 2, 1.5});
    const Mesh b = test::makeBox({0, 0, 0}, {2.2, 1.1, 0.9});
    const Mat4d placeB = turnAboutZ(90, {3.0, 0.7, 0.4});
    const double exact = 1.1 * 1.3 * 0.9;
    double previousBound = INFINITY;
    for (const int64_t resolution : {32, 128}) {
        FitOptions fit;
        fit.resolution = resolution;
        const VolumeEstimate e = intersectionVolume(a.view(), Mat4d(), b.view(), placeB, fit);
        expectWithinBound(e, exact, resolution == 32 ? 0.3 : 0.08, "boxes at " + std::to_string(resolution));
        EXPECT_LT(e.errorBound, previousBound / 3); // about 4x finer cells: about 4x smaller bound
        previousBound = e.errorBound;
    }
    // Boxes whose bounds do not overlap: nothing in common, nothing voxelized.
    FitOptions fit;
    fit.resolution = 32;
    const VolumeEstimate none = intersectionVolume(a.view(), Mat4d(), b.view(), translation({10, 0, 0}), fit);
    EXPECT_EQ(none.volume, 0);
    EXPECT_EQ(none.errorBound, 0);
}

TEST(IntersectionVolumeTest, TwoBallGridsGiveTheLensVolumeWithinTheirSurfaceCells) {
    // Grids built here from the balls themselves (a cell is filled when its centre is within the
    // radius): the estimate of two grids is their common cells (exact for the cells), and it
    // differs from the closed-form lens by at most the cells either sphere passes through (their
    // box has corners both nearer and farther than the radius).
    const double r1 = 0.9, r2 = 0.6, d = 1.0;
    const Vec3d c1{0.03, -0.02, 0.01}, c2 = c1 + Vec3d{d * 0.6, d * 0.8, 0};
    const int64_t n = 96;
    const Frame frame = Frame::orthographic({{-1, -1, -1}, {2, 2, 2}}, Axis::Z, n, n, n);
    VoxelGrid ga{frame, BitGrid(n, n, n)}, gb{frame, BitGrid(n, n, n)};
    const double h = 3.0 / double(n);
    int64_t common = 0, surfaceCells = 0;
    for (int64_t z = 0; z < n; ++z)
        for (int64_t y = 0; y < n; ++y)
            for (int64_t x = 0; x < n; ++x) {
                const Vec3d lo{-1 + double(x) * h, -1 + double(y) * h, -1 + double(z) * h};
                const Vec3d c = lo + Vec3d{h, h, h} * 0.5;
                const bool in1 = length(c - c1) < r1, in2 = length(c - c2) < r2;
                ga.bits.set(x, y, z, in1);
                gb.bits.set(x, y, z, in2);
                common += in1 && in2;
                // Nearest and farthest points of the cell's box from each centre.
                bool onSurface = false;
                for (const auto& [ctr, r] : {std::pair{c1, r1}, std::pair{c2, r2}}) {
                    double nearest = 0, farthest = 0;
                    for (int a = 0; a < 3; ++a) {
                        const double l = lo[a] - ctr[a], u = lo[a] + h - ctr[a];
                        const double dn = l > 0 ? l : (u < 0 ? -u : 0);
                        const double df = std::max(std::abs(l), std::abs(u));
                        nearest += dn * dn;
                        farthest += df * df;
                    }
                    onSurface = onSurface || (std::sqrt(nearest) <= r && std::sqrt(farthest) >= r);
                }
                surfaceCells += onSurface;
            }
    const VolumeEstimate e = intersectionVolume(ga, gb);
    EXPECT_EQ(e.cells, common);
    EXPECT_NEAR(e.volume, double(common) * h * h * h, 1e-12);
    EXPECT_EQ(e.errorBound, 0); // the grids themselves are exact
    const double exact = lensVolume(r1, r2, d);
    EXPECT_LE(std::abs(e.volume - exact), double(surfaceCells) * h * h * h);
    EXPECT_LT(std::abs(e.volume - exact), 0.02 * exact) << e.volume << " against " << exact;
    // Grids of different frames are refused.
    const VoxelGrid other{Frame::orthographic({{-1, -1, -1}, {2, 2, 2}}, Axis::Z, n, n, n + 1),
                          BitGrid(n, n, n + 1)};
    EXPECT_THROW(intersectionVolume(ga, other), Error);
}

TEST(IntersectionVolumeTest, BallMeshesGiveTheLensVolumeWithinTheBound) {
    // UV spheres (vertices on the sphere, so each polyhedron lies between the ball of its radius
    // and the ball of radius r cos(pi / rings), the nearest any facet plane comes): their exact
    // intersection volume lies between the lenses of those radii.
    const double r1 = 0.9, r2 = 0.6, d = 1.0;
    const int rings = 48;
    const Mesh s1 = test::makeUvSphere({0, 0, 0}, r1, rings, 2 * rings);
    const Mesh s2 = test::makeUvSphere({0, 0, 0}, r2, rings, 2 * rings);
    const double shrink = std::cos(M_PI / rings);
    const Vec3d c1{0.03, -0.02, 0.01}, c2 = c1 + Vec3d{d * 0.6, 0, d * 0.8};
    FitOptions fit;
    fit.resolution = 96;
    const VolumeEstimate e =
        intersectionVolume(s1.view(), translation(c1), s2.view(), turnAboutZ(33, c2), fit);
    const double lo = lensVolume(r1 * shrink, r2 * shrink, d), hi = lensVolume(r1, r2, d);
    EXPECT_GE(e.volume + e.errorBound, lo);
    EXPECT_LE(e.volume - e.errorBound, hi);
    EXPECT_LT(e.errorBound, 0.25 * lo); // 0.17 at 96 cells: the surface cells' volume
    std::cout << "[ volume   ] two ball meshes: " << e.volume << " +- " << e.errorBound << ", lens between "
              << lo << " and " << hi << "\n";
}

TEST(IntersectionVolumeTest, GridCutByAPlacedBallGivesTheBallMinusItsCap) {
    // The grid: every cell below z = 0.25 of [-1, 1]^3 at 64 cells (a half-space along cell
    // faces, exact as cells). The mesh: a UV sphere of radius 0.5 placed at (0.1, -0.05, 0.05),
    // turned by 20 degrees. In common: the ball minus its cap above z = 0.25, cap height
    // 0.5 - 0.2 = 0.3: V = 4/3 pi r^3 - pi h^2 (3 r - h) / 3, bracketed by the radii as above.
    const int64_t n = 64;
    const Frame frame = Frame::orthographic({{-1, -1, -1}, {1, 1, 1}}, Axis::Z, n, n, n);
    VoxelGrid grid{frame, BitGrid(n, n, n)};
    for (int64_t z = 0; z < 40; ++z) // 40 cells of 1/32: up to z = 0.25
        for (int64_t y = 0; y < n; ++y)
            for (int64_t x = 0; x < n; ++x) grid.bits.set(x, y, z);
    const int rings = 48;
    const double r = 0.5, shrink = std::cos(M_PI / rings);
    const Mesh ball = test::makeUvSphere({0, 0, 0}, r, rings, 2 * rings);
    const Vec3d centre{0.1, -0.05, 0.05};
    const VolumeEstimate e = intersectionVolume(grid, ball.view(), turnAboutZ(20, centre));
    const auto minusCap = [&](double radius) {
        const double capHeight = radius - (0.25 - centre.z);
        return 4.0 / 3.0 * M_PI * radius * radius * radius -
               M_PI * capHeight * capHeight * (3 * radius - capHeight) / 3;
    };
    EXPECT_GE(e.volume + e.errorBound, minusCap(r * shrink));
    EXPECT_LE(e.volume - e.errorBound, minusCap(r));
    EXPECT_LT(e.errorBound, 0.3 * minusCap(r)); // 0.25 at 64 cells over [-1, 1]
    // The grid's flat face is exact: only the sphere's cells are uncertain, none above the grid.
    EXPECT_GT(e.uncertainCells, 0);
}

TEST(IntersectionVolumeTest, RealMeshesMatchCgalsExactIntersectionVolume) {
    // The elephant against itself shifted by a fifth of its extent, and against the data set's
    // sphere placed across its back: CGAL's corefinement with exact constructions gives the
    // exact volume of the polyhedra's intersection.
    for (const char* file : {"meshes/elephant.off", "meshes/sphere.off"}) VOXFX_REQUIRE_DATA(file);
    const Mesh elephant = loadMesh(test::dataPath("meshes/elephant.off"));
    const Mesh sphere = loadMesh(test::dataPath("meshes/sphere.off"));
    const Box3d be = computeBounds(elephant.view()), bs = computeBounds(sphere.view());
    // Placements applied here (double, then float, as the library does) and handed to CGAL.
    const auto moved = [](const Mesh& m, const Mat4d& t) {
        Mesh out = m;
        for (Vec3f& p : out.positions) p = Vec3f(t.point(Vec3d(p)));
        return out;
    };
    const Mat4d shift = translation(be.extent() * 0.2);
    const double sphereScale = 0.3 * be.extent().x / bs.extent().x;
    Mat4d placeSphere =
        translation(be.center() + Vec3d{0, 0, 0.25 * be.extent().z} - bs.center() * sphereScale);
    for (int i = 0; i < 3; ++i) placeSphere.m[i][i] = sphereScale;
    struct Case {
        const char* what;
        const Mesh& b;
        Mat4d place;
    };
    for (const Case& c : {Case{"elephant and shifted elephant", elephant, shift},
                          Case{"elephant and sphere", sphere, placeSphere}}) {
        const double exact = test::oracleIntersectionVolume(elephant.view(), moved(c.b, c.place).view());
        ASSERT_TRUE(std::isfinite(exact)) << c.what << ": CGAL could not intersect the meshes";
        ASSERT_GT(exact, 0);
        FitOptions fit;
        fit.resolution = 128;
        expectWithinBound(intersectionVolume(elephant.view(), Mat4d(), c.b.view(), c.place, fit), exact, 0.5,
                          c.what);
    }
}

TEST(IntersectionVolumeTest, CsgBoundsFollowEachOperationOnHandMadeCells) {
    // One column of 6 cells; per operand, lower/upper as strings (1 = set), the expected bounds
    // of each operation worked out by hand from the rules in csg.hpp.
    const auto bits = [](const char* s) {
        BitGrid g(1, 1, 6);
        for (int i = 0; i < 6; ++i) g.set(0, 0, i, s[i] == '1');
        return g;
    };
    const auto text = [](const BitGrid& g) {
        std::string s;
        for (int i = 0; i < 6; ++i) s += g.get(0, 0, i) ? '1' : '0';
        return s;
    };
    // a: surely in at 0-1, maybe at 2-3, out at 4-5; b: surely in at 0, 2, maybe at 1, 4.
    const CsgBounds a{bits("110000"), bits("111100")}, b{bits("101000"), bits("111010")};
    const auto eval = [&](const char* op) {
        return evaluateCsgBounds(parseCsgExpression(std::string(op) + "(a, b)"),
                                 [&](const std::string& name) { return name == "a" ? a : b; });
    };
    const struct {
        const char* op;
        const char* lower;
        const char* upper;
    } cases[] = {{"union", "111000", "111110"},
                 {"intersection", "100000", "111000"},
                 {"difference", "000000", "010100"},
                 {"xor", "000000", "011110"}};
    for (const auto& c : cases) {
        const CsgBounds r = eval(c.op);
        EXPECT_EQ(text(r.lower), c.lower) << c.op;
        EXPECT_EQ(text(r.upper), c.upper) << c.op;
    }
}

TEST(IntersectionVolumeTest, CsgVolumeCommandPrintsTheVolumeWithinItsBound) {
    test::TempDir dir;
    const auto writeBox = [&](const std::string& name, const Vec3d& lo, const Vec3d& hi) {
        const Mesh m = test::makeBox(lo, hi);
        std::string off = "OFF\n8 12 0\n";
        for (const Vec3f& p : m.positions)
            off += std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
        for (std::size_t t = 0; t < 12; ++t)
            off += "3 " + std::to_string(m.indices[3 * t]) + " " + std::to_string(m.indices[3 * t + 1]) +
                   " " + std::to_string(m.indices[3 * t + 2]) + "\n";
        return test::writeFile(dir.file(name), off);
    };
    const std::string a = writeBox("a.off", {0, 0, 0}, {3, 2, 1.5}),
                      b = writeBox("b.off", {1.9, 0.7, 0.4}, {3.1, 2.9, 1.3});
    const test::CommandRun run = test::runVoxfx(dir, "csg \"intersection(" + a + ", " + b +
                                                         ")\" -r 64 --volume -o " + dir.file("i.vdb"));
    ASSERT_EQ(run.exitCode, 0) << run.err;
    double volume = 0, bound = 0;
    const std::size_t at = run.out.find("volume: ");
    ASSERT_NE(at, std::string::npos) << run.out;
    ASSERT_EQ(std::sscanf(run.out.c_str() + at, "volume: %lf +- %lf", &volume, &bound), 2) << run.out;
    const double exact = 1.1 * 1.3 * 0.9;                               // [1.9, 3] x [0.7, 2] x [0.4, 1.3]
    EXPECT_LE(std::abs(volume - exact), bound * (1 + 1e-6)) << run.out; // printed to 8 and 3 digits
    EXPECT_LT(bound, 0.5 * exact) << run.out;
    // --volume alone needs no output; neither of them is an error.
    EXPECT_EQ(test::runVoxfx(dir, "csg \"intersection(" + a + ", " + b + ")\" -r 32 --volume").exitCode, 0);
    const test::CommandRun none = test::runVoxfx(dir, "csg \"intersection(" + a + ", " + b + ")\"");
    EXPECT_NE(none.exitCode, 0);
    EXPECT_NE(none.err.find("--volume"), std::string::npos) << none.err;
}

} // namespace
} // namespace voxfx
