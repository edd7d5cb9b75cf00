// voxfx — the one parallel-for of the library (wraps TBB; nothing else names TBB).
//
// Results never depend on the thread count: bodies own disjoint output ranges, and reductions
// combine per-chunk values in a fixed order.
// Thread-safety: parallelFor and withThreads may be called from several threads and nest; the
// body must only write ranges it owns.
#pragma once

#include <cstdint>
#include <functional>

namespace voxfx {

/// Calls body(b, e) over disjoint sub-ranges covering [begin, end), in parallel where the range
/// holds more than `grain` items. Chunks are split at multiples of `grain` from `begin`, so the
/// chunking (not only the result) is independent of the thread count.
void parallelFor(int64_t begin, int64_t end, int64_t grain,
                 const std::function<void(int64_t, int64_t)>& body);

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
