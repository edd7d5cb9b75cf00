// Memory made ready ahead of a voxelization (voxfx/prepared_memory.hpp): the voxelization takes its
// grid from it and produces the same grid; what it does not take is given back.
#include <cstdint>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/page_memory.hpp"
#include "voxfx/prepared_memory.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

TEST(PreparedMemoryTest, AVoxelizationTakesItsGridFromThePreparedMemoryAndGivesTheSameGrid) {
    const Mesh mesh = test::makeUvSphere({0.1, -0.2, 0.3}, 1.0, 48, 96);
    FitOptions fo;
    fo.resolution = 320; // a grid of two huge pages (BitGrid maps from 2 MiB up)
    const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
    VoxelizeOptions vo;
    vo.fill = Fill::Auto;
    vo.threads = 2;
    const VoxelGrid fresh = voxelize(mesh.view(), frame, vo);
    ASSERT_GT(fresh.bits.count(), 0);

    const std::size_t before = detail::reservedPageBytes();
    const uint64_t bound = voxelizeMemoryBound(frame.width(), frame.height(), frame.depth());
    const uint64_t gridBytes = BitGrid::requiredBytes(frame.width(), frame.height(), frame.depth());
    ASSERT_GE(gridBytes, uint64_t(1) << 21);
    ASSERT_GT(bound, gridBytes);
    PreparedMemory prepared = prepareVoxelizeMemory(bound);
    prepared.wait();
    ASSERT_GE(detail::reservedPageBytes() - before, bound);
    const VoxelGrid fromPrepared = voxelize(mesh.view(), frame, vo);
    // The grid (at least) came out of the prepared memory...
    EXPECT_LE(detail::reservedPageBytes() - before + gridBytes, bound);
    // ...and it holds what a fresh mapping holds: the memory was zero where the voxelization
    // relied on it.
    EXPECT_TRUE(fromPrepared.bits == fresh.bits);
    prepared.release();
    EXPECT_EQ(detail::reservedPageBytes(), before);
    EXPECT_TRUE(fromPrepared.bits == fresh.bits); // the grid stays with its taker
}

TEST(PreparedMemoryTest, DestroyingOrMovingAPreparationGivesItsMemoryBack) {
    const std::size_t before = detail::reservedPageBytes();
    {
        PreparedMemory a = prepareVoxelizeMemory(uint64_t(8) << 20);
        PreparedMemory b = prepareVoxelizeMemory(uint64_t(4) << 20);
        a.wait();
        b.wait();
        EXPECT_EQ(detail::reservedPageBytes() - before, uint64_t(12) << 20);
        a = std::move(b); // a's own memory is given back, b's now belongs to a
        EXPECT_EQ(detail::reservedPageBytes() - before, uint64_t(4) << 20);
        PreparedMemory none;
        none.wait();
        none.release();
    }
    EXPECT_EQ(detail::reservedPageBytes(), before);
    // Destroyed without a wait: the destructor waits for the worker first.
    { PreparedMemory c = prepareVoxelizeMemory(uint64_t(6) << 20); }
    EXPECT_EQ(detail::reservedPageBytes(), before);
}

} // namespace
} // namespace voxfx
