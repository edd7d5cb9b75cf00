// Tests of src/io/grid_io.cpp and the format files (binvox.cpp, vdb.cpp, nrrd.cpp,
// voxel_mesh.cpp, atomic_file.cpp): round trips on random non-cubic grids of every slicing axis,
// the written bytes against small independent decoders written here from the format specs (and
// plain OpenVDB calls for .vdb), hand-counted voxel meshes and a brute-force face count, and bad
// input: malformed and truncated files, failed writes.
#include <algorithm>
#include <csignal>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <sys/resource.h>

#include "core/atomic_file.hpp"
#include "test_util.hpp"
#include "voxfx/grid_io.hpp"

#if defined(__SANITIZE_ADDRESS__) // GCC
#define VOXFX_TEST_UNDER_ASAN 1
#elif defined(__has_feature) // clang
#if __has_feature(address_sanitizer)
#define VOXFX_TEST_UNDER_ASAN 1
#endif
#endif
#ifdef VOXFX_TEST_UNDER_ASAN
// OpenVDB 10 leaks the node it is reading when a truncated file makes it throw
// (RootNode::readTopology news each child before reading it); EveryTruncationOfAFileIsAnError
// triggers that on purpose. Not ours to fix, so LeakSanitizer is told. OpenVDB now runs inside
// the dlopen()ed voxfx_vdb module, where the leaking frame may show only as libopenvdb.so+offset
// (the module's library is not symbolized by name), so the library itself is named too. Issue
// #13 (hostile input) is to refuse such files before OpenVDB reads them.
extern "C" const char* __lsan_default_suppressions() {
    return "leak:openvdb::v10_0::tree::RootNode\nleak:libopenvdb.so\n";
}
#endif

namespace voxfx {
namespace {

constexpr Axis kAxes[3] = {Axis::X, Axis::Y, Axis::Z};

// Files in `dir` other than the ones named (temporaries left behind show up here).
std::vector<std::string> listDir(const std::filesystem::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

// A box with cubic cells of size `cell` for world dims n, off the origin.
Box3d cubicCellBox(const Vec3i& n, double cell) {
    const Vec3d lo{-1.25, 3.5, 0.0625};
    return {lo, lo + Vec3d(double(n.x), double(n.y), double(n.z)) * cell};
}

void expectSameVoxels(const VoxelGrid& a, const VoxelGrid& b) {
    ASSERT_EQ(a.worldDims(), b.worldDims());
    EXPECT_EQ(test::worldMismatches(a, b), 0);
}

// Relative tolerance for world boxes: the formats store doubles in shortest round-trip text or
// binary, so only the lo + n * cell reconstruction rounds (a few ulps of the extent).
void expectNearBox(const Box3d& a, const Box3d& b) {
    const double tol = 1e-12 * std::max(1.0, std::max({b.extent().x, b.extent().y, b.extent().z}));
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(a.lo[i], b.lo[i], tol) << "axis " << i;
        EXPECT_NEAR(a.hi[i], b.hi[i], tol) << "axis " << i;
    }
}

void expectErrorMentioning(const std::function<void()>& f, const std::string& path,
                           const std::string& cause) {
    try {
        f();
        ADD_FAILURE() << "no voxfx::Error for " << path;
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(path), std::string::npos) << what;
        EXPECT_NE(what.find(cause), std::string::npos) << what;
    }
}

// ---- Formats and paths ------------------------------------------------------------------------

TEST(GridIoTest, FormatFromExtensionIgnoresCase) {
    EXPECT_EQ(gridFormatFromPath("a/b.binvox"), GridFormat::Binvox);
    EXPECT_EQ(gridFormatFromPath("B.VDB"), GridFormat::Vdb);
    EXPECT_EQ(gridFormatFromPath("c.Nrrd"), GridFormat::Nrrd);
    EXPECT_EQ(gridFormatFromPath("x.y.PLY"), GridFormat::Ply);
    EXPECT_EQ(gridFormatFromPath("mesh.obj"), GridFormat::Obj);
    expectErrorMentioning([] { gridFormatFromPath("dir/grid.nhdr"); }, "dir/grid.nhdr",
                          ".binvox, .vdb, .nrrd, .ply, .obj");
    expectErrorMentioning([] { gridFormatFromPath("noext"); }, "noext", ".binvox");
}

// ---- Round trips ------------------------------------------------------------------------------

TEST(GridIoTest, BinvoxRoundTripKeepsVoxelsAndCubicCellBox) {
    test::TempDir dir;
    const Vec3i n{37, 20, 70};
    uint64_t seed = 11;
    for (Axis axis : kAxes) {
        const VoxelGrid g = test::randomVoxelGrid(cubicCellBox(n, 0.05), axis, n, 0.3, seed++);
        const std::string path = dir.file(std::string("g_") + toString(axis) + ".binvox");
        writeGrid(g, path);
        const VoxelGrid r = readGrid(path);
        SCOPED_TRACE(toString(axis));
        EXPECT_EQ(r.frame.axis(), Axis::Z);
        expectSameVoxels(g, r);
        expectNearBox(r.frame.box(), g.frame.box());
    }
}

TEST(GridIoTest, BinvoxNonCubicCellsReadBackAsCubesOfLongestExtent) {
    // binvox stores one scale (the longest extent): cells come back as cubes of
    // scale / max(dims), here 6 / 30 = 0.2, from the stored corner. The voxels survive.
    test::TempDir dir;
    const Vec3i n{10, 30, 20};
    const Box3d box{{1, 2, 3}, {1 + 5, 2 + 3, 3 + 6}}; // cells 0.5 x 0.1 x 0.3
    const VoxelGrid g = test::randomVoxelGrid(box, Axis::X, n, 0.5, 3);
    writeGrid(g, dir.file("g.binvox"));
    const VoxelGrid r = readGrid(dir.file("g.binvox"));
    expectSameVoxels(g, r);
    expectNearBox(r.frame.box(), Box3d{{1, 2, 3}, {1 + 10 * 0.2, 2 + 30 * 0.2, 3 + 20 * 0.2}});
}

TEST(GridIoTest, NrrdRoundTripKeepsVoxelsAndBox) {
    test::TempDir dir;
    const Vec3i n{33, 70, 9};
    const Box3d box{{-3, 0.25, 7}, {-3 + 33 * 0.1, 0.25 + 70 * 0.07, 7 + 9 * 1.5}};
    uint64_t seed = 21;
    for (Axis axis : kAxes) {
        const VoxelGrid g = test::randomVoxelGrid(box, axis, n, 0.5, seed++);
        const std::string path = dir.file(std::string("g_") + toString(axis) + ".nrrd");
        writeGrid(g, path);
        const VoxelGrid r = readGrid(path);
        SCOPED_TRACE(toString(axis));
        EXPECT_EQ(r.frame.axis(), Axis::Z);
        expectSameVoxels(g, r);
        expectNearBox(r.frame.box(), box);
    }
}

TEST(GridIoTest, VdbRoundTripKeepsVoxelsBoxAndEmptyBorders) {
    test::TempDir dir;
    const Vec3i n{19, 40, 67};
    const Box3d box{{-3, 0.25, 7}, {-3 + 19 * 0.1, 0.25 + 40 * 0.07, 7 + 67 * 0.02}};
    uint64_t seed = 31;
    for (bool asFloat : {false, true})
        for (Axis axis : kAxes) {
            VoxelGrid g = test::randomVoxelGrid(box, axis, n, 0.5, seed++);
            // Empty the x = 0 slab: the stored dimensions, not the active box, must size the grid.
            for (int64_t j = 0; j < n.y; ++j)
                for (int64_t k = 0; k < n.z; ++k) {
                    Vec3i w{0, j, k};
                    g.bits.set(w[columnXAxis(axis)], w[columnYAxis(axis)], w[sliceAxis(axis)], false);
                }
            const std::string path =
                dir.file(std::string("g_") + toString(axis) + (asFloat ? "_f" : "_b") + ".vdb");
            GridWriteOptions o;
            o.vdbFloat = asFloat;
            writeGrid(g, path, o);
            const VoxelGrid r = readGrid(path);
            SCOPED_TRACE(testing::Message() << toString(axis) << (asFloat ? " float" : " bool"));
            expectSameVoxels(g, r);
            expectNearBox(r.frame.box(), box);
        }
}

// prepareGridFormat: loading the .vdb module ahead (in the background, from several threads at
// once, then waited for) changes nothing in what is written; other formats and unknown
// extensions are no-ops, not errors (the write reports a bad extension, as before).
TEST(GridIoTest, PreparingTheVdbFormatAheadWritesTheSameGrid) {
    test::TempDir dir;
    const Vec3i n{23, 17, 70};
    const Box3d box = cubicCellBox(n, 0.05);
    const VoxelGrid g = test::randomVoxelGrid(box, Axis::Y, n, 0.4, 77);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back(
            [&dir, t] { prepareGridFormat(dir.file("t" + std::to_string(t) + ".vdb"), true); });
    for (std::thread& t : threads) t.join();
    EXPECT_NO_THROW(prepareGridFormat(dir.file("a.vdb")));
    EXPECT_NO_THROW(prepareGridFormat(dir.file("a.binvox")));
    EXPECT_NO_THROW(prepareGridFormat(dir.file("a.unknown"), true));
    writeGrid(g, dir.file("a.vdb"));
    expectSameVoxels(g, readGrid(dir.file("a.vdb")));
    EXPECT_EQ(listDir(dir.path()), std::vector<std::string>{"a.vdb"});
}

TEST(GridIoTest, VdbRoundTripOfSolidBlocksThroughTiles) {
    // A 100^3 grid full inside [8, 90)^3: whole 8^3 leaves and 128^3 internal nodes prune into
    // tiles, which the reader must expand.
    test::TempDir dir;
    const Vec3i n{100, 100, 100};
    VoxelGrid g{Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 100, 100, 100), BitGrid(100, 100, 100)};
    for (int64_t x = 8; x < 90; ++x)
        for (int64_t y = 8; y < 90; ++y)
            for (int64_t z = 8; z < 90; ++z) g.bits.set(x, y, z);
    writeGrid(g, dir.file("solid.vdb"));
    const VoxelGrid r = readGrid(dir.file("solid.vdb"));
    EXPECT_EQ(r.bits.count(), 82 * 82 * 82);
    expectSameVoxels(g, r);
}

TEST(GridIoTest, LocallySlicedGridIsResampledBeforeWriting) {
    // Every column's 8 local slices span depths [0, 4): uniform cell k (centre k + 0.5) lies in
    // local slice 2k + 1 for k < 4 and outside the range (empty) for k >= 4.
    test::TempDir dir;
    Frame f = Frame::orthographic({{0, 0, 0}, {2, 2, 8}}, Axis::Z, 2, 2, 8);
    f.setLocalSlicing(std::vector<double>(4, 0.0), std::vector<double>(4, 4.0));
    VoxelGrid g{f, BitGrid(2, 2, 8)};
    for (int64_t s = 0; s < 8; ++s)
        if (s % 3 != 0) g.bits.set(1, 0, s); // local slices 1, 2, 4, 5, 7
    writeGrid(g, dir.file("local.nrrd"));
    const VoxelGrid r = readGrid(dir.file("local.nrrd"));
    for (int64_t k = 0; k < 8; ++k) {
        const bool expected = k < 4 && (2 * k + 1) % 3 != 0; // local 1, 3, 5, 7 -> on, off, on, on
        EXPECT_EQ(r.atWorldIndex(1, 0, k), expected) << k;
        EXPECT_FALSE(r.atWorldIndex(0, 0, k));
    }
}

// ---- Written bytes against independent decoders ------------------------------------------------

TEST(GridIoTest, BinvoxBytesDecodeWithSpecReader) {
    // test::readBinvoxBySpec decodes from the format's description: header lines, then (value,
    // count) pairs, count 1..255, voxel order x * (ny * nz) + z * ny + y, dims nx nz ny.
    test::TempDir dir;
    const Vec3i n{13, 70, 300}; // 300 > 255: runs must split
    for (Axis axis : kAxes) {
        const VoxelGrid g = test::randomVoxelGrid(cubicCellBox(n, 0.5), axis, n, 0.9, 41 + int(axis));
        const std::string path = dir.file("g.binvox");
        writeGrid(g, path);
        const test::BinvoxFile f = test::readBinvoxBySpec(path);
        ASSERT_EQ(f.dims, n);
        EXPECT_EQ(f.translate, g.frame.box().lo);
        EXPECT_DOUBLE_EQ(f.scale, 300 * 0.5);
        int64_t mismatches = 0;
        for (int64_t x = 0; x < n.x; ++x)
            for (int64_t y = 0; y < n.y; ++y)
                for (int64_t z = 0; z < n.z; ++z) mismatches += f.at(x, y, z) != g.atWorldIndex(x, y, z);
        EXPECT_EQ(mismatches, 0) << toString(axis);
    }
}

TEST(GridIoTest, NrrdBytesDecodeWithSpecReader) {
    // From the NRRD spec: "field: value" lines up to a blank line, then raw uchar samples with
    // x fastest; space origin = centre of voxel (0,0,0), space directions = cell vectors.
    test::TempDir dir;
    const Vec3i n{70, 5, 33};
    const Box3d box{{1, -2, 0}, {1 + 70 * 0.25, -2 + 5 * 2.0, 33 * 0.125}};
    for (Axis axis : kAxes) {
        const VoxelGrid g = test::randomVoxelGrid(box, axis, n, 0.5, 51 + int(axis));
        const std::string path = dir.file("g.nrrd");
        writeGrid(g, path);
        const std::string bytes = test::readFileBytes(path);
        const size_t end = bytes.find("\n\n");
        ASSERT_NE(end, std::string::npos);
        EXPECT_EQ(bytes.substr(0, 9), "NRRD0004\n");
        std::map<std::string, std::string> fields;
        std::istringstream header(bytes.substr(0, end));
        for (std::string line; std::getline(header, line);) {
            const size_t colon = line.find(": ");
            if (line.empty() || line[0] == '#' || colon == std::string::npos) continue;
            fields[line.substr(0, colon)] = line.substr(colon + 2);
        }
        EXPECT_EQ(fields["type"], "uchar");
        EXPECT_EQ(fields["dimension"], "3");
        EXPECT_EQ(fields["sizes"], "70 5 33");
        EXPECT_EQ(fields["encoding"], "raw");
        EXPECT_EQ(fields["space directions"], "(0.25,0,0) (0,2,0) (0,0,0.125)");
        EXPECT_EQ(fields["space origin"], "(1.125,-1,0.0625)");
        const std::string data = bytes.substr(end + 2);
        ASSERT_EQ(int64_t(data.size()), n.x * n.y * n.z);
        int64_t mismatches = 0, badValues = 0;
        for (int64_t z = 0; z < n.z; ++z)
            for (int64_t y = 0; y < n.y; ++y)
                for (int64_t x = 0; x < n.x; ++x) {
                    const auto v = uint8_t(data[size_t(x + n.x * (y + n.y * z))]);
                    badValues += v > 1;
                    mismatches += (v == 1) != g.atWorldIndex(x, y, z);
                }
        EXPECT_EQ(mismatches, 0) << toString(axis);
        EXPECT_EQ(badValues, 0);
    }
}

// A 3 x 2 x 4 pattern with no symmetry to hide a swapped or mirrored axis.
bool handPattern(int64_t i, int64_t j, int64_t k) {
    return (i + 2 * j + 3 * k) % 5 == 0 || (i == 2 && k == 3);
}

TEST(GridIoTest, ReadersDecodeHandWrittenFiles) {
    // The readers against files built here from the format descriptions, not by voxfx's writers.
    test::TempDir dir;
    const Vec3i n{3, 2, 4};
    // binvox: dim nx nz ny, order x * (ny * nz) + z * ny + y, (value, count) runs; cubic cells of
    // scale / max(dims) = 1 from the translate.
    std::vector<uint8_t> voxels(size_t(n.x * n.y * n.z));
    for (int64_t i = 0; i < n.x; ++i)
        for (int64_t j = 0; j < n.y; ++j)
            for (int64_t k = 0; k < n.z; ++k)
                voxels[size_t(i * n.y * n.z + k * n.y + j)] = handPattern(i, j, k);
    std::string binvox = "#binvox 1\ndim 3 4 2\ntranslate 1 2 3\nscale 4\ndata\n";
    for (size_t p = 0; p < voxels.size();) {
        size_t run = 1;
        while (p + run < voxels.size() && voxels[p + run] == voxels[p] && run < 255) ++run;
        binvox += char(voxels[p]);
        binvox += char(run);
        p += run;
    }
    // NRRD: raw uchar samples, x fastest; space origin is the centre of voxel (0, 0, 0).
    std::string nrrd =
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 2 4\nencoding: raw\nspace dimension: 3\n"
        "space directions: (0.5,0,0) (0,0.25,0) (0,0,2)\nspace origin: (1.25,2.125,4)\n\n";
    for (int64_t k = 0; k < n.z; ++k)
        for (int64_t j = 0; j < n.y; ++j)
            for (int64_t i = 0; i < n.x; ++i) nrrd += char(handPattern(i, j, k) ? 1 : 0);
    struct Case {
        std::string path;
        Box3d box;
    };
    const Case cases[] = {{test::writeFile(dir.file("hand.binvox"), binvox), {{1, 2, 3}, {4, 4, 7}}},
                          {test::writeFile(dir.file("hand.nrrd"), nrrd), {{1, 2, 3}, {2.5, 2.5, 11}}}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.path);
        const VoxelGrid g = readGrid(c.path);
        ASSERT_EQ(g.worldDims(), n);
        int64_t wrong = 0, on = 0;
        for (int64_t i = 0; i < n.x; ++i)
            for (int64_t j = 0; j < n.y; ++j)
                for (int64_t k = 0; k < n.z; ++k) {
                    wrong += g.atWorldIndex(i, j, k) != handPattern(i, j, k);
                    on += handPattern(i, j, k);
                }
        EXPECT_EQ(wrong, 0);
        EXPECT_EQ(g.bits.count(), on);
        expectNearBox(g.frame.box(), c.box);
    }
}

TEST(GridIoTest, VdbReadsBackWithPlainOpenVdbAtVoxelCentres) {
    test::TempDir dir;
    const Vec3i n{21, 9, 17};
    const Box3d box{{-1, 2, 3}, {-1 + 21 * 0.5, 2 + 9 * 0.25, 3 + 17 * 1.0}};
    const Vec3d cell{0.5, 0.25, 1.0};
    const VoxelGrid g = test::randomVoxelGrid(box, Axis::Y, n, 0.5, 61);
    openvdb::initialize();
    for (bool asFloat : {false, true}) {
        SCOPED_TRACE(asFloat ? "float" : "bool");
        GridWriteOptions o;
        o.vdbFloat = asFloat;
        o.gridName = asFloat ? "density" : "voxels";
        const std::string path = dir.file(asFloat ? "f.vdb" : "b.vdb");
        writeGrid(g, path, o);

        // Load everything now: the checks below must not depend on delayed loading (which
        // needs OPENVDB_USE_DELAYED_LOADING, defined only through the OpenVDB::openvdb target).
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        openvdb::GridBase::Ptr base = file.readGrid(o.gridName);
        file.close();
        ASSERT_TRUE(base);
        const openvdb::math::Transform& xform = base->transform();
        int64_t mismatches = 0, badCentres = 0;
        auto check = [&](const auto& grid) {
            auto acc = grid.getConstAccessor();
            for (int64_t i = 0; i < n.x; ++i)
                for (int64_t j = 0; j < n.y; ++j)
                    for (int64_t k = 0; k < n.z; ++k) {
                        const openvdb::Coord ijk{int(i), int(j), int(k)};
                        const bool on = acc.isValueOn(ijk) && acc.getValue(ijk) == 1;
                        mismatches += on != g.atWorldIndex(i, j, k);
                        const openvdb::Vec3d w = xform.indexToWorld(ijk);
                        const Vec3d expected =
                            box.lo + (Vec3d(double(i), double(j), double(k)) + Vec3d(0.5, 0.5, 0.5)) * cell;
                        badCentres += std::abs(w.x() - expected.x) > 1e-12 ||
                                      std::abs(w.y() - expected.y) > 1e-12 ||
                                      std::abs(w.z() - expected.z) > 1e-12;
                    }
        };
        if (asFloat) {
            auto fg = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
            ASSERT_TRUE(fg);
            EXPECT_EQ(fg->getGridClass(), openvdb::GRID_FOG_VOLUME);
            check(*fg);
        } else {
            auto bg = openvdb::gridPtrCast<openvdb::BoolGrid>(base);
            ASSERT_TRUE(bg);
            check(*bg);
        }
        EXPECT_EQ(mismatches, 0);
        EXPECT_EQ(badCentres, 0);
    }
}

TEST(GridIoTest, VdbTreeIsTheOneOpenVdbBuildsVoxelByVoxelAndPrunes) {
    // A 150 x 140 x 300 grid: a full 128^3 block (a tile of the upper node), a full 8^3 block in
    // a mixed lower node (a tile there), mixed leaves, and a full 128^3 block whose neighbour
    // node is mixed. The reference is OpenVDB's own tree with every voxel set on, then pruned.
    test::TempDir dir;
    const int64_t nx = 150, ny = 140, nz = 300;
    VoxelGrid g{Frame::orthographic({{0, 0, 0}, {1.5, 1.4, 3.0}}, Axis::Z, nx, ny, nz), BitGrid(nx, ny, nz)};
    auto on = [&](int64_t x, int64_t y, int64_t z) {
        if (x < 128 && y < 128 && z < 128) return true;                                     // full lower node
        if (x < 128 && y < 128 && z >= 128 && z < 256) return (x * 7 + y * 3 + z) % 5 == 0; // mixed
        if (x >= 136 && x < 144 && y >= 8 && y < 16 && z >= 256 && z < 264) return true;    // full leaf
        return x >= 130 && (x + y + z) % 11 == 0;
    };
    for (int64_t x = 0; x < nx; ++x)
        for (int64_t y = 0; y < ny; ++y)
            for (int64_t z = 0; z < nz; ++z)
                if (on(x, y, z)) g.bits.set(x, y, z);
    openvdb::initialize();
    openvdb::BoolGrid reference(false);
    {
        auto acc = reference.getAccessor();
        for (int64_t x = 0; x < nx; ++x)
            for (int64_t y = 0; y < ny; ++y)
                for (int64_t z = 0; z < nz; ++z)
                    if (on(x, y, z)) acc.setValueOn(openvdb::Coord(int(x), int(y), int(z)), true);
    }
    reference.tree().prune();
    writeGrid(g, dir.file("tree.vdb"));
    openvdb::io::File file(dir.file("tree.vdb"));
    file.open(/*delayLoad=*/false);
    auto written = openvdb::gridPtrCast<openvdb::BoolGrid>(file.readGrid("voxels"));
    file.close();
    ASSERT_TRUE(written);
    EXPECT_EQ(written->tree().nodeCount(), reference.tree().nodeCount()); // nodes per level
    EXPECT_EQ(written->tree().activeTileCount(), reference.tree().activeTileCount());
    EXPECT_EQ(written->tree().activeVoxelCount(), reference.tree().activeVoxelCount());
    EXPECT_EQ(written->tree().activeVoxelCount(), uint64_t(g.bits.count()));
    EXPECT_TRUE(written->tree().hasSameTopology(reference.tree()));
}

TEST(GridIoTest, VdbReadsForeignFloatGridWithoutDimensions) {
    // A fog volume made with plain OpenVDB: voxels > 0 count, the active box sizes the grid.
    test::TempDir dir;
    openvdb::initialize();
    auto fg = openvdb::FloatGrid::create(0.0f);
    fg->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    auto acc = fg->getAccessor();
    acc.setValue(openvdb::Coord(-3, 4, 10), 0.5f);
    acc.setValue(openvdb::Coord(2, 6, 10), 2.0f);
    acc.setValue(openvdb::Coord(0, 5, 12), 0.0f); // active but not > 0: empty, still in the box
    fg->setName("fog");
    openvdb::io::File(dir.file("fog.vdb")).write({fg});
    const VoxelGrid r = readGrid(dir.file("fog.vdb"));
    ASSERT_EQ(r.worldDims(), Vec3i(6, 3, 3));
    EXPECT_EQ(r.bits.count(), 2);
    EXPECT_TRUE(r.atWorldIndex(0, 0, 0));
    EXPECT_TRUE(r.atWorldIndex(5, 2, 0));
    // Index -3 has its centre at -1.5 (voxel size 0.5), so the box starts a half cell lower.
    expectNearBox(r.frame.box(), Box3d{{-1.75, 1.75, 4.75}, {1.25, 3.25, 6.25}});
}

// ---- Voxel meshes -----------------------------------------------------------------------------

struct PlyMesh {
    std::vector<std::array<float, 3>> vertices;
    std::vector<std::array<int32_t, 4>> quads;
};

// Reads the binary PLY this library writes, from the PLY spec (header, then packed records).
PlyMesh readPly(const std::string& path) {
    const std::string bytes = test::readFileBytes(path);
    const size_t end = bytes.find("end_header\n");
    EXPECT_NE(end, std::string::npos);
    std::istringstream header(bytes.substr(0, end));
    PlyMesh m;
    int64_t nv = -1, nf = -1;
    for (std::string line; std::getline(header, line);) {
        std::istringstream l(line);
        std::string a, b;
        int64_t count;
        if (l >> a >> b >> count && a == "element") (b == "vertex" ? nv : nf) = count;
        if (line.rfind("format", 0) == 0) { EXPECT_EQ(line, "format binary_little_endian 1.0"); }
    }
    size_t p = end + 11;
    EXPECT_EQ(bytes.size(), p + size_t(nv) * 12 + size_t(nf) * 17);
    if (bytes.size() != p + size_t(nv) * 12 + size_t(nf) * 17) return m;
    m.vertices.resize(size_t(nv));
    std::memcpy(m.vertices.data(), bytes.data() + p, size_t(nv) * 12);
    p += size_t(nv) * 12;
    for (int64_t f = 0; f < nf; ++f, p += 17) {
        EXPECT_EQ(bytes[p], 4);
        std::array<int32_t, 4> q;
        std::memcpy(q.data(), bytes.data() + p + 1, 16);
        m.quads.push_back(q);
    }
    return m;
}

// Exposed faces by brute force: each filled voxel's six neighbours, outside counting as empty.
int64_t bruteForceExposedFaces(const VoxelGrid& g) {
    const Vec3i n = g.worldDims();
    auto on = [&](int64_t i, int64_t j, int64_t k) {
        return i >= 0 && j >= 0 && k >= 0 && i < n.x && j < n.y && k < n.z && g.atWorldIndex(i, j, k);
    };
    int64_t faces = 0;
    for (int64_t i = 0; i < n.x; ++i)
        for (int64_t j = 0; j < n.y; ++j)
            for (int64_t k = 0; k < n.z; ++k)
                if (on(i, j, k))
                    faces += !on(i - 1, j, k) + !on(i + 1, j, k) + !on(i, j - 1, k) + !on(i, j + 1, k) +
                             !on(i, j, k - 1) + !on(i, j, k + 1);
    return faces;
}

TEST(GridIoTest, VoxelMeshOfOneVoxelIsACubeWithEightCorners) {
    test::TempDir dir;
    VoxelGrid g{Frame::orthographic({{0, 0, 0}, {3, 6, 9}}, Axis::Z, 3, 3, 3), BitGrid(3, 3, 3)};
    g.bits.set(1, 1, 1); // world box [1, 2] x [2, 4] x [3, 6]
    writeGrid(g, dir.file("one.ply"));
    const PlyMesh m = readPly(dir.file("one.ply"));
    EXPECT_EQ(m.quads.size(), 6u);
    std::set<std::array<float, 3>> corners(m.vertices.begin(), m.vertices.end());
    EXPECT_EQ(corners.size(), 8u);
    EXPECT_EQ(m.vertices.size(), 8u);
    for (float x : {1.f, 2.f})
        for (float y : {2.f, 4.f})
            for (float z : {3.f, 6.f}) EXPECT_EQ(corners.count({x, y, z}), 1u) << x << " " << y << " " << z;
}

TEST(GridIoTest, VoxelMeshOfTwoAdjacentVoxelsHasTenFaces) {
    test::TempDir dir;
    for (Axis axis : kAxes) {
        VoxelGrid g{Frame::orthographic({{0, 0, 0}, {4, 4, 4}}, axis, 4, 4, 4), BitGrid(4, 4, 4)};
        g.bits.set(1, 2, 2);
        g.bits.set(1, 2, 3); // neighbours along the slice axis
        writeGrid(g, dir.file("two.ply"));
        const PlyMesh m = readPly(dir.file("two.ply"));
        EXPECT_EQ(m.quads.size(), 10u) << toString(axis);
        EXPECT_EQ(m.vertices.size(), 12u) << toString(axis);
    }
}

TEST(GridIoTest, VoxelMeshFacesAreExactlyTheExposedOnesFacingOut) {
    test::TempDir dir;
    uint64_t seed = 71;
    // 64 along z: the lattice has one more point than a column word holds.
    for (const Vec3i n : {Vec3i{13, 9, 70}, Vec3i{7, 5, 64}})
        for (Axis axis : kAxes) {
            // Unit cells from the origin: corners are small integers, exact in float.
            const Box3d box{{0, 0, 0}, {double(n.x), double(n.y), double(n.z)}};
            const VoxelGrid g = test::randomVoxelGrid(box, axis, n, 0.5, seed++);
            writeGrid(g, dir.file("r.ply"));
            const PlyMesh m = readPly(dir.file("r.ply"));
            SCOPED_TRACE(testing::Message() << n.z << " " << toString(axis));
            EXPECT_EQ(int64_t(m.quads.size()), bruteForceExposedFaces(g));
            // Shared vertices: no position twice, none unused; no face twice.
            const std::set<std::array<float, 3>> distinct(m.vertices.begin(), m.vertices.end());
            EXPECT_EQ(distinct.size(), m.vertices.size());
            std::set<int32_t> used;
            std::set<std::array<int32_t, 4>> sortedQuads;
            for (auto q : m.quads) {
                used.insert(q.begin(), q.end());
                std::sort(q.begin(), q.end());
                sortedQuads.insert(q);
            }
            EXPECT_EQ(used.size(), m.vertices.size());
            EXPECT_EQ(sortedQuads.size(), m.quads.size());
            // Each quad is a unit square whose normal (right-hand rule) leaves a filled voxel into an
            // empty one (or the outside).
            auto on = [&](const Vec3d& p) {
                const Vec3i v{int64_t(std::floor(p.x)), int64_t(std::floor(p.y)), int64_t(std::floor(p.z))};
                return v.x >= 0 && v.y >= 0 && v.z >= 0 && v.x < n.x && v.y < n.y && v.z < n.z &&
                       g.atWorldIndex(v.x, v.y, v.z);
            };
            int64_t bad = 0;
            for (const auto& q : m.quads) {
                Vec3d c[4];
                for (int t = 0; t < 4; ++t) {
                    const auto& v = m.vertices.at(size_t(q[size_t(t)]));
                    c[t] = {v[0], v[1], v[2]};
                }
                const Vec3d normal = cross(c[1] - c[0], c[2] - c[1]);
                const Vec3d centre = (c[0] + c[1] + c[2] + c[3]) * 0.25;
                bad += length(normal) != 1 || length(c[2] - c[0]) != std::sqrt(2.0) ||
                       !on(centre - normal * 0.5) || on(centre + normal * 0.5);
            }
            EXPECT_EQ(bad, 0);
        }
}

TEST(GridIoTest, VoxelObjHasTheSameMeshAsPly) {
    test::TempDir dir;
    const VoxelGrid g = test::randomVoxelGrid({{0, 0, 0}, {1, 2, 3}}, Axis::X, {11, 7, 5}, 0.5, 81);
    writeGrid(g, dir.file("m.ply"));
    writeGrid(g, dir.file("m.obj"));
    const PlyMesh ply = readPly(dir.file("m.ply"));
    std::istringstream obj(test::readFileBytes(dir.file("m.obj")));
    std::vector<std::array<float, 3>> vertices;
    std::vector<std::array<int32_t, 4>> quads;
    for (std::string line; std::getline(obj, line);) {
        std::istringstream l(line);
        std::string tag;
        l >> tag;
        if (tag == "v") {
            std::array<float, 3> v;
            l >> v[0] >> v[1] >> v[2];
            vertices.push_back(v);
        } else if (tag == "f") {
            std::array<int32_t, 4> q;
            l >> q[0] >> q[1] >> q[2] >> q[3];
            for (auto& i : q) --i;
            quads.push_back(q);
        }
    }
    EXPECT_EQ(vertices, ply.vertices);
    EXPECT_EQ(quads, ply.quads);
    EXPECT_EQ(int64_t(quads.size()), bruteForceExposedFaces(g));
}

// ---- Bad input --------------------------------------------------------------------------------

TEST(GridIoTest, MalformedFilesRaiseErrorsNamingThePath) {
    test::TempDir dir;
    const std::string header = "#binvox 1\ndim 2 2 2\ntranslate 0 0 0\nscale 1\ndata\n";
    struct Case {
        std::string name, bytes, cause;
    };
    const Case cases[] = {
        {"truncated.binvox", header + std::string("\x01\x03", 2), "truncated"},
        {"odd.binvox", header + std::string("\x01\x07\x00", 3), "truncated"},
        {"overflow.binvox", header + std::string("\x01\x05\x00\x04", 4), "overruns"},
        {"trailing.binvox", header + std::string("\x01\x08\x00\x01", 4), "overruns"},
        {"garbage.binvox", "PK\x03\x04 this is a zip file", "not a binvox file"},
        {"nodim.binvox", "#binvox 1\nscale 1\ndata\n", "dim"},
        {"baddim.binvox", "#binvox 1\ndim 2 -2 2\ndata\n\x01\x08", "dim"},
        {"nodata.binvox", "#binvox 1\ndim 2 2 2\n", "data"},
        {"empty.binvox", "", "not a binvox file"},
        {"truncated.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n\x01\x01\x00",
         "truncated"},
        {"gzip.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: gzip\n\n", "gzip"},
        {"float.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n", "type"},
        {"rotated.nrrd",
         "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: raw\n"
         "space directions: (0,1,0) (1,0,0) (0,0,1)\n\n\x01",
         "axis-aligned"},
        {"noheaderend.nrrd", "NRRD0004\ntype: uchar\n", "truncated"},
        {"garbage.nrrd", "P6\n2 2\n255\n", "not a NRRD file"},
        {"garbage.vdb", "this is not an OpenVDB file at all", "OpenVDB"},
    };
    for (const Case& c : cases) {
        const std::string path = test::writeFile(dir.file(c.name), c.bytes);
        expectErrorMentioning([&] { readGrid(path); }, path, c.cause);
    }
    expectErrorMentioning([&] { readGrid(dir.file("missing.binvox")); }, dir.file("missing.binvox"),
                          "No such file");
    expectErrorMentioning([&] { readGrid(dir.file("missing.vdb")); }, dir.file("missing.vdb"),
                          "No such file");
    expectErrorMentioning([&] { readGrid(dir.file("grid.raw")); }, dir.file("grid.raw"), ".nrrd");
    expectErrorMentioning([&] { readGrid(dir.file("mesh.ply")); }, dir.file("mesh.ply"), "write-only");
}

TEST(GridIoTest, EveryTruncationOfAFileIsAnError) {
    // Every proper prefix of a valid file, header or data, must raise voxfx::Error (never crash,
    // hang or return a grid). For .vdb this covers OpenVDB's reader reading past the end.
    test::TempDir dir;
    const VoxelGrid g = test::randomVoxelGrid({{0, 0, 0}, {1, 1, 1}}, Axis::Z, {9, 6, 11}, 0.5, 91);
    for (const char* ext : {"binvox", "nrrd", "vdb"}) {
        const std::string full = dir.file(std::string("full.") + ext),
                          cut = dir.file(std::string("cut.") + ext);
        writeGrid(g, full);
        const std::string bytes = test::readFileBytes(full);
        // Every length through the headers and the last bytes, every 31st in between (a .vdb of
        // this grid is ~10 KB, mostly internal-node masks); shortened in place, longest first.
        test::writeFile(cut, bytes);
        int64_t tried = 0, errors = 0;
        for (size_t len = bytes.size(); len-- > 0;) {
            if (len >= 512 && len + 64 < bytes.size() && len % 31 != 0) continue;
            std::filesystem::resize_file(cut, len);
            ++tried;
            try {
                readGrid(cut);
            } catch (const Error&) { ++errors; }
        }
        EXPECT_EQ(errors, tried) << ext;
    }
}

TEST(GridIoTest, PerspectiveGridsAreRejected) {
    test::TempDir dir;
    const Frame f = Frame::perspective({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 1.0, 4, 4, 1, 2, 4);
    const VoxelGrid g{f, BitGrid(4, 4, 4)};
    expectErrorMentioning([&] { writeGrid(g, dir.file("p.binvox")); }, dir.file("p.binvox"), "perspective");
    EXPECT_TRUE(listDir(dir.path()).empty());
}

// ---- Failed writes ------------------------------------------------------------------------------

TEST(GridIoTest, FailedWritesLeaveNoTemporaryAndKeepTheTarget) {
    test::TempDir dir;
    const VoxelGrid g = test::randomVoxelGrid({{0, 0, 0}, {1, 1, 1}}, Axis::Z, {8, 8, 8}, 0.5, 101);
    // Missing directory.
    const std::string missing = dir.file("nope/g.binvox");
    expectErrorMentioning([&] { writeGrid(g, missing); }, missing, "No such file");
    EXPECT_TRUE(listDir(dir.path()).empty());
    // The target is a directory (with a file in it, which must survive).
    std::filesystem::create_directory(dir.path() / "target.nrrd");
    test::writeFile(dir.file("target.nrrd/keep"), "x");
    for (const char* name : {"target.nrrd"}) {
        expectErrorMentioning([&] { writeGrid(g, dir.file(name)); }, dir.file(name), "directory");
    }
    EXPECT_EQ(listDir(dir.path()), std::vector<std::string>{"target.nrrd"});
    EXPECT_EQ(test::readFileBytes(dir.file("target.nrrd/keep")), "x");
}

TEST(GridIoTest, WriteFailingMidwayKeepsTheOldFile) {
    // A file-size limit makes the writes fail part way (EFBIG) like a full disk would.
    test::TempDir dir;
    const std::string target = test::writeFile(dir.file("g.nrrd"), "old contents");
    const VoxelGrid g = test::randomVoxelGrid({{0, 0, 0}, {1, 1, 1}}, Axis::Z, {64, 64, 64}, 0.5, 111);
    rlimit old{};
    ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
    const auto oldHandler = std::signal(SIGXFSZ, SIG_IGN);
    rlimit small = old;
    small.rlim_cur = 64 << 10;
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
    bool threw = false;
    std::string what;
    try {
        writeGrid(g, target);
    } catch (const Error& e) {
        threw = true;
        what = e.what();
    }
    setrlimit(RLIMIT_FSIZE, &old);
    std::signal(SIGXFSZ, oldHandler);
    EXPECT_TRUE(threw);
    EXPECT_NE(what.find(target), std::string::npos) << what;
    EXPECT_EQ(test::readFileBytes(target), "old contents");
    EXPECT_EQ(listDir(dir.path()), std::vector<std::string>{"g.nrrd"});
}

TEST(GridIoTest, AtomicFileReplacesOnlyOnCommit) {
    test::TempDir dir;
    const std::string target = test::writeFile(dir.file("t.bin"), "old");
    {
        detail::AtomicFile f(target);
        f.stream() << "new";
        EXPECT_EQ(listDir(dir.path()).size(), 2u); // target + temporary
    }
    EXPECT_EQ(test::readFileBytes(target), "old");
    EXPECT_EQ(listDir(dir.path()), std::vector<std::string>{"t.bin"});
    {
        detail::AtomicFile f(target);
        f.stream() << "new";
        f.commit();
    }
    EXPECT_EQ(test::readFileBytes(target), "new");
    EXPECT_EQ(listDir(dir.path()), std::vector<std::string>{"t.bin"});
}

} // namespace
} // namespace voxfx
