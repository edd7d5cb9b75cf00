// parallelFor and parallelReduce (src/core/parallel.cpp): the reduction combines per-chunk values
// in chunk order, so its result (floating-point sums and order-sensitive combinations included)
// is the one a serial loop over the same chunks gives, for every thread count.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include "voxfx/parallel.hpp"

namespace voxfx {
namespace {

// Terms whose float sum depends on the order of the additions (large and tiny values mixed).
double term(int64_t i) { return (i % 7 == 0 ? 1e16 : 1.0) * (i % 2 ? -1.0 : 1.0) + 1e-3 * double(i % 13); }

double chunkSum(int64_t b, int64_t e) {
    double s = 0;
    for (int64_t i = b; i < e; ++i) s += term(i);
    return s;
}

TEST(ParallelTest, ReduceEqualsTheSerialSumOverTheSameChunksForEveryThreadCount) {
    const int64_t begin = 3, end = 3 + 1000003, grain = 997; // over kReduceBlock chunks, a short last one
    double serial = 0;
    for (int64_t b = begin; b < end; b += grain) serial += chunkSum(b, std::min(end, b + grain));
    double unchunked = 0;
    for (int64_t i = begin; i < end; ++i) unchunked += term(i);
    ASSERT_NE(serial, unchunked) << "the terms must make the order of the additions matter";
    for (const int threads : {1, 2, 3, 8}) {
        double got = -1;
        withThreads(threads, [&] { got = parallelReduce(begin, end, grain, 0.0, chunkSum, std::plus<>()); });
        EXPECT_EQ(got, serial) << threads << " threads";
    }
}

TEST(ParallelTest, ReduceCombinesChunksInOrder) {
    // An order-sensitive combination: the chunk starts read as digits of a number in base 1000.
    const int64_t grain = 10, end = 10 * 600;
    uint64_t expected = 0;
    for (int64_t b = 0; b < end; b += grain) expected = expected * 1000 + uint64_t(b / grain);
    for (const int threads : {1, 4}) {
        uint64_t got = 0;
        withThreads(threads, [&] {
            got = parallelReduce(
                0, end, grain, uint64_t(0), [&](int64_t b, int64_t) { return uint64_t(b / grain); },
                [](uint64_t acc, uint64_t v) { return acc * 1000 + v; });
        });
        EXPECT_EQ(got, expected) << threads << " threads";
    }
}

TEST(ParallelTest, ReduceOfAnEmptyRangeIsTheIdentityAndChunksCoverTheRangeOnce) {
    EXPECT_EQ(parallelReduce(
                  5, 5, 4, int64_t(42), [](int64_t, int64_t) { return int64_t(1); }, std::plus<>()),
              42);
    EXPECT_EQ(parallelReduce(
                  9, 2, 4, int64_t(42), [](int64_t, int64_t) { return int64_t(1); }, std::plus<>()),
              42);
    // Sum of i over [7, 100007) in chunks of any grain: n (first + last) / 2.
    for (const int64_t grain : {int64_t(1), int64_t(3), int64_t(4096), int64_t(1) << 20}) {
        const int64_t sum = parallelReduce(
            7, 100007, grain, int64_t(0),
            [](int64_t b, int64_t e) {
                int64_t s = 0;
                for (int64_t i = b; i < e; ++i) s += i;
                return s;
            },
            std::plus<>());
        EXPECT_EQ(sum, int64_t(100000) * (7 + 100006) / 2) << "grain " << grain;
    }
}

TEST(ParallelTest, ForCoversEveryIndexExactlyOnce) {
    std::vector<int> hits(100003, 0);
    parallelFor(0, int64_t(hits.size()), 101, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i) ++hits[size_t(i)];
    });
    for (size_t i = 0; i < hits.size(); ++i) ASSERT_EQ(hits[i], 1) << i;
}

struct Recorder final : Progress {
    std::vector<double> seen; // written under ProgressSteps' lock
    std::size_t stopAt = SIZE_MAX;
    bool update(double f) override {
        seen.push_back(f);
        return seen.size() < stopAt;
    }
};

TEST(ParallelTest, InvokeRunsBothBodiesOnceAndReturnsAfterBoth) {
    // Each body runs a parallelFor of its own (nesting), for every thread count; after the call
    // both have finished: every index of both ranges is covered exactly once.
    for (const int threads : {1, 2, 0}) {
        SCOPED_TRACE(threads);
        std::vector<std::atomic<int>> a(10000), b(777);
        std::atomic<int> calls{0};
        withThreads(threads, [&] {
            parallelInvoke(
                [&] {
                    ++calls;
                    parallelFor(0, int64_t(a.size()), 64, [&](int64_t s, int64_t e) {
                        for (int64_t i = s; i < e; ++i) ++a[size_t(i)];
                    });
                },
                [&] {
                    ++calls;
                    parallelFor(0, int64_t(b.size()), 10, [&](int64_t s, int64_t e) {
                        for (int64_t i = s; i < e; ++i) ++b[size_t(i)];
                    });
                });
        });
        EXPECT_EQ(calls.load(), 2);
        for (const auto& v : a) ASSERT_EQ(v.load(), 1);
        for (const auto& v : b) ASSERT_EQ(v.load(), 1);
    }
}

TEST(ParallelTest, ProgressStepsReportGrowingFractionsFromEveryThread) {
    // Steps finish on many threads at once; the fractions must still arrive in order (a count
    // taken outside the report's lock lets a later step report before an earlier one).
    for (int round = 0; round < 20; ++round) {
        Recorder r;
        constexpr int64_t kSteps = 5000;
        ProgressSteps steps(&r, kSteps);
        parallelFor(0, kSteps, 1, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) EXPECT_TRUE(steps.step());
        });
        ASSERT_EQ(r.seen.size(), std::size_t(kSteps));
        EXPECT_TRUE(std::is_sorted(r.seen.begin(), r.seen.end())) << round;
        EXPECT_DOUBLE_EQ(r.seen.back(), 1.0);
        EXPECT_FALSE(steps.cancelled());
    }
}

TEST(ParallelTest, ProgressStepsStopReportingOnceCancelled) {
    Recorder r;
    r.stopAt = 10;
    ProgressSteps steps(&r, 1000);
    std::atomic<int> falses{0};
    parallelFor(0, 1000, 1, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i)
            if (!steps.step()) ++falses;
    });
    EXPECT_TRUE(steps.cancelled());
    EXPECT_EQ(r.seen.size(), 10u); // nothing reported after the Progress said stop
    EXPECT_GT(falses, 0);
    ProgressSteps silent(nullptr, 5); // no Progress: steps never cancel
    for (int i = 0; i < 10; ++i) EXPECT_TRUE(silent.step());
}

} // namespace
} // namespace voxfx
