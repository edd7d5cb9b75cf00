// voxfx — SparseGrid and voxelizeSparse (voxfx/sparse_grid.hpp): the tiled voxelization into
// OpenVDB's tree equals the dense voxelize() bit for bit (every mode and fill, brick sizes and
// slicing axes, so every transposition of a brick into leaves); the tree holds leaves only where
// cells are mixed and tiles where they are uniform (closed forms on lattice boxes, read back with
// plain OpenVDB); topology operations and morphology against the dense word operations and
// voxfx::morphology (two implementations); coordinates against the dense cells; the file against
// the dense writer's.
#include <algorithm>
#include <set>
#include <tuple>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include "test_util.hpp"
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

} // namespace
} // namespace voxfx
