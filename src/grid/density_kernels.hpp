// voxfx — the density map's word kernels (internal; GI08 §6): the words of one output column of
// a density level from the words of its 2 x 2 input column block, bit-parallel (SWAR).
//
// They are VOXFX_HOSTDEV and free of loops over columns and of allocation, so that density.cpp
// (scalar and AVX2 paths over rows of columns) and a device back end (one thread per output
// column and input word) compute the same words from the same code; density.hpp's file comment
// gives the layout they read and write.
#pragma once

#include <cstdint>

#include "voxfx/error.hpp"

namespace voxfx::detail {

inline constexpr uint64_t kDensityBits01 = 0x5555555555555555ull;   // bit 0 of every 2-bit lane
inline constexpr uint64_t kDensityNibble01 = 0x3333333333333333ull; // low 2 bits of every 4-bit lane

/// Mask of the even b-bit lanes (the low half of every 2b-bit lane), b = 4, 8, 16, 32.
VOXFX_HOSTDEV constexpr uint64_t densityEvenLanes(int b) {
    uint64_t m = 0;
    for (int i = 0; i < 64; i += 2 * b) m |= ((uint64_t(1) << b) - 1) << i;
    return m;
}

/// Spreads the 8 nibbles of a 32-bit value to the low nibbles of the 8 bytes of a word:
///   x      = n7 n6 n5 n4 n3 n2 n1 n0                       (32 bits)
///   result = 0 n7 0 n6 0 n5 0 n4 0 n3 0 n2 0 n1 0 n0       (64 bits, one nibble per byte)
VOXFX_HOSTDEV inline uint64_t spreadNibbles(uint64_t x) {
    x = (x | (x << 16)) & 0x0000FFFF0000FFFFull; // n7..n4 move to bits 32..47
    x = (x | (x << 8)) & 0x00FF00FF00FF00FFull;  // one nibble pair per 16 bits
    x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0Full;  // one nibble per byte
    return x;
}

/// The 2 x 2 columns (2X, 2Y) .. (2X+1, 2Y+1) of a grid of W x H columns of P words that feed
/// output column (X, Y). A missing neighbour column (odd W or H) reads as the first column, with
/// its words masked to zero by its `keep` mask, so the loops over words stay branch-free.
struct DensityColumnBlock {
    const uint64_t* col[4];
    uint64_t keep[4];
    VOXFX_HOSTDEV DensityColumnBlock(const uint64_t* words, int64_t W, int64_t H, int64_t P, int64_t X,
                                     int64_t Y) {
        const int64_t x0 = 2 * X, y0 = 2 * Y;
        const bool hasX1 = x0 + 1 < W, hasY1 = y0 + 1 < H;
        const uint64_t* c00 = words + (y0 * W + x0) * P;
        col[0] = c00;
        col[1] = hasX1 ? c00 + P : c00;
        col[2] = hasY1 ? c00 + W * P : c00;
        col[3] = hasX1 && hasY1 ? c00 + (W + 1) * P : c00;
        keep[0] = ~uint64_t(0);
        keep[1] = hasX1 ? ~uint64_t(0) : 0;
        keep[2] = hasY1 ? ~uint64_t(0) : 0;
        keep[3] = hasX1 && hasY1 ? ~uint64_t(0) : 0;
    }
    VOXFX_HOSTDEV uint64_t word(int i, int64_t k) const { return col[i][k] & keep[i]; }
};

/// Level 1 from bits: output words 2k and 2k + 1 (cells 32k .. 32k + 31, 4-bit lanes) from input
/// word k (fine slices 64k .. 64k + 63) of the four columns of the block:
///   w            = ... s5 s4 s3 s2 s1 s0                     (one bit per fine slice)
///   p = (w & 0101..) + ((w >> 1) & 0101..)                   2-bit lanes: s2j + s2j+1 = pair j
///   even = p & 0011..,  odd = (p >> 2) & 0011..               4-bit lanes: pairs 2i and 2i + 1
///   E = sum of the four columns' even, O = sum of odd         nibble i <= 8, no spill
/// and the output nibbles are E and O interleaved: cell 2i from E nibble i, 2i+1 from O nibble i.
/// When 2k + 1 is past the output column (the last input word of a column whose output has an
/// odd word count) `hi` holds only padding cells and is zero; the caller does not store it.
VOXFX_HOSTDEV inline void densityLevel1Words(const DensityColumnBlock& blk, int64_t k, uint64_t& lo,
                                             uint64_t& hi) {
    uint64_t E = 0, O = 0;
    for (int i = 0; i < 4; ++i) {
        const uint64_t w = blk.word(i, k);
        const uint64_t p = (w & kDensityBits01) + ((w >> 1) & kDensityBits01);
        E += p & kDensityNibble01;
        O += (p >> 2) & kDensityNibble01;
    }
    lo = spreadNibbles(E & 0xFFFFFFFFull) | (spreadNibbles(O & 0xFFFFFFFFull) << 4);
    hi = spreadNibbles(E >> 32) | (spreadNibbles(O >> 32) << 4);
}

/// Level L+1 from level L (b-bit lanes in, 2b-bit lanes out; `even` = densityEvenLanes(b)):
/// output word k from input word k of the block. Pairs of neighbouring lanes along the column add
/// into one lane of twice the width, which keeps cell order inside the word:
///   w = ... c3 c2 c1 c0          (b-bit lanes)
///   (w & even) + ((w >> b) & even) = ... (c3 + c2) (c1 + c0)   (2b-bit lanes)
/// and the four columns of the 2x2 block add lane-wise (8^(L+1) < 2^(2b), no spill).
VOXFX_HOSTDEV inline uint64_t densityCoarsenWord(const DensityColumnBlock& blk, int64_t k, int b,
                                                 uint64_t even) {
    uint64_t sum = 0;
    for (int i = 0; i < 4; ++i) {
        const uint64_t w = blk.word(i, k);
        sum += (w & even) + ((w >> b) & even);
    }
    return sum;
}

} // namespace voxfx::detail
