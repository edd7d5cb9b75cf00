// Tests of `voxfx volume-info`: a summary for good volumes, one error line and no output for bad
// volumes and transfer functions.
#include <string>

#include "test_util.hpp"
#include "voxfx/grid_io.hpp"

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

} // namespace
} // namespace voxfx
