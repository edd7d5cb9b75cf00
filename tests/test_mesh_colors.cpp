// Tests of the per-vertex colours of src/io/mesh_off.cpp and src/io/mesh_ply.cpp (loadMesh with
// vertexColors): COFF with integer and decimal components, alpha, the N and ST prefixes and a
// comment glued to a value; PLY ascii and binary with uchar, ushort and float colours; files
// without colours; malformed colours as errors naming the line.
#include <cstring>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/mesh_io.hpp"

namespace voxfx {
namespace {

std::vector<Vec3f> coloursOf(const std::string& path) {
    std::vector<Vec3f> c;
    const Mesh m = loadMesh(path, nullptr, &c);
    EXPECT_TRUE(c.empty() || c.size() == m.positions.size());
    return c;
}

TEST(MeshColors, CoffComponentsAreIntegersOver255OrDecimals) {
    test::TempDir dir;
    const std::string tri = "3 0 1 2\n";
    EXPECT_EQ(
        coloursOf(test::writeFile(dir.file("a.off"), "COFF\n3 1 0\n0 0 0 255 0 51 255\n1 0 0 0 0 0 255\n"
                                                     "0 1 0 102 204 255 0\n" +
                                                         tri)),
        (std::vector<Vec3f>{{1, 0, 0.2f}, {0, 0, 0}, {0.4f, 0.8f, 1}}));
    EXPECT_EQ(
        coloursOf(test::writeFile(dir.file("b.off"), "COFF\n3 1 0\n0 0 0 0.5 0 0.25#red\n1 0 0 1.0 1 1\n"
                                                     "0 1 0 0 0 1e-1\n" +
                                                         tri)),
        (std::vector<Vec3f>{{0.5f, 0, 0.25f}, {1, 1, 1}, {0, 0, 0.1f}}));
    // N: a normal before the colour; ST: texture coordinates after it.
    EXPECT_EQ(coloursOf(test::writeFile(dir.file("c.off"),
                                        "STCNOFF\n3 1 0\n0 0 0 0 0 1 0.5 0.5 0.5 1 9 9\n"
                                        "1 0 0 0 0 1 1.0 0 0 1 9 9\n0 1 0 0 0 1 0 1.0 0 1 9 9\n" +
                                            tri)),
              (std::vector<Vec3f>{{0.5f, 0.5f, 0.5f}, {1, 0, 0}, {0, 1, 0}}));
    EXPECT_TRUE(
        coloursOf(test::writeFile(dir.file("d.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n" + tri)).empty());
    for (const char* bad :
         {"COFF\n3 1 0\n0 0 0 1 0\n1 0 0 1 0 0\n0 1 0 1 0 0\n", "COFF\n3 1 0\n0 0 0 1 0 x\n"}) {
        try {
            coloursOf(
                test::writeFile(dir.file("e.off"), std::string(bad) + "1 0 0 1 0 0\n0 1 0 1 0 0\n" + tri));
            ADD_FAILURE() << "accepted " << bad;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("e.off:3: vertex 0"), std::string::npos) << e.what();
        }
    }
}

TEST(MeshColors, PlyColoursScaleIntegerTypesByTheirLargestValue) {
    test::TempDir dir;
    const std::string ascii =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty ushort red\nproperty ushort green\nproperty ushort blue\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 65535 0 0\n1 0 0 0 65535 0\n0 1 0 0 0 13107\n3 0 1 2\n";
    EXPECT_EQ(coloursOf(test::writeFile(dir.file("a.ply"), ascii)),
              (std::vector<Vec3f>{{1, 0, 0}, {0, 1, 0}, {0, 0, 0.2f}}));
    std::string binary =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nproperty float red\nproperty float green\n"
        "property float blue\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[3][6] = {{0, 0, 0, 0.25f, 0.5f, 0.75f}, {1, 0, 0, 1, 1, 1}, {0, 1, 0, 0, 0, 0}};
    binary.append(reinterpret_cast<const char*>(v), sizeof(v));
    const unsigned char n = 3;
    const int32_t idx[3] = {0, 1, 2};
    binary.append(reinterpret_cast<const char*>(&n), 1);
    binary.append(reinterpret_cast<const char*>(idx), sizeof(idx));
    EXPECT_EQ(coloursOf(test::writeFile(dir.file("b.ply"), binary)),
              (std::vector<Vec3f>{{0.25f, 0.5f, 0.75f}, {1, 1, 1}, {0, 0, 0}}));
    // Red alone is not a colour.
    const std::string partial =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0 1\n1 0 0 2\n0 1 0 3\n"
        "3 0 1 2\n";
    EXPECT_TRUE(coloursOf(test::writeFile(dir.file("c.ply"), partial)).empty());
}

} // namespace
} // namespace voxfx
