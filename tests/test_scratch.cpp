// The scratch vectors kept between calls (core/scratch.hpp): what take() hands out.
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/scratch.hpp"

namespace voxfx::detail {
namespace {

// A type of its own, so that no other user of the pool hands vectors in between.
struct Probe {
    int64_t a, b;
};

// Empties the pool of Probe vectors (what an earlier test left there).
void drain() {
    for (std::size_t i = 0; i <= Scratch<Probe>::kMaxKept; ++i) (void)Scratch<Probe>::take(0);
}

TEST(ScratchTest, TakeHandsBackTheMemoryOfAVectorGivenBackEmpty) {
    drain();
    PageVector<Probe> v = Scratch<Probe>::take(1000);
    v.resize(1000, Probe{7, 7});
    const Probe* memory = v.data();
    Scratch<Probe>::give(std::move(v));
    PageVector<Probe> again = Scratch<Probe>::take(500);
    EXPECT_TRUE(again.empty());
    EXPECT_EQ(again.data(), memory);
    EXPECT_GE(again.capacity(), 1000u);
    Scratch<Probe>::give(std::move(again));
}

TEST(ScratchTest, TakePicksTheSmallestThatFitsElseTheLargest) {
    drain();
    PageVector<Probe> small = Scratch<Probe>::take(0), large = Scratch<Probe>::take(0);
    small.reserve(100);
    large.reserve(10000);
    const Probe *smallMemory = small.data(), *largeMemory = large.data();
    Scratch<Probe>::give(std::move(large));
    Scratch<Probe>::give(std::move(small));
    PageVector<Probe> a = Scratch<Probe>::take(50);      // both fit: the smaller
    PageVector<Probe> b = Scratch<Probe>::take(1000000); // none left that fits: the one left
    EXPECT_EQ(a.data(), smallMemory);
    EXPECT_EQ(b.data(), largeMemory);
    Scratch<Probe>::give(std::move(a));
    Scratch<Probe>::give(std::move(b));
    PageVector<Probe> c = Scratch<Probe>::take(1000000); // neither fits: the larger, to grow
    EXPECT_EQ(c.data(), largeMemory);
    Scratch<Probe>::give(std::move(c));
}

TEST(ScratchTest, ConcurrentCallsNeverShareAVector) {
    constexpr int kThreads = 4, kRounds = 2000;
    std::vector<std::thread> threads;
    std::vector<int> bad(kThreads, 0);
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back([t, &bad] {
            for (int r = 0; r < kRounds; ++r) {
                PageVector<Probe> v = Scratch<Probe>::take(64);
                v.assign(64, Probe{t, r});
                for (const Probe& p : v) bad[size_t(t)] += p.a != t || p.b != r;
                Scratch<Probe>::give(std::move(v));
            }
        });
    for (std::thread& th : threads) th.join();
    for (int t = 0; t < kThreads; ++t) EXPECT_EQ(bad[size_t(t)], 0) << "thread " << t;
}

} // namespace
} // namespace voxfx::detail
