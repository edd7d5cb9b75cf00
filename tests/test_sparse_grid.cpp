// voxfx — SparseGrid and voxelizeSparse (voxfx/sparse_grid.hpp): the tiled voxelization into
// OpenVDB's tree equals the dense voxelize() bit for bit (every mode and fill, brick sizes and
// slicing axes, so every transposition of a brick into leaves); the tree holds leaves only where
// cells are mixed and tiles where they are uniform (closed forms on lattice boxes, read back with
// plain OpenVDB); topology operations and morphology against the dense word operations and
// voxfx::morphology (two implementations); coordinates against the dense cells; the file against
// the dense writer's.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <tuple>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include "test_util.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/sparse_grid.hpp"

namespace voxfx {
namespace {

Mesh bunny() { return loadMesh(test::dataPath("meshes/bunny00.off")); }

Frame bunnyFrame(const Mesh& mesh, int64_t resolution, Axis axis) {
    FitOptions fit;
    fit.resolution = resolution;
    fit.axis = axis;
    return fitFrame(computeBounds(mesh.view()), fit);
}

// The dense grid of a sparse one, compared bit for bit (toDense reads the tree back through the
// module's dense reader, the one .vdb files go through).
::testing::AssertionResult sameCells(const SparseGrid& sparse, const VoxelGrid& dense) {
    const VoxelGrid back = sparse.toDense();
    if (!back.frame.sameGrid(dense.frame)) return ::testing::AssertionFailure() << "frames differ";
    if (!(back.bits == dense.bits))
        return ::testing::AssertionFailure()
               << "sparse " << back.bits.count() << " cells, dense " << dense.bits.count();
    if (sparse.count() != dense.bits.count())
        return ::testing::AssertionFailure() << "count " << sparse.count() << " vs " << dense.bits.count();
    return ::testing::AssertionSuccess();
}

void expectSparseEqualsDense(const std::vector<Axis>& axes, const std::vector<int64_t>& bricks) {
    const Mesh mesh = bunny();
    const std::tuple<VoxelizeMode, Fill> cases[] = {
        {VoxelizeMode::Surface, Fill::Parity}, {VoxelizeMode::Conservative, Fill::Parity},
        {VoxelizeMode::Solid, Fill::Parity},   {VoxelizeMode::Solid, Fill::Winding},
        {VoxelizeMode::Solid, Fill::Gwn},      {VoxelizeMode::Solid, Fill::Flood},
        {VoxelizeMode::Solid, Fill::Vote},     {VoxelizeMode::SolidConservative, Fill::Parity},
        {VoxelizeMode::Interior, Fill::Parity}};
    for (Axis axis : axes) {
        const Frame frame = bunnyFrame(mesh, 53, axis);
        for (const auto& [mode, fill] : cases) {
            VoxelizeOptions o;
            o.mode = mode;
            o.fill = fill;
            const VoxelGrid dense = voxelize(mesh.view(), frame, o);
            for (int64_t brick : bricks) {
                if (fill == Fill::Gwn && brick % 16 != 0) continue; // the gwn fill's blocks are 16 cells
                SCOPED_TRACE(::testing::Message() << toString(mode) << " (" << toString(fill) << "), axis "
                                                  << toString(axis) << ", bricks of " << brick);
                TileOptions t;
                t.brickSize = brick;
                EXPECT_TRUE(sameCells(voxelizeSparse(mesh.view(), frame, o, t), dense));
            }
        }
    }
}

// Every slicing axis: each transposes a brick into OpenVDB's leaves its own way.
TEST(SparseGridTest, VoxelizeSparseEqualsTheDenseGridForEveryModeFillAndAxis) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    expectSparseEqualsDense({Axis::X, Axis::Y, Axis::Z}, {48});
}

TEST(SparseGridTest, VoxelizeSparseEqualsTheDenseGridForEveryModeFillBrickAndAxisSlow) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    expectSparseEqualsDense({Axis::X, Axis::Y, Axis::Z}, {16, 24, 128});
}

TEST(SparseGridTest, AtLargeResolutionsOnlyTheSurfaceTakesMemory) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = bunny();
    // The tree at 1024^3 (about 215 million filled cells, 128 MiB as a dense grid) against 256^3:
    // 16 times the surface, 64 times the volume.
    const SparseGrid small = voxelizeSparse(mesh.view(), bunnyFrame(mesh, 256, Axis::Z));
    FitOptions fit;
    fit.resolution = 1024;
    fit.checkDenseMemory = false;
    const SparseGrid large = voxelizeSparse(mesh.view(), fitFrame(computeBounds(mesh.view()), fit));
    EXPECT_GT(large.count(), 60 * small.count());
    EXPECT_LT(large.memoryBytes(), 24 * small.memoryBytes());
    // Already at 1024^3 the tree is about an eighth of the dense grid (its share halves with
    // every doubling of the resolution).
    EXPECT_LT(large.memoryBytes(), BitGrid::requiredBytes(1024, 1014, 794) / 4);
}

// An axis-aligned box of cells [lo, hi) of a lattice frame (one unit per cell).
Mesh latticeBox(const Vec3d& lo, const Vec3d& hi) {
    Mesh m;
    test::appendBox(m, lo, hi);
    return m;
}

// The written file read by plain OpenVDB: leaves, active tiles by size, active voxels.
struct TreeShape {
    int64_t leaves = 0, tiles8 = 0, tiles128 = 0, tiles4096 = 0, active = 0;
};
TreeShape readShape(const std::string& path) {
    openvdb::initialize();
    openvdb::io::File file(path);
    file.open();
    const auto grid = openvdb::gridPtrCast<openvdb::BoolGrid>(file.readGrid("voxels"));
    file.close();
    TreeShape s;
    s.leaves = int64_t(grid->tree().leafCount());
    s.active = int64_t(grid->tree().activeVoxelCount());
    auto it = grid->tree().cbeginValueOn();
    it.setMaxDepth(openvdb::BoolTree::ValueOnCIter::LEAF_DEPTH - 1);
    for (; it; ++it) {
        const int64_t edge = it.getBoundingBox().dim().x();
        (edge == 8 ? s.tiles8 : edge == 128 ? s.tiles128 : s.tiles4096)++;
    }
    return s;
}

TEST(SparseGridTest, UniformRegionsAreTilesAndMixedOnesLeaves) {
    test::TempDir dir;
    const Frame frame = Frame::orthographic({{0, 0, 0}, {320, 320, 320}}, Axis::Z, 320, 320, 320);
    // Faces on multiples of 8: no mixed 8^3 block at all. Cells [32, 288)^3: the 128^3 node
    // [128, 256)^3 is one tile; the rest of the box is 8^3 tiles: 256^3 / 8^3 - 16^3 of them.
    const SparseGrid aligned = voxelizeSparse(latticeBox({32, 32, 32}, {288, 288, 288}).view(), frame);
    writeGrid(aligned, dir.file("aligned.vdb"));
    const TreeShape a = readShape(dir.file("aligned.vdb"));
    EXPECT_EQ(a.leaves, 0);
    EXPECT_EQ(a.tiles128, 1);
    EXPECT_EQ(a.tiles8, 32 * 32 * 32 - 16 * 16 * 16);
    EXPECT_EQ(a.active, 256 * 256 * 256);
    // Faces at 36 and 284 (centres 36.5 ... 283.5 inside): the blocks they cut, and only those,
    // are leaves: [32, 40) and [280, 288) along each axis, 32 blocks across.
    const SparseGrid cut = voxelizeSparse(latticeBox({36, 36, 36}, {284, 284, 284}).view(), frame);
    writeGrid(cut, dir.file("cut.vdb"));
    const TreeShape c = readShape(dir.file("cut.vdb"));
    EXPECT_EQ(c.leaves, 32 * 32 * 32 - 30 * 30 * 30);
    EXPECT_EQ(c.tiles128, 1);
    EXPECT_EQ(c.active, 248 * 248 * 248);
}

TEST(SparseGridTest, TheFileHasTheDenseWritersTransformAndCells) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    test::TempDir dir;
    const Mesh mesh = bunny();
    for (Axis axis : {Axis::Z, Axis::X}) {
        const Frame frame = bunnyFrame(mesh, 90, axis);
        writeGrid(voxelize(mesh.view(), frame), dir.file("dense.vdb"));
        writeGrid(voxelizeSparse(mesh.view(), frame), dir.file("sparse.vdb"));
        openvdb::initialize();
        openvdb::io::File fd(dir.file("dense.vdb")), fs(dir.file("sparse.vdb"));
        fd.open();
        fs.open();
        const auto gd = openvdb::gridPtrCast<openvdb::BoolGrid>(fd.readGrid("voxels"));
        const auto gs = openvdb::gridPtrCast<openvdb::BoolGrid>(fs.readGrid("voxels"));
        EXPECT_EQ(gd->transform(), gs->transform());
        EXPECT_EQ(gd->metaValue<openvdb::Vec3i>("voxfx_dims"), gs->metaValue<openvdb::Vec3i>("voxfx_dims"));
        EXPECT_TRUE(gd->tree().hasSameTopology(gs->tree()));
        // And readGrid and readSparseGrid give the cells back.
        EXPECT_TRUE(readGrid(dir.file("sparse.vdb")).bits ==
                    reslice(voxelize(mesh.view(), frame), Axis::Z).bits);
        EXPECT_TRUE(sameCells(readSparseGrid(dir.file("dense.vdb")), readGrid(dir.file("dense.vdb"))));
    }
}

TEST(SparseGridTest, DenseRoundTripsKeepEveryCell) {
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        const Frame frame = Frame::orthographic({{-1, 0, 2}, {1.5, 3, 4}}, axis, 37, 70, 41);
        const VoxelGrid dense{frame, test::randomBits(frame.width(), frame.height(), frame.depth(), 0.4, 7)};
        const SparseGrid sparse = SparseGrid::fromDense(dense);
        EXPECT_TRUE(sameCells(sparse, dense)) << toString(axis);
        const SparseGrid copy = sparse;
        EXPECT_EQ(copy.count(), dense.bits.count());
        const IndexBox box = sparse.bounds();
        EXPECT_EQ(box.lo, Vec3i(0, 0, 0));
        EXPECT_EQ(box.hi, dense.worldDims() - Vec3i(1, 1, 1));
    }
}

TEST(SparseGridTest, TopologyOperationsEqualTheDenseWordOperations) {
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 90, 61, 130);
    const BitGrid a = test::randomBits(90, 61, 130, 0.5, 1), b = test::randomBits(90, 61, 130, 0.3, 2);
    const SparseGrid sa = SparseGrid::fromDense({frame, a}), sb = SparseGrid::fromDense({frame, b});
    for (int op = 0; op < 3; ++op) {
        BitGrid expected = a;
        for (int64_t k = 0; k < expected.wordCount(); ++k)
            expected.words()[k] = op == 0   ? a.words()[k] | b.words()[k]
                                  : op == 1 ? a.words()[k] & b.words()[k]
                                            : a.words()[k] & ~b.words()[k];
        SparseGrid r = sa;
        if (op == 0) r.unite(sb);
        if (op == 1) r.intersect(sb);
        if (op == 2) r.subtract(sb);
        EXPECT_TRUE(sameCells(r, {frame, expected})) << op;
    }
    const SparseGrid other(Frame::orthographic({{0, 0, 0}, {2, 1, 1}}, Axis::Z, 90, 61, 130));
    SparseGrid r = sa;
    EXPECT_THROW(r.unite(other), Error);
}

TEST(SparseGridTest, OpenVdbMorphologyEqualsVoxfxBoxMorphology) {
    // OpenVDB's dilation and erosion over 26 neighbours, r steps, against voxfx::morphology's box
    // of radius r with empty outside (cells the dilation grows past the grid's sides are dropped).
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 70, 53, 81);
    const BitGrid bits = test::randomBits(70, 53, 81, 0.93, 3);
    for (int r : {1, 2}) {
        MorphologyOptions mo;
        mo.rx = mo.ry = mo.rz = r;
        mo.border = MorphBorder::Empty;
        SparseGrid eroded = SparseGrid::fromDense({frame, bits});
        eroded.erode(r);
        EXPECT_TRUE(sameCells(eroded, {frame, erode(bits, mo)})) << "erode " << r;
        const BitGrid sparseBits = test::randomBits(70, 53, 81, 0.02, 4);
        SparseGrid dilated = SparseGrid::fromDense({frame, sparseBits});
        dilated.dilate(r);
        EXPECT_TRUE(dilated.toDense().bits == dilate(sparseBits, mo)) << "dilate " << r;
        EXPECT_GT(dilated.count(), dilate(sparseBits, mo).count()); // it grew past the sides too
    }
}

TEST(SparseGridTest, CoordinatesAreTheFilledCellsWithoutADenseGrid) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = bunny();
    for (Axis axis : {Axis::Z, Axis::Y}) {
        const Frame frame = bunnyFrame(mesh, 48, axis);
        const VoxelGrid dense = voxelize(mesh.view(), frame);
        const std::vector<int32_t> xyz = voxelizeSparse(mesh.view(), frame).coordinates();
        ASSERT_EQ(int64_t(xyz.size()), 3 * dense.bits.count());
        std::set<std::tuple<int32_t, int32_t, int32_t>> seen;
        for (std::size_t n = 0; n < xyz.size(); n += 3) {
            EXPECT_TRUE(dense.atWorldIndex(xyz[n], xyz[n + 1], xyz[n + 2]));
            seen.insert({xyz[n], xyz[n + 1], xyz[n + 2]});
        }
        EXPECT_EQ(int64_t(seen.size()), dense.bits.count()); // each cell once
    }
    EXPECT_TRUE(
        SparseGrid(Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 4, 4, 4)).coordinates().empty());
}

TEST(SparseGridTest, MorphologyOfTilesEqualsVoxfxBoxMorphology) {
    // A box whose faces lie on multiples of 8: only tiles, no leaf (see above), eroded and dilated.
    const Frame frame = Frame::orthographic({{0, 0, 0}, {64, 64, 64}}, Axis::Z, 64, 64, 64);
    const VoxelGrid dense = voxelize(latticeBox({8, 16, 8}, {56, 48, 40}).view(), frame);
    MorphologyOptions mo;
    mo.rx = mo.ry = mo.rz = 3;
    mo.border = MorphBorder::Empty;
    SparseGrid sparse = voxelizeSparse(latticeBox({8, 16, 8}, {56, 48, 40}).view(), frame);
    SparseGrid grown = sparse;
    EXPECT_TRUE(sameCells(sparse.erode(3), {frame, erode(dense.bits, mo)}));
    EXPECT_TRUE(sameCells(grown.dilate(3), {frame, dilate(dense.bits, mo)}));
}

// Fill::Auto as voxelize() decides it: parity for the closed bunny, flood (through the dense
// grid, which fits) for an open mesh; the report says which and why.
TEST(SparseGridTest, AutoFillGivesTheDenseGridsCells) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    VOXFX_REQUIRE_DATA("meshes/cube-ouvert.off");
    for (const char* name : {"meshes/bunny00.off", "meshes/cube-ouvert.off"}) {
        SCOPED_TRACE(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const Frame frame = bunnyFrame(mesh, 41, Axis::Z);
        VoxelizeOptions o;
        o.fill = Fill::Auto;
        VoxelizeReport sparseReport, denseReport;
        o.report = &denseReport;
        const VoxelGrid dense = voxelize(mesh.view(), frame, o);
        o.report = &sparseReport;
        EXPECT_TRUE(sameCells(voxelizeSparse(mesh.view(), frame, o), dense));
        EXPECT_EQ(sparseReport.fill, denseReport.fill);
        EXPECT_EQ(sparseReport.fillNote, denseReport.fillNote);
        EXPECT_EQ(sparseReport.fill, analyzeTopology(mesh.view()).closed() ? Fill::Parity : Fill::Flood);
        EXPECT_GT(dense.bits.count(), 0);
    }
}

TEST(SparseGridTest, BudgetsAreEnforcedWithAMessageThatSaysWhat) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = bunny();
    const Frame frame = bunnyFrame(mesh, 300, Axis::Z);
    // What the tiles hold (reported before the first brick), and 64 KiB for the tree.
    uint64_t working = 0;
    TileOptions t;
    t.workingBytes = &working;
    voxelizeTiles(mesh.view(), frame, {}, t, [](const GridTile&) {});
    ASSERT_GT(working, 0u);
    t.workingBytes = nullptr;
    t.memoryBytes = working + (64 << 10);
    try {
        voxelizeSparse(mesh.view(), frame, {}, t);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("outgrew the memory budget"), std::string::npos) << e.what();
    }
    VoxelizeOptions flood;
    flood.fill = Fill::Flood;
    t.memoryBytes = 1 << 20;
    try {
        voxelizeSparse(mesh.view(), frame, flood, t);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("fill 'flood' needs the whole grid"), std::string::npos) << what;
        EXPECT_NE(what.find("but the memory budget is 1.0 MiB"), std::string::npos) << what;
    }
}

// ---- OpenVDB's tools in place of the dense operations (voxfx morph / csg on .vdb) -------------

TEST(SparseGridTest, SparseMorphologyEqualsTheDenseOneForEveryOpBorderAndRadius) {
    // Oracle: voxfx::morphology's separable word passes on the dense grid (independent of OpenVDB).
    // Random grids of sizes that are no multiple of 8, dense and sparse, and a box that reaches
    // two sides of the grid (tiles and leaves at the borders).
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 45, 37, 51);
    const VoxelGrid box = voxelize(latticeBox({0, 5, 3}, {45, 37, 40}).view(),
                                   Frame::orthographic({{0, 0, 0}, {45, 37, 51}}, Axis::Z, 45, 37, 51));
    const BitGrid grids[] = {test::randomBits(45, 37, 51, 0.9, 11), test::randomBits(45, 37, 51, 0.03, 12),
                             box.bits};
    for (const BitGrid& bits : grids) {
        const SparseGrid sparse = SparseGrid::fromDense({frame, bits});
        for (MorphOp op : {MorphOp::Erode, MorphOp::Dilate, MorphOp::Open, MorphOp::Close})
            for (MorphBorder border : {MorphBorder::Neutral, MorphBorder::Empty, MorphBorder::Filled})
                for (int r : {0, 1, 2, 3}) {
                    SCOPED_TRACE(::testing::Message() << toString(op) << " " << toString(border) << " r " << r
                                                      << ", " << bits.count() << " cells");
                    MorphologyOptions mo;
                    mo.rx = mo.ry = mo.rz = r;
                    mo.border = border;
                    const BitGrid expected = morphology(bits, op, mo);
                    EXPECT_TRUE(sameCells(morphology(sparse, op, r, border), {frame, expected}));
                }
    }
    EXPECT_THROW(morphology(SparseGrid::fromDense({frame, grids[0]}), MorphOp::Dilate, -1), Error);
}

TEST(SparseGridTest, SparseCsgEqualsTheDenseExpression) {
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Y, 41, 66, 29);
    std::map<std::string, BitGrid> dense;
    dense["a"] = test::randomBits(41, 66, 29, 0.5, 21);
    dense["b"] = test::randomBits(41, 66, 29, 0.3, 22);
    dense["c"] = test::randomBits(41, 66, 29, 0.7, 23);
    for (const char* text : {"difference(a, union(b, c), xor(a, c))", "xor(a, b, c)", "intersection(c, a, b)",
                             "union(difference(c, b), intersection(a, b))", "a"}) {
        const CsgNode root = parseCsgExpression(text);
        const BitGrid expected = evaluateCsg(root, [&](const std::string& p) { return dense.at(p); });
        const SparseGrid got = evaluateCsg(root, [&](const std::string& p) {
            return SparseGrid::fromDense({frame, dense.at(p)});
        });
        EXPECT_TRUE(sameCells(got, {frame, expected})) << text;
    }
}

TEST(SparseGridTest, CliMorphAndCsgOnVdbStaySparseAndEqualTheDensePath) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    test::TempDir dir;
    const std::string bunnyPath = test::dataPath("meshes/bunny00.off");
    const Mesh mesh = bunny();
    const Frame frame = bunnyFrame(mesh, 61, Axis::Z);
    VoxelizeOptions surface;
    surface.mode = VoxelizeMode::Surface;
    writeGrid(voxelize(mesh.view(), frame), dir.file("solid.vdb"));
    writeGrid(voxelize(mesh.view(), frame, surface), dir.file("shell.vdb"));
    const std::string runs[][2] = {
        {"morph " + dir.file("solid.vdb") + " --op open --radius 2", "morph"},
        {"morph " + dir.file("shell.vdb") + " --op close --radius 1 --border filled", "morph"},
        {"morph " + dir.file("solid.vdb") + " --op erode --radius 3 --border empty", "morph"},
        {"csg \"xor(" + dir.file("solid.vdb") + ", " + dir.file("shell.vdb") + ")\"", "csg"},
        {"csg \"difference(" + bunnyPath + ", " + dir.file("shell.vdb") + ")\"", "csg"}};
    for (const auto& [args, what] : runs) {
        SCOPED_TRACE(args);
        const test::CommandRun sparse = test::runVoxfx(dir, args + " --sparse -o " + dir.file("sparse.vdb"));
        ASSERT_EQ(sparse.exitCode, 0) << sparse.err;
        EXPECT_NE(sparse.out.find("(OpenVDB, sparse)"), std::string::npos) << sparse.out;
        const test::CommandRun dense = test::runVoxfx(dir, args + " --dense -o " + dir.file("dense.vdb"));
        ASSERT_EQ(dense.exitCode, 0) << dense.err;
        EXPECT_EQ(dense.out.find("(OpenVDB, sparse)"), std::string::npos) << dense.out;
        const VoxelGrid a = readGrid(dir.file("sparse.vdb")), b = readGrid(dir.file("dense.vdb"));
        EXPECT_TRUE(a.frame.sameGrid(b.frame));
        EXPECT_TRUE(a.bits == b.bits) << a.bits.count() << " vs " << b.bits.count();
        EXPECT_GT(b.bits.count(), 0);
    }
}

TEST(SparseGridTest, CliMorphsAVdbThatDoesNotFitDensely) {
    // A cube filling a 256^3 grid (2 MiB densely, three grids for the dense morph: 6 MiB) under a
    // 4 MiB budget: the sparse path erodes
    // it; closed forms: a neutral border keeps every cell, an empty one eats 2 from every side.
    test::TempDir dir;
    const std::string mesh = test::writeFile(
        dir.file("cube.off"), "OFF\n8 12 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                              "3 0 2 3\n3 0 3 1\n3 4 5 7\n3 4 7 6\n3 0 1 5\n3 0 5 4\n"
                              "3 2 6 7\n3 2 7 3\n3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n");
    const test::ScopedEnv budget("VOXFX_MEMORY_LIMIT", "4M");
    const std::string cube = dir.file("cube.vdb"), out = dir.file("eroded.vdb");
    ASSERT_EQ(test::runVoxfx(dir, "voxelize " + mesh + " -r 256 -o " + cube).exitCode, 0);
    test::CommandRun r = test::runVoxfx(dir, "morph " + cube + " --op erode --radius 2 -o " + out);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("16,777,216 filled"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(OpenVDB, sparse)"), std::string::npos) << r.out;
    EXPECT_EQ(readSparseGrid(out).count(), int64_t(1) << 24);
    r = test::runVoxfx(dir, "morph " + cube + " --op erode --radius 2 --border empty -o " + out);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(readSparseGrid(out).count(), int64_t(252) * 252 * 252);
    const IndexBox b = readSparseGrid(out).bounds();
    EXPECT_EQ(b.lo, Vec3i(2, 2, 2));
    EXPECT_EQ(b.hi, Vec3i(253, 253, 253));
    r = test::runVoxfx(dir, "csg \"difference(" + cube + ", " + out + ")\" -o " + dir.file("shell.vdb"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("(OpenVDB, sparse)"), std::string::npos) << r.out;
    EXPECT_EQ(readSparseGrid(dir.file("shell.vdb")).count(), (int64_t(1) << 24) - int64_t(252) * 252 * 252);
}

// ---- Sparse grids streamed into .binvox and .nrrd ---------------------------------------------

namespace sparse_stream_test {
std::string fileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
} // namespace sparse_stream_test

TEST(SparseGridTest, StreamedBinvoxAndNrrdAreTheDenseWritersBytes) {
    // Oracle: the dense writers' files (writeBinvox, writeNrrd of the whole grid). Slabs of one
    // cell up to the whole grid, grids of several axes, runs longer than 255 and runs that cross
    // slabs (a solid box), random cells.
    test::TempDir dir;
    const Frame box = Frame::orthographic({{0, 0, 0}, {45, 37, 150}}, Axis::Z, 45, 37, 150);
    const VoxelGrid grids[] = {voxelize(latticeBox({0, 3, 0}, {45, 37, 140}).view(), box),
                               {Frame::orthographic({{-1, 2, 0.5}, {3.5, 5.7, 15.5}}, Axis::Z, 45, 37, 150),
                                test::randomBits(45, 37, 150, 0.4, 31)},
                               {Frame::orthographic({{0, 0, 0}, {1, 2, 3}}, Axis::Y, 70, 129, 33),
                                test::randomBits(70, 129, 33, 0.1, 32)}};
    for (const VoxelGrid& dense : grids) {
        const SparseGrid sparse = SparseGrid::fromDense(dense);
        for (const char* ext : {".binvox", ".nrrd"}) {
            writeGrid(dense, dir.file(std::string("dense") + ext));
            const std::string expected = sparse_stream_test::fileBytes(dir.file(std::string("dense") + ext));
            for (uint64_t slabBytes : {uint64_t(1), uint64_t(5000), uint64_t(1) << 30}) {
                SCOPED_TRACE(::testing::Message() << ext << ", slabs of " << slabBytes << " bytes, "
                                                  << dense.bits.count() << " cells");
                GridWriteOptions wo;
                wo.slabBytes = slabBytes;
                const std::string path = dir.file(std::string("sparse") + ext);
                writeGrid(sparse, path, wo);
                const std::string got = sparse_stream_test::fileBytes(path);
                EXPECT_EQ(got.size(), expected.size());
                EXPECT_TRUE(got == expected);
            }
        }
    }
}

TEST(SparseGridTest, CliStreamsBinvoxAndNrrdThatDoNotFitAndWritesTheDenseBytes) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    test::TempDir dir;
    const std::string bunnyPath = test::dataPath("meshes/bunny00.off");
    for (const char* ext : {".binvox", ".nrrd"}) {
        SCOPED_TRACE(ext);
        const std::string dense = dir.file(std::string("dense") + ext),
                          tiled = dir.file(std::string("tiled") + ext);
        // 512 x 507 x 397 cells: 13.9 MiB densely, over a 12 MiB budget; slabs of 1.5 MiB.
        const test::CommandRun d = test::runVoxfx(dir, "voxelize " + bunnyPath + " -r 512 -o " + dense);
        ASSERT_EQ(d.exitCode, 0) << d.err;
        EXPECT_EQ(d.out.find(", sparse)"), std::string::npos) << d.out;
        const test::CommandRun t =
            test::runVoxfx(dir, "voxelize " + bunnyPath + " -r 512 --memory 12M -o " + tiled);
        ASSERT_EQ(t.exitCode, 0) << t.err;
        EXPECT_NE(t.out.find("(tiled: "), std::string::npos) << t.out;
        EXPECT_NE(t.out.find(", sparse)"), std::string::npos) << t.out;
        EXPECT_TRUE(sparse_stream_test::fileBytes(dense) == sparse_stream_test::fileBytes(tiled));
        // --dense under the budget: the one-line refusal, no file.
        const test::CommandRun r =
            test::runVoxfx(dir, "voxelize " + bunnyPath + " -r 512 --memory 12M --dense -o " +
                                    dir.file(std::string("x") + ext));
        EXPECT_NE(r.exitCode, 0);
        EXPECT_NE(r.err.find("needs"), std::string::npos) << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file(std::string("x") + ext)));
    }
}

} // namespace
} // namespace voxfx
