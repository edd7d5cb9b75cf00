// Tests of src/batch/ and `voxfx batch`: outputs byte-identical to one `voxfx voxelize` process per
// mesh (the oracle: the single-file command, run separately), restart, bad meshes recorded without
// stopping the others, duplicate stems refused before any work, a report that parses as JSON.
#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_util.hpp"
#include "voxfx/batch.hpp"

namespace voxfx {
namespace {

namespace fs = std::filesystem;

// Real meshes, closed and open (the open ones take the flood fill), small enough for -r 24.
const char* const kBatchRealMeshes[] = {"meshes/bunny00.off", "meshes/elephant-with-holes.off",
                                        "meshes/cube-ouvert.off", "meshes/fandisk.off",
                                        "meshes/mushroom.off"};

const char* kBatchCubeOff = "OFF\n8 12 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                            "3 0 2 3\n3 0 3 1\n3 4 5 7\n3 4 7 6\n3 0 1 5\n3 0 5 4\n"
                            "3 2 6 7\n3 2 7 3\n3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n";

std::string batchManifest(const test::TempDir& dir, const std::vector<std::string>& lines) {
    std::string text = "# meshes of this test\n\n";
    for (const std::string& l : lines) text += l + "\n";
    return test::writeFile(dir.file("manifest.txt"), text);
}

nlohmann::json batchReadReport(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in); // throws (failing the test) when it is not JSON
}

TEST(BatchTest, LibraryAndCommandOutputsAreByteIdenticalToVoxelizeOnRealMeshes) {
    for (const char* m : kBatchRealMeshes) VOXFX_REQUIRE_DATA(m);
    test::TempDir dir;
    std::vector<std::string> meshes;
    for (const char* m : kBatchRealMeshes) meshes.push_back(test::dataPath(m));
    struct Case {
        std::string options, format;
        VoxelizeMode mode;
    };
    const Case cases[] = {{"-r 24", "binvox", VoxelizeMode::Solid},
                          {"-r 20 --mode interior", "nrrd", VoxelizeMode::Interior}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.options);
        const GridFormat format = gridFormatFromPath("x." + c.format);
        // The library, two threads per batch, one per mesh.
        BatchOptions bo;
        bo.fit.resolution = c.options == "-r 24" ? 24 : 20;
        bo.voxelize.mode = c.mode;
        bo.threads = 2;
        const std::string libDir = dir.file("lib-" + c.format);
        const BatchSummary s = runBatch(batchJobs(meshes, libDir, format), bo);
        EXPECT_EQ(s.ok, int64_t(meshes.size()));
        EXPECT_EQ(s.errors, 0);
        // The command, from a manifest with relative paths.
        const std::string cliDir = dir.file("cli-" + c.format);
        std::vector<std::string> lines;
        for (const std::string& m : meshes) lines.push_back(fs::relative(m, dir.path()).string());
        const std::string manifest = batchManifest(dir, lines);
        const test::CommandRun r = test::runVoxfx(dir, "batch " + manifest + " -o " + cliDir + " --format " +
                                                           c.format + " " + c.options);
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_NE(r.out.find(std::to_string(meshes.size()) + " ok"), std::string::npos) << r.out;
        for (const std::string& m : meshes) {
            const std::string stem = fs::path(m).stem().string();
            const std::string single = dir.file(stem + "-single." + c.format);
            const test::CommandRun v =
                test::runVoxfx(dir, "voxelize " + m + " -o " + single + " " + c.options);
            ASSERT_EQ(v.exitCode, 0) << v.err;
            const std::string expected = test::readFileBytes(single);
            ASSERT_FALSE(expected.empty());
            EXPECT_EQ(test::readFileBytes(libDir + "/" + stem + "." + c.format), expected) << m;
            EXPECT_EQ(test::readFileBytes(cliDir + "/" + stem + "." + c.format), expected) << m;
        }
    }
}

TEST(BatchTest, ResultsDoNotDependOnThreadsOrNesting) {
    test::TempDir dir;
    std::vector<std::string> meshes;
    for (int i = 0; i < 6; ++i) {
        Mesh m = test::makeOctahedron({0.1 * i, 0, 0}, 1 + 0.1 * i);
        std::string off =
            "OFF\n" + std::to_string(m.positions.size()) + " " + std::to_string(m.triangleCount()) + " 0\n";
        for (const Vec3f& v : m.positions)
            off += std::to_string(v.x) + " " + std::to_string(v.y) + " " + std::to_string(v.z) + "\n";
        for (size_t t = 0; t < m.triangleCount(); ++t)
            off += "3 " + std::to_string(m.indices[3 * t]) + " " + std::to_string(m.indices[3 * t + 1]) +
                   " " + std::to_string(m.indices[3 * t + 2]) + "\n";
        meshes.push_back(test::writeFile(dir.file("oct" + std::to_string(i) + ".off"), off));
    }
    std::vector<std::string> first;
    for (const auto& [threads, nested] : {std::pair{1, false}, std::pair{2, false}, std::pair{2, true}}) {
        BatchOptions bo;
        bo.fit.resolution = 16;
        bo.threads = threads;
        bo.nested = nested;
        const std::string out = dir.file("out" + std::to_string(threads) + (nested ? "n" : ""));
        const BatchSummary s = runBatch(batchJobs(meshes, out, GridFormat::Binvox), bo);
        ASSERT_EQ(s.ok, 6);
        for (size_t i = 0; i < meshes.size(); ++i) {
            const std::string bytes = test::readFileBytes(s.results[i].output);
            EXPECT_EQ(s.results[i].mesh, meshes[i]); // job order, whatever the finishing order
            if (first.size() < meshes.size())
                first.push_back(bytes);
            else
                EXPECT_EQ(bytes, first[i]) << threads << (nested ? " nested" : "");
        }
    }
}

TEST(BatchTest, RestartSkipsExistingOutputsAndIgnoresPartialTemporaries) {
    test::TempDir dir;
    std::vector<std::string> lines;
    for (const char* name : {"a", "b", "c"}) {
        test::writeFile(dir.file(std::string(name) + ".off"), kBatchCubeOff);
        lines.push_back(std::string(name) + ".off");
    }
    const std::string manifest = batchManifest(dir, lines);
    const std::string out = dir.file("out");
    test::CommandRun r = test::runVoxfx(dir, "batch " + manifest + " -o " + out + " -r 8 -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string cube = test::readFileBytes(out + "/a.binvox");
    ASSERT_FALSE(cube.empty());
    // An interrupted run: b's output is gone and only a partial temporary file of it remains;
    // a's output is marked so that redoing it would show.
    fs::remove(out + "/b.binvox");
    test::writeFile(out + "/.b.binvox.tmp.12345.0", "partial");
    test::writeFile(out + "/a.binvox", "marker");
    r = test::runVoxfx(dir, "batch " + manifest + " -o " + out + " -r 8 -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("1 ok, 2 skipped"), std::string::npos) << r.out;
    EXPECT_EQ(test::readFileBytes(out + "/a.binvox"), "marker");
    EXPECT_EQ(test::readFileBytes(out + "/b.binvox"), cube);
    const nlohmann::json report = batchReadReport(out + "/report.json");
    ASSERT_EQ(report["jobs"].size(), 3u);
    EXPECT_EQ(report["jobs"][0]["status"], "skipped");
    EXPECT_EQ(report["jobs"][1]["status"], "ok");
    EXPECT_EQ(report["jobs"][1]["triangles"], 12);
    EXPECT_EQ(report["jobs"][2]["status"], "skipped");
    EXPECT_TRUE(report["jobs"][2]["triangles"].is_null());
    // --force redoes everything.
    r = test::runVoxfx(dir, "batch " + manifest + " -o " + out + " -r 8 -q --force");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(test::readFileBytes(out + "/a.binvox"), cube);
}

TEST(BatchTest, BadMeshesAreReportedWhileTheOthersSucceed) {
    test::TempDir dir;
    const std::string cube(kBatchCubeOff);
    test::writeFile(dir.file("good1.off"), cube);
    test::writeFile(dir.file("truncated.off"), cube.substr(0, cube.size() / 2));
    std::string nan = cube;
    nan.replace(nan.find("1 1 1\n"), 5, "1 nan 1");
    test::writeFile(dir.file("nan.off"), nan);
    std::string badIndex = cube;
    badIndex.replace(badIndex.find("3 1 7 5"), 7, "3 1 7 50");
    test::writeFile(dir.file("index.off"), badIndex);
    test::writeFile(dir.file("good2.off"), cube);
    const std::string manifest = batchManifest(
        dir, {"good1.off", "truncated.off", "nan.off", "index.off", "missing.off", "good2.off"});
    const std::string out = dir.file("out");
    const test::CommandRun r = test::runVoxfx(dir, "batch " + manifest + " -o " + out + " -r 8");
    EXPECT_EQ(r.exitCode, 2) << r.err; // documented: 2 when a mesh failed
    EXPECT_NE(r.out.find("2 ok, 0 skipped (already done), 4 failed"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(out + "/good1.binvox"));
    EXPECT_TRUE(fs::exists(out + "/good2.binvox"));
    for (const char* bad : {"truncated", "nan", "index", "missing"}) {
        EXPECT_FALSE(fs::exists(out + "/" + bad + ".binvox")) << bad;
        EXPECT_NE(r.err.find(std::string(bad) + ".off"), std::string::npos) << r.err;
    }
    for (const auto& e : fs::directory_iterator(out))
        EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
    const nlohmann::json report = batchReadReport(out + "/report.json");
    EXPECT_EQ(report["ok"], 2);
    EXPECT_EQ(report["errors"], 4);
    ASSERT_EQ(report["jobs"].size(), 6u);
    // The rate counts the two meshes written, not the four that failed.
    EXPECT_DOUBLE_EQ(report["ok_per_second"].get<double>(), 2 / report["seconds"].get<double>());
    const char* expected[] = {"ok", "error", "error", "error", "error", "ok"};
    for (size_t i = 0; i < 6; ++i) {
        const nlohmann::json& j = report["jobs"][i];
        EXPECT_EQ(j["status"], expected[i]) << j.dump();
        EXPECT_TRUE(j["mesh"].is_string());
        EXPECT_TRUE(j["output"].is_string());
        EXPECT_TRUE(j["ms"].is_number());
        if (expected[i] == std::string("ok")) {
            EXPECT_TRUE(j["error"].is_null());
            EXPECT_EQ(j["triangles"], 12);
        } else {
            ASSERT_TRUE(j["error"].is_string());
            EXPECT_FALSE(j["error"].get<std::string>().empty());
        }
    }
    // The messages say what is wrong.
    EXPECT_NE(report["jobs"][2]["error"].get<std::string>().find("nan"), std::string::npos)
        << report["jobs"][2]["error"];
    EXPECT_NE(report["jobs"][3]["error"].get<std::string>().find("50"), std::string::npos)
        << report["jobs"][3]["error"];
}

TEST(BatchTest, RateLeavesOutFailedMeshes) {
    // Files that fail fast (the corpus of a broken dataset) must not read as a fast batch.
    test::TempDir dir;
    const std::string cube(kBatchCubeOff);
    std::vector<std::string> meshes;
    for (int i = 0; i < 8; ++i)
        meshes.push_back(
            test::writeFile(dir.file("cut" + std::to_string(i) + ".off"), cube.substr(0, 20 + i)));
    BatchOptions bo;
    bo.fit.resolution = 8;
    const BatchSummary s = runBatch(batchJobs(meshes, dir.file("out"), GridFormat::Binvox), bo);
    EXPECT_EQ(s.errors, 8);
    EXPECT_EQ(s.ok, 0);
    EXPECT_GT(s.seconds, 0);
    EXPECT_EQ(s.okPerSecond(), 0);
}

TEST(BatchTest, DuplicateStemsAreRefusedBeforeAnyWork) {
    test::TempDir dir;
    fs::create_directories(dir.file("a"));
    fs::create_directories(dir.file("b"));
    test::writeFile(dir.file("a/part.off"), kBatchCubeOff);
    test::writeFile(dir.file("b/part.off"), kBatchCubeOff);
    test::writeFile(dir.file("first.off"), kBatchCubeOff);
    const std::string manifest = batchManifest(dir, {"first.off", "a/part.off", "b/part.off"});
    const std::string out = dir.file("out");
    EXPECT_THROW(readBatchManifest(manifest, out, GridFormat::Binvox), Error);
    const test::CommandRun r = test::runVoxfx(dir, "batch " + manifest + " -o " + out + " -r 8");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("a/part.off"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("b/part.off"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("line 5"), std::string::npos) << r.err; // 2 header lines, then 3 meshes
    EXPECT_FALSE(fs::exists(out + "/first.binvox"));
}

TEST(BatchTest, ManifestPathsAreRelativeToItsFolderAndCommentsAreIgnored) {
    test::TempDir dir;
    fs::create_directories(dir.file("list"));
    test::writeFile(dir.file("cube.off"), kBatchCubeOff);
    const std::string manifest =
        test::writeFile(dir.file("list/m.txt"), "# header\n\n   ../cube.off  \n# ../other.off\n");
    const std::vector<BatchJob> jobs = readBatchManifest(manifest, dir.file("out"), GridFormat::Vdb);
    ASSERT_EQ(jobs.size(), 1u);
    EXPECT_TRUE(fs::equivalent(jobs[0].mesh, dir.file("cube.off")));
    EXPECT_EQ(fs::path(jobs[0].output), fs::path(dir.file("out")) / "cube.vdb");
}

// What is not a manifest says so, before any work: a folder, a mesh file, a binary file, a NUL
// byte in a path (the C library would open the path up to the NUL: another file).
TEST(BatchTest, WhatIsNotAManifestIsRefusedSayingWhy) {
    test::TempDir dir;
    const std::string mesh = test::writeFile(dir.file("cube.off"), kBatchCubeOff);
    fs::create_directories(dir.file("meshes"));
    const std::string binary = test::writeFile(dir.file("list.txt"), std::string("cube.off\nab\0c\n", 14));
    const std::string out = dir.file("out");
    const auto message = [&](const std::string& manifest) {
        try {
            readBatchManifest(manifest, out, GridFormat::Binvox);
        } catch (const Error& e) { return std::string(e.what()); }
        return std::string("no error");
    };
    EXPECT_NE(message(dir.file("meshes")).find("is a folder"), std::string::npos)
        << message(dir.file("meshes"));
    EXPECT_NE(message(mesh).find("is a mesh file (.off)"), std::string::npos) << message(mesh);
    EXPECT_NE(message(binary).find("line 2 holds a NUL byte"), std::string::npos) << message(binary);
    EXPECT_NE(message(mesh + std::string("\0.txt", 5)).find("NUL byte"), std::string::npos);
    try {
        batchJobs({mesh, std::string("x\0y.off", 7)}, out, GridFormat::Binvox);
        ADD_FAILURE() << "a NUL byte in a mesh path was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("mesh 2: the mesh path holds a NUL byte"), std::string::npos)
            << e.what();
    }
    // The command prints the one line and exits 1, writing nothing.
    for (const std::string& manifest : {dir.file("meshes"), mesh, binary}) {
        const test::CommandRun r = test::runVoxfx(dir, "batch " + manifest + " -o " + out + " -r 8");
        EXPECT_EQ(r.exitCode, 1) << manifest;
        EXPECT_NE(r.err.find(message(manifest)), std::string::npos) << r.err;
    }
    EXPECT_FALSE(fs::exists(out + "/cube.binvox"));
}

// BatchOptions::cancel: polled before each mesh; once it says stop, no mesh starts and runBatch
// throws. One worker, so the order is fixed: the poll after the second mesh stops the batch.
TEST(BatchTest, CancelStopsBetweenMeshesAndThrows) {
    test::TempDir dir;
    std::vector<std::string> meshes;
    for (int i = 0; i < 6; ++i)
        meshes.push_back(test::writeFile(dir.file(detail::concat("c", i, ".off")), kBatchCubeOff));
    struct StopAfterTwo final : Progress, BatchProgress {
        std::atomic<int64_t> finished{0}, polls{0};
        bool update(double) override {
            ++polls;
            return finished < 2;
        }
        void jobDone(const BatchResult&, int64_t, int64_t) override { ++finished; }
    } stop;
    BatchOptions bo;
    bo.fit.resolution = 8;
    bo.threads = 1;
    bo.cancel = &stop;
    bo.progress = &stop;
    const std::string out = dir.file("out");
    try {
        runBatch(batchJobs(meshes, out, GridFormat::Binvox), bo);
        ADD_FAILURE() << "the batch was not cancelled";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("batch cancelled after 2 of 6 meshes"), std::string::npos)
            << e.what();
    }
    int64_t written = 0;
    for (const auto& e : fs::directory_iterator(out)) written += e.path().extension() == ".binvox";
    EXPECT_EQ(written, 2);
    EXPECT_EQ(stop.finished, 2);
    EXPECT_GE(stop.polls, 3);
    // A cancel object that never stops changes nothing: every mesh, skipping the two written.
    struct Never final : Progress {
        bool update(double) override { return true; }
    } never;
    bo.cancel = &never;
    bo.progress = nullptr;
    const BatchSummary s = runBatch(batchJobs(meshes, out, GridFormat::Binvox), bo);
    EXPECT_EQ(s.ok, 4);
    EXPECT_EQ(s.skipped, 2);
}

TEST(BatchTest, HelpStatesTheExitStatus) {
    test::TempDir dir;
    const test::CommandRun r = test::runVoxfx(dir, "batch --help");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_NE(r.out.find("Exit status"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("report.json"), std::string::npos) << r.out;
}

} // namespace
} // namespace voxfx
