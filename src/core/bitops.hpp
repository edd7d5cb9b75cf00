// voxfx — word-level bit operations shared by the grid kernels (internal header).
#pragma once

#include <bit>
#include <cstdint>

#include "voxfx/error.hpp"

namespace voxfx::detail {

/// Prefix XOR inside a word: bit b of the result is the XOR of bits 0..b of x.
///   x      = 0 0 1 0 0 1 0 0   (bits 7..0)
///   result = 1 1 1 0 0 0 0 0   -> bits between the two set bits (inclusive of the lower) are on
VOXFX_HOSTDEV inline uint64_t prefixXor(uint64_t x) {
    x ^= x << 1;
    x ^= x << 2;
    x ^= x << 4;
    x ^= x << 8;
    x ^= x << 16;
    x ^= x << 32;
    return x;
}

/// Mask of bits [lo, hi) of a word, 0 <= lo <= hi <= 64.
VOXFX_HOSTDEV inline uint64_t bitRange(int lo, int hi) {
    const uint64_t upper = hi >= 64 ? ~uint64_t(0) : ((uint64_t(1) << hi) - 1);
    const uint64_t lower = lo >= 64 ? ~uint64_t(0) : ((uint64_t(1) << lo) - 1);
    return upper & ~lower;
}

/// Transposes a 64 x 64 bit matrix in place: bit j of a[i] <-> bit i of a[j].
/// Recursive block swap (Hacker's Delight 7-3): swap the off-diagonal 32x32 blocks, then the
/// 16x16 blocks inside each, ... down to single bits; 6 rounds of 32 word pairs.
inline void transpose64(uint64_t a[64]) {
    uint64_t m = 0x00000000FFFFFFFFull;
    for (int j = 32; j != 0; j >>= 1, m ^= (m << j)) {
        for (int k = 0; k < 64; k = ((k | j) + 1) & ~j) {
            const uint64_t t = ((a[k] >> j) ^ a[k | j]) & m;
            a[k] ^= t << j;
            a[k | j] ^= t;
        }
    }
}

} // namespace voxfx::detail
