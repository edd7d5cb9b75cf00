// Tests of src/grid/vertex_colors.cpp: a linear colour field on a plane seen along its normal, whose
// per-voxel mean is the field at the column centre (closed form), the written voxels being the
// surface voxelization's, the same colours for every thread count, and bad input. The loaders'
// colours (PLY, COFF) are in test_mesh_colors.cpp.
#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/vertex_colors.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

// A 7 x 7 grid of vertices on z = 0.3 over [0, 1]^2, triangulated; colours A p + b.
struct ColouredPlane {
    Mesh mesh;
    std::vector<Vec3f> colors;
    static Vec3d colour(const Vec3d& p) {
        return {0.5 * p.x + 0.1 * p.y + 0.1, 0.7 * p.y + 0.05, 0.2 * (p.x + p.y) + 0.3};
    }
    ColouredPlane() {
        for (int i = 0; i < 7; ++i)
            for (int j = 0; j < 7; ++j) {
                const Vec3d p{i / 6.0, j / 6.0, 0.3};
                mesh.positions.push_back(Vec3f(p));
                colors.push_back(Vec3f(colour(Vec3d(mesh.positions.back()))));
            }
        for (uint32_t i = 0; i < 6; ++i)
            for (uint32_t j = 0; j < 6; ++j) {
                const uint32_t a = i * 7 + j, b = a + 7, c = a + 8, d = a + 1;
                mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
            }
    }
};

TEST(VertexColors, ALinearFieldAveragesToItsValueAtEachColumnCentre) {
    const ColouredPlane plane;
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 10, 10, 10);
    const ColorGrid g = voxelizeVertexColors(plane.mesh.view(), plane.colors, frame);
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Surface;
    const VoxelGrid surface = voxelize(plane.mesh.view(), frame, vo);
    int64_t written = 0;
    for (int64_t y = 0; y < 10; ++y)
        for (int64_t x = 0; x < 10; ++x)
            for (int64_t s = 0; s < 10; ++s) {
                const int64_t i = g.index(x, y, s);
                ASSERT_EQ(g.count[std::size_t(i)] > 0, surface.bits.get(x, y, s))
                    << x << " " << y << " " << s;
                if (g.count[std::size_t(i)] == 0) {
                    ASSERT_EQ(g.color[std::size_t(i)], Vec3f{});
                    continue;
                }
                ++written;
                // The colour at the centre's projection onto the plane: (x + 0.5, y + 0.5) / 10.
                const Vec3d want = ColouredPlane::colour({(x + 0.5) / 10, (y + 0.5) / 10, 0.3});
                const Vec3f got = g.color[std::size_t(i)];
                for (int k = 0; k < 3; ++k) ASSERT_NEAR(got[k], want[k], 2e-6) << x << " " << y;
            }
    EXPECT_EQ(written, 100);
    VertexColorOptions one;
    one.threads = 1;
    const ColorGrid h = voxelizeVertexColors(plane.mesh.view(), plane.colors, frame, one);
    EXPECT_EQ(h.color, g.color);
    EXPECT_EQ(h.count, g.count);
}

TEST(VertexColors, BadInputIsAClearError) {
    ColouredPlane plane;
    const Frame frame = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 4, 4, 4);
    std::vector<Vec3f> few(plane.colors.begin(), plane.colors.end() - 1);
    EXPECT_THROW(voxelizeVertexColors(plane.mesh.view(), few, frame), Error);
    plane.colors[3].y = std::nanf("");
    EXPECT_THROW(voxelizeVertexColors(plane.mesh.view(), plane.colors, frame), Error);
}

} // namespace
} // namespace voxfx
