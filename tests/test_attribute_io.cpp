// voxfx — writing attribute grids (voxfx/attribute_io.hpp) and the `voxfx attributes` command.
//
// Oracles: boxes whose faces lie mid-voxel, so center coverage writes exactly the voxels of the
// faces across the slicing axis (a face along it is edge-on to every column); the files are read
// back by plain OpenVDB or decoded from the formats' descriptions, and every voxel's normal,
// material and refraction index is compared with what the geometry says, for every slicing axis
// (the world order of the file must not depend on it).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include "test_util.hpp"
#include "voxfx/attribute_io.hpp"
#include "voxfx/mesh_io.hpp"

namespace voxfx {
namespace {

constexpr int64_t kN = 16;

// Box A [2.3, 9.3]^3 (material 0, ior 1.3) and box B [11.3, 13.3] x [2.3, 5.3] x [2.3, 5.3]
// (material 1, ior 1.7) in the unit grid [0, 16]^3: faces at .3 lie inside a voxel, and a face's
// columns are those with centres (i + 0.5) inside its range.
struct TwoBoxes {
    Mesh mesh;
    std::vector<uint32_t> triangleMaterial;
    std::vector<AttributeMaterial> materials{{1.3f, {0.1f, 0.2f, 0.3f}}, {1.7f, {0, 0, 0}}};
    static constexpr double kLoA[3] = {2.3, 2.3, 2.3}, kHiA[3] = {9.3, 9.3, 9.3};
    static constexpr double kLoB[3] = {11.3, 2.3, 2.3}, kHiB[3] = {13.3, 5.3, 5.3};
    TwoBoxes() {
        test::appendBox(mesh, {kLoA[0], kLoA[1], kLoA[2]}, {kHiA[0], kHiA[1], kHiA[2]});
        triangleMaterial.assign(mesh.triangleCount(), 0);
        test::appendBox(mesh, {kLoB[0], kLoB[1], kLoB[2]}, {kHiB[0], kHiB[1], kHiB[2]});
        triangleMaterial.resize(mesh.triangleCount(), 1);
    }
    AttributeGrid voxelize(Axis axis, AttributeChannels channels = AttributeChannels::all()) const {
        AttributeOptions o;
        o.channels = channels;
        o.triangleMaterial = triangleMaterial;
        o.materials = materials;
        const Frame f =
            Frame::orthographic({{0, 0, 0}, {double(kN), double(kN), double(kN)}}, axis, kN, kN, kN);
        return voxelizeAttributes(mesh.view(), f, std::vector<float>(mesh.triangleCount(), 0.5f), o);
    }
};

// What the geometry says voxel (i, j, k) holds when slicing along `axis`: the outward normal of
// the face across the axis it lies on (zero if none) and the material (-1 if none).
struct Expected {
    Vec3f normal{0, 0, 0};
    int material = -1;
};

Expected expectedAt(int64_t i, int64_t j, int64_t k, Axis axis) {
    const int a = int(axis);
    const int64_t v[3] = {i, j, k};
    Expected e;
    const auto box = [&](const double* lo, const double* hi, int material) {
        for (int b = 0; b < 3; ++b)
            if (b != a && !(double(v[b]) + 0.5 > lo[b] && double(v[b]) + 0.5 < hi[b])) return;
        const auto cellOf = [](double x) { return int64_t(std::floor(x)); };
        if (v[a] == cellOf(lo[a]) || v[a] == cellOf(hi[a])) {
            e.material = material;
            e.normal[a] = v[a] == cellOf(hi[a]) ? 1.0f : -1.0f;
        }
    };
    box(TwoBoxes::kLoA, TwoBoxes::kHiA, 0);
    box(TwoBoxes::kLoB, TwoBoxes::kHiB, 1);
    return e;
}

template <class GridT> typename GridT::Ptr readGrid(const std::string& path, const std::string& name) {
    openvdb::initialize();
    openvdb::io::File file(path);
    file.open();
    auto grid = openvdb::gridPtrCast<GridT>(file.readGrid(name));
    file.close();
    return grid;
}

TEST(AttributeIo, VdbHoldsEveryChannelOfEveryVoxelInWorldOrderForEverySlicingAxis) {
    const TwoBoxes boxes;
    test::TempDir dir;
    for (const Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        const AttributeGrid g = boxes.voxelize(axis);
        const std::string path = dir.file("boxes.vdb");
        writeAttributeGrid(g, path);
        const auto normal = readGrid<openvdb::Vec3SGrid>(path, "normal");
        const auto material = readGrid<openvdb::FloatGrid>(path, "material");
        const auto ior = readGrid<openvdb::FloatGrid>(path, "ior");
        const auto count = readGrid<openvdb::FloatGrid>(path, "count");
        const auto attenuation = readGrid<openvdb::Vec3SGrid>(path, "attenuation");
        const auto absorption = readGrid<openvdb::FloatGrid>(path, "absorption");
        ASSERT_TRUE(normal && material && ior && count && attenuation && absorption) << toString(axis);
        // Index (i, j, k) is the centre of voxel (i, j, k).
        const openvdb::Vec3d c = normal->indexToWorld(openvdb::Coord(3, 5, 7));
        EXPECT_NEAR(c[0], 3.5, 1e-12);
        EXPECT_NEAR(c[1], 5.5, 1e-12);
        EXPECT_NEAR(c[2], 7.5, 1e-12);
        int64_t written = 0, wrong = 0;
        for (int64_t k = 0; k < kN; ++k)
            for (int64_t j = 0; j < kN; ++j)
                for (int64_t i = 0; i < kN; ++i) {
                    const openvdb::Coord ijk{int(i), int(j), int(k)};
                    const Expected e = expectedAt(i, j, k, axis);
                    const bool on = e.material >= 0;
                    written += on;
                    const openvdb::Vec3s n = normal->tree().getValue(ijk);
                    bool ok = normal->tree().isValueOn(ijk) == on && material->tree().isValueOn(ijk) == on &&
                              material->tree().getValue(ijk) == float(e.material);
                    for (int a = 0; a < 3; ++a) ok = ok && std::abs(n[a] - e.normal[a]) < 1e-6f;
                    if (on) {
                        const AttributeMaterial& m = boxes.materials[std::size_t(e.material)];
                        ok = ok && ior->tree().getValue(ijk) == m.ior && count->tree().getValue(ijk) >= 1 &&
                             attenuation->tree().getValue(ijk)[2] == m.attenuation.z &&
                             absorption->tree().getValue(ijk) == 0.5f * count->tree().getValue(ijk);
                    } else {
                        ok = ok && ior->tree().getValue(ijk) == 0 && count->tree().getValue(ijk) == 0;
                    }
                    if (!ok && ++wrong < 5)
                        ADD_FAILURE() << toString(axis) << " voxel " << i << " " << j << " " << k;
                }
        // The faces across the axis: A's two 7 x 7 faces, B's two (2 x 3, 3 x 3 or 2 x 3).
        const int64_t bFace[3] = {3 * 3, 2 * 3, 2 * 3};
        EXPECT_EQ(written, 2 * 49 + 2 * bFace[int(axis)]) << toString(axis);
        EXPECT_EQ(wrong, 0) << toString(axis);
    }
}

// A .nrrd or .npy file's samples after its header.
std::string payload(const std::string& bytes, bool nrrd) {
    if (nrrd) return bytes.substr(bytes.find("\n\n") + 2);
    const std::size_t headerLen = uint8_t(bytes[8]) | std::size_t(uint8_t(bytes[9])) << 8;
    return bytes.substr(10 + headerLen);
}

TEST(AttributeIo, NrrdAndNpyHoldOneChannelInTheirFormatsOrder) {
    const TwoBoxes boxes;
    const AttributeGrid g = boxes.voxelize(Axis::Y);
    test::TempDir dir;
    // Normals: a 3-vector axis first, then x fastest.
    writeAttributeGrid(g, dir.file("n.nrrd"), AttributeChannel::Normal);
    const std::string nrrd = test::readFileBytes(dir.file("n.nrrd"));
    EXPECT_NE(nrrd.find("type: float\n"), std::string::npos);
    EXPECT_NE(nrrd.find("sizes: 3 16 16 16\n"), std::string::npos) << nrrd.substr(0, 400);
    EXPECT_NE(nrrd.find("kinds: 3-vector domain domain domain\n"), std::string::npos);
    EXPECT_NE(nrrd.find("space origin: (0.5,0.5,0.5)"), std::string::npos) << nrrd.substr(0, 400);
    const std::string n = payload(nrrd, true);
    ASSERT_EQ(n.size(), std::size_t(kN * kN * kN * 3 * 4));
    // Materials: uint32, 0xffffffff where nothing was written.
    writeAttributeGrid(g, dir.file("m.npy"), AttributeChannel::Material);
    const std::string npy = test::readFileBytes(dir.file("m.npy"));
    EXPECT_NE(npy.find("'descr': '<u4', 'fortran_order': True, 'shape': (16, 16, 16)"), std::string::npos);
    const std::string m = payload(npy, false);
    ASSERT_EQ(m.size(), std::size_t(kN * kN * kN * 4));
    int64_t wrong = 0;
    for (int64_t k = 0; k < kN; ++k)
        for (int64_t j = 0; j < kN; ++j)
            for (int64_t i = 0; i < kN; ++i) {
                const std::size_t v = std::size_t(i + kN * (j + kN * k));
                const Expected e = expectedAt(i, j, k, Axis::Y);
                float normal[3];
                std::memcpy(normal, n.data() + 12 * v, 12);
                uint32_t material;
                std::memcpy(&material, m.data() + 4 * v, 4);
                bool ok = material == (e.material < 0 ? AttributeGrid::kNoMaterial : uint32_t(e.material));
                for (int a = 0; a < 3; ++a) ok = ok && std::abs(normal[a] - e.normal[a]) < 1e-6f;
                wrong += !ok;
            }
    EXPECT_EQ(wrong, 0);
}

TEST(AttributeIo, BadRequestsAreErrorsAndLeaveNoFile) {
    const TwoBoxes boxes;
    const AttributeGrid g = boxes.voxelize(Axis::Z);
    test::TempDir dir;
    // Several channels in a one-channel format, an unknown extension, a missing channel.
    EXPECT_THROW(writeAttributeGrid(g, dir.file("a.nrrd")), Error);
    EXPECT_THROW(writeAttributeGrid(g, dir.file("a.binvox")), Error);
    const AttributeGrid normalsOnly = boxes.voxelize(Axis::Z, {false, false, true, false, false, false});
    EXPECT_THROW(writeAttributeGrid(normalsOnly, dir.file("a.vdb"), AttributeChannel::Ior), Error);
    EXPECT_TRUE(std::filesystem::is_empty(dir.file("")));
    EXPECT_EQ(parseAttributeChannels("normals,ior").ior, true);
    EXPECT_THROW(parseAttributeChannels("normal,colour"), Error);
    EXPECT_THROW(parseAttributeChannels(","), Error);
}

TEST(AttributesCli, WritesTheGridAndSaysWhatItMade) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    test::TempDir dir;
    const std::string out = dir.file("bunny.vdb");
    const test::CommandRun r =
        test::runVoxfx(dir, "attributes " + test::dataPath("meshes/bunny00.off") + " -o " + out + " -r 48");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find(" triangles, 1 material -> "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("channels count, normal, material, ior"), std::string::npos) << r.out;
    // The bunny is closed and outward: a written voxel's normal points away from the inside, so
    // stepping along it leaves the mesh's box sooner than stepping against it, on average.
    const auto normal = readGrid<openvdb::Vec3SGrid>(out, "normal");
    ASSERT_TRUE(normal);
    openvdb::Vec3d centre(0, 0, 0);
    int64_t n = 0;
    for (auto it = normal->cbeginValueOn(); it; ++it, ++n) centre += normal->indexToWorld(it.getCoord());
    ASSERT_GT(n, 1000);
    centre /= double(n);
    int64_t outward = 0;
    for (auto it = normal->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d p = normal->indexToWorld(it.getCoord());
        outward += (p - centre).dot(openvdb::Vec3d(*it)) > 0;
    }
    EXPECT_GT(outward, n * 8 / 10) << outward << " of " << n;
}

TEST(AttributesCli, BadArgumentsGiveOneErrorLineAndNoFile) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    test::TempDir dir;
    const std::string mesh = test::dataPath("meshes/bunny00.off");
    for (const std::string& args :
         {" -o " + dir.file("a.nrrd") + " --channels normal,ior",
          " -o " + dir.file("a.vdb") + " --channels colour",
          " -o " + dir.file("a.vdb") + " --channels absorption",
          " -o " + dir.file("a.vdb") + " --coverage exact", " -o " + dir.file("a.txt")}) {
        const test::CommandRun r = test::runVoxfx(dir, "attributes " + mesh + args);
        EXPECT_NE(r.exitCode, 0) << args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << ": " << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("a.nrrd")) ||
                     std::filesystem::exists(dir.file("a.vdb")) || std::filesystem::exists(dir.file("a.txt")))
            << args;
    }
}

} // namespace
} // namespace voxfx
