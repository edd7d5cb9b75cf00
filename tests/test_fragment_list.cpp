// Tests of fragment lists (voxfx/fragment_list.hpp): every crossing of each column kept, sorted and
// alternating on a closed mesh against brute-force ray-triangle crossings
// (tests/support/volume_reference.hpp), and independent of the thread count.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::dsmrCrossings;
using test::dsmrLoadScaled;

TEST(FragmentListTest, KeepsEveryCrossingOfEachColumnSortedAndAlternatingOnAClosedMesh) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    const Mesh mesh = dsmrLoadScaled("knot1", {{-1, -1, -1}, {1, 1, 1}});
    const Frame frame = Frame::orthographic({{-1.1, -1.1, -1.1}, {1.1, 1.1, 1.1}}, Axis::Z, 40, 40, 64);
    const FragmentLists lists = FragmentLists::build(frame, mesh.view());
    VolumeScene scene;
    scene.addLeaf(mesh);
    int64_t checked = 0;
    for (int64_t y = 0; y < 40; ++y)
        for (int64_t x = 0; x < 40; ++x) {
            const auto col = lists.column(x, y);
            for (std::size_t i = 0; i + 1 < col.size(); ++i) ASSERT_LE(col[i].depth, col[i + 1].depth);
            // A ray along the column from below the box: brute-force crossings.
            const Vec3d a = frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, -1.0});
            const Vec3d b = frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 65.0});
            bool nearEdge = false;
            const auto hits = dsmrCrossings(scene, a, b - a, 1.0, nearEdge);
            if (nearEdge) continue;
            ASSERT_EQ(col.size(), hits.size()) << "column " << x << ", " << y;
            for (std::size_t i = 0; i < col.size(); ++i) {
                EXPECT_EQ(col[i].front, i % 2 == 0); // enters, leaves, enters ...
                const double depth = -1.0 + hits[i].t * 66.0;
                EXPECT_NEAR(col[i].depth, depth, 1e-6);
            }
            ++checked;
        }
    EXPECT_GT(checked, 1000);
    EXPECT_GT(lists.maxPerColumn(), 2);
}

TEST(FragmentListTest, ListsDoNotDependOnTheThreadCount) {
    const Mesh mesh = test::makeTorus({0, 0, 0}, 0.6, 0.25, 24, 12);
    const Frame frame = Frame::perspective({0.3, 0.2, 3}, {0, 0, 0}, {0, 1, 0}, 0.8, 37, 29, 0.5, 6, 1);
    FragmentLists one, all;
    withThreads(1, [&] { one = FragmentLists::build(frame, mesh.view()); });
    withThreads(0, [&] { all = FragmentLists::build(frame, mesh.view()); });
    ASSERT_EQ(one.fragmentCount(), all.fragmentCount());
    ASSERT_GT(one.fragmentCount(), 0);
    for (int64_t y = 0; y < 29; ++y)
        for (int64_t x = 0; x < 37; ++x) {
            const auto a = one.column(x, y), b = all.column(x, y);
            ASSERT_EQ(a.size(), b.size());
            for (std::size_t i = 0; i < a.size(); ++i) {
                EXPECT_EQ(a[i].depth, b[i].depth);
                EXPECT_EQ(a[i].triangle, b[i].triangle);
                EXPECT_EQ(a[i].front, b[i].front);
            }
        }
}

// A renderer keeps its lists between frames and rebuilds them in place (FragmentLists::rebuild):
// lists rebuilt over memory left by a larger frame of another mesh, and by a smaller one, must be
// the lists a fresh build gives, with no fragment of the earlier frame left over.
TEST(FragmentListTest, ListsRebuiltInPlaceAreThoseOfAFreshBuild) {
    const Mesh torus = test::makeTorus({0, 0, 0}, 0.6, 0.25, 24, 12);
    const Mesh ball = test::makeUvSphere({0.1, 0, 0}, 0.7, 12, 24);
    const Frame small = Frame::perspective({0.3, 0.2, 3}, {0, 0, 0}, {0, 1, 0}, 0.8, 37, 29, 0.5, 6, 1);
    const Frame large = Frame::perspective({-0.4, 0.5, 2.5}, {0, 0, 0}, {0, 1, 0}, 0.9, 61, 47, 0.5, 6, 1);
    auto expectSame = [](const FragmentLists& a, const FragmentLists& b) {
        ASSERT_EQ(a.width(), b.width());
        ASSERT_EQ(a.height(), b.height());
        ASSERT_EQ(a.fragmentCount(), b.fragmentCount());
        ASSERT_GT(a.fragmentCount(), 0);
        for (int64_t y = 0; y < a.height(); ++y)
            for (int64_t x = 0; x < a.width(); ++x) {
                const auto u = a.column(x, y), v = b.column(x, y);
                ASSERT_EQ(u.size(), v.size()) << x << ", " << y;
                for (std::size_t i = 0; i < u.size(); ++i) {
                    EXPECT_EQ(u[i].depth, v[i].depth);
                    EXPECT_EQ(u[i].triangle, v[i].triangle);
                    EXPECT_EQ(u[i].front, v[i].front);
                    if (i + 1 < u.size()) { EXPECT_LE(u[i].depth, u[i + 1].depth); }
                }
            }
    };
    FragmentLists reused = FragmentLists::build(large, ball.view());
    reused.rebuild(small, torus.view());
    expectSame(reused, FragmentLists::build(small, torus.view()));
    reused.rebuild(large, ball.view());
    expectSame(reused, FragmentLists::build(large, ball.view()));
}

// Columns of many fragments and of ties: a stack of 24 squares (two triangles each) across the
// frame's slices, every third one twice (the same corners, so the same depths), some slanted, seen
// along their normal. Each column's list against a brute-force one: per square, the triangle
// whose interior holds the column's centre (centres on a diagonal skipped), at the depth where
// the column meets the square's plane, ordered by (depth, triangle). Columns of more than 16
// fragments (the lists' std::sort) and of fewer (their insertion sort), for one thread and all.
TEST(FragmentListTest, ColumnsOfManyFragmentsAndTiesAreInDepthThenTriangleOrder) {
    Mesh mesh;
    struct Square {
        double z0, slope; // z = z0 + slope * x over the square
        double lo, hi;    // x and y extent
    };
    std::vector<Square> squares;
    for (int k = 0; k < 24; ++k) {
        const double z0 = 0.9 - 0.07 * k, slope = k % 4 == 1 ? 0.02 * (k % 3 - 1) : 0.0;
        const double lo = -0.95 + 0.012 * k, hi = 0.95 - 0.009 * k;
        for (int copy = 0; copy < (k % 3 == 0 ? 2 : 1); ++copy) {
            squares.push_back({z0, slope, lo, hi});
            const uint32_t b = uint32_t(mesh.positions.size());
            for (const auto& [x, y] :
                 std::initializer_list<std::pair<double, double>>{{lo, lo}, {hi, lo}, {hi, hi}, {lo, hi}})
                mesh.positions.push_back(Vec3f(Vec3d{x, y, z0 + slope * x}));
            for (const uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) mesh.indices.push_back(b + i);
        }
    }
    const int64_t N = 48;
    const Frame frame = Frame::orthographic({{-1, -1, -1}, {1, 1, 1}}, Axis::Z, N, N, 64);
    FragmentLists one, all;
    withThreads(1, [&] { one = FragmentLists::build(frame, mesh.view()); });
    withThreads(0, [&] { all = FragmentLists::build(frame, mesh.view()); });
    int64_t checked = 0, many = 0, ties = 0;
    for (int64_t y = 0; y < N; ++y)
        for (int64_t x = 0; x < N; ++x) {
            const Vec3d c = frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 0.0});
            std::vector<std::pair<double, uint32_t>> expected; // (depth, triangle)
            bool skip = false;
            for (std::size_t q = 0; q < squares.size(); ++q) {
                const Square& s = squares[q];
                const double eps = 1e-9;
                if (c.x < s.lo - eps || c.x > s.hi + eps || c.y < s.lo - eps || c.y > s.hi + eps) continue;
                const double u = (c.x - s.lo) / (s.hi - s.lo), v = (c.y - s.lo) / (s.hi - s.lo);
                if (std::abs(u - v) < 1e-6 || u < 1e-6 || v < 1e-6 || u > 1 - 1e-6 || v > 1 - 1e-6) {
                    skip = true; // on an edge or the diagonal: the rasterizer's tie rule decides
                    break;
                }
                const uint32_t triangle = uint32_t(2 * q + (u > v ? 0 : 1)); // (0,1,2) below the diagonal
                const Vec3d p{c.x, c.y, s.z0 + s.slope * c.x};
                expected.push_back({frame.gridFromWorld(p).z, triangle});
            }
            if (skip) continue;
            std::sort(expected.begin(), expected.end(), [](const auto& a, const auto& b) {
                return std::abs(a.first - b.first) > 1e-7 ? a.first < b.first : a.second < b.second;
            });
            const auto got = one.column(x, y), other = all.column(x, y);
            ASSERT_EQ(got.size(), expected.size()) << x << ", " << y;
            ASSERT_EQ(other.size(), got.size());
            for (std::size_t i = 0; i < got.size(); ++i) {
                EXPECT_NEAR(got[i].depth, expected[i].first, 1e-4) << x << ", " << y << " #" << i;
                EXPECT_EQ(got[i].triangle, expected[i].second) << x << ", " << y << " #" << i;
                EXPECT_EQ(other[i].depth, got[i].depth);
                EXPECT_EQ(other[i].triangle, got[i].triangle);
                if (i > 0) {
                    EXPECT_TRUE(got[i - 1].depth < got[i].depth ||
                                (got[i - 1].depth == got[i].depth && got[i - 1].triangle < got[i].triangle));
                    ties += got[i - 1].depth == got[i].depth;
                }
            }
            many += got.size() > 16;
            ++checked;
        }
    EXPECT_GT(checked, 1500);
    EXPECT_GT(many, 500);  // std::sort's columns
    EXPECT_GT(ties, 5000); // equal depths, lower triangle first
    EXPECT_GT(one.maxPerColumn(), 30);
}

} // namespace
} // namespace voxfx
