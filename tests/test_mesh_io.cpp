// Tests of src/io/mesh_io.cpp and the per-format readers: small hand-written files in every
// format, every error case, truncated and corrupted files, and real meshes checked against CGAL's
// readers as an independent oracle.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "io/mesh_formats.hpp"
#include "test_util.hpp"
#include "voxfx/error.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/mesh_io.hpp"

namespace voxfx {
namespace {

using test::TempDir;
using test::writeFile;

// ---------------------------------------------------------------------------------------------
// The test cube: [-1,1]^3, vertex i at (x, y, z) = (bit 0, bit 1, bit 2 of i) ? 1 : -1, six
// outward counter-clockwise quads. Fan-triangulated it has 12 triangles and is closed.

constexpr int kCubeQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

std::array<float, 3> cubeVertex(int i) {
    return {i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 1.0f : -1.0f};
}

// The cube's 12 triangles as corner indices (quad a b c d -> a b c, a c d).
std::vector<std::array<int, 3>> cubeTriangles() {
    std::vector<std::array<int, 3>> t;
    for (const auto& q : kCubeQuads) {
        t.push_back({q[0], q[1], q[2]});
        t.push_back({q[0], q[2], q[3]});
    }
    return t;
}

const Box3d kCubeBox{{-1, -1, -1}, {1, 1, 1}};

void expectCube(const Mesh& mesh, const Box3d& box = kCubeBox, std::size_t triangles = 12) {
    EXPECT_EQ(mesh.triangleCount(), triangles);
    EXPECT_EQ(computeBounds(mesh.view()).lo, box.lo);
    EXPECT_EQ(computeBounds(mesh.view()).hi, box.hi);
    EXPECT_TRUE(analyzeTopology(mesh.view()).closed());
}

std::string cubeOff() {
    std::string s = "OFF\n# a cube\n8 6 12\n";
    for (int i = 0; i < 8; ++i) {
        const auto p = cubeVertex(i);
        s += std::to_string(int(p[0])) + " " + std::to_string(int(p[1])) + " " + std::to_string(int(p[2])) +
             "\n";
    }
    for (const auto& q : kCubeQuads)
        s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " +
             std::to_string(q[3]) + "\n";
    return s;
}

std::string cubeObj() {
    std::string s = "# a cube\nmtllib cube.mtl\no cube\n";
    for (int i = 0; i < 8; ++i) {
        const auto p = cubeVertex(i);
        s += "v " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
    }
    s += "vt 0 0\nvn 0 0 1\ng sides\nusemtl red\ns off\n";
    // Each face in another corner syntax: v, v/vt, v//vn, v/vt/vn, relative (-8 is the first
    // vertex after eight), and v again.
    const char* suffixes[] = {"", "/1", "//1", "/1/1", "", ""};
    for (int f = 0; f < 6; ++f) {
        s += "f";
        for (int v : kCubeQuads[f]) {
            // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on " " + std::string.
            s += ' ';
            s += std::to_string(f == 4 ? v - 8 : v + 1);
            s += suffixes[f];
        }
        s += "\n";
    }
    return s;
}

std::string cubePlyAscii() {
    std::string s =
        "ply\nformat ascii 1.0\ncomment a cube\nelement vertex 8\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nelement face 6\nproperty list uchar int vertex_indices\n"
        "property int label\nend_header\n";
    for (int i = 0; i < 8; ++i) {
        const auto p = cubeVertex(i);
        s += std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + " 255\n";
    }
    for (const auto& q : kCubeQuads)
        s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " +
             std::to_string(q[3]) + " 7\n";
    return s;
}

template <class T> void append(std::string& s, T value, bool bigEndian = false) {
    char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (bigEndian) std::reverse(b, b + sizeof(T)); // the tests run on little-endian hosts
    s.append(b, sizeof(T));
}

// Binary PLY: double coordinates, an extra short property, uint8 list lengths and uint32 indices,
// then an unrelated element that must be skipped.
std::string cubePlyBinary(bool bigEndian) {
    std::string s = std::string("ply\nformat ") + (bigEndian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 8\nproperty double x\nproperty short flags\nproperty double y\n"
                    "property double z\nelement face 6\nproperty list uchar uint vertex_indices\n"
                    "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
    for (int i = 0; i < 8; ++i) {
        const auto p = cubeVertex(i);
        append<double>(s, p[0], bigEndian);
        append<int16_t>(s, -3, bigEndian);
        append<double>(s, p[1], bigEndian);
        append<double>(s, p[2], bigEndian);
    }
    for (const auto& q : kCubeQuads) {
        append<uint8_t>(s, 4);
        for (int c : q) append<uint32_t>(s, uint32_t(c), bigEndian);
    }
    append<int32_t>(s, 0, bigEndian);
    append<int32_t>(s, 1, bigEndian);
    return s;
}

std::string cubeStlAscii() {
    std::string s = "solid cube\n";
    for (const auto& t : cubeTriangles()) {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for (int c : t) {
            const auto p = cubeVertex(c);
            s += "      vertex " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " +
                 std::to_string(p[2]) + "\n";
        }
        s += "    endloop\n  endfacet\n";
    }
    return s + "endsolid cube\n";
}

// Binary STL; the header starts with "solid" as some writers do, which must not fool the reader.
std::string cubeStlBinary() {
    std::string s = "solid but binary";
    s.resize(80, ' ');
    append<uint32_t>(s, 12);
    for (const auto& t : cubeTriangles()) {
        for (int k = 0; k < 3; ++k) append<float>(s, 0.0f);
        for (int c : t)
            for (float x : cubeVertex(c)) append<float>(s, x);
        append<uint16_t>(s, 0);
    }
    return s;
}

using test::base64;

// glTF 2.0 scene: node 0 (translation 10 20 30) has child node 1 (scale 2 3 4) with the cube;
// node 2 (translation 100 0 0) instances the cube again. World bounds: x [8, 12] u [99, 101],
// y [17, 23] u [-1, 1], z [26, 34] u [-1, 1]; 24 triangles.
const Box3d kGltfBox{{8, -1, -1}, {101, 23, 34}};

std::string cubeGltfBuffer() {
    std::string buffer;
    for (int i = 0; i < 8; ++i)
        for (float x : cubeVertex(i)) append<float>(buffer, x);
    for (const auto& t : cubeTriangles())
        for (int c : t) append<uint16_t>(buffer, uint16_t(c));
    return buffer; // 96 + 72 bytes, a multiple of 4
}

std::string cubeGltfJson(const std::string& bufferUri) {
    const std::string buffer = cubeGltfBuffer();
    std::string uri = bufferUri.empty() ? "" : "\"uri\": \"" + bufferUri + "\", ";
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 2]}],
  "nodes": [{"translation": [10, 20, 30], "children": [1]}, {"scale": [2, 3, 4], "mesh": 0},
            {"translation": [100, 0, 0], "mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
  "buffers": [{)" +
           uri + "\"byteLength\": " + std::to_string(buffer.size()) + R"(}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96, "target": 34962},
                  {"buffer": 0, "byteOffset": 96, "byteLength": 72, "target": 34963}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                 "min": [-1, -1, -1], "max": [1, 1, 1]},
                {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]})";
}

std::string cubeGlb() {
    std::string json = cubeGltfJson("");
    json.resize((json.size() + 3) / 4 * 4, ' ');
    const std::string bin = cubeGltfBuffer();
    std::string s = "glTF";
    append<uint32_t>(s, 2);
    append<uint32_t>(s, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
    append<uint32_t>(s, uint32_t(json.size()));
    s += "JSON" + json;
    append<uint32_t>(s, uint32_t(bin.size()));
    s += std::string("BIN\0", 4) + bin;
    return s;
}

// Replaces the one occurrence of `from` in `s` (the test's own data: a miss is a test bug).
void replaceOnce(std::string& s, const std::string& from, const std::string& to) {
    const std::size_t at = s.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    ASSERT_EQ(s.find(from, at + 1), std::string::npos) << from;
    s.replace(at, from.size(), to);
}

// Loads `path` expecting voxfx::Error; checks the message names the file and holds each part.
void expectLoadError(const std::string& path, std::initializer_list<std::string> parts) {
    const std::string name = std::filesystem::path(path).filename().string();
    try {
        loadMesh(path);
        ADD_FAILURE() << "no error loading " << path;
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(name), std::string::npos) << msg;
        for (const auto& part : parts)
            EXPECT_NE(msg.find(part), std::string::npos) << "'" << part << "' in: " << msg;
    }
}

// ---------------------------------------------------------------------------------------------
// Every format reads the cube.

TEST(MeshIoTest, ReadsOffQuadsFanTriangulated) {
    TempDir dir;
    MeshLoadReport report;
    const Mesh m = loadMesh(writeFile(dir.file("cube.off"), cubeOff()), &report);
    expectCube(m);
    EXPECT_EQ(m.positions.size(), 8u); // shared vertices stay shared
    EXPECT_EQ(report.format, "off");
    EXPECT_EQ(report.fileBytes, cubeOff().size());
    EXPECT_EQ(report.inputTriangles, 12u);
    EXPECT_EQ(report.degenerateRemoved, 0u);
    // Fan of the first quad 0 2 3 1: (0 2 3) (0 3 1).
    EXPECT_EQ(std::vector<uint32_t>(m.indices.begin(), m.indices.begin() + 6),
              (std::vector<uint32_t>{0, 2, 3, 0, 3, 1}));
}

TEST(MeshIoTest, ReadsOffVariants) {
    TempDir dir;
    // Counts on the keyword's line, COFF colours per vertex and face, comments, blank lines, CRLF.
    const std::string off = "COFF 4 2 0\r\n\r\n# vertices\r\n0 0 0 255 0 0 255\r\n2 0 0 0 255 0 255 # x\r\n"
                            "0 4 0 0 0 255 255\r\n0 0 8 1 1 1 1\r\n3 0 2 1 10 20 30\r\n3 0 1 3\r\n";
    const Mesh m = loadMesh(writeFile(dir.file("variant.OFF"), off));
    EXPECT_EQ(m.triangleCount(), 2u);
    EXPECT_EQ(computeBounds(m.view()).hi, (Vec3d{2, 4, 8}));
}

TEST(MeshIoTest, ReadsObjWithAllCornerForms) {
    TempDir dir;
    MeshLoadReport report;
    const Mesh m = loadMesh(writeFile(dir.file("cube.obj"), cubeObj()), &report);
    expectCube(m);
    EXPECT_EQ(m.positions.size(), 8u);
    EXPECT_EQ(report.format, "obj");
}

TEST(MeshIoTest, ReadsObjFacesBeforeTheirVertices) {
    TempDir dir;
    const Mesh m = loadMesh(writeFile(dir.file("late.obj"), "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"));
    EXPECT_EQ(m.triangleCount(), 1u);
}

TEST(MeshIoTest, ReadsAsciiPly) {
    TempDir dir;
    MeshLoadReport report;
    expectCube(loadMesh(writeFile(dir.file("cube.ply"), cubePlyAscii()), &report));
    EXPECT_EQ(report.format, "ply");
}

TEST(MeshIoTest, ReadsBinaryPlyBothEndiannesses) {
    TempDir dir;
    expectCube(loadMesh(writeFile(dir.file("le.ply"), cubePlyBinary(false))));
    expectCube(loadMesh(writeFile(dir.file("be.ply"), cubePlyBinary(true))));
}

TEST(MeshIoTest, ReadsAsciiStl) {
    TempDir dir;
    MeshLoadReport report;
    const Mesh m = loadMesh(writeFile(dir.file("cube.stl"), cubeStlAscii()), &report);
    expectCube(m);
    EXPECT_EQ(m.positions.size(), 36u); // STL stores three vertices per triangle
    EXPECT_EQ(report.format, "stl");
}

TEST(MeshIoTest, ReadsBinaryStlEvenWhenItsHeaderSaysSolid) {
    TempDir dir;
    expectCube(loadMesh(writeFile(dir.file("cube.stl"), cubeStlBinary())));
}

TEST(MeshIoTest, ReadsGltfWithNodeTransformsAndInstances) {
    TempDir dir;
    const std::string uri = "data:application/octet-stream;base64," + base64(cubeGltfBuffer());
    MeshLoadReport report;
    const Mesh m = loadMesh(writeFile(dir.file("scene.gltf"), cubeGltfJson(uri)), &report);
    EXPECT_EQ(m.triangleCount(), 24u);
    const Box3d box = computeBounds(m.view());
    EXPECT_EQ(box.lo, kGltfBox.lo);
    EXPECT_EQ(box.hi, kGltfBox.hi);
    EXPECT_EQ(report.format, "gltf");
    EXPECT_TRUE(analyzeTopology(m.view()).closed()); // two disjoint closed cubes
}

TEST(MeshIoTest, ReadsGltfWithAnExternalBuffer) {
    TempDir dir;
    writeFile(dir.file("cube.bin"), cubeGltfBuffer());
    const Mesh m = loadMesh(writeFile(dir.file("scene.gltf"), cubeGltfJson("cube.bin")));
    EXPECT_EQ(m.triangleCount(), 24u);
    EXPECT_EQ(computeBounds(m.view()).hi, kGltfBox.hi);
}

TEST(MeshIoTest, ReadsGlb) {
    TempDir dir;
    MeshLoadReport report;
    const Mesh m = loadMesh(writeFile(dir.file("scene.glb"), cubeGlb()), &report);
    EXPECT_EQ(m.triangleCount(), 24u);
    const Box3d box = computeBounds(m.view());
    EXPECT_EQ(box.lo, kGltfBox.lo);
    EXPECT_EQ(box.hi, kGltfBox.hi);
    EXPECT_EQ(report.format, "gltf");
}

TEST(MeshIoTest, ReadsOtherFormatsThroughAssimp) {
    // Assimp's RAW format: one triangle per line as nine coordinates.
    TempDir dir;
    MeshLoadReport report;
    const Mesh m =
        loadMesh(writeFile(dir.file("tri.raw"), "0 0 0 3 0 0 0 5 0\n0 0 0 0 5 0 0 0 7\n"), &report);
    EXPECT_EQ(m.triangleCount(), 2u);
    EXPECT_EQ(computeBounds(m.view()).hi, (Vec3d{3, 5, 7}));
    EXPECT_EQ(report.format, "raw");
}

TEST(MeshIoTest, CountsAndRemovesDegenerateTriangles) {
    TempDir dir;
    std::string off = cubeOff();
    replaceOnce(off, "8 6 12", "8 8 12");
    off += "3 0 0 1\n"; // repeated index
    off += "3 0 1 1\n";
    MeshLoadReport report;
    const Mesh m = loadMesh(writeFile(dir.file("degenerate.off"), off), &report);
    EXPECT_EQ(report.inputTriangles, 14u);
    EXPECT_EQ(report.degenerateRemoved, 2u);
    expectCube(m);
}

TEST(MeshIoTest, IgnoresPointsAndLinesInPolygonFiles) {
    TempDir dir;
    std::string off = cubeOff();
    replaceOnce(off, "8 6 12", "8 8 12");
    off += "1 5\n2 0 7\n";
    expectCube(loadMesh(writeFile(dir.file("mixed.off"), off)));
}

TEST(MeshIoTest, AcceptsNonFiniteVerticesNoFaceUses) {
    TempDir dir;
    std::string off = cubeOff();
    replaceOnce(off, "8 6 12", "9 6 12");
    replaceOnce(off, "\n4 0 2 3 1\n", "\nnan inf -inf\n4 0 2 3 1\n");
    expectCube(loadMesh(writeFile(dir.file("unused-nan.off"), off)));
}

// ---------------------------------------------------------------------------------------------
// Errors name the file and the cause.

TEST(MeshIoTest, MissingFile) {
    TempDir dir;
    expectLoadError(dir.file("missing.off"), {"cannot open", "No such file"});
}

TEST(MeshIoTest, DirectoryInsteadOfFile) {
    TempDir dir;
    std::filesystem::create_directory(dir.file("folder.off"));
    expectLoadError(dir.file("folder.off"), {"directory"});
}

TEST(MeshIoTest, UnknownExtension) {
    TempDir dir;
    expectLoadError(writeFile(dir.file("cube.notamesh"), cubeOff()),
                    {"unknown mesh format", ".notamesh", ".off"});
    expectLoadError(writeFile(dir.file("cube"), cubeOff()), {"no extension"});
}

TEST(MeshIoTest, TruncatedBinaryStl) {
    TempDir dir;
    const std::string stl = cubeStlBinary().substr(0, 84 + 5 * 50 + 17); // 5 whole triangles and a bit
    expectLoadError(writeFile(dir.file("short.stl"), stl),
                    {"truncated", "byte 334", "12 triangles", "triangle 5"});
    expectLoadError(writeFile(dir.file("tiny.stl"), std::string(40, '\0')), {"too few"});
}

TEST(MeshIoTest, TruncatedOff) {
    TempDir dir;
    const std::string off = cubeOff();
    // Cut after the third face line: header 3 lines, 8 vertices, 3 faces -> the file ends at line 15.
    std::size_t cut = 0;
    for (int line = 0; line < 14; ++line) cut = off.find('\n', cut) + 1;
    expectLoadError(writeFile(dir.file("short.off"), off.substr(0, cut)),
                    {"end of file", "face 3 of 6", ":15:"});
    // Cut early: the header's counts cannot fit in what is left.
    expectLoadError(writeFile(dir.file("cut.off"), off.substr(0, 40)),
                    {":3:", "8 vertices and 6 faces", "truncated"});
    // A vertex line missing its z, on line 5.
    std::string missing = off;
    replaceOnce(missing, "\n1 -1 -1\n", "\n1 -1\n");
    expectLoadError(writeFile(dir.file("missing.off"), missing), {":5:", "z of vertex 1", "end of the line"});
}

TEST(MeshIoTest, AsciiStlWithoutEndsolidIsTruncated) {
    TempDir dir;
    const std::string stl = cubeStlAscii();
    expectLoadError(writeFile(dir.file("short.stl"), stl.substr(0, stl.rfind("endsolid"))),
                    {"endsolid", "truncated"});
    expectLoadError(writeFile(dir.file("mid.stl"), stl.substr(0, stl.size() / 2)), {"truncated"});
}

TEST(MeshIoTest, MalformedNumberNamesTheLine) {
    TempDir dir;
    std::string off = cubeOff();
    replaceOnce(off, "\n1 1 1\n", "\n1 1x 1\n"); // vertex 7, line 11
    expectLoadError(writeFile(dir.file("bad.off"), off), {":11:", "y of vertex 7", "'1x'"});
    expectLoadError(writeFile(dir.file("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 zero\nf 1 2 3\n"),
                    {":4:", "z of vertex 4", "'zero'"});
    expectLoadError(writeFile(dir.file("header.off"), "OFF\n8 six 0\n"), {":2:", "face count", "'six'"});
    expectLoadError(writeFile(dir.file("notoff.off"), "PLY\n8 6 0\n"), {":1:", "not an OFF file"});
}

TEST(MeshIoTest, NonFiniteCoordinateNamesTheVertex) {
    TempDir dir;
    std::string off = cubeOff();
    replaceOnce(off, "\n1 1 -1\n", "\n1 nan -1\n"); // vertex 3, line 7
    expectLoadError(writeFile(dir.file("nan.off"), off), {":7:", "vertex 3", "non-finite"});

    std::string obj = cubeObj();
    replaceOnce(obj, "v -1.000000 1.000000 1.000000", "v -1.0 1e39 1.0"); // overflows a float
    expectLoadError(writeFile(dir.file("inf.obj"), obj),
                    {":10:", "vertex 7", "non-finite", "inf"}); // OBJ counts from 1

    std::string stl = cubeStlBinary();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(&stl[84 + 2 * 50 + 12 + 12 + 4], &nan, 4); // triangle 2, vertex 1 (at byte 208), y
    expectLoadError(writeFile(dir.file("nan.stl"), stl),
                    {"byte 208", "vertex 1 of triangle 2", "non-finite"});

    std::string ply = cubePlyBinary(false);
    const double inf = std::numeric_limits<double>::infinity();
    const std::size_t body = ply.find("end_header\n") + 11;
    std::memcpy(&ply[body + 5 * 26 + 18], &inf, 8); // vertex 5, z
    expectLoadError(writeFile(dir.file("inf.ply"), ply),
                    {"byte " + std::to_string(body + 5 * 26), "vertex 5", "non-finite"});
}

TEST(MeshIoTest, OutOfRangeIndexNamesTheFaceAndIndex) {
    TempDir dir;
    std::string off = cubeOff();
    replaceOnce(off, "4 0 1 5 4", "4 0 1 8 4"); // face 2, line 14
    expectLoadError(writeFile(dir.file("index.off"), off), {":14:", "face 2", "index 8", "8 vertices"});

    expectLoadError(writeFile(dir.file("index.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 9\n"),
                    {":5:", "index 9", "3 vertices"});
    expectLoadError(writeFile(dir.file("zero.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
                    {":4:", "index 0"});
    expectLoadError(writeFile(dir.file("relative.obj"), "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n"), {":3:", "-3"});

    std::string ascii = cubePlyAscii();
    replaceOnce(ascii, "4 2 6 7 3 7", "4 2 6 -7 3 7"); // face 3, line 24
    expectLoadError(writeFile(dir.file("index.ply"), ascii), {":24:", "face 3", "index -7"});

    std::string binary = cubePlyBinary(false);
    const std::size_t faces = binary.find("end_header\n") + 11 + 8 * 26;
    const uint32_t big = 1000;
    std::memcpy(&binary[faces + 4 * 17 + 1 + 2 * 4], &big, 4); // face 4, corner 2
    expectLoadError(writeFile(dir.file("index-bin.ply"), binary),
                    {"byte " + std::to_string(faces + 4 * 17 + 1 + 8), "face 4", "index 1000"});
}

TEST(MeshIoTest, FileWithoutTriangles) {
    TempDir dir;
    expectLoadError(writeFile(dir.file("empty.off"), "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), {"no triangles"});
    expectLoadError(writeFile(dir.file("points.obj"), "v 0 0 0\nv 1 0 0\np 1 2\nl 1 2\n"), {"no triangles"});
    expectLoadError(writeFile(dir.file("flat.off"), "OFF\n3 1 0\n0 0 0\n1 1 1\n2 2 2\n3 0 1 2\n"),
                    {"no triangles", "degenerate"});
    expectLoadError(writeFile(dir.file("nothing.stl"), "solid x\nendsolid x\n"), {"no triangles"});
    expectLoadError(writeFile(dir.file("zero.off"), ""), {"empty file"});
}

TEST(MeshIoTest, PlyHeaderCountsBeyondTheBody) {
    TempDir dir;
    const std::string ply = cubePlyBinary(false);
    // Without the edge (8 bytes) and 22 bytes of faces, face 4 has 12 of its 17 bytes.
    expectLoadError(writeFile(dir.file("faces.ply"), ply.substr(0, ply.size() - 30)),
                    {"truncated", "'face' 4 of 6"});
    std::string huge = ply;
    replaceOnce(huge, "element vertex 8", "element vertex 4000000000");
    expectLoadError(writeFile(dir.file("huge.ply"), huge),
                    {"element 'vertex' declares 4000000000", "truncated"});
    std::string ascii = cubePlyAscii();
    expectLoadError(writeFile(dir.file("short.ply"), ascii.substr(0, ascii.size() - 12)),
                    {"end of file", "'face' 5 of 6"});
    expectLoadError(writeFile(dir.file("noheader.ply"), ascii.substr(0, 60)), {"end_header"});
    expectLoadError(writeFile(dir.file("nopos.ply"),
                              "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                              "end_header\n0\n"),
                    {"x, y and z"});
}

// ---------------------------------------------------------------------------------------------
// No crash on any malformed input: every prefix of every small file, and single-byte corruptions,
// either parse or throw voxfx::Error. The readers get each variant in a heap block of exactly its
// size, so that ASan (VOXFX_SANITIZE=ON) sees any read past the end; files on disk would make
// this test take minutes.

void parseOrThrowError(const std::string& name, const std::string& content) {
    const std::unique_ptr<char[]> exact(new char[std::max<std::size_t>(content.size(), 1)]);
    std::memcpy(exact.get(), content.data(), content.size());
    const std::string_view bytes(exact.get(), content.size());
    const std::string ext = std::filesystem::path(name).extension().string();
    try {
        detail::ParsedMesh parsed = ext == ".off"   ? detail::parseOff(bytes, name)
                                    : ext == ".obj" ? detail::parseObj(bytes, name)
                                    : ext == ".ply" ? detail::parsePly(bytes, name)
                                                    : detail::parseStl(bytes, name);
        // What loadMesh does next must cope with whatever a reader accepted.
        for (uint32_t v : parsed.mesh.indices) ASSERT_LT(v, parsed.mesh.positions.size()) << name;
        removeDegenerateTriangles(parsed.mesh);
        analyzeTopology(parsed.mesh.view());
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    } catch (const std::exception& e) { ADD_FAILURE() << name << ": non-voxfx exception " << e.what(); }
}

TEST(MeshIoTest, EveryTruncationAndCorruptionFailsCleanly) {
    const std::pair<const char*, std::string> files[] = {
        {"f.off", cubeOff()},           {"f.obj", cubeObj()},
        {"f.ply", cubePlyAscii()},      {"g.ply", cubePlyBinary(false)},
        {"h.ply", cubePlyBinary(true)}, {"f.stl", cubeStlAscii()},
        {"g.stl", cubeStlBinary()}};
    const char replacements[] = {'\0', '\n', ' ', '-', '9', 'e', '\xff', '/'};
    for (const auto& [name, content] : files) {
        for (std::size_t n = 0; n < content.size(); ++n) parseOrThrowError(name, content.substr(0, n));
        for (std::size_t i = 0; i < content.size(); ++i) {
            for (char r : replacements) {
                std::string bad = content;
                bad[i] = r;
                parseOrThrowError(name, bad);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Real meshes (scripts/fetch-data.sh), with CGAL's readers as the oracle.

using Soup = test::CgalSoup;
using test::readWithCgal;

// Floats equal or adjacent: a text coordinate parsed straight to float (voxfx) and through
// double (CGAL, then rounded to float) can differ by one rounding step in rare halfway cases.
bool withinOneUlp(float a, float b) { return a == b || std::nextafter(a, b) == b; }

// The voxfx mesh must hold the soup's polygons, fan-triangulated, corner by corner at the same
// positions (so STL, whose vertices CGAL merges and voxfx does not, compares too).
void expectSameTriangles(const Mesh& mesh, const Soup& soup, const std::string& what) {
    std::size_t t = 0, mismatches = 0;
    for (const auto& polygon : soup.polygons) {
        for (std::size_t k = 2; k < polygon.size(); ++k, ++t) {
            if (t >= mesh.triangleCount()) break;
            const std::size_t corners[3] = {polygon[0], polygon[k - 1], polygon[k]};
            for (int c = 0; c < 3; ++c) {
                const Vec3f& got = mesh.positions[mesh.indices[3 * t + c]];
                const auto& want = soup.points[corners[c]];
                if (!withinOneUlp(got.x, float(want.x)) || !withinOneUlp(got.y, float(want.y)) ||
                    !withinOneUlp(got.z, float(want.z)))
                    ++mismatches;
            }
        }
    }
    EXPECT_EQ(t, mesh.triangleCount()) << what;
    EXPECT_EQ(mismatches, 0u) << what;
}

TEST(MeshIoRealDataTest, Bunny) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const std::string path = test::dataPath("meshes/bunny00.off");
    MeshLoadReport report;
    const Mesh m = loadMesh(path, &report);
    EXPECT_EQ(m.positions.size(), 37706u); // from the file's header
    EXPECT_EQ(m.triangleCount(), 75408u);
    EXPECT_EQ(report.inputTriangles, 75408u);
    EXPECT_EQ(report.fileBytes, std::filesystem::file_size(path));
    EXPECT_TRUE(analyzeTopology(m.view()).closed());
    expectSameTriangles(m, readWithCgal(path), path);
}

TEST(MeshIoRealDataTest, Closedness) {
    struct Case {
        const char* file;
        bool closed;
    };
    for (const Case& c :
         {Case{"bunny00.off", true}, Case{"armadillo.off", true}, Case{"refined_elephant.off", true},
          Case{"elephant.off", true}, Case{"ChineseDragon-10kv.off", false},
          Case{"elephant-with-holes.off", false}, Case{"sphere.stl", true}, Case{"sphere.ply", true}}) {
        VOXFX_REQUIRE_DATA(std::string("meshes/") + c.file);
        const std::string path = test::dataPath(std::string("meshes/") + c.file);
        const MeshTopology topo = analyzeTopology(loadMesh(path).view());
        EXPECT_EQ(topo.closed(), c.closed)
            << c.file << ": " << topo.boundaryEdges << " boundary, " << topo.nonManifoldEdges
            << " non-manifold, " << topo.misorientedEdges << " misoriented edges";
        if (!c.closed) { EXPECT_GT(topo.boundaryEdges, 0u) << c.file; }
    }
}

TEST(MeshIoRealDataTest, MatchesCgalOnFetchedFiles) {
    for (const char* file : {"armadillo.off", "ChineseDragon-10kv.off", "cube_quad.off", "pig.stl",
                             "sphere.stl", "sphere.ply", "colored_tetra.ply"}) {
        VOXFX_REQUIRE_DATA(std::string("meshes/") + file);
        const std::string path = test::dataPath(std::string("meshes/") + file);
        MeshLoadReport report;
        const Mesh m = loadMesh(path, &report);
        EXPECT_EQ(report.degenerateRemoved, 0u) << file;
        expectSameTriangles(m, readWithCgal(path), file);
    }
}

TEST(MeshIoRealDataTest, PointCloudPlyHasNoTriangles) {
    VOXFX_REQUIRE_DATA("meshes/b9.ply");
    const std::string path = test::dataPath("meshes/b9.ply");
    expectLoadError(path, {"no triangles"});
}

TEST(MeshIoRealDataTest, EveryFormatMatchesCgalOnArmadillo) {
    // CGAL writes the armadillo in each format; what CGAL reads back is what voxfx must read.
    VOXFX_REQUIRE_DATA("meshes/armadillo.off");
    const std::string source = test::dataPath("meshes/armadillo.off");
    const Soup soup = readWithCgal(source);
    TempDir dir;
    for (const char* name : {"a.off", "a.obj", "a-bin.ply", "a-ascii.ply", "a-bin.stl", "a-ascii.stl"}) {
        const std::string path = dir.file(name);
        const bool binary = std::string(name).find("-bin") != std::string::npos;
        ASSERT_TRUE(test::writeWithCgal(path, soup, binary));
        MeshLoadReport report;
        const Mesh m = loadMesh(path, &report);
        EXPECT_EQ(report.inputTriangles, 52000u) << name;
        expectSameTriangles(m, readWithCgal(path), name);
        EXPECT_TRUE(analyzeTopology(m.view()).closed()) << name;
    }
}

} // namespace
} // namespace voxfx
