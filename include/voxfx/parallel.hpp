// voxfx — the one parallel-for and the one reduction of the library (wrap TBB; nothing else names
// TBB).
//
// Results never depend on the thread count: bodies own disjoint output ranges, and parallelReduce
// combines per-chunk values in chunk order.
// Thread-safety: parallelFor, parallelReduce and withThreads may be called from several threads
// and nest; the body must only write ranges it owns.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <type_traits>

namespace voxfx {

namespace detail {
/// Runs run(context, cb, ce) over disjoint sub-ranges covering chunk indices [0, chunks), in
/// parallel (TBB, simple partitioner; kept out of this header).
void parallelChunks(int64_t chunks, void* context, void (*run)(void*, int64_t, int64_t));
/// Runs run(context, 0) and run(context, 1) concurrently (TBB's parallel_invoke).
void parallelPair(void* context, void (*run)(void*, int));
} // namespace detail

/// Calls body(b, e) over disjoint sub-ranges covering [begin, end), in parallel where the range
/// holds more than `grain` items. Chunks are split at multiples of `grain` from `begin`, so the
/// chunking (not only the result) is independent of the thread count. A template over the body:
/// the body is called directly (no std::function), through one function pointer per batch of
/// chunks that TBB hands a thread. Thread-safe: bodies run concurrently on disjoint ranges.
template <class Body> void parallelFor(int64_t begin, int64_t end, int64_t grain, Body&& body) {
    if (end <= begin) return;
    grain = std::max<int64_t>(grain, 1);
    const int64_t chunks = (end - begin + grain - 1) / grain;
    // Small inputs run serially: a task spawn costs more than the work.
    if (chunks == 1) {
        body(begin, end);
        return;
    }
    struct Context {
        std::remove_reference_t<Body>* body;
        int64_t begin, end, grain;
    } context{&body, begin, end, grain};
    detail::parallelChunks(chunks, &context, [](void* p, int64_t cb, int64_t ce) {
        const Context& c = *static_cast<const Context*>(p);
        for (int64_t k = cb; k < ce; ++k) {
            const int64_t b = c.begin + k * c.grain;
            (*c.body)(b, std::min(c.end, b + c.grain));
        }
    });
}

/// Runs a() and b() concurrently and returns when both have; each may use parallelFor inside. For
/// independent work of unequal kinds (an analysis beside a raster pass). Neither may throw: catch
/// inside and rethrow after the call.
template <class A, class B> void parallelInvoke(A&& a, B&& b) {
    struct Context {
        std::remove_reference_t<A>* a;
        std::remove_reference_t<B>* b;
    } context{&a, &b};
    detail::parallelPair(&context, [](void* p, int which) {
        const Context& c = *static_cast<const Context*>(p);
        if (which == 0)
            (*c.a)();
        else
            (*c.b)();
    });
}

/// Fixed-order reduction: splits [begin, end) into chunks at multiples of `grain` from `begin` (as
/// parallelFor does), computes v_k = body(b_k, e_k) for every chunk k in parallel, and returns
/// combine(...combine(combine(identity, v_0), v_1)..., v_last) with the chunks in order. The
/// chunking and the order of the combination do not depend on the thread count, so neither does
/// the result, floating-point sums included. T must be default-constructible and small: partial
/// values are kept on the stack, kReduceBlock chunks at a time (no allocation). combine(T, T) -> T
/// runs on the calling thread. A range of one chunk runs serially.
inline constexpr int64_t kReduceBlock = 256;
template <class T, class Body, class Combine>
T parallelReduce(int64_t begin, int64_t end, int64_t grain, T identity, Body&& body, Combine&& combine) {
    if (end <= begin) return identity;
    grain = std::max<int64_t>(grain, 1);
    const int64_t chunks = (end - begin + grain - 1) / grain;
    T result = std::move(identity);
    std::array<T, size_t(kReduceBlock)> partial{};
    for (int64_t c0 = 0; c0 < chunks; c0 += kReduceBlock) {
        const int64_t c1 = std::min(chunks, c0 + kReduceBlock);
        parallelFor(c0, c1, 1, [&](int64_t cb, int64_t ce) {
            for (int64_t c = cb; c < ce; ++c) {
                const int64_t b = begin + c * grain;
                partial[size_t(c - c0)] = body(b, std::min(end, b + grain));
            }
        });
        for (int64_t c = c0; c < c1; ++c) result = combine(std::move(result), partial[size_t(c - c0)]);
    }
    return result;
}

/// Runs f with at most `threads` worker threads (0 = all hardware threads).
void withThreads(int threads, const std::function<void()>& f);

/// Number of hardware threads.
int hardwareThreads();

/// Progress and cancellation, polled between tiles of long operations (the CLI prints it).
class Progress {
public:
    virtual ~Progress() = default;
    /// fraction in [0, 1]; return false to cancel (the operation then throws voxfx::Error).
    virtual bool update(double fraction) = 0;
};

/// The finished steps of a parallel loop, reported to a Progress as done / total. The count is
/// taken under the lock that guards the report, so the fractions a Progress sees only grow
/// whatever the thread count (counting first and locking after lets two threads report out of
/// order). Thread-safe; with a null Progress it only carries the cancelled flag.
class ProgressSteps {
public:
    ProgressSteps(Progress* progress, int64_t total)
        : progress_(progress), total_(std::max<int64_t>(total, 1)) {}
    /// One more step done; false once the Progress has asked to stop.
    bool step() {
        if (!progress_) return !cancelled();
        const std::lock_guard lock(mutex_);
        if (!cancelled_.load(std::memory_order_relaxed) &&
            !progress_->update(double(++done_) / double(total_)))
            cancelled_.store(true, std::memory_order_relaxed);
        return !cancelled();
    }
    /// Whether the Progress has asked to stop (workers poll this between steps).
    bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }

private:
    Progress* progress_;
    int64_t total_;
    int64_t done_ = 0; // under mutex_
    std::mutex mutex_;
    std::atomic<bool> cancelled_{false};
};

} // namespace voxfx
