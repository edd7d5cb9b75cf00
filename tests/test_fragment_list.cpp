// Tests of fragment lists (voxfx/fragment_list.hpp): every crossing of each column kept, sorted and
// alternating on a closed mesh against brute-force ray-triangle crossings
// (tests/support/volume_reference.hpp), and independent of the thread count.
#include <cstddef>
#include <cstdint>

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

} // namespace
} // namespace voxfx
