// Tests of src/cli/: the voxfx command end to end. Bad input must exit non-zero with a one-line
// message that says what is wrong, and leave no output file (and an existing one untouched).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace voxfx {
namespace {

using CliRun = test::CommandRun;

CliRun runCli(const test::TempDir& dir, const std::string& args) { return test::runVoxfx(dir, args); }

const char* kCubeOff = "OFF\n8 12 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                       "3 0 2 3\n3 0 3 1\n3 4 5 7\n3 4 7 6\n3 0 1 5\n3 0 5 4\n"
                       "3 2 6 7\n3 2 7 3\n3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n";

// Asserts a failed run: non-zero exit, one "voxfx: error:" line naming `needle`, no output file,
// and no temporary file left beside it.
void expectCleanFailure(const test::TempDir& dir, const CliRun& r, const std::string& needle,
                        const std::string& output) {
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("voxfx: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << "expected '" << needle << "' in: " << r.err;
    EXPECT_FALSE(std::filesystem::exists(output)) << output;
    for (const auto& e : std::filesystem::directory_iterator(dir.path()))
        EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(CliTest, VoxelizesACubeAndPrintsASummary) {
    test::TempDir dir;
    const std::string mesh = test::writeFile(dir.file("cube.off"), kCubeOff);
    const CliRun r = runCli(dir, "voxelize " + mesh + " -o " + dir.file("cube.binvox") + " -r 8");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // The unit cube fills its 8^3 bounding grid completely: in the file (decoded from the format's
    // description, not by voxfx) and in the summary.
    const test::BinvoxFile f = test::readBinvoxBySpec(dir.file("cube.binvox"));
    EXPECT_EQ(f.dims, Vec3i(8, 8, 8));
    EXPECT_EQ(f.count(), 512);
    EXPECT_EQ(f.translate, Vec3d(0, 0, 0));
    EXPECT_EQ(f.scale, 1.0);
    EXPECT_NE(r.out.find("512 filled voxels"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("8 x 8 x 8 grid"), std::string::npos) << r.out;
}

TEST(CliTest, VdbOutputIsVoxelizedInTilesWithinTheMemoryBudget) {
    // A cube at 2048^3: 1 GiB as a dense grid, a few tiles as a sparse one.
    test::TempDir dir;
    const std::string mesh = test::writeFile(dir.file("cube.off"), kCubeOff);
    const std::string out = dir.file("cube.vdb");
    const CliRun r = runCli(dir, "voxelize " + mesh + " -o " + out + " -r 2048 --memory 256M");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("8,589,934,592 filled voxels"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("for the whole grid and its tree, over the budget"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(vdb, sparse)"), std::string::npos) << r.out;
    EXPECT_LT(std::filesystem::file_size(out), 100000u);
    // The whole grid does not fit the budget: --dense and a fill that needs the whole grid stop
    // with one line saying so.
    std::filesystem::remove(out);
    expectCleanFailure(dir, runCli(dir, "voxelize " + mesh + " -o " + out + " -r 2048 --memory 256M --dense"),
                       "needs 1.00 GiB", out);
    expectCleanFailure(dir,
                       runCli(dir, "voxelize " + mesh + " -o " + out + " -r 2048 --memory 256M --fill flood"),
                       "fill 'flood' needs the whole grid", out);
    expectCleanFailure(dir, runCli(dir, "voxelize " + mesh + " -o " + out + " -r 8 --memory lots"),
                       "--memory must be bytes", out);
    // A budget the tiles' triangle lists do not fit: one line before anything large is allocated.
    const CliRun tiny = runCli(dir, "voxelize " + mesh + " -o " + out + " -r 16384 --memory 64K");
    expectCleanFailure(dir, tiny, "but the memory budget is", out);
    EXPECT_EQ(std::count(tiny.err.begin(), tiny.err.end(), '\n'), 1) << tiny.err;
    const CliRun help = runCli(dir, "voxelize --help");
    EXPECT_NE(help.out.find("flood and vote need the"), std::string::npos) << help.out;
    EXPECT_NE(help.out.find("the default is the memory available"), std::string::npos) << help.out;
    EXPECT_NE(help.out.find("A size that cannot fit stops before"), std::string::npos) << help.out;
}

TEST(CliTest, HelpExplainsWhereVoxelCentresLie) {
    test::TempDir dir;
    const CliRun r = runCli(dir, "voxelize --help");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_NE(r.out.find("CENTRE is lo + (i + 0.5) * cell"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--resolution"), std::string::npos);
}

TEST(CliTest, MissingInputFailsCleanly) {
    test::TempDir dir;
    const std::string out = dir.file("out.vdb");
    expectCleanFailure(dir, runCli(dir, "voxelize " + dir.file("nope.off") + " -o " + out), "nope.off", out);
}

TEST(CliTest, MalformedMeshesFailCleanly) {
    test::TempDir dir;
    const std::string out = dir.file("out.nrrd");
    const std::pair<const char*, std::string> cases[] = {
        {"nan.off", "OFF\n3 1 0\n0 0 0\nnan 1 0\n0 1 1\n3 0 1 2\n"},
        {"index.off", "OFF\n3 1 0\n0 0 0\n1 1 0\n0 1 1\n3 0 1 7\n"},
        {"empty.off", "OFF\n3 0 0\n0 0 0\n1 1 0\n0 1 1\n"},
        {"truncated.off", std::string(kCubeOff).substr(0, 60)},
        {"truncated.stl", std::string(80, 'x') + std::string("\x10\x00\x00\x00", 4) + std::string(100, '\0')},
        {"mesh.xyz123", "not a mesh"},
    };
    for (const auto& [name, content] : cases) {
        const std::string mesh = test::writeFile(dir.file(name), content);
        SCOPED_TRACE(name);
        expectCleanFailure(dir, runCli(dir, "voxelize " + mesh + " -o " + out + " -r 8"), name, out);
    }
}

TEST(CliTest, UnknownOutputFormatFailsBeforeAnyWork) {
    test::TempDir dir;
    const std::string mesh = test::writeFile(dir.file("cube.off"), kCubeOff);
    const std::string out = dir.file("out.jpeg");
    expectCleanFailure(dir, runCli(dir, "voxelize " + mesh + " -o " + out), ".binvox", out);
}

TEST(CliTest, GridTooLargeForMemoryFailsUpFrontWithTheSizeNeeded) {
    test::TempDir dir;
    const std::string mesh = test::writeFile(dir.file("cube.off"), kCubeOff);
    const std::string out = dir.file("out.vdb");
    expectCleanFailure(dir, runCli(dir, "voxelize " + mesh + " -o " + out + " --dims 200000 200000 200000"),
                       "needs", out);
}

TEST(CliTest, FailedRunLeavesAnExistingOutputUntouched) {
    test::TempDir dir;
    const std::string out = test::writeFile(dir.file("keep.vdb"), "precious");
    const CliRun r = runCli(dir, "voxelize " + dir.file("missing.off") + " -o " + out);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(test::readFileBytes(out), "precious");
}

TEST(CliTest, InfoReportsClosedAndOpenMeshes) {
    test::TempDir dir;
    const std::string closed = test::writeFile(dir.file("cube.off"), kCubeOff);
    CliRun r = runCli(dir, "info " + closed);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("triangles:  12"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("closed:     yes"), std::string::npos) << r.out;
    // Drop the last face: four boundary edges.
    std::string open = kCubeOff;
    open.replace(open.find("8 12 0"), 6, "8 11 0");
    open.erase(open.rfind("3 1 7 5\n"));
    r = runCli(dir, "info " + test::writeFile(dir.file("open.off"), open));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("closed:     no"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("3 boundary"), std::string::npos) << r.out;
}

TEST(CliTest, OpenMeshSwitchesToFloodFillAndSaysSo) {
    test::TempDir dir;
    std::string open = kCubeOff;
    open.replace(open.find("8 12 0"), 6, "8 11 0");
    open.erase(open.rfind("3 1 7 5\n"));
    const std::string mesh = test::writeFile(dir.file("open.off"), open);
    const CliRun r = runCli(dir, "voxelize " + mesh + " -o " + dir.file("o.binvox") + " -r 8");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("not closed"), std::string::npos) << r.err;
    EXPECT_NE(r.out.find("(flood)"), std::string::npos) << r.out;
}

} // namespace
} // namespace voxfx
