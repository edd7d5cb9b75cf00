#include "voxfx/parallel.hpp"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

namespace voxfx {

namespace detail {

void parallelChunks(int64_t chunks, void* context, void (*run)(void*, int64_t, int64_t)) {
    // Chunks are fixed by the caller's grain (simple_partitioner over chunk indices), so which
    // items share a body call does not depend on the number of threads.
    tbb::parallel_for(
        tbb::blocked_range<int64_t>(0, chunks, 1),
        [&](const tbb::blocked_range<int64_t>& r) { run(context, r.begin(), r.end()); },
        tbb::simple_partitioner());
}

void parallelPair(void* context, void (*run)(void*, int)) {
    tbb::parallel_invoke([&] { run(context, 0); }, [&] { run(context, 1); });
}

} // namespace detail

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
