// voxfx — BitGrid: the slicemap (ED06 §2), one bit per cell.
//
// Layout (the only one; CPU and CUDA back ends share it):
//
//   words:  [ column 0 | column 1 | ... | column W*H-1 ]      column c = y * W + x (row-major)
//   column: [ word 0 | word 1 | ... | word P-1 ]              P = wordsPerColumn = ceil(D / 64)
//   word k: bit b (value 1 << b) is slice s = 64 * k + b      slice 0 in bit 0 of word 0
//
//   column (x, y), D = 100:
//     word 0: s63 ................................ s1 s0    (bit 63 ... bit 0)
//     word 1: [27 padding bits, always 0] s99 ...... s65 s64
//
// Padding bits (slices >= D in the last word) are always zero: every operation keeps them so,
// which lets whole-word popcounts and comparisons ignore D. The buffer is 64-byte aligned and
// holds no pointers, so it can be uploaded to a GPU unchanged. All index arithmetic is 64-bit.
//
// Kernels see a grid through BitGridView (words pointer and dimensions, no ownership, no
// allocation or exceptions), obtained with grid.view().
//
// Thread-safety: const members may be called concurrently. Writes (set, clear, assignment,
// writes through words()/column()/view()) must not race with other accesses to the same words;
// different columns are different words, so threads that own disjoint columns may write at
// once (the rasterizer's tiles do), and concurrent writes to one word need atomic operations
// (std::atomic_ref, as the rasterizer's direct path does). count() and clear() run in parallel
// internally and must not overlap writes.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "voxfx/error.hpp"

namespace voxfx {

/// A BitGrid as kernels see it: the words and the dimensions, trivially copyable, not owning.
/// Valid while the grid lives and is not reassigned.
struct BitGridView {
    uint64_t* words = nullptr;
    int64_t width = 0, height = 0, depth = 0, wordsPerColumn = 0;

    VOXFX_HOSTDEV uint64_t* column(int64_t c) const { return words + c * wordsPerColumn; }
    VOXFX_HOSTDEV uint64_t* column(int64_t x, int64_t y) const { return column(y * width + x); }
    VOXFX_HOSTDEV int64_t columnCount() const { return width * height; }
    /// Mask of the valid bits of the last word of a column (all ones when D % 64 == 0).
    VOXFX_HOSTDEV uint64_t lastWordMask() const {
        return (depth & 63) ? (~uint64_t(0) >> (64 - (depth & 63))) : ~uint64_t(0);
    }
    VOXFX_HOSTDEV bool get(int64_t x, int64_t y, int64_t s) const {
        return (column(x, y)[s >> 6] >> (s & 63)) & 1u;
    }
    VOXFX_HOSTDEV void set(int64_t x, int64_t y, int64_t s, bool on = true) const {
        uint64_t& word = column(x, y)[s >> 6];
        const uint64_t bit = uint64_t(1) << (s & 63);
        word = on ? (word | bit) : (word & ~bit);
    }
};

class BitGrid {
public:
    BitGrid() = default;
    /// A zeroed W x H x D grid. Throws voxfx::Error when a dimension is <= 0 or the grid needs
    /// more memory than the machine has available (the message says how much it needed).
    BitGrid(int64_t w, int64_t h, int64_t d);
    BitGrid(const BitGrid& o);
    BitGrid& operator=(const BitGrid& o);
    BitGrid(BitGrid&&) noexcept = default;
    BitGrid& operator=(BitGrid&&) noexcept = default;

    /// Bytes a W x H x D grid occupies (without checking anything).
    static uint64_t requiredBytes(int64_t w, int64_t h, int64_t d);

    int64_t width() const { return w_; }
    int64_t height() const { return h_; }
    int64_t depth() const { return d_; }
    int64_t wordsPerColumn() const { return wpc_; }
    int64_t columnCount() const { return w_ * h_; }
    int64_t wordCount() const { return w_ * h_ * wpc_; }
    uint64_t byteCount() const { return uint64_t(wordCount()) * 8; }
    bool empty() const { return wordCount() == 0; }

    uint64_t* words() { return words_.get(); }
    const uint64_t* words() const { return words_.get(); }
    uint64_t* column(int64_t c) { return words_.get() + c * wpc_; }
    const uint64_t* column(int64_t c) const { return words_.get() + c * wpc_; }
    uint64_t* column(int64_t x, int64_t y) { return column(y * w_ + x); }
    const uint64_t* column(int64_t x, int64_t y) const { return column(y * w_ + x); }

    /// Mask of the valid bits of the last word of a column (all ones when D % 64 == 0).
    uint64_t lastWordMask() const { return (d_ & 63) ? (~uint64_t(0) >> (64 - (d_ & 63))) : ~uint64_t(0); }
    /// The grid as kernels see it.
    BitGridView view() { return {words_.get(), w_, h_, d_, wpc_}; }

    bool get(int64_t x, int64_t y, int64_t s) const {
        VOXFX_DCHECK(x >= 0 && x < w_ && y >= 0 && y < h_ && s >= 0 && s < d_);
        return (column(x, y)[s >> 6] >> (s & 63)) & 1u;
    }
    void set(int64_t x, int64_t y, int64_t s, bool on = true) {
        VOXFX_DCHECK(x >= 0 && x < w_ && y >= 0 && y < h_ && s >= 0 && s < d_);
        uint64_t& word = column(x, y)[s >> 6];
        const uint64_t bit = uint64_t(1) << (s & 63);
        word = on ? (word | bit) : (word & ~bit);
    }

    /// Number of set cells (popcount of all words; padding is zero).
    int64_t count() const;
    /// Sets every cell to zero.
    void clear();
    bool operator==(const BitGrid& o) const;

private:
    // Large grids are mapped directly (zero pages from the kernel, transparent huge pages
    // requested), small ones come from the heap; the deleter remembers which.
    struct Free {
        uint64_t mappedBytes; // value-initialized to 0 (heap) by unique_ptr
        void operator()(uint64_t* p) const;
    };
    int64_t w_ = 0, h_ = 0, d_ = 0, wpc_ = 0;
    std::unique_ptr<uint64_t[], Free> words_;
};

/// Bytes of memory the machine can still hand out (MemAvailable), for up-front size checks; at
/// most the budget in the environment variable VOXFX_MEMORY_LIMIT when it is set (bytes, or with
/// a K, M, G or T suffix in powers of 1024: "512M"), so that a service reading untrusted files
/// can cap what any one file may make voxfx allocate. A malformed value is an Error.
uint64_t availableMemoryBytes();
/// Throws voxfx::Error("<what> needs X GiB, but only Y GiB of memory is available") when
/// `bytes` exceeds what is available.
void checkMemory(uint64_t bytes, const char* what);

} // namespace voxfx
