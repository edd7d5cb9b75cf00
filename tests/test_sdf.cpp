// voxfx — signed distance fields (voxfx/sdf.hpp) against CGAL and the voxelizer.
//
// Oracles:
//   - CGAL's AABB tree squared_distance (Epick, double) at every voxel centre of the grid: in the
//     band (distance < W) the voxel is active and its value within a float ulp of it; beyond, the
//     voxel is inactive at +-W; the largest error is reported in float ulps of the cell size;
//   - the solid voxelization with the same frame and fill: the sign bit of every voxel's value is
//     its bit (the property the field promises), and CGAL::Side_of_triangle_mesh off the surface;
//   - the dense field against the sparse one (value(), activeVoxels()), and one thread against all;
//   - the sign taken brick by brick from the tiled voxelization against the one dense solid
//     voxelization (the former path, kept for the fills that need the whole grid), bit for bit;
//   - at 2048^3, the closed-form distance to a box, under a memory budget the dense solid exceeds.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "grid/sdf_detail.hpp"
#include "test_util.hpp"
#include "voxfx/distance.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

/// The centres of every voxel of the field, x fastest (dense() order).
std::vector<Vec3d> sdfCentres(const SignedDistanceField& f) {
    const test::CellGeometry g{f.frame.box().lo, f.frame.cellSize(), f.dims()};
    std::vector<Vec3d> out;
    out.reserve(std::size_t(g.dims.x * g.dims.y * g.dims.z));
    for (int64_t k = 0; k < g.dims.z; ++k)
        for (int64_t j = 0; j < g.dims.y; ++j)
            for (int64_t i = 0; i < g.dims.x; ++i)
                out.push_back({g.center(0, i), g.center(1, j), g.center(2, k)});
    return out;
}

double floatUlp(double v) {
    const auto f = float(std::abs(v));
    return double(std::nextafter(f, std::numeric_limits<float>::infinity())) - double(f);
}

struct SdfCheck {
    int64_t band = 0;         ///< voxels the oracle puts in the band
    double worstCellUlps = 0; ///< largest |value - oracle| in float ulps of the cell size
};

// Checks every voxel of `f` against CGAL's distance and the solid voxelization's bits.
SdfCheck checkSdf(const MeshView& mesh, const SignedDistanceField& f, const std::string& name) {
    SdfCheck r;
    const std::vector<Vec3d> centres = sdfCentres(f);
    const std::vector<test::OracleNearest> cgal = test::oracleNearest(mesh, centres, false);
    const std::vector<float> dense = f.dense();
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Solid;
    vo.fill = f.fill;
    const VoxelGrid solid = voxelize(mesh, f.frame, vo);
    const Vec3i d = f.dims();
    const double cellUlp = floatUlp(f.frame.cellSize().x);
    const double W = f.background;
    int wrong = 0;
    for (int64_t k = 0; k < d.z; ++k)
        for (int64_t j = 0; j < d.y; ++j)
            for (int64_t i = 0; i < d.x; ++i) {
                const std::size_t c = std::size_t((k * d.y + j) * d.x + i);
                const float v = dense[c];
                const double o = cgal[c].distance;
                // The sign is the solid voxel's bit, everywhere.
                if (std::signbit(v) != solid.bits.get(i, j, k) && wrong++ < 5)
                    ADD_FAILURE() << name << " voxel (" << i << ", " << j << ", " << k << "): value " << v
                                  << " but the solid bit is " << solid.bits.get(i, j, k);
                // In the band (with a margin for CGAL's and our rounding at the edge): exact.
                const double tol = floatUlp(o) + 1e-12 * W;
                if (o < W - tol || f.full) {
                    ++r.band;
                    r.worstCellUlps = std::max(r.worstCellUlps, std::abs(std::abs(double(v)) - o) / cellUlp);
                    if (!(std::abs(std::abs(double(v)) - o) <= tol) && wrong++ < 5)
                        ADD_FAILURE() << name << " voxel (" << i << ", " << j << ", " << k << "): |value| "
                                      << v << ", CGAL " << o;
                } else if (o > W + tol) {
                    if (!(std::abs(double(v)) == float(W)) && wrong++ < 5)
                        ADD_FAILURE() << name << " voxel (" << i << ", " << j << ", " << k << "): value " << v
                                      << " beyond the band (CGAL " << o << ", W " << W << ")";
                }
            }
    // Active voxels are exactly the band's (checked through the sparse view).
    std::vector<std::array<int32_t, 3>> idx;
    std::vector<float> vals;
    f.activeVoxels(idx, vals);
    EXPECT_EQ(int64_t(idx.size()), f.activeCount());
    for (std::size_t a = 0; a < idx.size(); ++a) {
        const auto [i, j, k] = idx[a];
        const std::size_t c = std::size_t((int64_t(k) * d.y + j) * d.x + i);
        EXPECT_EQ(vals[a], dense[c]);
        EXPECT_LT(std::abs(vals[a]), float(W) + floatUlp(W)) << name;
        EXPECT_EQ(f.value(i, j, k), dense[c]);
    }
    EXPECT_LE(std::abs(int64_t(idx.size()) - r.band), r.band / 1000 + 2)
        << name << ": active voxels against the band";
    return r;
}

Frame sdfFrame(const MeshView& mesh, int64_t resolution, int64_t margin) {
    FitOptions fo;
    fo.resolution = resolution;
    fo.marginCells = margin;
    return fitFrame(computeBounds(mesh), fo);
}

TEST(Sdf, BandMatchesCgalAtEveryVoxelAndSignsMatchTheSolid) {
    for (const char* name :
         {"meshes/elephant.off", "meshes/knot.off", "meshes/fandisk.off", "meshes/cross.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const SignedDistanceField f = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 48, 4));
        EXPECT_EQ(f.fill, Fill::Parity);
        EXPECT_DOUBLE_EQ(f.background, 3 * f.frame.cellSize().x);
        const SdfCheck r = checkSdf(mesh.view(), f, name);
        EXPECT_GT(r.band, 1000) << name;
        std::cout << name << ": " << r.band << " band voxels, largest error " << r.worstCellUlps
                  << " float ulps of the cell size\n";
    }
}

TEST(Sdf, SlowBandMatchesCgalAtEveryVoxelOfLargerGrids) {
    for (const char* name : {"meshes/bunny00.off", "meshes/armadillo.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const SignedDistanceField f = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 160, 4));
        const SdfCheck r = checkSdf(mesh.view(), f, name);
        std::cout << name << ": " << r.band << " band voxels, largest error " << r.worstCellUlps
                  << " float ulps of the cell size\n";
    }
}

TEST(Sdf, SignsMatchCgalSideOfMeshOffTheSurface) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/elephant.off"));
    const SignedDistanceField f = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 48, 3));
    const std::vector<Vec3d> centres = sdfCentres(f);
    const std::vector<int> side = test::sideOfClosedMesh(mesh.view(), centres);
    ASSERT_EQ(side.size(), centres.size());
    const std::vector<float> dense = f.dense();
    int64_t inside = 0;
    for (std::size_t c = 0; c < centres.size(); ++c) {
        if (side[c] == 0) continue;
        EXPECT_EQ(std::signbit(dense[c]), side[c] > 0) << c;
        inside += side[c] > 0;
    }
    EXPECT_GT(inside, 1000);
}

TEST(Sdf, FullGridIsExactEverywhere) {
    for (const char* name : {"meshes/knot.off", "meshes/cube-meshed.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        SdfOptions o;
        o.full = true;
        const SignedDistanceField f = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 32, 6), o);
        const Vec3i d = f.dims();
        EXPECT_EQ(f.activeCount(), d.x * d.y * d.z);
        const SdfCheck r = checkSdf(mesh.view(), f, name);
        EXPECT_EQ(r.band, d.x * d.y * d.z);
    }
}

TEST(Sdf, OpenMeshesTakeTheSignOfTheGwnFill) {
    for (const char* name : {"meshes/elephant-with-holes.off", "meshes/mushroom.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const SignedDistanceField f = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 44, 3));
        EXPECT_EQ(f.fill, Fill::Gwn) << name;
        checkSdf(mesh.view(), f, name); // the signs against voxelize(..., Fill::Gwn)
    }
}

TEST(Sdf, MeshCutByTheGridBorderIsExactAtTheBorder) {
    // The grid holds the middle of the bunny only: voxels next to the border whose nearest
    // triangle lies outside the grid must still be in the band with their exact distance.
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/bunny00.off"));
    const Box3d b = computeBounds(mesh.view());
    FitOptions fo;
    fo.voxelSize = b.extent().x / 50;
    fo.bounds = {b.lo + b.extent() * 0.3, b.hi - b.extent() * 0.25};
    const SignedDistanceField f = signedDistanceField(mesh.view(), fitFrame(b, fo));
    checkSdf(mesh.view(), f, "bunny cut");
}

TEST(Sdf, WideBandsAndOddBlocks) {
    // A band wider than the 64-bit window of the z dilation, and dimensions that are not multiples
    // of the 8^3 blocks.
    VOXFX_REQUIRE_DATA("meshes/knot.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/knot.off"));
    SdfOptions o;
    o.bandVoxels = 30.5;
    const SignedDistanceField f = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 29, 2), o);
    EXPECT_NE(f.dims().x % 8, 0);
    checkSdf(mesh.view(), f, "knot, band 30.5");
    o.bandVoxels = 1;
    checkSdf(mesh.view(), signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 45, 1), o), "knot, band 1");
}

TEST(Sdf, SameFieldForEveryThreadCountAndSlicingAxis) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/bunny00.off"));
    SdfOptions o;
    o.threads = 1;
    const SignedDistanceField one = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 80, 3), o);
    o.threads = 0;
    FitOptions fo;
    fo.resolution = 80;
    fo.marginCells = 3;
    fo.axis = Axis::X; // the field is sliced along z whatever the frame's axis
    const SignedDistanceField all =
        signedDistanceField(mesh.view(), fitFrame(computeBounds(mesh.view()), fo), o);
    ASSERT_EQ(one.leaves.size(), all.leaves.size());
    for (std::size_t l = 0; l < one.leaves.size(); ++l) {
        ASSERT_EQ(one.leaves[l].origin, all.leaves[l].origin);
        ASSERT_EQ(one.leaves[l].active, all.leaves[l].active);
        ASSERT_EQ(0,
                  std::memcmp(one.leaves[l].values.data(), all.leaves[l].values.data(), 512 * sizeof(float)));
    }
    ASSERT_EQ(one.insideRuns.size(), all.insideRuns.size());
}

TEST(Sdf, SameFieldForEveryBrickSize) {
    // Bricks that cut the mesh anywhere (8 voxels, 24, 64) give the field of one brick, bit for bit.
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/bunny00.off"));
    for (const bool full : {false, true}) {
        const Frame frame = sdfFrame(mesh.view(), full ? 36 : 90, 3);
        SdfOptions o;
        o.full = full;
        o.brickSize = 1024;
        const SignedDistanceField one = signedDistanceField(mesh.view(), frame, o);
        for (const int64_t b : {int64_t(8), full ? int64_t(16) : int64_t(24), int64_t(64)}) {
            o.brickSize = b;
            const SignedDistanceField f = signedDistanceField(mesh.view(), frame, o);
            ASSERT_EQ(f.leaves.size(), one.leaves.size()) << b;
            for (std::size_t l = 0; l < f.leaves.size(); ++l) {
                ASSERT_EQ(f.leaves[l].origin, one.leaves[l].origin) << b;
                ASSERT_EQ(f.leaves[l].active, one.leaves[l].active) << b;
                ASSERT_EQ(0, std::memcmp(f.leaves[l].values.data(), one.leaves[l].values.data(), 2048)) << b;
            }
            ASSERT_EQ(f.insideRuns.size(), one.insideRuns.size()) << b;
            for (std::size_t r = 0; r < f.insideRuns.size(); ++r)
                ASSERT_EQ(0, std::memcmp(&f.insideRuns[r], &one.insideRuns[r], sizeof(SdfInsideRun))) << b;
        }
        o.brickSize = 12;
        EXPECT_THROW(signedDistanceField(mesh.view(), frame, o), Error);
    }
}

TEST(Sdf, ValuesAreTheClosestPointDistancesRoundedToFloat) {
    // One closest-point query serves both: the field's values are closestPoints()' distances.
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/elephant.off"));
    const SignedDistanceField f = signedDistanceField(mesh.view(), sdfFrame(mesh.view(), 40, 3));
    std::vector<std::array<int32_t, 3>> idx;
    std::vector<float> vals;
    f.activeVoxels(idx, vals);
    const test::CellGeometry g{f.frame.box().lo, f.frame.cellSize(), f.dims()};
    std::vector<Vec3d> pts;
    for (const auto& [i, j, k] : idx) pts.push_back({g.center(0, i), g.center(1, j), g.center(2, k)});
    const std::vector<ClosestPoint> cp = closestPoints(mesh.view(), pts);
    for (std::size_t a = 0; a < pts.size(); ++a) ASSERT_EQ(std::abs(vals[a]), float(cp[a].distance)) << a;
}

TEST(Sdf, ProgressGrowsToOneAndCancels) {
    // One line for the whole operation: fractions in [0, 1] that only grow and end at 1 (the solid
    // voxelization's tenth first, then the bricks); a false from the callback stops the work.
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/bunny00.off"));
    const Frame frame = sdfFrame(mesh.view(), 64, 3);
    struct Recorder final : Progress {
        std::vector<double> seen;
        std::size_t stopAfter = std::numeric_limits<std::size_t>::max();
        bool update(double f) override {
            seen.push_back(f);
            return seen.size() < stopAfter;
        }
    };
    for (const int threads : {1, 0}) {
        Recorder r;
        SdfOptions o;
        o.brickSize = 16; // 64 bricks
        o.threads = threads;
        o.progress = &r;
        (void)signedDistanceField(mesh.view(), frame, o);
        ASSERT_GE(r.seen.size(), 64u);
        EXPECT_GE(r.seen.front(), 0.0);
        EXPECT_TRUE(std::is_sorted(r.seen.begin(), r.seen.end())) << threads;
        EXPECT_DOUBLE_EQ(r.seen.back(), 1.0);
        Recorder stop;
        stop.stopAfter = r.seen.size() / 2;
        o.progress = &stop;
        EXPECT_THROW(signedDistanceField(mesh.view(), frame, o), Error);
        EXPECT_LT(stop.seen.size(), r.seen.size());
    }
}

TEST(Sdf, BadInputIsAnError) {
    const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1});
    const Frame frame = sdfFrame(box.view(), 16, 2);
    SdfOptions o;
    o.bandVoxels = 0.5;
    EXPECT_THROW(signedDistanceField(box.view(), frame, o), Error);
    o.bandVoxels = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(signedDistanceField(box.view(), frame, o), Error);
    const Frame persp = Frame::perspective({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 0.5, 16, 16, 1, 10, 16);
    EXPECT_THROW(signedDistanceField(box.view(), persp), Error);
    Mesh bad = box;
    bad.positions[0].x = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(signedDistanceField(bad.view(), frame), Error);
    // No triangles: everything outside, at the background.
    const Mesh empty;
    const SignedDistanceField f = signedDistanceField(empty.view(), frame);
    EXPECT_EQ(f.activeCount(), 0);
    EXPECT_EQ(f.value(3, 4, 5), float(f.background));
}

/// Whether two fields are the same, bit for bit (leaves, their masks and values, inside runs).
void expectSameField(const SignedDistanceField& a, const SignedDistanceField& b, const std::string& what) {
    EXPECT_EQ(a.fill, b.fill) << what;
    EXPECT_EQ(a.background, b.background) << what;
    ASSERT_EQ(a.leaves.size(), b.leaves.size()) << what;
    for (std::size_t l = 0; l < a.leaves.size(); ++l) {
        ASSERT_EQ(a.leaves[l].origin, b.leaves[l].origin) << what << ", leaf " << l;
        ASSERT_EQ(a.leaves[l].active, b.leaves[l].active) << what << ", leaf " << l;
        ASSERT_EQ(0, std::memcmp(a.leaves[l].values.data(), b.leaves[l].values.data(), 512 * sizeof(float)))
            << what << ", leaf " << l;
    }
    ASSERT_EQ(a.insideRuns.size(), b.insideRuns.size()) << what;
    for (std::size_t r = 0; r < a.insideRuns.size(); ++r)
        ASSERT_EQ(0, std::memcmp(&a.insideRuns[r], &b.insideRuns[r], sizeof(SdfInsideRun)))
            << what << ", run " << r;
}

// The sign brick by brick from voxelizeTiles (parity, winding and gwn carried down each stack)
// against one dense solid voxelization of the grid: the same field, bit for bit, for one thread and
// all, and bricks of 8 and 24 that cut the mesh anywhere (the gwn fill, which tiles in multiples
// of 16, in bricks of 48 cut into the field's 24) and 64.
void expectTiledSignGivesTheDenseField(const Mesh& mesh, const Frame& frame, Fill fill, Fill resolved,
                                       const std::string& name) {
    SdfOptions o;
    o.fill = fill;
    detail::SdfSignReport dense, tiled;
    const SignedDistanceField reference =
        detail::signedDistanceField(mesh.view(), frame, o, detail::SdfSign::Dense, &dense);
    EXPECT_FALSE(dense.tiled) << name;
    EXPECT_GT(reference.activeCount(), 1000) << name;
    EXPECT_EQ(reference.fill, resolved) << name;
    for (const int threads : {1, 0})
        for (const int64_t brick : {int64_t(8), int64_t(24), int64_t(64)}) {
            o.threads = threads;
            o.brickSize = brick;
            const SignedDistanceField f =
                detail::signedDistanceField(mesh.view(), frame, o, detail::SdfSign::Auto, &tiled);
            EXPECT_TRUE(tiled.tiled) << name;
            expectSameField(f, reference,
                            name + ", " + std::to_string(threads) + " threads, bricks of " +
                                std::to_string(brick));
        }
}

TEST(Sdf, TiledSignGivesTheDenseSolidsFieldOnAClosedMesh) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh bunny = loadMesh(test::dataPath("meshes/bunny00.off"));
    const Frame frame = sdfFrame(bunny.view(), 44, 3);
    expectTiledSignGivesTheDenseField(bunny, frame, Fill::Auto, Fill::Parity, "bunny");
    expectTiledSignGivesTheDenseField(bunny, frame, Fill::Winding, Fill::Winding, "bunny, winding fill");
}

TEST(Sdf, TiledSignGivesTheDenseSolidsFieldOnAMeshCutByTheGrid) {
    // The grid is not a multiple of 8 on any axis, so the border cuts blocks inside the mesh.
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh bunny = loadMesh(test::dataPath("meshes/bunny00.off"));
    const Box3d b = computeBounds(bunny.view());
    FitOptions fo;
    fo.voxelSize = b.extent().x / 61;
    fo.bounds = {b.lo + b.extent() * 0.3, b.hi - b.extent() * 0.22};
    const Frame cut = fitFrame(b, fo);
    ASSERT_TRUE(cut.width() % 8 && cut.height() % 8 && cut.depth() % 8)
        << cut.width() << " x " << cut.height() << " x " << cut.depth();
    expectTiledSignGivesTheDenseField(bunny, cut, Fill::Auto, Fill::Parity, "bunny cut by the grid");
}

TEST(Sdf, TiledSignGivesTheDenseSolidsFieldOnAnOpenMesh) {
    VOXFX_REQUIRE_DATA("meshes/elephant-with-holes.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/elephant-with-holes.off"));
    expectTiledSignGivesTheDenseField(mesh, sdfFrame(mesh.view(), 56, 3), Fill::Auto, Fill::Gwn,
                                      "elephant with holes");
}

TEST(Sdf, FillsThatNeedTheWholeGridKeepTheDenseSolid) {
    // Flood and vote cannot run tile by tile: their sign still comes from the dense voxelization.
    const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1});
    for (const Fill fill : {Fill::Flood, Fill::Vote}) {
        SdfOptions o;
        o.fill = fill;
        detail::SdfSignReport used;
        const SignedDistanceField f = detail::signedDistanceField(box.view(), sdfFrame(box.view(), 16, 2), o,
                                                                  detail::SdfSign::Auto, &used);
        EXPECT_FALSE(used.tiled);
        EXPECT_EQ(f.value(8, 8, 8), -float(f.background));
    }
}

TEST(Sdf, BricksLargerThanTheGridAreTheGrid) {
    // A brick edge far beyond the grid (8192 for a 24^3 grid) makes one brick of the grid's size:
    // the tiled voxelizer's bricks are not sized for it (8192^3 bits per brick would exceed the
    // budget), and the field is the one of the default bricks.
    const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1});
    const Frame frame = sdfFrame(box.view(), 20, 2);
    const SignedDistanceField reference = signedDistanceField(box.view(), frame);
    const test::ScopedEnv budget("VOXFX_MEMORY_LIMIT", "256M");
    SdfOptions o;
    o.brickSize = 8192;
    expectSameField(signedDistanceField(box.view(), frame, o), reference, "bricks of 8192");
}

TEST(Sdf, LargeGridsNeedNoSolidOfTheWholeVolume) {
    // A box of 180 voxels in a 2048^3 grid under a 64 MiB budget: the dense solid alone would be
    // 1 GiB (refused by the budget), the tiled sign holds a few bricks. The field against the
    // closed-form distance to the box at every voxel within 4 of it (all of the band: none lies
    // elsewhere), the inside far from the surface and the outside far from it.
    const int64_t n = 2048, lo = 120, hi = 300;
    const Mesh box = test::makeBox(Vec3d{1, 1, 1} * double(lo), Vec3d{1, 1, 1} * double(hi));
    const Frame frame = Frame::orthographic({{0, 0, 0}, Vec3d{1, 1, 1} * double(n)}, Axis::Z, n, n, n);
    const uint64_t denseBytes = BitGrid::requiredBytes(n, n, n);
    const test::ScopedEnv budget("VOXFX_MEMORY_LIMIT", "64M");
    EXPECT_THROW(detail::signedDistanceField(box.view(), frame, {}, detail::SdfSign::Dense), Error);
    detail::SdfSignReport used;
    const SignedDistanceField f =
        detail::signedDistanceField(box.view(), frame, {}, detail::SdfSign::Auto, &used);
    EXPECT_TRUE(used.tiled);
    std::cout << "2048^3: the tiled sign held " << used.workingBytes << " bytes, the dense solid needs "
              << denseBytes << "\n";
    EXPECT_LT(used.workingBytes * 100, denseBytes);
    const double W = f.background;
    ASSERT_EQ(W, 3.0);
    // Closed form: outside, the distance to the box; inside, to its nearest face.
    const auto exact = [&](int64_t i, int64_t j, int64_t k, bool& inside) {
        double out2 = 0, in = std::numeric_limits<double>::infinity();
        inside = true;
        for (const int64_t v : {i, j, k}) {
            const double c = double(v) + 0.5, below = double(lo) - c, above = c - double(hi);
            const double d = std::max(below, above);
            if (d > 0) {
                inside = false;
                out2 += d * d;
            }
            in = std::min(in, -d);
        }
        return inside ? in : std::sqrt(out2);
    };
    int64_t band = 0, wrong = 0;
    for (int64_t k = lo - 4; k < hi + 4; ++k)
        for (int64_t j = lo - 4; j < hi + 4; ++j)
            for (int64_t i = lo - 4; i < hi + 4; ++i) {
                bool inside = false;
                const double d = exact(i, j, k, inside);
                if (d >= W) continue; // no voxel's distance is W itself (half-integer offsets)
                ++band;
                const float v = f.value(i, j, k);
                if ((std::abs(double(v) - (inside ? -d : d)) > floatUlp(d) + 1e-12 * W) && wrong++ < 5)
                    ADD_FAILURE() << "voxel (" << i << ", " << j << ", " << k << "): " << v << ", exact "
                                  << (inside ? -d : d);
            }
    EXPECT_EQ(f.activeCount(), band);
    EXPECT_EQ(f.value(210, 210, 210), -float(W)); // a run of inside blocks
    EXPECT_EQ(f.value(0, 0, 0), float(W));
    EXPECT_EQ(f.value(n - 1, n - 1, n - 1), float(W));
    EXPECT_EQ(f.value(1000, 210, 210), float(W));
}

} // namespace
} // namespace voxfx
