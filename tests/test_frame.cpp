// voxfx — Frame: world <-> grid maps, cell centres, slicing maps and perspective frames, each
// against formulas written out here from the definitions in frame.hpp (not the code's own).
#include <cmath>
#include <random>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/error.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/voxelize.hpp"

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

// A right-handed orthonormal basis from two angles (rows: right, up, forward).
void frameTestBasis(double yaw, double pitch, Vec3d& right, Vec3d& up, Vec3d& forward) {
    forward =
        normalize(Vec3d{std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw)});
    const Vec3d hint{0, 1, 0};
    up = normalize(hint - forward * dot(hint, forward));
    right = cross(up, forward);
}

TEST(FrameTest, OrientedOrthographicMapsLocalCoordinatesOntoTheGridAndBack) {
    Vec3d r, u, f;
    frameTestBasis(0.7, -0.4, r, u, f);
    const Frame fr = Frame::orthographic(kBox, r, u, f, 10, 5, 3);
    EXPECT_TRUE(fr.isOriented());
    EXPECT_FALSE(fr.isPerspective());
    const Vec3d ext = kBox.extent();
    expectNear(fr.cellSize(), {ext.x / 10, ext.y / 5, ext.z / 3}, 1e-15, "cellSize");
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> uni(-2, 5);
    for (int k = 0; k < 200; ++k) {
        const Vec3d p{uni(rng), uni(rng), uni(rng)};
        // The definition: local coordinates relative to the local box's corner, in cells.
        const Vec3d local{dot(p, r), dot(p, u), dot(p, f)};
        const Vec3d expected = (local - kBox.lo) * Vec3d{10 / ext.x, 5 / ext.y, 3 / ext.z};
        const Vec3d g = fr.gridFromWorld(p);
        expectNear(g, expected, 1e-12, "gridFromWorld");
        expectNear(fr.worldFromGrid(g), p, 1e-12, "round trip");
        EXPECT_TRUE(fr.view().projection.gridFromWorld(p) == g) << "the view projects bit for bit";
    }
    // Cell centres sit at half-integer grid coordinates and inside the rotated box.
    const Vec3d c = fr.cellCenter(9, 0, 2);
    expectNear(fr.gridFromWorld(c), {9.5, 0.5, 2.5}, 1e-12, "cellCenter");
    // Non-orthonormal or left-handed bases are refused.
    EXPECT_THROW(Frame::orthographic(kBox, r, u, -f, 2, 2, 2), Error);
    EXPECT_THROW(Frame::orthographic(kBox, r * 2.0, u, f, 2, 2, 2), Error);
    EXPECT_THROW(Frame::orthographic(kBox, r, r, f, 2, 2, 2), Error);
    EXPECT_THROW(Frame::orthographic(Box3d{}, r, u, f, 2, 2, 2), Error);
    // Same basis and box: the same grid; another basis: not.
    EXPECT_TRUE(fr.sameGrid(Frame::orthographic(kBox, r, u, f, 10, 5, 3)));
    EXPECT_FALSE(fr.sameGrid(Frame::orthographic(kBox, Axis::Z, 10, 5, 3)));
    // Axis-aligned-only operations refuse oriented frames instead of misreading box().
    VoxelizeOptions solid;
    solid.mode = VoxelizeMode::Solid;
    solid.fill = Fill::Vote;
    const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1});
    EXPECT_THROW(voxelize(box.view(), fr, solid), Error);
}

// Centre-sampled surface cells of a rotated torus in an oriented frame against a brute-force ray
// cast: each column's centre ray (world space, along forward) against every triangle
// (Moller-Trumbore), the hit's slice from its distance. Hits within 1e-7 of a triangle edge or a
// slice boundary may go either way.
TEST(FrameTest, OrientedFrameSurfaceCellsOfARotatedTorusMatchBruteForceRays) {
    Vec3d r, u, f;
    frameTestBasis(-1.1, 0.5, r, u, f);
    const Vec3d centre{0.3, -0.2, 0.4};
    const Mesh torus = test::makeTorus(centre, 1.0, 0.35, 24, 12);
    Box3d local;
    for (const Vec3f& q : torus.positions)
        local.extend(Vec3d{dot(Vec3d(q), r), dot(Vec3d(q), u), dot(Vec3d(q), f)});
    local.lo -= Vec3d{0.05, 0.05, 0.05};
    local.hi += Vec3d{0.05, 0.05, 0.05};
    const int64_t W = 24, H = 20, D = 16;
    const Frame fr = Frame::orthographic(local, r, u, f, W, H, D);
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Surface;
    const VoxelGrid g = voxelize(torus.view(), fr, vo);
    const Vec3d cell = fr.cellSize();
    const Vec3d origin = r * local.lo.x + u * local.lo.y + f * local.lo.z;
    std::vector<int> expected(size_t(W * H * D), 0), uncertain(size_t(W * H * D), 0);
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const Vec3d o = origin + r * ((double(x) + 0.5) * cell.x) + u * ((double(y) + 0.5) * cell.y);
            for (std::size_t t = 0; t < torus.triangleCount(); ++t) {
                const Vec3d a(torus.positions[torus.indices[3 * t]]),
                    b(torus.positions[torus.indices[3 * t + 1]]),
                    c(torus.positions[torus.indices[3 * t + 2]]);
                const Vec3d e1 = b - a, e2 = c - a, pv = cross(f, e2);
                const double det = dot(e1, pv);
                if (std::abs(det) < 1e-14) continue;
                const Vec3d tv = o - a;
                const double bu = dot(tv, pv) / det;
                const Vec3d qv = cross(tv, e1);
                const double bv = dot(f, qv) / det;
                const double dist = dot(e2, qv) / det;
                const double slice = dist / cell.z;
                const double m = std::min({bu, bv, 1 - bu - bv});
                if (m < -1e-7) continue;
                const int64_t s = std::clamp<int64_t>(int64_t(std::floor(slice)), 0, D - 1);
                const size_t i = size_t((y * W + x) * D + s);
                const bool edge = m < 1e-7 || std::abs(slice - std::round(slice)) < 1e-7;
                if (edge)
                    uncertain[i] = 1;
                else
                    expected[i] = 1;
            }
        }
    int64_t certain = 0, mismatches = 0;
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x)
            for (int64_t s = 0; s < D; ++s) {
                const size_t i = size_t((y * W + x) * D + s);
                if (uncertain[i] && !expected[i]) continue;
                certain += expected[i];
                mismatches += int(g.bits.get(x, y, s)) != expected[i];
            }
    EXPECT_GT(certain, 100);
    EXPECT_EQ(mismatches, 0);
}

// A mesh rotated by a signed axis permutation (exact in floating point) voxelized through an
// oriented frame with that rotation as basis gives bit for bit the cells of the unrotated mesh in
// the axis-aligned frame: the oriented path projects exactly like the axis-aligned one.
TEST(FrameTest, RasterizerThroughAnOrientedFrameMatchesTheAxisAlignedFrameOnARotatedMesh) {
    const Mesh torus = test::makeTorus({0.1, 0.2, -0.1}, 1.0, 0.4, 20, 10);
    const Box3d box{{-1.5, -1.3, -0.6}, {1.6, 1.7, 0.5}};
    // Columns of the rotation: world images of the local x, y, z axes (90 degrees about z, then x).
    const Vec3d r{0, 0, 1}, u{-1, 0, 0}, f{0, -1, 0};
    ASSERT_TRUE(cross(r, u) == f);
    Mesh rotated = torus;
    for (Vec3f& q : rotated.positions) q = Vec3f(r * double(q.x) + u * double(q.y) + f * double(q.z));
    for (VoxelizeMode mode : {VoxelizeMode::Surface, VoxelizeMode::Conservative}) {
        SCOPED_TRACE(toString(mode));
        VoxelizeOptions vo;
        vo.mode = mode;
        const VoxelGrid aligned = voxelize(torus.view(), Frame::orthographic(box, Axis::Z, 30, 28, 12), vo);
        const VoxelGrid oriented =
            voxelize(rotated.view(), Frame::orthographic(box, r, u, f, 30, 28, 12), vo);
        EXPECT_GT(aligned.bits.count(), 200);
        EXPECT_EQ(aligned.bits.count(), oriented.bits.count());
        int64_t diff = 0;
        for (int64_t y = 0; y < 28; ++y)
            for (int64_t x = 0; x < 30; ++x)
                for (int64_t s = 0; s < 12; ++s)
                    diff += aligned.bits.get(x, y, s) != oriented.bits.get(x, y, s);
        EXPECT_EQ(diff, 0);
    }
    // A generic rotation: the same mesh rotated in double precision and rounded to float differs
    // only in cells whose sample sits within rounding of an edge: a handful at most.
    Vec3d gr, gu, gf;
    frameTestBasis(0.9, 0.3, gr, gu, gf);
    Mesh generic = torus;
    for (Vec3f& q : generic.positions) q = Vec3f(gr * double(q.x) + gu * double(q.y) + gf * double(q.z));
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Surface;
    const VoxelGrid aligned = voxelize(torus.view(), Frame::orthographic(box, Axis::Z, 30, 28, 12), vo);
    const VoxelGrid oriented = voxelize(generic.view(), Frame::orthographic(box, gr, gu, gf, 30, 28, 12), vo);
    int64_t diff = 0;
    for (int64_t y = 0; y < 28; ++y)
        for (int64_t x = 0; x < 30; ++x)
            for (int64_t s = 0; s < 12; ++s) diff += aligned.bits.get(x, y, s) != oriented.bits.get(x, y, s);
    EXPECT_LE(diff, 4) << "of " << aligned.bits.count();
}

TEST(FrameTest, TranslatedMovesTheBoxAndKeepsTheGrid) {
    Frame f = Frame::orthographic({{-0.15, -0.2, -0.1}, {0.15, 0.2, 0.3}}, Axis::Y, 8, 5, 12);
    const Vec3d offset{5e6, -3, 0.5};
    const Frame t = f.translated(offset);
    EXPECT_EQ(t.axis(), Axis::Y);
    EXPECT_EQ(t.width(), 8);
    EXPECT_EQ(t.height(), 5);
    EXPECT_EQ(t.depth(), 12);
    EXPECT_EQ(t.box().lo, f.box().lo + offset);
    EXPECT_EQ(t.box().hi, f.box().hi + offset);
    // Grid coordinates of moved points are the same up to the rounding of the moved box.
    for (const Vec3d p : {Vec3d{0.01, 0.02, 0.03}, Vec3d{-0.14, 0.19, 0.29}}) {
        const Vec3d a = f.gridFromWorld(p), b = t.gridFromWorld(p + offset);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-6);
    }
    // Local slicing tables are in grid units: they carry over unchanged.
    std::vector<double> nearD(std::size_t(f.columnCount()), 1.0), farD(std::size_t(f.columnCount()), 7.0);
    f.setLocalSlicing(nearD, farD);
    const Frame tl = f.translated(offset);
    EXPECT_EQ(tl.slicing(), Slicing::Local);
    EXPECT_EQ(tl.depthToSlice(3).near, f.depthToSlice(3).near);
    EXPECT_EQ(tl.depthToSlice(3).scale, f.depthToSlice(3).scale);
    EXPECT_THROW(Frame::perspective({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 0.5, 8, 8, 1, 10, 8).translated(offset),
                 Error);
    EXPECT_THROW(f.translated({std::nan(""), 0, 0}), Error);
}

} // namespace
} // namespace voxfx
