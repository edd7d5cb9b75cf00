// Memory for large temporaries in whole huge pages (voxfx/page_memory.hpp): what mapPages hands
// out and what a PageVector keeps when it grows across the mapping threshold.
#include <cstddef>
#include <cstdint>
#include <numeric>

#include <gtest/gtest.h>

#include "voxfx/page_memory.hpp"

namespace voxfx::detail {
namespace {

constexpr std::size_t kTwoMiB = std::size_t(1) << 21;

TEST(PageMemoryTest, MappedBlocksAreZeroWritableAndAlignedToHugePages) {
    for (const std::size_t bytes :
         {kPageBlockBytes, kTwoMiB - 1, kTwoMiB, kTwoMiB + 1, 5 * kTwoMiB + 12345}) {
        auto* p = static_cast<unsigned char*>(mapPages(bytes));
        ASSERT_NE(p, nullptr);
        EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % kTwoMiB, 0u) << bytes << " bytes";
        // Zero where touched first, at both ends and across the 2 MiB boundaries.
        for (std::size_t i = 0; i < bytes; i += 4093) ASSERT_EQ(p[i], 0) << "byte " << i << " of " << bytes;
        EXPECT_EQ(p[bytes - 1], 0);
        for (std::size_t i = 0; i < bytes; i += 4093) p[i] = static_cast<unsigned char>(i * 7 + 1);
        p[bytes - 1] = 0xAB;
        for (std::size_t i = 0; i < bytes - 1; i += 4093)
            ASSERT_EQ(p[i], static_cast<unsigned char>(i * 7 + 1));
        EXPECT_EQ(p[bytes - 1], 0xAB);
        unmapPages(p, bytes);
    }
}

TEST(PageMemoryTest, TwoBlocksDoNotOverlap) {
    const std::size_t bytes = 3 * kTwoMiB / 2;
    auto* a = static_cast<unsigned char*>(mapPages(bytes));
    auto* b = static_cast<unsigned char*>(mapPages(bytes));
    EXPECT_TRUE(a + bytes <= b || b + bytes <= a);
    a[bytes - 1] = 1;
    b[0] = 2;
    EXPECT_EQ(a[bytes - 1], 1);
    EXPECT_EQ(b[0], 2);
    unmapPages(a, bytes);
    unmapPages(b, bytes);
}

TEST(PageMemoryTest, VectorKeepsItsElementsWhenItGrowsAcrossTheThreshold) {
    // From the heap (small) into mapped blocks (large) and between mapped blocks.
    PageVector<uint64_t> v;
    const std::size_t n = 3 * kTwoMiB / sizeof(uint64_t);
    for (std::size_t i = 0; i < n; ++i) v.push_back(i * 2654435761u);
    ASSERT_EQ(v.size(), n);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(v[i], i * 2654435761u) << "element " << i;
    PageVector<uint64_t> copy = v;
    EXPECT_EQ(copy, v);
    v.resize(10);
    v.shrink_to_fit(); // back to the heap
    EXPECT_EQ(v.size(), 10u);
    EXPECT_EQ(std::accumulate(v.begin(), v.end(), uint64_t(0)), uint64_t(45) * 2654435761u);
}

} // namespace
} // namespace voxfx::detail
