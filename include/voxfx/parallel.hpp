// voxfx — the one parallel-for of the library (wraps TBB; nothing else names TBB).
//
// Results never depend on the thread count: bodies own disjoint output ranges, and reductions
// combine per-chunk values in a fixed order.
// Thread-safety: parallelFor and withThreads may be called from several threads and nest; the
// body must only write ranges it owns.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <type_traits>

namespace voxfx {

namespace detail {
/// Runs run(context, cb, ce) over disjoint sub-ranges covering chunk indices [0, chunks), in
/// parallel (TBB, simple partitioner; kept out of this header).
void parallelChunks(int64_t chunks, void* context, void (*run)(void*, int64_t, int64_t));
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

} // namespace voxfx
