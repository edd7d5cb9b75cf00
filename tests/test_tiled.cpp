// voxfx — tiled voxelization (voxfx/tiled.hpp): bricks assembled into a grid are the dense
// voxelize() result bit for bit (the requirement of #23: the dense path is itself checked against
// CGAL in test_voxelize_oracle.cpp and test_voxelize_border.cpp), for every mode and tileable fill,
// brick sizes that cut the meshes through vertices, edges and faces, every slicing axis; the
// tiled solid against CGAL directly; what needs the whole grid is refused by name.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/tiled.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

struct Assembled {
    BitGrid bits;
    int64_t bricks = 0, uniform = 0;
};

// Sets the brick's cells in `out`, the grid of the whole frame.
void paintTile(const GridTile& tile, const BitGridView& out) {
    for (int64_t y = 0; y < tile.height; ++y)
        for (int64_t x = 0; x < tile.width; ++x)
            for (int64_t s = 0; s < tile.depth; ++s)
                if (tile.uniform ? tile.value : tile.bits.get(x, y, s))
                    out.set(tile.x0 + x, tile.y0 + y, tile.s0 + s);
}

// Every brick written into one grid of the frame's size (bricks of different stacks own different
// columns; one stack's bricks come in slice order on one thread, so plain writes are safe).
Assembled assemble(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& o, int64_t brick) {
    Assembled a;
    a.bits = BitGrid(frame.width(), frame.height(), frame.depth());
    const BitGridView out = a.bits.view();
    std::atomic<int64_t> bricks{0}, uniform{0};
    TileOptions t;
    t.brickSize = brick;
    voxelizeTiles(mesh, frame, o, t, [&](const GridTile& tile) {
        ++bricks;
        uniform += tile.uniform;
        EXPECT_EQ(tile.bits.words == nullptr, tile.uniform);
        EXPECT_TRUE(tile.width > 0 && tile.height > 0 && tile.depth > 0 && tile.width <= brick &&
                    tile.height <= brick && tile.depth <= brick);
        paintTile(tile, out);
        if (!tile.uniform) { // padding bits stay zero, as in every slicemap
            for (int64_t c = 0; c < tile.bits.columnCount(); ++c)
                EXPECT_EQ(tile.bits.column(c)[tile.bits.wordsPerColumn - 1] & ~tile.bits.lastWordMask(), 0u);
        }
    });
    a.bricks = bricks;
    a.uniform = uniform;
    return a;
}

struct Case {
    VoxelizeMode mode;
    Fill fill;
};
constexpr Case kCases[] = {{VoxelizeMode::Surface, Fill::Parity},
                           {VoxelizeMode::Conservative, Fill::Parity},
                           {VoxelizeMode::Solid, Fill::Parity},
                           {VoxelizeMode::Solid, Fill::Winding},
                           {VoxelizeMode::SolidConservative, Fill::Parity},
                           {VoxelizeMode::SolidConservative, Fill::Winding},
                           {VoxelizeMode::Interior, Fill::Parity},
                           {VoxelizeMode::Interior, Fill::Winding},
                           {VoxelizeMode::Solid, Fill::Gwn},
                           {VoxelizeMode::SolidConservative, Fill::Gwn},
                           {VoxelizeMode::Interior, Fill::Gwn}};

// Tiled equals dense for every case and brick size; returns how many bricks were uniform.
int64_t expectTiledEqualsDense(const Mesh& mesh, const Frame& frame, const std::vector<int64_t>& bricks) {
    int64_t uniform = 0;
    for (const Case& c : kCases) {
        VoxelizeOptions o;
        o.mode = c.mode;
        o.fill = c.fill;
        const VoxelGrid dense = voxelize(mesh.view(), frame, o);
        for (int64_t b : bricks) {
            if (c.fill == Fill::Gwn && c.mode != VoxelizeMode::Surface &&
                c.mode != VoxelizeMode::Conservative && b % 16 != 0)
                continue; // the gwn fill's blocks are 16 cells
            SCOPED_TRACE(::testing::Message() << toString(c.mode) << " (" << toString(c.fill)
                                              << "), bricks of " << b << ", axis " << toString(frame.axis()));
            const Assembled a = assemble(mesh.view(), frame, o, b);
            EXPECT_TRUE(a.bits == dense.bits)
                << "tiled " << a.bits.count() << " cells, dense " << dense.bits.count();
            const int64_t perAxis[3] = {(frame.width() + b - 1) / b, (frame.height() + b - 1) / b,
                                        (frame.depth() + b - 1) / b};
            EXPECT_EQ(a.bricks, perAxis[0] * perAxis[1] * perAxis[2]);
            uniform += a.uniform;
        }
    }
    return uniform;
}

Mesh loadData(const char* name) { return loadMesh(test::dataPath(std::string("meshes/") + name)); }

void expectBunnyTiledEqualsDense(const std::vector<Axis>& axes, const std::vector<int64_t>& bricks) {
    const Mesh bunny = loadData("bunny00.off");
    for (Axis axis : axes) {
        FitOptions fit;
        fit.resolution = 61;
        fit.axis = axis;
        const Frame frame = fitFrame(computeBounds(bunny.view()), fit);
        EXPECT_GT(expectTiledEqualsDense(bunny, frame, bricks), 0);
    }
}

TEST(TiledTest, EveryModeAndFillEqualsTheDenseGridForSeveralBrickSizes) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    expectBunnyTiledEqualsDense({Axis::Z}, {8, 48});
    expectBunnyTiledEqualsDense({Axis::X}, {16});
}

TEST(TiledTest, EveryModeAndFillEqualsTheDenseGridForEveryBrickSizeAndAxisSlow) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    expectBunnyTiledEqualsDense({Axis::X, Axis::Y, Axis::Z}, {8, 16, 24, 40, 48, 128});
}

TEST(TiledTest, OpenMeshesEqualTheDenseGridWithEveryFill) {
    // Open meshes: the gwn fill's curtains behind the boundary edges cross bricks.
    for (const char* name : {"ChineseDragon-10kv.off", "cube-ouvert.off"}) {
        VOXFX_REQUIRE_DATA(std::string("meshes/") + name);
        SCOPED_TRACE(name);
        const Mesh mesh = loadData(name);
        ASSERT_FALSE(analyzeTopology(mesh.view()).closed());
        FitOptions fit;
        fit.resolution = 70;
        fit.marginCells = 2;
        expectTiledEqualsDense(mesh, fitFrame(computeBounds(mesh.view()), fit), {16, 32});
    }
}

TEST(TiledTest, MeshesOfTheCgalSetEqualTheDenseGridSlow) {
    for (const char* name : {"armadillo.off", "cow.off", "elephant.off", "3torus.off", "blobby_3cc.off"}) {
        VOXFX_REQUIRE_DATA(std::string("meshes/") + name);
        SCOPED_TRACE(name);
        const Mesh mesh = loadData(name);
        for (Axis axis : {Axis::X, Axis::Z}) {
            FitOptions fit;
            fit.resolution = 150;
            fit.axis = axis;
            expectTiledEqualsDense(mesh, fitFrame(computeBounds(mesh.view()), fit), {16, 48, 128});
        }
    }
}

// A frame of power-of-two cells placed so that mesh vertex `v` sits exactly on the corner of
// brick (1, 1, 1) for bricks of 8 (grid coordinates (8, 8, 8)): the bricks cut the mesh through
// that vertex, the edges and faces around it.
Frame frameThroughVertex(const Mesh& mesh, const Vec3d& v, double cell, Axis axis) {
    const Box3d bounds = computeBounds(mesh.view());
    Box3d box;
    Vec3i n;
    for (int a = 0; a < 3; ++a) {
        box.lo[a] = v[a] - 8 * cell;
        while (box.lo[a] > bounds.lo[a]) box.lo[a] -= 8 * cell;
        n[a] = int64_t(std::ceil((bounds.hi[a] - box.lo[a]) / cell)) + 1;
        box.hi[a] = box.lo[a] + double(n[a]) * cell;
    }
    return Frame::orthographic(box, axis, n[columnXAxis(axis)], n[columnYAxis(axis)], n[int(axis)]);
}

void expectCutsThroughVerticesAndFacesEqualDense(const std::vector<Axis>& axes,
                                                 const std::vector<int64_t>& bricks) {
    const Mesh bunny = loadData("bunny00.off");
    for (Axis axis : axes) {
        const Frame frame = frameThroughVertex(bunny, Vec3d(bunny.positions[1234]), 1.0 / 64, axis);
        const Vec3d g = frame.gridFromWorld(Vec3d(bunny.positions[1234]));
        ASSERT_EQ(std::fmod(g.x, 8.0), 0.0);
        ASSERT_EQ(std::fmod(g.y, 8.0), 0.0);
        ASSERT_EQ(std::fmod(g.z, 8.0), 0.0);
        expectTiledEqualsDense(bunny, frame, bricks);
    }
    // Boxes whose faces lie in the bricks' planes and an octahedron with corners on brick corners.
    Mesh lattice;
    test::appendBox(lattice, {8, 8, 8}, {24, 32, 16});
    test::appendBox(lattice, {33, 5, 16}, {48, 24, 40});
    const Mesh octahedron = test::makeOctahedron({32, 40, 24}, 16);
    const auto base = uint32_t(lattice.positions.size());
    lattice.positions.insert(lattice.positions.end(), octahedron.positions.begin(),
                             octahedron.positions.end());
    for (uint32_t i : octahedron.indices) lattice.indices.push_back(base + i);
    for (Axis axis : axes) {
        const Frame frame = Frame::orthographic({{0, 0, 0}, {64, 64, 48}}, axis, 64, 64, 48);
        EXPECT_GT(expectTiledEqualsDense(lattice, frame, bricks), 0);
    }
}

TEST(TiledTest, BricksCuttingTheMeshThroughVerticesAndFacesEqualTheDenseGrid) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    expectCutsThroughVerticesAndFacesEqualDense({Axis::Z}, {8});
}

TEST(TiledTest, BricksCuttingTheMeshThroughVerticesAndFacesAlongEveryAxisEqualTheDenseGridSlow) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    expectCutsThroughVerticesAndFacesEqualDense({Axis::X, Axis::Y, Axis::Z}, {8, 16, 24});
}

// Meshes oriented inward (w = -1 inside): the winding and gwn fills decide by |w| >= 1/2 on
// the dense path; the bricks must too (the flipped bunny, and CGAL's tetrahedron, oriented inward
// as written).
TEST(TiledTest, InwardOrientedMeshesEqualTheDenseGrid) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    VOXFX_REQUIRE_DATA("meshes/tetrahedron.off");
    for (const Mesh& mesh : {test::flippedMesh(loadData("bunny00.off")), loadData("tetrahedron.off")}) {
        ASSERT_LT(test::meshVolume(mesh.view()), 0);
        FitOptions fit;
        fit.resolution = 45;
        fit.marginCells = 1;
        const Frame frame = fitFrame(computeBounds(mesh.view()), fit);
        expectTiledEqualsDense(mesh, frame, {16});
        // And the inside is there: the gwn fill's solid holds parity's, which ignores orientation.
        VoxelizeOptions gwn;
        gwn.fill = Fill::Gwn;
        const Assembled a = assemble(mesh.view(), frame, gwn, 16);
        const BitGrid parity = voxelize(mesh.view(), frame).bits;
        EXPECT_GT(parity.count(), 0);
        EXPECT_GE(a.bits.count(), parity.count() * 9 / 10);
    }
}

// Fill::Auto is decided as voxelize() decides it: parity for a closed mesh (the same cells), and
// flood for an open one, which the bricks refuse by name.
TEST(TiledTest, AutoFillIsDecidedAsVoxelizeDecidesIt) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    VOXFX_REQUIRE_DATA("meshes/cube-ouvert.off");
    const Mesh bunny = loadData("bunny00.off");
    FitOptions fit;
    fit.resolution = 40;
    const Frame frame = fitFrame(computeBounds(bunny.view()), fit);
    VoxelizeOptions o;
    o.fill = Fill::Auto;
    VoxelizeReport report;
    o.report = &report;
    const Assembled a = assemble(bunny.view(), frame, o, 16);
    EXPECT_EQ(report.fill, Fill::Parity);
    EXPECT_TRUE(a.bits == voxelize(bunny.view(), frame).bits);
    EXPECT_GT(a.bits.count(), 0);
    const Mesh open = loadData("cube-ouvert.off");
    const Frame openFrame = fitFrame(computeBounds(open.view()), fit);
    try {
        voxelizeTiles(open.view(), openFrame, o, {}, [](const GridTile&) {});
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("fill 'flood' needs the whole grid"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(report.fill, Fill::Flood);
}

TEST(TiledTest, TheTiledSolidMatchesCgal) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh bunny = loadData("bunny00.off");
    FitOptions fit;
    fit.resolution = 72;
    const Frame frame = fitFrame(computeBounds(bunny.view()), fit);
    const Assembled a = assemble(bunny.view(), frame, {}, 24);
    const VoxelGrid tiled{frame, a.bits};
    const test::SolidOracle oracle = test::oracleSolid(bunny.view(), test::CellGeometry::of(tiled));
    const test::GridDiff d = test::compareGrids(test::toWorldGrid(tiled), oracle.inside, &oracle.leftOut);
    EXPECT_TRUE(d.equal()) << d;
    EXPECT_GT(a.bits.count(), 0);
}

TEST(TiledTest, InteriorBricksOfALargeGridAreUniformAndTheirCountGrowsWithTheSurface) {
    const Mesh box = test::makeBox({0.1, 0.1, 0.1}, {0.9, 0.9, 0.9});
    int64_t previous = 0;
    for (int64_t n : {128, 256, 512}) {
        const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, n, n, n);
        int64_t mixed = 0, inside = 0, total = 0;
        std::mutex m;
        TileOptions t;
        t.brickSize = 16;
        voxelizeTiles(box.view(), frame, {}, t, [&](const GridTile& tile) {
            std::lock_guard<std::mutex> lock(m);
            ++total;
            mixed += !tile.uniform;
            inside += tile.uniform && tile.value;
        });
        // The box's faces at 0.1 n and 0.9 n cut bricks of 16 along six planes.
        EXPECT_EQ(total, (n / 16) * (n / 16) * (n / 16));
        EXPECT_GT(inside, 0);
        // Mixed bricks grow like the surface: about 4x per doubling, never like the volume (8x).
        if (previous) { EXPECT_LE(mixed, 5 * previous) << n; }
        previous = mixed;
    }
}

// What voxfx.dask's tasks do: each voxelizes a rectangle of stacks on its own (a fresh call, no
// state from the others); the pieces together are the dense grid, and each brick comes exactly once.
TEST(TiledTest, PiecesOfStacksVoxelizedOnTheirOwnAssembleIntoTheDenseGrid) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    const Mesh elephant = loadData("elephant.off");
    FitOptions fit;
    fit.resolution = 77;
    const Frame frame = fitFrame(computeBounds(elephant.view()), fit);
    for (const Fill fill : {Fill::Parity, Fill::Winding, Fill::Gwn}) {
        VoxelizeOptions o;
        o.fill = fill;
        const VoxelGrid dense = voxelize(elephant.view(), frame, o);
        const int64_t B = 16, sx = (frame.width() + B - 1) / B, sy = (frame.height() + B - 1) / B;
        BitGrid bits(frame.width(), frame.height(), frame.depth());
        const BitGridView out = bits.view();
        std::vector<int> seen(size_t(sx * sy * ((frame.depth() + B - 1) / B)), 0);
        std::mutex m;
        // Rectangles of 2 x 3 stacks (the last ones clipped by the grid), one call each.
        for (int64_t y0 = 0; y0 < sy; y0 += 3)
            for (int64_t x0 = 0; x0 < sx; x0 += 2) {
                TileOptions t;
                t.brickSize = B;
                t.stackX0 = x0;
                t.stackX1 = x0 + 2;
                t.stackY0 = y0;
                t.stackY1 = y0 + 3;
                voxelizeTiles(elephant.view(), frame, o, t, [&](const GridTile& tile) {
                    std::lock_guard<std::mutex> lock(m);
                    EXPECT_TRUE(tile.x0 / B >= x0 && tile.x0 / B < x0 + 2 && tile.y0 / B >= y0 &&
                                tile.y0 / B < y0 + 3);
                    ++seen[size_t(((tile.s0 / B) * sy + tile.y0 / B) * sx + tile.x0 / B)];
                    paintTile(tile, out);
                });
            }
        EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
        EXPECT_TRUE(bits == dense.bits)
            << toString(fill) << ": pieces " << bits.count() << " cells, dense " << dense.bits.count();
    }
}

TEST(TiledTest, ResultsDoNotDependOnTheThreadCount) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh bunny = loadData("bunny00.off");
    FitOptions fit;
    fit.resolution = 90;
    const Frame frame = fitFrame(computeBounds(bunny.view()), fit);
    VoxelizeOptions one;
    one.threads = 1;
    VoxelizeOptions all;
    all.threads = 0;
    EXPECT_TRUE(assemble(bunny.view(), frame, one, 16).bits == assemble(bunny.view(), frame, all, 16).bits);
}

TEST(TiledTest, WhatNeedsTheWholeGridIsRefusedByName) {
    const Mesh box = test::makeBox({0.1, 0.1, 0.1}, {0.9, 0.9, 0.9});
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 32, 32, 32);
    const auto nothing = [](const GridTile&) {};
    for (Fill fill : {Fill::Flood, Fill::Vote}) {
        VoxelizeOptions o;
        o.fill = fill;
        EXPECT_NE(wholeGridReason(frame, o), "");
        try {
            voxelizeTiles(box.view(), frame, o, {}, nothing);
            ADD_FAILURE() << "no error for " << toString(fill);
        } catch (const Error& e) {
            EXPECT_NE(
                std::string(e.what()).find(std::string("fill '") + toString(fill) + "' needs the whole grid"),
                std::string::npos)
                << e.what();
        }
        o.mode = VoxelizeMode::Conservative; // a surface mode has no fill
        EXPECT_EQ(wholeGridReason(frame, o), "");
    }
    VoxelizeOptions local;
    local.slicing = Slicing::Local;
    EXPECT_THROW(voxelizeTiles(box.view(), frame, local, {}, nothing), Error);
    const Frame perspective =
        Frame::perspective({0.5, 0.5, -2}, {0.5, 0.5, 0.5}, {0, 1, 0}, 0.8, 32, 32, 1, 4, 32);
    EXPECT_THROW(voxelizeTiles(box.view(), perspective, {}, {}, nothing), Error);
    for (int64_t bad : {-8, 12, 100}) {
        TileOptions t;
        t.brickSize = bad;
        EXPECT_THROW(voxelizeTiles(box.view(), frame, {}, t, nothing), Error) << bad;
    }
    TileOptions tiny;
    tiny.memoryBytes = 4096;
    try {
        voxelizeTiles(box.view(), frame, {}, tiny, nothing);
        ADD_FAILURE() << "no error for a 4 KiB budget";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("memory budget"), std::string::npos) << e.what();
    }
}

TEST(TiledTest, AnExceptionFromTheVisitorStopsTheWorkAndReachesTheCaller) {
    const Mesh box = test::makeBox({0.1, 0.1, 0.1}, {0.9, 0.9, 0.9});
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 64, 64, 64);
    std::atomic<int> calls{0};
    TileOptions t;
    t.brickSize = 8;
    EXPECT_THROW(voxelizeTiles(box.view(), frame, {}, t,
                               [&](const GridTile&) {
                                   if (++calls == 5) fail("visitor failed");
                               }),
                 Error);
    EXPECT_LT(calls.load(), 8 * 8 * 8);
}

} // namespace
} // namespace voxfx
