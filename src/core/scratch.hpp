// voxfx — scratch vectors kept between calls (internal header).
//
// The voxelize step's temporaries (projected vertices, tile bins, the closed-mesh test's tables:
// a few MiB at 512^3) are large enough that the allocator maps them fresh on every call, and a
// fresh page costs a fault on first touch (on virtual machines the faults were 10-20 % of a
// call in the profile of #39). The vectors are PageVectors (huge pages from the first call on:
// page_memory.hpp). Scratch<T>::take() hands out a vector that an earlier call gave
// back (empty, its capacity kept), give() keeps a vector's memory for the next call. The pool
// is process-wide and locked, so concurrent calls each get their own vectors; it keeps a few
// vectors of at most kMaxBytes each, so a huge mesh does not pin its memory.
#pragma once

#include <cstddef>
#include <iterator>
#include <mutex>
#include <utility>
#include <vector>

#include "voxfx/page_memory.hpp"

namespace voxfx::detail {

template <class T> class Scratch {
public:
    static constexpr std::size_t kMaxBytes = std::size_t(64) << 20;
    static constexpr std::size_t kMaxKept = 8;

    /// An empty vector, with the memory of one given back earlier when there is one: the
    /// smallest that holds `size` elements, else the largest (which then grows).
    static PageVector<T> take(std::size_t size) {
        PageVector<T> v;
        std::lock_guard<std::mutex> lock(state().mutex);
        auto& kept = state().kept;
        std::size_t best = kept.size();
        for (std::size_t i = 0; i < kept.size(); ++i) {
            const std::size_t c = kept[i].capacity();
            const bool fits = c >= size;
            if (best == kept.size()) {
                best = i;
                continue;
            }
            const std::size_t b = kept[best].capacity();
            if (fits ? (b < size || c < b) : (b < size && c > b)) best = i;
        }
        if (best < kept.size()) {
            v = std::move(kept[best]);
            kept.erase(kept.begin() + std::ptrdiff_t(best));
        }
        v.clear();
        return v;
    }
    /// Keeps v's memory for a later take() (drops it when too large or enough are kept).
    static void give(PageVector<T>&& v) {
        if (v.capacity() == 0 || v.capacity() * sizeof(T) > kMaxBytes) return;
        PageVector<T> mine = std::move(v);
        std::lock_guard<std::mutex> lock(state().mutex);
        if (state().kept.size() < kMaxKept) state().kept.push_back(std::move(mine));
    }

private:
    struct State {
        std::mutex mutex;
        std::vector<PageVector<T>> kept;
    };
    static State& state() {
        static State s;
        return s;
    }
};

} // namespace voxfx::detail
