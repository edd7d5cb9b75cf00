// voxfx — the voxelization consumers of the fragment rasterizer (internal header).
//
//   SurfaceConsumer       ED06 §2: a centre fragment sets the bit of its slice (OR).
//   ConservativeConsumer  every slice whose closed extent meets the fragment's exact depth span.
//   ParityConsumer        GI08 §4: a fragment flips the first slice whose centre lies behind it;
//                         one prefix-XOR down each column then gives inside = odd crossings.
//   WindingConsumer       nonzero winding from signed (front +1 / back -1) crossings, sorted per
//                         column: the union of overlapping closed parts.
//   DepthRangeConsumer    ED06 fig. 2 first pass: nearest and farthest fragment per column.
// Each tile consumer writes only the columns of its own rows, so tiles run in parallel. The
// surface, conservative and parity consumers also offer the rasterizer's direct path (see
// raster.hpp): their writes are ORs and XORs, which commute, so the same bits result when any
// thread writes any column with atomic word operations in any order. The slicemap consumers hold
// plain views (FrameView, BitGridView) and their fragment/span kernels are VOXFX_HOSTDEV.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

#include "core/bitops.hpp"
#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/raster.hpp"

namespace voxfx::detail {

/// Index of the first slice whose centre (s + 0.5) lies strictly behind slice coordinate t,
/// clamped to [0, D]; D means "no slice behind". Geometry in front of the near plane gives 0
/// (GI08's depth clamping: it still flips every cell of the column).
VOXFX_HOSTDEV inline int64_t firstSliceBehind(double t, int64_t D) {
    const double u = t - 0.5;
    if (!(u >= 0)) return 0; // also catches -inf
    if (u >= double(D)) return D;
    return std::min<int64_t>(D, int64_t(std::floor(u)) + 1);
}

/// The slice that holds a centre fragment at frame depth `depth` in `column` (ED06: the cell of
/// the depth), or -1 when the depth lies outside the near/far range (clipped, as on the GPU).
VOXFX_HOSTDEV inline int64_t fragmentSlice(const FrameView& frame, int64_t column, double depth) {
    const double t = frame.depthToSlice(column)(depth);
    const int64_t D = frame.depth;
    if (!(t >= 0 && t <= double(D))) return -1;
    return std::min<int64_t>(int64_t(t), D - 1);
}

/// The slices [s0, s1] whose closed cells [s, s+1] meet a conservative span's depth range
/// [depthMin, depthMax] in `column`; false when none does. Widened by kConservativeSlack as in
/// the rasterizer, so a depth exactly on a slice boundary keeps both cells.
VOXFX_HOSTDEV inline bool spanSlices(const FrameView& frame, int64_t column, double depthMin, double depthMax,
                                     int64_t& s0, int64_t& s1) {
    const DepthToSlice m = frame.depthToSlice(column);
    const double t0 = m(depthMin) - kConservativeSlack, t1 = m(depthMax) + kConservativeSlack;
    const int64_t D = frame.depth;
    if (!(t1 >= 0 && t0 <= double(D))) return false;
    // Cells [s, s+1] meeting [t0, t1]: s from ceil(t0) - 1 to floor(t1).
    s0 = std::max<int64_t>(0, int64_t(std::ceil(std::max(t0, -1.0))) - 1);
    s1 = std::min<int64_t>(D - 1, int64_t(std::floor(std::min(t1, double(D)))));
    return s0 <= s1;
}

/// One word write: plain when the calling tile owns the column, atomic on the direct path.
template <bool Atomic> VOXFX_HOSTDEV inline void orWord(uint64_t& word, uint64_t bits) {
    if constexpr (Atomic) {
#ifdef __CUDA_ARCH__
        atomicOr(reinterpret_cast<unsigned long long*>(&word), static_cast<unsigned long long>(bits));
#else
        std::atomic_ref<uint64_t>(word).fetch_or(bits, std::memory_order_relaxed);
#endif
    } else {
        word |= bits;
    }
}
template <bool Atomic> VOXFX_HOSTDEV inline void xorWord(uint64_t& word, uint64_t bits) {
    if constexpr (Atomic) {
#ifdef __CUDA_ARCH__
        atomicXor(reinterpret_cast<unsigned long long*>(&word), static_cast<unsigned long long>(bits));
#else
        std::atomic_ref<uint64_t>(word).fetch_xor(bits, std::memory_order_relaxed);
#endif
    } else {
        word ^= bits;
    }
}

/// Sets slices [s0, s1] (inclusive, within [0, D)) of a column.
template <bool Atomic = false>
VOXFX_HOSTDEV inline void setSliceRange(uint64_t* column, int64_t s0, int64_t s1) {
    const int64_t w0 = s0 >> 6, w1 = s1 >> 6;
    if (w0 == w1) {
        orWord<Atomic>(column[w0], bitRange(int(s0 & 63), int(s1 & 63) + 1));
        return;
    }
    orWord<Atomic>(column[w0], bitRange(int(s0 & 63), 64));
    for (int64_t w = w0 + 1; w < w1; ++w) orWord<Atomic>(column[w], ~uint64_t(0));
    orWord<Atomic>(column[w1], bitRange(0, int(s1 & 63) + 1));
}

/// Prefix XOR along n words of a column, word 0 first, starting from `carry` (all ones when the
/// parity in front of the column is odd; 0 otherwise); returns the carry out. A word without a
/// set bit takes the carry as it is (prefixXor(0) ^ carry == carry): most words of a solid
/// grid hold no crossing, so only the words with one pay for the in-word prefix.
VOXFX_HOSTDEV inline uint64_t prefixXorWords(uint64_t* col, int64_t n, uint64_t carry) {
    for (int64_t w = 0; w < n; ++w) {
        const uint64_t x = col[w];
        if (x == 0) {
            col[w] = carry;
            continue;
        }
        const uint64_t v = prefixXor(x) ^ carry;
        col[w] = v;
        carry = uint64_t(0) - (v >> 63);
    }
    return carry;
}

/// Prefix-XOR every column of rows [y0, y1): bit s becomes the XOR of bits 0..s of the column.
/// A column's words lie one after the other and the rows' columns too, so blocks of columns
/// without a crossing (most of a grid: the columns beside the solid) are found by one OR over
/// their words and left as they are (zero stays zero); a column with a crossing starts at its
/// first non-zero word (the zero words in front of it stay zero: the carry there is 0).
VOXFX_HOSTDEV inline void prefixXorRows(const BitGridView& grid, int64_t y0, int64_t y1) {
    constexpr int64_t kBlock = 8; // columns per OR test
    const int64_t wpc = grid.wordsPerColumn;
    const uint64_t lastMask = grid.lastWordMask();
    const int64_t e = y1 * grid.width;
    for (int64_t c = y0 * grid.width; c < e;) {
        if (c + kBlock <= e) {
            const uint64_t* block = grid.column(c);
            uint64_t any = 0;
            for (int64_t w = 0; w < kBlock * wpc; ++w) any |= block[w];
            if (any == 0) {
                c += kBlock;
                continue;
            }
        }
        for (const int64_t end = std::min(e, c + kBlock); c < end; ++c) {
            uint64_t* col = grid.column(c);
            int64_t w = 0;
            while (w < wpc && col[w] == 0) ++w;
            if (w == wpc) continue;
            prefixXorWords(col + w, wpc - w, 0);
            col[wpc - 1] &= lastMask;
        }
    }
}

struct SurfaceConsumer {
    FrameView frame;
    BitGridView grid;
    template <bool Atomic> struct Sink {
        FrameView frame;
        BitGridView grid;
        VOXFX_HOSTDEV void fragment(int64_t x, int64_t y, double depth, uint32_t, bool) {
            const int64_t c = y * grid.width + x;
            const int64_t s = fragmentSlice(frame, c, depth);
            if (s >= 0) orWord<Atomic>(grid.column(c)[s >> 6], uint64_t(1) << (s & 63));
        }
        void finish() {}
    };
    Sink<false> tile(const Tile&) const { return {frame, grid}; }
    Sink<true> direct() const { return {frame, grid}; }
    void finishRows(const Tile&) const {}
};

struct ConservativeConsumer {
    FrameView frame;
    BitGridView grid;
    template <bool Atomic> struct Sink {
        FrameView frame;
        BitGridView grid;
        VOXFX_HOSTDEV void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t) {
            const int64_t c = y * grid.width + x;
            int64_t s0, s1;
            if (spanSlices(frame, c, depthMin, depthMax, s0, s1))
                setSliceRange<Atomic>(grid.column(c), s0, s1);
        }
        void finish() {}
    };
    Sink<false> tile(const Tile&) const { return {frame, grid}; }
    Sink<true> direct() const { return {frame, grid}; }
    void finishRows(const Tile&) const {}
};

struct ParityConsumer {
    FrameView frame;
    BitGridView grid;
    template <bool Atomic> struct Sink {
        FrameView frame;
        BitGridView grid;
        Tile rows;
        VOXFX_HOSTDEV void fragment(int64_t x, int64_t y, double depth, uint32_t, bool) {
            const int64_t c = y * grid.width + x;
            const int64_t s = firstSliceBehind(frame.depthToSlice(c)(depth), grid.depth);
            if (s < grid.depth) xorWord<Atomic>(grid.column(c)[s >> 6], uint64_t(1) << (s & 63));
        }
        void finish() {
            if constexpr (!Atomic) prefixXorRows(grid, rows.y0, rows.y1);
        }
    };
    Sink<false> tile(const Tile& t) const { return {frame, grid, t}; }
    Sink<true> direct() const { return {frame, grid, {}}; }
    void finishRows(const Tile& t) const { prefixXorRows(grid, t.y0, t.y1); }
};

struct WindingConsumer {
    FrameView frame;
    BitGridView grid;
    struct Crossing {
        int64_t column;
        int64_t slice; // first slice behind the crossing
        int sign;      // +1 entering (front face), -1 leaving (back face)
        bool operator<(const Crossing& o) const {
            return column != o.column ? column < o.column : slice < o.slice;
        }
    };
    struct Sink {
        FrameView frame;
        BitGridView grid;
        std::vector<Crossing> crossings;
        void fragment(int64_t x, int64_t y, double depth, uint32_t, bool front) {
            const int64_t c = y * grid.width + x;
            const int64_t s = firstSliceBehind(frame.depthToSlice(c)(depth), grid.depth);
            if (s < grid.depth) crossings.push_back({c, s, front ? 1 : -1});
        }
        void finish() {
            // Sort once per tile (deterministic: equal keys carry equal effects, order is irrelevant).
            std::sort(crossings.begin(), crossings.end());
            for (std::size_t i = 0; i < crossings.size();) {
                const int64_t c = crossings[i].column;
                int winding = 0;
                while (i < crossings.size() && crossings[i].column == c) {
                    const int64_t s = crossings[i].slice;
                    while (i < crossings.size() && crossings[i].column == c && crossings[i].slice == s)
                        winding += crossings[i++].sign;
                    const int64_t next =
                        i < crossings.size() && crossings[i].column == c ? crossings[i].slice : grid.depth;
                    if (winding != 0 && next > s) setSliceRange(grid.column(c), s, next - 1);
                }
            }
        }
    };
    Sink tile(const Tile&) const { return {frame, grid, {}}; }
};

struct DepthRangeConsumer {
    int64_t width;
    std::vector<double>& nearDepth;
    std::vector<double>& farDepth;
    struct Sink {
        int64_t width;
        std::vector<double>& nearDepth;
        std::vector<double>& farDepth;
        void fragment(int64_t x, int64_t y, double depth, uint32_t, bool) { span(x, y, depth, depth, 0); }
        void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t) {
            const auto c = size_t(y * width + x);
            nearDepth[c] = std::min(nearDepth[c], depthMin);
            farDepth[c] = std::max(farDepth[c], depthMax);
        }
        void finish() {}
    };
    Sink tile(const Tile&) const { return {width, nearDepth, farDepth}; }
};

} // namespace voxfx::detail
