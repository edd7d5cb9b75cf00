// voxfx tests — the loadable modules (core/module_loader, io/module_api): where they are searched,
// the error when one is missing, that the command starts without the heavy libraries, and the one
// Assimp-to-mesh conversion (mirrored nodes keep closed meshes outward-oriented).
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/module_loader.hpp"
#include "io/module_api.hpp"
#include "test_util.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/scene_io.hpp"

namespace voxfx {
namespace {

using test::TempDir;

using test::ScopedEnv;

TEST(ModuleLoaderTest, SearchesTheEnvironmentThenBesideTheBinaryThenItsLibDir) {
    ScopedEnv env("VOXFX_MODULE_PATH", "/first/dir::/second/dir");
    const std::vector<std::string> dirs = detail::moduleSearchPath();
    ASSERT_GE(dirs.size(), 4u);
    EXPECT_EQ(dirs[0], "/first/dir");
    EXPECT_EQ(dirs[1], "/second/dir");
    // The tests link the library statically or share it from the build folder, which holds the
    // test program too: either way the binary's folder comes next.
    const std::filesystem::path exe = std::filesystem::canonical("/proc/self/exe");
    EXPECT_EQ(dirs[2], exe.parent_path().string());
    EXPECT_EQ(dirs[3], (exe.parent_path() / ".." / "lib" / "voxfx").lexically_normal().string());
}

TEST(ModuleLoaderTest, MissingModuleNamesTheFileAndWhereItWasSearched) {
    TempDir dir;
    ScopedEnv env("VOXFX_MODULE_PATH", dir.path().string());
    try {
        detail::loadModule("nosuch", detail::kModuleAbi, "for this test");
        FAIL() << "a missing module loaded";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("voxfx_nosuch.so"), std::string::npos) << msg;
        EXPECT_NE(msg.find("for this test"), std::string::npos) << msg;
        EXPECT_NE(msg.find(dir.path().string()), std::string::npos) << msg;
        EXPECT_NE(msg.find("VOXFX_MODULE_PATH"), std::string::npos) << msg;
    }
}

TEST(ModuleLoaderTest, AFileThatIsNoModuleIsAClearError) {
    TempDir dir;
    test::writeFile(dir.file("voxfx_broken.so"), "not an ELF file");
    ScopedEnv env("VOXFX_MODULE_PATH", dir.path().string());
    try {
        detail::loadModule("broken", detail::kModuleAbi, "for this test");
        FAIL() << "a broken module loaded";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(dir.file("voxfx_broken.so")), std::string::npos) << msg;
    }
}

TEST(ModuleLoaderTest, EveryModuleLoadsAndAnswersThisInterface) {
    EXPECT_EQ(detail::vdbModule().abi, detail::kModuleAbi);
    EXPECT_EQ(detail::assimpModule().abi, detail::kModuleAbi);
    EXPECT_EQ(detail::exrModule().abi, detail::kModuleAbi);
    EXPECT_TRUE(detail::assimpModule().readsExtension("gltf"));
}

// The dynamic loader lists what a program needs without running it (what ldd does).
TEST(ModuleLoaderTest, TheCommandStartsWithoutOpenVdbAssimpOrOpenExr) {
    TempDir dir;
    const std::string out = dir.file("needed.txt");
    const std::string cmd = "LD_TRACE_LOADED_OBJECTS=1 " + std::string(VOXFX_CLI_PATH) + " >" + out + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream in(out);
    std::stringstream text;
    text << in.rdbuf();
    const std::string libs = text.str();
    ASSERT_NE(libs.find("libc.so"), std::string::npos) << libs; // the listing worked
    for (const char* heavy : {"libopenvdb", "libassimp", "libOpenEXR", "libImath", "libIex", "libboost"})
        EXPECT_EQ(libs.find(heavy), std::string::npos) << heavy << " is loaded at start-up:\n" << libs;
}

// ---- One Assimp-to-mesh conversion: mirrored nodes ---------------------------------------------

template <class T> void appendBytes(std::string& s, T v) {
    s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// The cube [-1, 1]^3 wound outward (counter-clockwise seen from outside), as a glTF buffer.
std::string outwardCubeBuffer() {
    std::string b;
    for (int v = 0; v < 8; ++v)
        for (int a = 0; a < 3; ++a) appendBytes<float>(b, (v >> a) & 1 ? 1.0f : -1.0f);
    // Vertex v has x = bit 0, y = bit 1, z = bit 2.
    const uint16_t faces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                   {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    for (const auto& f : faces)
        for (uint16_t i : f) appendBytes<uint16_t>(b, i);
    return b;
}

// Three instances of the cube: plain (volume 8), mirrored in x by its node (volume 8), and mirrored
// twice (y by the parent, z by the child, scale 2 along z: not mirrored, volume 16).
std::string mirroredGltf() {
    const std::string buffer = outwardCubeBuffer();
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [{"name": "plain", "mesh": 0},
            {"name": "mirrored", "scale": [-1, 1, 1], "translation": [5, 0, 0], "mesh": 0},
            {"name": "parent", "scale": [1, -1, 1], "translation": [0, 5, 0], "children": [3]},
            {"name": "twice", "scale": [1, 1, -2], "mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
  "buffers": [{"uri": "data:application/octet-stream;base64,)" +
           test::base64(buffer) + R"(", "byteLength": )" + std::to_string(buffer.size()) + R"(}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96, "target": 34962},
                  {"buffer": 0, "byteOffset": 96, "byteLength": 72, "target": 34963}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                 "min": [-1, -1, -1], "max": [1, 1, 1]},
                {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]})";
}

TEST(AssimpConversionTest, TheTestCubeIsWoundOutward) {
    // The oracle's own data: the plain cube's signed volume is +8 (divergence theorem).
    const std::string b = outwardCubeBuffer();
    Mesh m;
    for (int v = 0; v < 8; ++v) {
        float p[3];
        std::memcpy(p, b.data() + 12 * v, 12);
        m.positions.push_back({p[0], p[1], p[2]});
    }
    for (int i = 0; i < 36; ++i) {
        uint16_t k;
        std::memcpy(&k, b.data() + 96 + 2 * i, 2);
        m.indices.push_back(k);
    }
    EXPECT_DOUBLE_EQ(test::meshVolume(m.view()), 8.0);
}

TEST(AssimpConversionTest, MirroredNodesStayOutwardAsMesh) {
    TempDir dir;
    const Mesh m = loadMesh(test::writeFile(dir.file("mirrored.gltf"), mirroredGltf()));
    ASSERT_EQ(m.triangleCount(), 36u);
    // Outward everywhere: the signed volume is the sum of the instances' |det| * 8.
    EXPECT_DOUBLE_EQ(test::meshVolume(m.view()), 8.0 + 8.0 + 16.0);
    // Each instance on its own (12 triangles each, in node order) is outward too.
    for (std::size_t part = 0; part < 3; ++part) {
        Mesh one;
        one.positions = m.positions;
        one.indices.assign(m.indices.begin() + long(36 * part), m.indices.begin() + long(36 * part + 36));
        EXPECT_GT(test::meshVolume(one.view()), 0.0) << "instance " << part;
    }
}

TEST(AssimpConversionTest, MirroredNodesStayOutwardAsScene) {
    TempDir dir;
    const Scene s = loadScene(test::writeFile(dir.file("mirrored.gltf"), mirroredGltf()));
    ASSERT_EQ(s.meshes.size(), 3u);
    for (const SceneMesh& sm : s.meshes) {
        const double expected = sm.name == "twice" ? 16.0 : 8.0;
        EXPECT_DOUBLE_EQ(test::meshVolume(sm.mesh.view()), expected) << sm.name;
    }
}

} // namespace
} // namespace voxfx
