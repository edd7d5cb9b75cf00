// voxfx — writing signed distance fields (voxfx/sdf_io.hpp) and the `voxfx sdf` command.
//
// Oracles: the .vdb read back by plain OpenVDB (class, background, transform against the voxel
// centres computed here, every voxel's value against the field's), the .nrrd and .npy decoded
// from their format descriptions (not by voxfx), and the command's files against the library's
// field; bad input leaves one error line and no file.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include "test_util.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/sdf_io.hpp"

namespace voxfx {
namespace {

/// 1234567 as "1,234,567", as the command prints counts.
std::string sdfIoCommas(int64_t v) {
    // Appended digit by digit: GCC 12 warns (-Wrestrict, a false positive) on string::insert here
    // when inlined into some unity batches.
    const std::string digits = std::to_string(v);
    std::string s;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) s += ',';
        s += digits[i];
    }
    return s;
}

SignedDistanceField sdfOfMesh(const Mesh& mesh, int64_t resolution, SdfOptions o = {}) {
    FitOptions fo;
    fo.resolution = resolution;
    fo.marginCells = 3;
    return signedDistanceField(mesh.view(), fitFrame(computeBounds(mesh.view()), fo), o);
}

TEST(SdfIo, VdbIsALevelSetWithTheFieldsValuesAndTheVoxelCentres) {
    // The bunny at 64: deep inside, whole blocks beyond the band become tiles.
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/bunny00.off"));
    const SignedDistanceField f = sdfOfMesh(mesh, 64);
    ASSERT_FALSE(f.insideRuns.empty());
    test::TempDir dir;
    writeSdf(f, dir.file("bunny.vdb"));
    openvdb::initialize();
    openvdb::io::File file(dir.file("bunny.vdb"));
    file.open();
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("sdf"));
    file.close();
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_EQ(grid->background(), float(f.background));
    EXPECT_EQ(int64_t(grid->activeVoxelCount()), f.activeCount());
    // Index (i, j, k) is the centre of voxel (i, j, k): lo + (i + 0.5) * cell.
    const Vec3d lo = f.frame.box().lo, cell = f.frame.cellSize();
    for (const Vec3i& ijk : {Vec3i{0, 0, 0}, Vec3i{7, 30, 11}, f.dims() - Vec3i{1, 1, 1}}) {
        const openvdb::Vec3d w = grid->indexToWorld(openvdb::Coord(int(ijk.x), int(ijk.y), int(ijk.z)));
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(w[a], lo[a] + (double(ijk[a]) + 0.5) * cell[a], 1e-12);
    }
    EXPECT_NEAR(grid->voxelSize()[0], cell.x, 1e-15);
    // Every voxel of the grid, active or not (inside tiles included), holds the field's value.
    const auto acc = grid->getConstAccessor();
    const Vec3i d = f.dims();
    const std::vector<float> dense = f.dense();
    int64_t wrong = 0, inside = 0;
    for (int64_t k = 0; k < d.z; ++k)
        for (int64_t j = 0; j < d.y; ++j)
            for (int64_t i = 0; i < d.x; ++i) {
                const openvdb::Coord c{int(i), int(j), int(k)};
                const float v = dense[std::size_t((k * d.y + j) * d.x + i)];
                wrong += acc.getValue(c) != v || std::signbit(acc.getValue(c)) != std::signbit(v);
                inside += v < 0 && !acc.isValueOn(c);
            }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(inside, 1000); // inside voxels beyond the band: tiles at -background
}

/// The FloatGrid "sdf" of a .vdb file, read by plain OpenVDB.
openvdb::FloatGrid::Ptr sdfIoReadGrid(const std::string& path) {
    openvdb::initialize();
    openvdb::io::File file(path);
    file.open();
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("sdf"));
    file.close();
    return grid;
}

/// Counts the differences between two level-set files' trees, voxel for voxel: every leaf (origin,
/// active mask, the 512 values bit for bit, sign of zero included) and every tile (level, origin,
/// value bit for bit, state), in both directions, and the grids' class, background, transform and
/// "voxfx_dims".
int64_t sdfIoTreeDifferences(const openvdb::FloatGrid& a, const openvdb::FloatGrid& b) {
    int64_t diff = 0;
    diff += a.getGridClass() != b.getGridClass();
    diff += std::memcmp(&a.background(), &b.background(), sizeof(float)) != 0;
    diff += a.transform() != b.transform();
    diff += a.metaValue<openvdb::Vec3i>("voxfx_dims") != b.metaValue<openvdb::Vec3i>("voxfx_dims");
    diff += a.tree().leafCount() != b.tree().leafCount();
    diff += a.tree().activeVoxelCount() != b.tree().activeVoxelCount();
    const auto leavesOf = [&](const openvdb::FloatGrid& x, const openvdb::FloatGrid& y) {
        for (auto leaf = x.tree().cbeginLeaf(); leaf; ++leaf) {
            const auto* other = y.tree().probeConstLeaf(leaf->origin());
            if (!other || other->getValueMask() != leaf->getValueMask() ||
                std::memcmp(other->buffer().data(), leaf->buffer().data(), 512 * sizeof(float)) != 0)
                ++diff;
        }
    };
    leavesOf(a, b);
    leavesOf(b, a);
    struct Tile {
        int level;
        openvdb::Coord origin;
        uint32_t bits;
        bool on;
        bool operator==(const Tile&) const = default;
    };
    const auto tilesOf = [](const openvdb::FloatGrid& x) {
        std::vector<Tile> tiles;
        for (auto it = x.tree().cbeginValueAll(); it; ++it)
            if (it.isTileValue()) {
                uint32_t bits = 0;
                std::memcpy(&bits, &*it, sizeof bits);
                tiles.push_back({int(it.getLevel()), it.getBoundingBox().min(), bits, it.isValueOn()});
            }
        return tiles;
    };
    const std::vector<Tile> ta = tilesOf(a), tb = tilesOf(b);
    diff += ta != tb;
    return diff;
}

TEST(SdfIo, StreamedVdbIsTheFieldsVdbVoxelForVoxel) {
    // writeSdf(mesh, ...) puts each brick into the tree as it is made (bricks of 16 voxels on
    // every thread, so insertions interleave); the oracle is the file of the whole field, read by
    // plain OpenVDB, whose values the other tests check against CGAL. Parity is the tiled sign,
    // flood the dense one (the two ways the bricks are made).
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/bunny00.off"));
    FitOptions fo;
    fo.resolution = 64;
    fo.marginCells = 3;
    const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
    test::TempDir dir;
    SignedDistanceField parity;
    for (const Fill fill : {Fill::Parity, Fill::Flood}) {
        SCOPED_TRACE(toString(fill));
        SdfOptions o;
        o.fill = fill;
        o.brickSize = 16;
        const SignedDistanceField whole = signedDistanceField(mesh.view(), frame, o);
        ASSERT_FALSE(whole.insideRuns.empty());
        writeSdf(whole, dir.file("whole.vdb"));
        const SdfWriteReport streamed = writeSdf(mesh.view(), frame, o, dir.file("streamed.vdb"));
        EXPECT_TRUE(streamed.field.leaves.empty());
        EXPECT_EQ(streamed.activeCount, whole.activeCount());
        EXPECT_EQ(streamed.field.background, whole.background);
        EXPECT_EQ(streamed.field.fill, whole.fill);
        const auto a = sdfIoReadGrid(dir.file("whole.vdb")), b = sdfIoReadGrid(dir.file("streamed.vdb"));
        ASSERT_TRUE(a && b);
        EXPECT_GT(a->tree().leafCount(), 200u);
        EXPECT_EQ(int64_t(b->activeVoxelCount()), whole.activeCount());
        EXPECT_EQ(sdfIoTreeDifferences(*a, *b), 0);
        if (fill == Fill::Parity) parity = whole;
    }
    // The comparison sees a single changed value (its own check).
    const SignedDistanceField& whole = parity;
    SignedDistanceField changed = whole;
    changed.leaves[changed.leaves.size() / 2].values[100] =
        std::nextafter(changed.leaves[changed.leaves.size() / 2].values[100], 1e9f);
    writeSdf(whole, dir.file("a.vdb"));
    writeSdf(changed, dir.file("b.vdb"));
    EXPECT_EQ(sdfIoTreeDifferences(*sdfIoReadGrid(dir.file("a.vdb")), *sdfIoReadGrid(dir.file("b.vdb"))), 2);
}

TEST(SdfIo, NrrdAndNpyHoldEveryVoxelInTheirFormatsOrder) {
    VOXFX_REQUIRE_DATA("meshes/elephant.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/elephant.off"));
    const SignedDistanceField f = sdfOfMesh(mesh, 24);
    const std::vector<float> dense = f.dense();
    const Vec3i d = f.dims();
    const std::size_t bytes = dense.size() * sizeof(float);
    test::TempDir dir;
    // NRRD: header, a blank line, float32 samples x fastest.
    writeSdf(f, dir.file("e.nrrd"));
    const std::string nrrd = test::readFileBytes(dir.file("e.nrrd"));
    const std::string sizes =
        "sizes: " + std::to_string(d.x) + " " + std::to_string(d.y) + " " + std::to_string(d.z);
    EXPECT_NE(nrrd.find("type: float\n"), std::string::npos);
    EXPECT_NE(nrrd.find(sizes), std::string::npos) << nrrd.substr(0, 400);
    const std::size_t data = nrrd.find("\n\n") + 2;
    ASSERT_EQ(nrrd.size() - data, bytes);
    EXPECT_EQ(0, std::memcmp(nrrd.data() + data, dense.data(), bytes));
    // .npy 1.0: magic, little-endian header length, a dict padded to 64 bytes, then the data;
    // Fortran order over shape (nx, ny, nz) is x fastest, as dense() is.
    writeSdf(f, dir.file("e.npy"));
    const std::string npy = test::readFileBytes(dir.file("e.npy"));
    ASSERT_EQ(npy.compare(0, 8, std::string("\x93NUMPY\x01\x00", 8)), 0);
    const std::size_t headerLen = uint8_t(npy[8]) | std::size_t(uint8_t(npy[9])) << 8;
    EXPECT_EQ((10 + headerLen) % 64, 0u);
    const std::string header = npy.substr(10, headerLen);
    EXPECT_NE(header.find("'descr': '<f4'"), std::string::npos) << header;
    EXPECT_NE(header.find("'fortran_order': True"), std::string::npos) << header;
    EXPECT_NE(header.find("'shape': (" + std::to_string(d.x) + ", " + std::to_string(d.y) + ", " +
                          std::to_string(d.z) + ")"),
              std::string::npos)
        << header;
    ASSERT_EQ(npy.size() - 10 - headerLen, bytes);
    EXPECT_EQ(0, std::memcmp(npy.data() + 10 + headerLen, dense.data(), bytes));
}

TEST(SdfIo, BadPathsAreErrorsAndLeaveNoFile) {
    const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1});
    const SignedDistanceField f = sdfOfMesh(box, 8);
    test::TempDir dir;
    EXPECT_THROW(writeSdf(f, dir.file("x.binvox")), Error);
    EXPECT_THROW(writeSdf(f, dir.file("missing/x.vdb")), Error);
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.binvox")));
    EXPECT_EQ(sdfFormatFromPath("A.NPY"), SdfFormat::Npy);
}

TEST(SdfCli, WritesALevelSetAndSaysWhatItMade) {
    VOXFX_REQUIRE_DATA("meshes/knot.off");
    test::TempDir dir;
    const std::string out = dir.file("knot.npy");
    const test::CommandRun r =
        test::runVoxfx(dir, "sdf " + test::dataPath("meshes/knot.off") + " -o " + out + " -r 40 --band 2.5");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // The library's field with the same choices (margin: the band rounded up).
    const Mesh mesh = loadMesh(test::dataPath("meshes/knot.off"));
    FitOptions fo;
    fo.resolution = 40;
    fo.marginCells = 3;
    SdfOptions o;
    o.bandVoxels = 2.5;
    const SignedDistanceField f =
        signedDistanceField(mesh.view(), fitFrame(computeBounds(mesh.view()), fo), o);
    const std::vector<float> dense = f.dense();
    const std::string npy = test::readFileBytes(out);
    ASSERT_GE(npy.size(), dense.size() * 4);
    EXPECT_EQ(0, std::memcmp(npy.data() + npy.size() - dense.size() * 4, dense.data(), dense.size() * 4));
    const Vec3i d = f.dims();
    EXPECT_NE(
        r.out.find(std::to_string(d.x) + " x " + std::to_string(d.y) + " x " + std::to_string(d.z) + " grid"),
        std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("band 2.5 voxels"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("sign from parity"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(sdfIoCommas(f.activeCount()) + " active voxels"), std::string::npos) << r.out;
}

TEST(SdfCli, HelpTeachesWhatTheValuesAre) {
    test::TempDir dir;
    const test::CommandRun r = test::runVoxfx(dir, "sdf --help");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_NE(r.out.find("CENTRE"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--band full"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("level set"), std::string::npos) << r.out;
}

TEST(SdfCli, BadArgumentsGiveOneErrorLineAndNoFile) {
    VOXFX_REQUIRE_DATA("meshes/knot.off");
    test::TempDir dir;
    const std::string mesh = test::dataPath("meshes/knot.off");
    const std::pair<std::string, std::string> cases[] = {
        {"sdf " + mesh + " -o " + dir.file("a.vdb") + " --band 0.5", "--band"},
        {"sdf " + mesh + " -o " + dir.file("a.vdb") + " --band wide", "--band"},
        {"sdf " + mesh + " -o " + dir.file("a.binvox"), "unknown distance field extension"},
        {"sdf " + dir.file("none.off") + " -o " + dir.file("a.vdb"), "none.off"},
        {"sdf " + mesh + " -o " + dir.file("a.vdb") + " --fill spill", "unknown fill"},
    };
    for (const auto& [args, needle] : cases) {
        const test::CommandRun r = test::runVoxfx(dir, args);
        EXPECT_NE(r.exitCode, 0) << args;
        EXPECT_NE(r.err.find("voxfx: error:"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(needle), std::string::npos) << args << ": " << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("a.vdb")));
        EXPECT_FALSE(std::filesystem::exists(dir.file("a.binvox")));
    }
}

} // namespace
} // namespace voxfx
