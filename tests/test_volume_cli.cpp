// Tests of `voxfx volume-info`: a summary for good volumes, one error line and no output for bad
// volumes and transfer functions; and of `voxfx voxelize VOLUME --threshold T` (GI08 §7): the
// grid files it writes, read back, against a brute-force threshold of the samples.
#include <filesystem>
#include <string>

#include "test_util.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx {
namespace {

using test::TempDir;
using test::writeFile;

// A 2 x 3 x 4 volume of uint8 values 0..23, x fastest, and a transfer function over it.
std::string rampNrrd() {
    std::string s = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 3 4\nencoding: raw\nspacings: 1 2 3\n\n";
    for (int v = 0; v < 24; ++v) s += char(v);
    return s;
}

TEST(VolumeCli, VolumeInfoSummarizesAVolumeAndATransferFunction) {
    TempDir dir;
    const std::string vol = writeFile(dir.file("ramp.nrrd"), rampNrrd());
    // Opacity > 0 above 10.5: the values 11..23, 13 voxels.
    const std::string tf = writeFile(dir.file("tf.json"),
                                     R"({"color": [[0, 1, 1, 1]], "opacity": [[0, 0], [10.5, 0], [23, 1]]})");
    const test::CommandRun r = test::runVoxfx(dir, "volume-info " + vol + " --tf " + tf);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("dims:       2 x 3 x 4 (24 voxels)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("type:       uint8"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("min 0, max 23, mean 11.5, 23 non-zero"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("13 voxels with opacity > 0"), std::string::npos) << r.out;
}

TEST(VolumeCli, VolumeInfoReadsAnOpenVdbFloatGrid) {
    // A float fog volume with 1 in the filled voxels of a random grid (writeGrid's --vdb-float).
    TempDir dir;
    const VoxelGrid g = test::randomVoxelGrid(Box3d{{0, 0, 0}, {2, 1, 1}}, Axis::Z, {10, 6, 5}, 0.3, 11);
    const std::string vdb = dir.file("fog.vdb");
    writeGrid(g, vdb, GridWriteOptions{true, "fog"});
    const test::CommandRun r = test::runVoxfx(dir, "volume-info " + vdb + " --grid fog");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("grid:       'fog' (fog volume)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("dims:       10 x 6 x 5 (300 voxels)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(", " + std::to_string(g.bits.count()) + " non-zero"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("spacing:    (0.2, 0.166667, 0.2)"), std::string::npos) << r.out;
}

TEST(VolumeCli, BadVolumeOrTransferFunctionGivesOneErrorAndNoOutput) {
    TempDir dir;
    const std::string vol = writeFile(dir.file("ramp.nrrd"), rampNrrd());
    const std::string cut = writeFile(dir.file("cut.nrrd"), rampNrrd().substr(0, rampNrrd().size() - 5));
    const std::string tf =
        writeFile(dir.file("tf.json"), R"({"color": [[1, 1, 1, 1], [0, 0, 0, 0]], "opacity": [[0, 1]]})");
    const struct {
        std::string args, needle;
    } cases[] = {
        {"volume-info " + cut, "truncated"},
        {"volume-info " + vol + " --tf " + tf, "not sorted"},
        {"volume-info " + dir.file("missing.inr"), "missing.inr"},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.args);
        const test::CommandRun r = test::runVoxfx(dir, c.args);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(r.out, "");
        EXPECT_NE(r.err.find("voxfx: error:"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
    }
}

// 1234567 -> "1,234,567", as the command prints counts.
std::string commas(int64_t v) {
    const std::string digits = std::to_string(v);
    std::string s;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) s += ',';
        s += digits[i];
    }
    return s;
}

// Cells of the grid read back from `path` that differ from "value >= t" at world index (i, j, k)
// of a volume of `dims` whose samples, x fastest, are `values`; and the grid's box against `box`.
int64_t thresholdFileMismatches(const std::string& path, const Vec3i& dims, const std::vector<float>& values,
                                double t, const Box3d& box) {
    const VoxelGrid g = readGrid(path);
    EXPECT_EQ(g.worldDims(), dims) << path;
    if (!(g.worldDims() == dims)) return -1;
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(g.frame.box().lo[a], box.lo[a], 1e-6 * (1 + std::abs(box.lo[a]))) << path;
        EXPECT_NEAR(g.frame.box().hi[a], box.hi[a], 1e-6 * (1 + std::abs(box.hi[a]))) << path;
    }
    int64_t wrong = 0;
    for (int64_t k = 0; k < dims.z; ++k)
        for (int64_t j = 0; j < dims.y; ++j)
            for (int64_t i = 0; i < dims.x; ++i)
                wrong += (double(values[std::size_t(i + dims.x * (j + dims.y * k))]) >= t) !=
                         g.atWorldIndex(i, j, k);
    return wrong;
}

TEST(VolumeCli, VoxelizeThresholdOfCtImagesWritesTheirLatticeAsABruteForceThreshold) {
    TempDir dir;
    for (const char* file : {"images/skull_2.9.inr", "images/liver.inr.gz"}) {
        VOXFX_REQUIRE_DATA(file);
        const Volume v = loadVolume(test::dataPath(file));
        const double t = v.minValue() + 0.3 * (v.maxValue() - v.minValue());
        int64_t inside = 0;
        for (const float x : v.values()) inside += double(x) >= t;
        for (const char* ext : {".nrrd", ".vdb"}) {
            SCOPED_TRACE(std::string(file) + " -> " + ext);
            const std::string out = dir.file(std::string("ct") + ext);
            const test::CommandRun r = test::runVoxfx(
                dir, "voxelize " + test::dataPath(file) + " --threshold " + std::to_string(t) + " -o " + out);
            ASSERT_EQ(r.exitCode, 0) << r.err;
            // std::to_string prints 6 decimals: the threshold the command used.
            const double used = std::stod(std::to_string(t));
            int64_t usedInside = 0;
            for (const float x : v.values()) usedInside += double(x) >= used;
            EXPECT_EQ(thresholdFileMismatches(out, v.dims(), v.values(), used, v.box()), 0);
            EXPECT_NE(r.out.find(" " + std::to_string(v.dims().x) + " x " + std::to_string(v.dims().y) +
                                 " x " + std::to_string(v.dims().z) + " grid"),
                      std::string::npos)
                << r.out;
            EXPECT_NE(r.out.find(commas(usedInside) + " filled voxels"), std::string::npos) << r.out;
            EXPECT_GT(usedInside, 0);
            EXPECT_NEAR(double(usedInside), double(inside), 0.01 * double(v.voxelCount()));
        }
    }
}

TEST(VolumeCli, VoxelizeThresholdReadsRawJsonAndFloatVdbVolumes) {
    TempDir dir;
    // Raw uint16 samples written here: the truth is these numbers, not what a reader makes of them.
    const Vec3i dims{7, 5, 6};
    std::vector<float> values;
    std::string raw;
    for (int64_t i = 0; i < dims.x * dims.y * dims.z; ++i) {
        const auto x = uint16_t((i * 2654435761u) % 4096);
        values.push_back(float(x));
        raw += char(x & 0xff);
        raw += char(x >> 8);
    }
    writeFile(dir.file("ct.raw"), raw);
    const std::string json =
        writeFile(dir.file("ct.json"), R"({"file": "ct.raw", "dims": [7, 5, 6], "type": "uint16",
        "endian": "little", "spacing": [0.5, 0.25, 2], "origin": [1.25, -2.125, 3]})");
    // origin is the centre of voxel (0, 0, 0): the box starts half a voxel before it.
    const Box3d box{{1, -2.25, 2}, {1 + 7 * 0.5, -2.25 + 5 * 0.25, 2 + 6 * 2.0}};
    ASSERT_EQ(
        test::runVoxfx(dir, "voxelize " + json + " --threshold 2048 -q -o " + dir.file("raw.nrrd")).exitCode,
        0);
    EXPECT_EQ(thresholdFileMismatches(dir.file("raw.nrrd"), dims, values, 2048, box), 0);

    // A float fog volume: 1 in the filled voxels of a random grid, 0 elsewhere.
    const VoxelGrid g = test::randomVoxelGrid(Box3d{{0, 0, 0}, {2, 1, 1.5}}, Axis::Z, {10, 5, 6}, 0.4, 7);
    writeGrid(g, dir.file("fog.vdb"), GridWriteOptions{true, "fog"});
    std::vector<float> fog;
    for (int64_t k = 0; k < 6; ++k)
        for (int64_t j = 0; j < 5; ++j)
            for (int64_t i = 0; i < 10; ++i) fog.push_back(g.atWorldIndex(i, j, k) ? 1.0f : 0.0f);
    ASSERT_EQ(test::runVoxfx(dir, "voxelize " + dir.file("fog.vdb") + " --threshold 0.5 -q -o " +
                                      dir.file("fog.nrrd"))
                  .exitCode,
              0);
    EXPECT_EQ(thresholdFileMismatches(dir.file("fog.nrrd"), {10, 5, 6}, fog, 0.5, g.frame.box()), 0);
}

TEST(VolumeCli, VoxelizeThresholdErrorsGiveOneLineAndNoOutput) {
    TempDir dir;
    const std::string vol = writeFile(dir.file("ramp.nrrd"), rampNrrd());
    // Oblique directions: a turned volume, which the grid formats cannot hold.
    const std::string turned = writeFile(
        dir.file("turned.nrrd"),
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 3 4\nencoding: raw\nspace: right-anterior-superior\n"
        "space directions: (0.6,0.8,0) (-0.8,0.6,0) (0,0,1)\nspace origin: (0,0,0)\n\n" +
            rampNrrd().substr(rampNrrd().size() - 24));
    const struct {
        std::string args, needle;
    } cases[] = {
        {"voxelize " + dir.file("missing.inr") + " --threshold 1", "missing.inr"},
        {"voxelize " + vol + " --threshold 1 -r 64", "-r/--resolution"},
        {"voxelize " + vol + " --threshold 1 --mode surface", "--mode"},
        {"voxelize " + vol + " --threshold nan", "threshold"},
        {"voxelize " + turned + " --threshold 1", "oriented"},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.args);
        const std::string out = dir.file("out.nrrd");
        const test::CommandRun r = test::runVoxfx(dir, c.args + " -o " + out);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_EQ(r.out, "");
        EXPECT_NE(r.err.find("voxfx: error:"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
        EXPECT_FALSE(std::filesystem::exists(out));
    }
}

} // namespace
} // namespace voxfx
