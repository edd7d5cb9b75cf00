// voxfx — BitGrid (the slicemap) against a brute-force model: one bool per cell.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/bitgrid.hpp"
#include "voxfx/error.hpp"

namespace voxfx {
namespace {

// The brute-force model: cells in (x, y, s) order, one byte each.
struct Model {
    int64_t w, h, d;
    std::vector<uint8_t> cells;
    Model(int64_t w_, int64_t h_, int64_t d_) : w(w_), h(h_), d(d_), cells(size_t(w * h * d), 0) {}
    uint8_t& at(int64_t x, int64_t y, int64_t s) { return cells[size_t((y * w + x) * d + s)]; }
    int64_t count() const {
        int64_t n = 0;
        for (uint8_t c : cells) n += c;
        return n;
    }
};

const int64_t kDepths[] = {1, 5, 63, 64, 65, 127, 128, 130};

TEST(BitGridTest, LayoutIsColumnsOfWholeWordsWithSliceSInBitSModulo64) {
    for (int64_t d : kDepths) {
        SCOPED_TRACE(d);
        BitGrid g(3, 2, d);
        EXPECT_EQ(g.wordsPerColumn(), (d + 63) / 64);
        EXPECT_EQ(g.wordCount(), 3 * 2 * g.wordsPerColumn());
        EXPECT_EQ(BitGrid::requiredBytes(3, 2, d), uint64_t(g.wordCount()) * 8);
        EXPECT_EQ(reinterpret_cast<uintptr_t>(g.words()) % 64, 0u);
        // Set one cell and find its bit by scanning all words.
        const int64_t x = 2, y = 1, s = d - 1;
        g.set(x, y, s);
        int64_t found = -1, setBits = 0;
        for (int64_t i = 0; i < g.wordCount(); ++i)
            for (int b = 0; b < 64; ++b)
                if ((g.words()[i] >> b) & 1u) {
                    found = i * 64 + b;
                    ++setBits;
                }
        EXPECT_EQ(setBits, 1);
        EXPECT_EQ(found, ((y * 3 + x) * g.wordsPerColumn()) * 64 + s);
        // The valid-bit mask of the last word: exactly the slices below D.
        const int valid = int(d - 64 * (g.wordsPerColumn() - 1));
        for (int b = 0; b < 64; ++b) EXPECT_EQ((g.lastWordMask() >> b) & 1u, b < valid ? 1u : 0u) << b;
    }
}

TEST(BitGridTest, SetGetAndCountAgreeWithABruteForceModelAndPaddingStaysZero) {
    std::mt19937_64 rng(7);
    for (int64_t d : kDepths) {
        SCOPED_TRACE(d);
        const int64_t w = 5, h = 4;
        BitGrid g(w, h, d);
        Model m(w, h, d);
        EXPECT_EQ(g.count(), 0);
        for (int step = 0; step < 400; ++step) {
            const int64_t x = int64_t(rng() % w), y = int64_t(rng() % h), s = int64_t(rng() % d);
            const bool on = rng() % 3 != 0;
            g.set(x, y, s, on);
            m.at(x, y, s) = on;
        }
        for (int64_t x = 0; x < w; ++x)
            for (int64_t y = 0; y < h; ++y)
                for (int64_t s = 0; s < d; ++s) ASSERT_EQ(g.get(x, y, s), bool(m.at(x, y, s)));
        EXPECT_EQ(g.count(), m.count());
        EXPECT_TRUE(test::paddingIsZero(g));
        // Every cell on: count is W * H * D, padding still zero.
        for (int64_t x = 0; x < w; ++x)
            for (int64_t y = 0; y < h; ++y)
                for (int64_t s = 0; s < d; ++s) g.set(x, y, s);
        EXPECT_EQ(g.count(), w * h * d);
        EXPECT_TRUE(test::paddingIsZero(g));
        g.clear();
        EXPECT_EQ(g.count(), 0);
    }
}

TEST(BitGridTest, CopiesAreDeepAndEqualityComparesDimensionsAndCells) {
    BitGrid a(4, 3, 70);
    a.set(1, 2, 69);
    a.set(0, 0, 0);
    BitGrid b = a;
    EXPECT_TRUE(b == a);
    EXPECT_NE(b.words(), a.words());
    b.set(3, 1, 5);
    EXPECT_FALSE(b == a);
    EXPECT_FALSE(a.get(3, 1, 5)) << "the copy shares storage";
    BitGrid c;
    c = b;
    EXPECT_TRUE(c == b);
    // Same cells (none) but other dimensions: not equal.
    EXPECT_FALSE(BitGrid(4, 3, 70) == BitGrid(3, 4, 70));
    EXPECT_FALSE(BitGrid(4, 3, 70) == BitGrid(4, 3, 71));
    EXPECT_TRUE(BitGrid(4, 3, 70) == BitGrid(4, 3, 70));
    // Empty grids.
    EXPECT_TRUE(BitGrid() == BitGrid());
    EXPECT_TRUE(BitGrid().empty());
    const BitGrid emptyCopy = BitGrid();
    EXPECT_TRUE(emptyCopy.empty());
    // Moves leave the source empty-handed but the target intact.
    BitGrid moved = std::move(c);
    EXPECT_TRUE(moved == b);
}

TEST(BitGridTest, LargeGridsAreMappedZeroedAndCountCorrectly) {
    // Above the mapping threshold (2 MiB) the buffer comes from mmap; it must read as zero.
    BitGrid g(256, 256, 512);
    EXPECT_GE(g.byteCount(), uint64_t(1) << 21);
    EXPECT_EQ(g.count(), 0);
    g.set(255, 255, 511);
    g.set(0, 0, 0);
    g.set(17, 200, 300);
    EXPECT_EQ(g.count(), 3);
    const BitGrid copy = g;
    EXPECT_TRUE(copy == g);
}

TEST(BitGridTest, BadDimensionsAndImpossibleSizesFailWithAnError) {
    EXPECT_THROW(BitGrid(0, 1, 1), Error);
    EXPECT_THROW(BitGrid(1, -1, 1), Error);
    EXPECT_THROW(BitGrid(1, 1, 0), Error);
    EXPECT_EQ(BitGrid::requiredBytes(0, 5, 5), 0u);
    // A grid larger than any machine: the byte count saturates instead of overflowing, and the
    // constructor fails the memory check with a message that says so.
    const int64_t huge = int64_t(1) << 40;
    EXPECT_EQ(BitGrid::requiredBytes(huge, huge, huge), ~uint64_t(0));
    try {
        BitGrid g(huge, huge, 64);
        FAIL() << "a 2^80-cell grid was allocated";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("memory"), std::string::npos) << e.what();
    }
    EXPECT_THROW(checkMemory(~uint64_t(0), "everything"), Error);
    EXPECT_NO_THROW(checkMemory(1, "one byte"));
    EXPECT_GT(availableMemoryBytes(), 0u);
}

TEST(BitGridTest, TheMemoryBudgetInTheEnvironmentCapsWhatMayBeAllocated) {
    const uint64_t machine = availableMemoryBytes();
    {
        test::ScopedEnv env("VOXFX_MEMORY_LIMIT", "1M");
        EXPECT_EQ(availableMemoryBytes(), uint64_t(1) << 20);
        // 256^3 cells = 2 MiB of words: over the budget, refused before allocating, and the
        // message names the budget.
        try {
            BitGrid g(256, 256, 256);
            FAIL() << "a 2 MiB grid was allocated under a 1 MiB budget";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("VOXFX_MEMORY_LIMIT"), std::string::npos) << e.what();
        }
        EXPECT_NO_THROW(BitGrid(64, 64, 64)); // 32 KiB
    }
    for (const auto& [text, bytes] : std::initializer_list<std::pair<const char*, uint64_t>>{
             {"4096", 4096}, {"2k", 2048}, {"3MiB", 3u << 20}, {"1.5G", 3u << 29}, {"1gb", 1u << 30}}) {
        test::ScopedEnv env("VOXFX_MEMORY_LIMIT", text);
        // The budget, or what the machine has when that is less.
        if (bytes < machine / 2) { EXPECT_EQ(availableMemoryBytes(), bytes) << text; }
    }
    for (const char* bad : {"lots", "-1M", "12Q", "1e30T", "nan", "5 M"}) {
        test::ScopedEnv env("VOXFX_MEMORY_LIMIT", bad);
        EXPECT_THROW(availableMemoryBytes(), Error) << bad;
    }
}

TEST(BitGridTest, AViewReadsAndWritesTheGridsWords) {
    static_assert(std::is_trivially_copyable_v<BitGridView>);
    for (int64_t d : kDepths) {
        SCOPED_TRACE(d);
        BitGrid g(3, 5, d);
        const BitGridView v = g.view();
        EXPECT_EQ(v.words, g.words());
        EXPECT_EQ(v.wordsPerColumn, g.wordsPerColumn());
        EXPECT_EQ(v.lastWordMask(), g.lastWordMask());
        EXPECT_EQ(v.column(2, 4), g.column(2, 4));
        v.set(2, 4, d - 1);
        v.set(0, 1, 0);
        EXPECT_TRUE(g.get(2, 4, d - 1));
        EXPECT_TRUE(g.get(0, 1, 0));
        EXPECT_EQ(g.count(), 2);
        g.set(1, 1, d / 2);
        EXPECT_TRUE(v.get(1, 1, d / 2));
        v.set(2, 4, d - 1, false);
        EXPECT_EQ(g.count(), 2);
        EXPECT_TRUE(test::paddingIsZero(g));
    }
}

} // namespace
} // namespace voxfx
