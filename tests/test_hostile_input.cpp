// Hostile input: every reader checks the counts and sizes a header declares against what the
// file's bytes can hold before it allocates, refuses what would overflow or never end, and says
// which file and which field is wrong. Each case is a small crafted file written here; the oracle
// is the format's own arithmetic (what N records need at least), not the reader's numbers.
#include <chrono>
#include <cstring>
#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <zlib.h>

#include "test_util.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/error.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/transfer_function.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx {
namespace {

using test::TempDir;

// The message of the voxfx::Error that f throws; fails the test (and returns "") when f throws
// nothing, or something else (std::bad_alloc is exactly what these checks exist to prevent).
// Also fails when f takes more than a second: a refused header must cost no work.
std::string hostileError(const std::function<void()>& f) {
    const auto start = std::chrono::steady_clock::now();
    std::string what;
    try {
        f();
        ADD_FAILURE() << "no voxfx::Error";
    } catch (const Error& e) { what = e.what(); } catch (const std::exception& e) {
        ADD_FAILURE() << "not a voxfx::Error: " << e.what();
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0) << what;
    return what;
}

void expectMentions(const std::string& what, std::initializer_list<std::string> words) {
    for (const std::string& w : words)
        EXPECT_NE(what.find(w), std::string::npos) << "'" << w << "' in: " << what;
}

std::string hostileGzip(const std::string& bytes) {
    std::string out(compressBound(uLong(bytes.size())) + 32, '\0');
    z_stream z{};
    deflateInit2(&z, 9, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
    z.avail_in = uInt(bytes.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    deflate(&z, Z_FINISH);
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

// ---- meshes ------------------------------------------------------------------------------------

TEST(HostileInputTest, OffHeaderClaimingABillionVerticesInAKilobyteIsRefused) {
    TempDir dir;
    std::string text = "OFF\n1000000000 1 0\n";
    while (text.size() < 1024) text += "0 0 0\n";
    const std::string path = test::writeFile(dir.file("big.off"), text);
    // A vertex line is at least "0 0 0\n" (6 bytes): 10^9 of them cannot fit in 1 KB.
    expectMentions(hostileError([&] { loadMesh(path); }), {path, "1000000000 vertices", "can hold"});
}

TEST(HostileInputTest, PlyBinaryCountsBeyondTheBodyAreRefused) {
    TempDir dir;
    const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
                               "property float x\nproperty float y\nproperty float z\nend_header\n";
    const std::string path = test::writeFile(dir.file("big.ply"), header + std::string(120, '\0'));
    // 12 bytes a vertex: 120 bytes hold 10.
    expectMentions(hostileError([&] { loadMesh(path); }), {path, "vertex", "4000000000", "remain"});

    // A list whose uint32 length claims 4 billion indices.
    std::string face = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\n"
                       "property list uint int vertex_indices\nend_header\n";
    face += std::string(36, '\0');
    const uint32_t n = 4000000000u;
    face.append(reinterpret_cast<const char*>(&n), 4);
    face += std::string(12, '\0');
    const std::string listPath = test::writeFile(dir.file("list.ply"), face);
    expectMentions(hostileError([&] { loadMesh(listPath); }), {listPath, "face", "truncated"});
}

TEST(HostileInputTest, PlyAsciiCountsBeyondTheBodyEndAtTheTruncation) {
    TempDir dir;
    const std::string path = test::writeFile(
        dir.file("big.ply"), "ply\nformat ascii 1.0\nelement vertex 3000000000\nproperty float x\n"
                             "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n");
    expectMentions(hostileError([&] { loadMesh(path); }), {path, "vertex", "3000000000", "truncated"});
}

TEST(HostileInputTest, StlBinaryTriangleCountBeyondTheFileIsRefused) {
    TempDir dir;
    std::string bytes(80, ' ');
    const uint32_t count = 1000000000u;
    bytes.append(reinterpret_cast<const char*>(&count), 4);
    bytes += std::string(100, '\0'); // two whole 50-byte records
    const std::string path = test::writeFile(dir.file("big.stl"), bytes);
    expectMentions(hostileError([&] { loadMesh(path); }), {path, "1000000000 triangles", "truncated"});
}

TEST(HostileInputTest, ObjIndexBeyondThirtyTwoBitsIsRefused) {
    TempDir dir;
    const std::string path =
        test::writeFile(dir.file("big.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n");
    expectMentions(hostileError([&] { loadMesh(path); }), {path, "out of range"});
}

// ---- grids -------------------------------------------------------------------------------------

TEST(HostileInputTest, BinvoxDimsBeyondItsRunsAreRefusedBeforeTheGrid) {
    TempDir dir;
    // 2^60 voxels need at least 2^60 / 255 pairs of bytes; four bytes are there.
    const std::string path =
        test::writeFile(dir.file("big.binvox"),
                        std::string("#binvox 1\ndim 1048576 1048576 1048576\ndata\n") + "\x01\xff\x00\xff");
    expectMentions(hostileError([&] { readGrid(path); }), {path, "cannot encode"});
}

TEST(HostileInputTest, NrrdGridSizesBeyondItsDataAreRefused) {
    TempDir dir;
    const std::string path = test::writeFile(
        dir.file("big.nrrd"),
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1048576 1048576 1048576\nencoding: raw\n\n" +
            std::string(64, '\1'));
    expectMentions(hostileError([&] { readGrid(path); }), {path, "truncated", "64 of"});
}

// ---- volumes -----------------------------------------------------------------------------------

TEST(HostileInputTest, VolumeHeadersClaimingMoreThanTheirDataAreRefused) {
    TempDir dir;
    const std::string big = "sizes: 10000 10000 1000\n"; // 10^11 voxels, below the 2^40 limit
    const std::string nrrd =
        test::writeFile(dir.file("raw.nrrd"), "NRRD0004\ntype: uchar\ndimension: 3\n" + big +
                                                  "encoding: raw\n\n" + std::string(100, '\0'));
    expectMentions(hostileError([&] { loadVolume(nrrd); }), {nrrd, "truncated", "100 of"});

    // gzip: deflate cannot exceed about 1032:1, so 10^11 bytes cannot come out of a few hundred.
    const std::string gz =
        test::writeFile(dir.file("gz.nrrd"), "NRRD0004\ntype: uchar\ndimension: 3\n" + big +
                                                 "encoding: gzip\n\n" + hostileGzip(std::string(4096, '\0')));
    expectMentions(hostileError([&] { loadVolume(gz); }), {gz, "gzip data can hold"});

    std::string inrHeader = "#INRIMAGE-4#{\nXDIM=10000\nYDIM=10000\nZDIM=1000\nTYPE=unsigned fixed\n"
                            "PIXSIZE=8 bits\n";
    inrHeader += std::string(256 - 4 - inrHeader.size(), '\n') + "##}\n";
    const std::string inr = test::writeFile(dir.file("big.inr"), inrHeader + std::string(100, '\0'));
    expectMentions(hostileError([&] { loadVolume(inr); }), {inr, "truncated"});
    const std::string inrGz =
        test::writeFile(dir.file("big.inr.gz"), hostileGzip(inrHeader + std::string(100, '\0')));
    expectMentions(hostileError([&] { loadVolume(inrGz); }), {inrGz, "gzip data can hold"});

    test::writeFile(dir.file("small.raw"), std::string(100, '\0'));
    const std::string json = test::writeFile(
        dir.file("big.json"), R"({"file": "small.raw", "dims": [10000, 10000, 1000], "type": "uint8"})");
    expectMentions(hostileError([&] { loadVolume(json); }), {"small.raw", "truncated", "100 of"});
}

TEST(HostileInputTest, GzipVolumeThatInflatesToLessThanDeclaredAllocatesOnlyWhatItHolds) {
    TempDir dir;
    // Within deflate's ratio (2 MiB declared from ~2 KiB of gzip), but the stream holds 1 KiB:
    // the error comes from the data, after at most what it held was allocated.
    const std::string path =
        test::writeFile(dir.file("short.nrrd"),
                        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 128 128 128\nencoding: gzip\n\n" +
                            hostileGzip(std::string(1024, '\7')) + std::string(2048, '\0'));
    expectMentions(hostileError([&] { loadVolume(path); }), {path});
}

TEST(HostileInputTest, DataFilesThatAreDevicesOrPipesAreRefused) {
    TempDir dir;
    // /dev/zero never ends and a FIFO blocks: a header naming one must not hang the reader.
    const std::string nrrd = test::writeFile(
        dir.file("dev.nhdr"),
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: /dev/zero\n");
    expectMentions(hostileError([&] { loadVolume(nrrd); }), {"/dev/zero", "not a regular file"});
    const std::string json =
        test::writeFile(dir.file("dev.json"), R"({"file": "/dev/zero", "dims": [2, 2, 2], "type": "uint8"})");
    expectMentions(hostileError([&] { loadVolume(json); }), {"/dev/zero", "not a regular file"});
}

// ---- scenes, CSG, transfer functions -----------------------------------------------------------

TEST(HostileInputTest, SceneRenderSizesOutsideIntegersAreRefused) {
    TempDir dir;
    // 1e300 or -1 as an image width would convert to an integer with undefined behaviour.
    for (const char* value : {"1e300", "-1", "2.5", "4294967296"}) {
        const std::string path =
            test::writeFile(dir.file("scene.json"), std::string(R"({"render": {"width": )") + value + "}}");
        expectMentions(hostileError([&] { loadScene(path); }), {path, "width", "whole number"});
    }
}

TEST(HostileInputTest, SceneSmokeNumbersOutsideTheirTypesAreRefused) {
    // Smoke dimensions, seed and octaves convert to integers: out of range or fractional values
    // would do so with undefined behaviour (found reading the code behind the scene_json target).
    auto smoke = [](const std::string& params) {
        return R"({"objects": [{"kind": "volume", "transfer": {"points": [[0, 0], [1, 1]]},
                   "volume": {"smoke": {)" +
               params + "}}}]}";
    };
    const std::string path = "/nonexistent-voxfx-test/scene.json";
    for (const char* dims : {"[1e300, 4, 4]", "[4, -1, 4]", "[4, 4, 2.5]", "[4, 4, 1e19]"})
        expectMentions(hostileError([&] { parseSceneJson(smoke(std::string(R"("dims": )") + dims), path); }),
                       {path, "dims", "whole number"});
    for (const char* seed : {"-1", "1e20", "0.5"})
        expectMentions(hostileError([&] { parseSceneJson(smoke(std::string(R"("seed": )") + seed), path); }),
                       {path, "seed", "whole number"});
    for (const char* octaves : {"1e10", "-3", "0"})
        expectMentions(
            hostileError([&] { parseSceneJson(smoke(std::string(R"("octaves": )") + octaves), path); }),
            {path, "octaves", "whole number"});
    // 2^39 voxels (2 TiB of floats) is within the volume limit but not within any memory here: an
    // error before the allocation, not std::bad_alloc.
    expectMentions(hostileError([&] { parseSceneJson(smoke(R"("dims": [8192, 8192, 8192])"), path); }),
                   {"smoke", "8192", "memory"});
}

TEST(HostileInputTest, JsonNumbersPastDoubleRangeAreErrorsInEveryJsonReader) {
    // nlohmann-json throws out_of_range, not parse_error, for a number that overflows a double;
    // readers that caught parse_error only let it escape (found by the scene_json target).
    TempDir dir;
    const std::string scene = "/nonexistent-voxfx-test/scene.json";
    expectMentions(hostileError([&] { parseSceneJson(R"({"render": {"width": 1e999}})", scene); }),
                   {scene, "1e999"});
    const std::string gltf = test::writeFile(dir.file("big.gltf"), R"({"asset": {"version": 1e999}})");
    expectMentions(hostileError([&] { loadScene(gltf); }), {gltf, "1e999"});
    expectMentions(hostileError([&] { parseCsgExpression(R"({"op": "union", "args": [1e999]})"); }),
                   {"CSG expression, column 26", "1e999"});
    expectMentions(hostileError([&] { parseTransferFunction(R"({"points": [[1e999, 0]]})", "tf.json"); }),
                   {"tf.json", "1e999"});
}

TEST(HostileInputTest, CsgNestingIsBoundedInBothSyntaxes) {
    // 100000 levels would overflow the stack of a recursive parser.
    std::string functional, json;
    for (int i = 0; i < 100000; ++i) functional += "union(";
    functional += "a.off";
    functional += std::string(100000, ')');
    expectMentions(hostileError([&] { parseCsgExpression(functional); }), {"nested deeper than 256"});
    // nlohmann-json parses the whole document first (iteratively): 2000 levels keep that cheap.
    for (int i = 0; i < 2000; ++i) json += R"({"op": "union", "args": [)";
    json += "\"a.off\"";
    for (int i = 0; i < 2000; ++i) json += "]}";
    expectMentions(hostileError([&] { parseCsgExpression(json); }), {"nested deeper than 256"});
    // 256 levels are fine.
    std::string deep;
    for (int i = 0; i < 256; ++i) deep += "xor(";
    deep += "a.off" + std::string(256, ')');
    EXPECT_EQ(toString(parseCsgExpression(deep)), deep);
}

TEST(HostileInputTest, CsgCanonicalFormReadsBackForAnyPathBytes) {
    // Paths are bytes: control characters, a vertical tab and non-UTF-8 bytes must survive
    // toString -> parseCsgExpression (the canonical form is what the CLI prints and logs).
    for (const std::string& mesh :
         {std::string("a\x0b b.off"), std::string("tab\there.off"), std::string("\xff\xfe name.stl"),
          std::string("q\"uote\\.off"), std::string("ctl\x01 x.ply")}) {
        CsgNode leaf;
        leaf.mesh = mesh;
        CsgNode node;
        node.isMesh = false;
        node.args = {leaf, leaf};
        const std::string text = toString(node);
        CsgNode back;
        ASSERT_NO_THROW(back = parseCsgExpression(text)) << text;
        ASSERT_EQ(back.args.size(), 2u);
        EXPECT_EQ(back.args[0].mesh, mesh);
        EXPECT_EQ(toString(back), text);
    }
}

TEST(HostileInputTest, CsgQuotedPathStartingWithABraceReadsBack) {
    // libFuzzer (voxfx_fuzz_csg), tests/regress/csg/: the quoted path "{" printed unquoted, and
    // the canonical form then read as the JSON syntax.
    const std::string text =
        test::readFileBytes(std::string(VOXFX_REGRESS_DIR) + "/csg/quoted-brace-path.txt");
    ASSERT_EQ(text, "\"{\"");
    const CsgNode node = parseCsgExpression(text);
    EXPECT_EQ(node.mesh, "{");
    EXPECT_EQ(parseCsgExpression(toString(node)).mesh, "{");
}

TEST(HostileInputTest, TransferFunctionGarbageIsAnError) {
    for (const char* text : {"", "{", "[1,2", R"({"points": 5})", R"({"points": [{"value": "x"}]})",
                             R"({"color": [[1e999, 0, 0, 0]]})"})
        expectMentions(hostileError([&] { parseTransferFunction(text, "tf.json"); }), {"tf.json"});
}

} // namespace
} // namespace voxfx
