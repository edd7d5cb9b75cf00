#include "voxfx/parallel.hpp"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace voxfx {

void parallelFor(int64_t begin, int64_t end, int64_t grain,
                 const std::function<void(int64_t, int64_t)>& body) {
    if (end <= begin) return;
    grain = std::max<int64_t>(grain, 1);
    const int64_t chunks = (end - begin + grain - 1) / grain;
    // Small inputs run serially: a task spawn costs more than the work.
    if (chunks == 1) {
        body(begin, end);
        return;
    }
    // Chunks are fixed by `grain` (simple_partitioner over chunk indices), so which items share a
    // body call does not depend on the number of threads.
    tbb::parallel_for(
        tbb::blocked_range<int64_t>(0, chunks, 1),
        [&](const tbb::blocked_range<int64_t>& r) {
            for (int64_t c = r.begin(); c != r.end(); ++c) {
                const int64_t b = begin + c * grain;
                body(b, std::min(end, b + grain));
            }
        },
        tbb::simple_partitioner());
}

void withThreads(int threads, const std::function<void()>& f) {
    if (threads <= 0) {
        f();
        return;
    }
    // More threads than cores only adds contention (and TBB warns about it).
    tbb::task_arena arena(std::min(threads, hardwareThreads()));
    arena.execute(f);
}

int hardwareThreads() { return tbb::info::default_concurrency(); }

} // namespace voxfx
