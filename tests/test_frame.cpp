// voxfx — Frame: world <-> grid maps, cell centres, slicing maps and perspective frames, each
// against formulas written out here from the definitions in frame.hpp (not the code's own).
#include <cmath>
#include <random>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "voxfx/error.hpp"
#include "voxfx/frame.hpp"

namespace voxfx {
namespace {

void expectNear(const Vec3d& a, const Vec3d& b, double tol, const char* what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}

const Box3d kBox{{-1.5, 2.0, 0.25}, {3.5, 4.5, 1.75}}; // extents 5, 2.5, 1.5

TEST(FrameTest, OrthographicAxesAreCyclicAndCellsTileTheBox) {
    // Slicing along a: columns run along a + 1 and a + 2 (right-handed); W, H, D count cells
    // along those axes.
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        SCOPED_TRACE(toString(axis));
        const int a = int(axis);
        const Frame f = Frame::orthographic(kBox, axis, 10, 5, 3);
        EXPECT_FALSE(f.isPerspective());
        EXPECT_EQ(columnXAxis(axis), (a + 1) % 3);
        EXPECT_EQ(columnYAxis(axis), (a + 2) % 3);
        EXPECT_EQ(f.columnCount(), 50);
        const Vec3d ext = kBox.extent();
        const Vec3d cell = f.cellSize();
        EXPECT_DOUBLE_EQ(cell[(a + 1) % 3], ext[(a + 1) % 3] / 10);
        EXPECT_DOUBLE_EQ(cell[(a + 2) % 3], ext[(a + 2) % 3] / 5);
        EXPECT_DOUBLE_EQ(cell[a], ext[a] / 3);
        // The basis: right x up = forward (right-handed).
        expectNear(cross(f.right(), f.up()), f.forward(), 0, "right x up");
        EXPECT_EQ(f.forward()[a], 1.0);
        // Box corners map to the grid corners.
        expectNear(f.gridFromWorld(kBox.lo), {0, 0, 0}, 1e-12, "lo");
        expectNear(f.gridFromWorld(kBox.hi), {10, 5, 3}, 1e-12, "hi");
        EXPECT_EQ(f.nearDepth(), 0);
        EXPECT_EQ(f.farDepth(), 3);
        EXPECT_EQ(f.slicing(), Slicing::Uniform);
    }
}

TEST(FrameTest, OrthographicWorldGridRoundTripsAndCellCentres) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-0.5, 1.5);
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        SCOPED_TRACE(toString(axis));
        const int a = int(axis), ax = (a + 1) % 3, ay = (a + 2) % 3;
        const Frame f = Frame::orthographic(kBox, axis, 10, 5, 3);
        const Vec3d ext = kBox.extent();
        for (int k = 0; k < 200; ++k) {
            const Vec3d p = kBox.lo + Vec3d{u(rng), u(rng), u(rng)} * ext;
            const Vec3d g = f.gridFromWorld(p);
            // Independent formula: grid coordinate = (p - lo) / cell along the mapped axis.
            const Vec3d expected{(p[ax] - kBox.lo[ax]) / (ext[ax] / 10),
                                 (p[ay] - kBox.lo[ay]) / (ext[ay] / 5), (p[a] - kBox.lo[a]) / (ext[a] / 3)};
            expectNear(g, expected, 1e-12, "gridFromWorld");
            expectNear(f.worldFromGrid(g), p, 1e-12, "world -> grid -> world");
        }
        // cellCenter (x, y, s) = lo + (index + 0.5) * cell per mapped axis.
        for (int64_t x : {0, 4, 9})
            for (int64_t y : {0, 4})
                for (int64_t s : {0, 2}) {
                    Vec3d c;
                    c[ax] = kBox.lo[ax] + (double(x) + 0.5) * ext[ax] / 10;
                    c[ay] = kBox.lo[ay] + (double(y) + 0.5) * ext[ay] / 5;
                    c[a] = kBox.lo[a] + (double(s) + 0.5) * ext[a] / 3;
                    expectNear(f.cellCenter(x, y, s), c, 1e-12, "cellCenter");
                }
    }
}

TEST(FrameTest, LocalSlicingMapsEachColumnsRangeOntoItsSlices) {
    Frame f = Frame::orthographic(kBox, Axis::Z, 3, 2, 8);
    std::vector<double> nearD(6), farD(6);
    for (int c = 0; c < 6; ++c) {
        nearD[size_t(c)] = 0.5 + 0.25 * c;
        farD[size_t(c)] = 2.0 + 0.75 * c;
    }
    farD[4] = nearD[4]; // empty column: keeps the uniform map
    farD[5] = std::nan("");
    f.setLocalSlicing(nearD, farD);
    EXPECT_EQ(f.slicing(), Slicing::Local);
    for (int64_t c = 0; c < 6; ++c) {
        SCOPED_TRACE(c);
        const DepthToSlice m = f.depthToSlice(c);
        if (c >= 4) {
            EXPECT_EQ(m(0.0), 0.0);
            EXPECT_EQ(m(8.0), 8.0);
            continue;
        }
        EXPECT_NEAR(m(nearD[size_t(c)]), 0.0, 1e-12);
        EXPECT_NEAR(m(farD[size_t(c)]), 8.0, 1e-12);
        // Cell centres of the column lie at near + (s + 0.5) * (far - near) / D, in grid depth
        // units (uniform slices of the box).
        const int64_t x = c % 3, y = c / 3;
        const double sliceWorld = kBox.extent().z / 8;
        for (int64_t s : {0, 3, 7}) {
            const double depth =
                nearD[size_t(c)] + (double(s) + 0.5) * (farD[size_t(c)] - nearD[size_t(c)]) / 8;
            EXPECT_NEAR(f.cellCenter(x, y, s).z, kBox.lo.z + depth * sliceWorld, 1e-12);
        }
    }
    Frame uniform = Frame::orthographic(kBox, Axis::Z, 3, 2, 8);
    EXPECT_FALSE(f.sameGrid(uniform));
    Frame again = uniform;
    again.setLocalSlicing(nearD, farD);
    EXPECT_TRUE(f.sameGrid(again));
    f.setUniformSlicing();
    EXPECT_EQ(f.slicing(), Slicing::Uniform);
    EXPECT_TRUE(f.sameGrid(uniform));
    EXPECT_THROW(f.setLocalSlicing({1.0}, {2.0}), Error);
}

TEST(FrameTest, PerspectiveMapsTheViewFrustumOntoTheImage) {
    const Vec3d eye{1, 2, 3}, target{1, 2, -7};
    const double fov = 0.9; // radians
    const int64_t W = 40, H = 20;
    const Frame f = Frame::perspective(eye, target, {0, 1, 0}, fov, W, H, 0.5, 20.0, 16);
    EXPECT_TRUE(f.isPerspective());
    expectNear(f.forward(), {0, 0, -1}, 1e-15, "forward");
    expectNear(f.up(), {0, 1, 0}, 1e-15, "up");
    expectNear(f.right(), {1, 0, 0}, 1e-15, "right");
    const double ty = std::tan(fov / 2), tx = ty * double(W) / double(H);
    for (double z : {0.5, 3.0, 19.0}) {
        // The view axis hits the image centre; the frustum's edges hit the image's edges.
        expectNear(f.gridFromWorld(eye + f.forward() * z), {W / 2.0, H / 2.0, z}, 1e-12, "centre");
        const Vec3d corner = eye + (f.forward() + f.right() * tx + f.up() * ty) * z;
        expectNear(f.gridFromWorld(corner), {double(W), double(H), z}, 1e-10, "upper right corner");
        const Vec3d lower = eye + (f.forward() - f.right() * tx - f.up() * ty) * z;
        expectNear(f.gridFromWorld(lower), {0, 0, z}, 1e-10, "lower left corner");
        EXPECT_NEAR(f.viewDepth(corner), z, 1e-12);
    }
    // Round trips and cell centres: the centre of cell (x, y, s) is on the ray through the pixel
    // centre, at view depth near + (s + 0.5) * (far - near) / D.
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 100; ++k) {
        const Vec3d g{u(rng) * W, u(rng) * H, 0.5 + u(rng) * 19.5};
        expectNear(f.gridFromWorld(f.worldFromGrid(g)), g, 1e-9, "grid -> world -> grid");
    }
    const Vec3d c = f.cellCenter(7, 3, 5);
    const double depth = 0.5 + 5.5 * (19.5 / 16);
    EXPECT_NEAR(f.viewDepth(c), depth, 1e-12);
    const Vec3d expectedDir =
        f.forward() + f.right() * ((7.5 / (W / 2.0) - 1) * tx) + f.up() * ((3.5 / (H / 2.0) - 1) * ty);
    expectNear(c, eye + expectedDir * depth, 1e-12, "cellCenter");
    EXPECT_NEAR(f.depthToSlice(0)(20.0), 16.0, 1e-12);
    EXPECT_NEAR(f.depthToSlice(0)(0.5), 0.0, 1e-12);
}

TEST(FrameTest, InvalidFramesFailWithAnError) {
    EXPECT_THROW(Frame::orthographic(Box3d{}, Axis::Z, 1, 1, 1), Error);
    EXPECT_THROW(Frame::orthographic(kBox, Axis::Z, 0, 1, 1), Error);
    EXPECT_THROW(Frame::orthographic({{0, 0, 0}, {1, 0, 1}}, Axis::Z, 1, 1, 1), Error); // flat
    EXPECT_THROW(Frame::orthographic({{0, 0, 0}, {INFINITY, 1, 1}}, Axis::Z, 1, 1, 1), Error);
    const Vec3d up{0, 1, 0};
    EXPECT_THROW(Frame::perspective({0, 0, 0}, {0, 0, 1}, up, 0.0, 4, 4, 1, 2, 4), Error);
    EXPECT_THROW(Frame::perspective({0, 0, 0}, {0, 0, 1}, up, M_PI, 4, 4, 1, 2, 4), Error);
    EXPECT_THROW(Frame::perspective({0, 0, 0}, {0, 0, 1}, up, 1.0, 4, 4, 0, 2, 4), Error);
    EXPECT_THROW(Frame::perspective({0, 0, 0}, {0, 0, 1}, up, 1.0, 4, 4, 2, 1, 4), Error);
    EXPECT_THROW(Frame::perspective({0, 0, 0}, {0, 1, 0}, up, 1.0, 4, 4, 1, 2, 4), Error); // up || view
    EXPECT_THROW(Frame::perspective({0, 0, 0}, {0, 0, 1}, up, 1.0, 4, 0, 1, 2, 4), Error);
}

TEST(FrameTest, ViewsCarryTheProjectionAndTheSlicingOfTheirFrame) {
    static_assert(std::is_trivially_copyable_v<FrameView>);
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> u(-0.5, 1.5);
    const Frame frames[] = {Frame::orthographic(kBox, Axis::Y, 6, 4, 9),
                            Frame::perspective({1, 2, 3}, {0, 0, 0}, {0, 0, 1}, 0.7, 6, 4, 0.5, 9, 9)};
    for (const Frame& f : frames) {
        SCOPED_TRACE(f.isPerspective() ? "perspective" : "orthographic");
        const FrameView v = f.view();
        EXPECT_EQ(v.isPerspective(), f.isPerspective());
        EXPECT_EQ(v.width, 6);
        EXPECT_EQ(v.height, 4);
        EXPECT_EQ(v.depth, 9);
        EXPECT_EQ(v.local, nullptr);
        for (int k = 0; k < 50; ++k) {
            const Vec3d p = kBox.lo + Vec3d{u(rng), u(rng), u(rng)} * kBox.extent();
            EXPECT_TRUE(v.projection.gridFromWorld(p) == f.gridFromWorld(p)) << "bit-identical";
        }
    }
    Frame local = frames[0];
    std::vector<double> nearD(24), farD(24);
    for (int c = 0; c < 24; ++c) {
        nearD[size_t(c)] = 0.1 * c;
        farD[size_t(c)] = 3 + 0.2 * c;
    }
    local.setLocalSlicing(nearD, farD);
    const FrameView v = local.view();
    ASSERT_NE(v.local, nullptr);
    EXPECT_EQ(v.localCount, 24);
    for (int64_t c = 0; c < 24; ++c) {
        EXPECT_EQ(v.depthToSlice(c).near, local.depthToSlice(c).near);
        EXPECT_EQ(v.depthToSlice(c).scale, local.depthToSlice(c).scale);
    }
}

} // namespace
} // namespace voxfx
