// Tests of src/core/voxel_grid.cpp: the world-index convention of atWorldIndex and worldDims
// (hand-derived from frame.hpp's cyclic axis rule), and reslice against a brute-force voxel
// comparison for every source / target axis pair on odd sizes.
#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx {
namespace {

constexpr Axis kAxes[3] = {Axis::X, Axis::Y, Axis::Z};

TEST(VoxelGridTest, AtWorldIndexFollowsTheCyclicAxisConvention) {
    // World dims (3, 4, 5). frame.hpp: axis Z -> columns (x, y); X -> (y, z); Y -> (z, x).
    const Box3d box{{0, 0, 0}, {3, 4, 5}};
    struct Case {
        Axis axis;
        int64_t w, h, d;   // bit-grid dims in (column x, column y, slice) order
        int64_t cx, cy, s; // the one set bit
        int64_t i, j, k;   // its world index, by hand
    };
    const Case cases[] = {
        {Axis::Z, 3, 4, 5, 2, 1, 3, 2, 1, 3},
        {Axis::X, 4, 5, 3, 1, 3, 2, 2, 1, 3},
        {Axis::Y, 5, 3, 4, 3, 2, 1, 2, 1, 3},
    };
    for (const Case& c : cases) {
        VoxelGrid g{Frame::orthographic(box, c.axis, c.w, c.h, c.d), BitGrid(c.w, c.h, c.d)};
        g.bits.set(c.cx, c.cy, c.s);
        EXPECT_EQ(g.worldDims(), Vec3i(3, 4, 5)) << toString(c.axis);
        for (int64_t i = 0; i < 3; ++i)
            for (int64_t j = 0; j < 4; ++j)
                for (int64_t k = 0; k < 5; ++k)
                    EXPECT_EQ(g.atWorldIndex(i, j, k), i == c.i && j == c.j && k == c.k)
                        << toString(c.axis) << " (" << i << ", " << j << ", " << k << ")";
    }
}

TEST(VoxelGridTest, ResliceKeepsEveryVoxelForEveryAxisPair) {
    const Vec3i sizes[] = {{70, 5, 130}, {1, 1, 1}, {64, 64, 64}, {65, 3, 129}};
    uint64_t seed = 1;
    for (const Vec3i& n : sizes)
        for (Axis from : kAxes)
            for (Axis to : kAxes) {
                const Box3d box{{-1, 2, 0.5},
                                {-1 + 0.1 * double(n.x), 2 + 0.2 * double(n.y), 0.5 + 0.3 * double(n.z)}};
                const VoxelGrid src = test::randomVoxelGrid(box, from, n, 0.4, seed++);
                const VoxelGrid dst = reslice(src, to);
                SCOPED_TRACE(testing::Message() << n.x << "x" << n.y << "x" << n.z << " " << toString(from)
                                                << " -> " << toString(to));
                ASSERT_EQ(dst.frame.axis(), to);
                ASSERT_EQ(dst.worldDims(), n);
                ASSERT_EQ(dst.bits.width(), dst.frame.width());
                ASSERT_EQ(dst.bits.height(), dst.frame.height());
                ASSERT_EQ(dst.bits.depth(), dst.frame.depth());
                EXPECT_EQ(dst.frame.box(), box);
                EXPECT_EQ(test::worldMismatches(dst, src), 0);
                EXPECT_EQ(dst.bits.count(), src.bits.count());
                // Padding bits (slices >= depth in each column's last word) stay zero.
                const uint64_t padding = ~dst.bits.lastWordMask();
                int64_t dirtyColumns = 0;
                for (int64_t c = 0; c < dst.bits.columnCount(); ++c)
                    dirtyColumns += (dst.bits.column(c)[dst.bits.wordsPerColumn() - 1] & padding) != 0;
                EXPECT_EQ(dirtyColumns, 0);
            }
}

TEST(VoxelGridTest, ResliceOfFullGridIsFullWithCleanPadding) {
    // All voxels on: any bit leaking from padding or a transposed block boundary would show up
    // as a wrong count (65 and 129 straddle word and block edges).
    const Vec3i n{65, 3, 129};
    const VoxelGrid src = test::randomVoxelGrid({{0, 0, 0}, {1, 1, 1}}, Axis::Z, n, 1.0, 7);
    ASSERT_EQ(src.bits.count(), n.x * n.y * n.z);
    for (Axis to : kAxes) {
        const VoxelGrid dst = reslice(src, to);
        EXPECT_EQ(dst.bits.count(), n.x * n.y * n.z) << toString(to);
    }
}

} // namespace
} // namespace voxfx
