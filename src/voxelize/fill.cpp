// voxfx — flood fill of the outside (robust fill for open meshes) and three-axis parity vote.
#include "voxelize/fill.hpp"

#include <deque>
#include <vector>

#include "voxfx/parallel.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx::detail {

namespace {

uint64_t reverseBits(uint64_t x) {
    x = ((x >> 1) & 0x5555555555555555ull) | ((x & 0x5555555555555555ull) << 1);
    x = ((x >> 2) & 0x3333333333333333ull) | ((x & 0x3333333333333333ull) << 2);
    x = ((x >> 4) & 0x0F0F0F0F0F0F0F0Full) | ((x & 0x0F0F0F0F0F0F0F0Full) << 4);
    x = ((x >> 8) & 0x00FF00FF00FF00FFull) | ((x & 0x00FF00FF00FF00FFull) << 8);
    x = ((x >> 16) & 0x0000FFFF0000FFFFull) | ((x & 0x0000FFFF0000FFFFull) << 16);
    return (x >> 32) | (x << 32);
}

// Grows seeds upward (towards higher slices) to the end of their runs of free bits, across words:
//   free  = 0 1 1 1 0 1 1   (bit 6 ... bit 0)
//   seeds = 0 0 0 1 0 0 0
//   free + seeds carries through the run above the seed: ((free + seeds) ^ free) & free = 0 1 1 1 0 0 0
void fillUp(const uint64_t* freeBits, uint64_t* seeds, int64_t words) {
    uint64_t carry = 0;
    for (int64_t w = 0; w < words; ++w) {
        const uint64_t f = freeBits[w], s = seeds[w] & f;
        const uint64_t sum = f + s;
        const uint64_t sumCarry = f + s + carry;
        const uint64_t nextCarry = (sum < f) || (sumCarry < sum) ? 1 : 0;
        seeds[w] = (((sumCarry ^ f) & f) | s) | (carry & f & 1);
        carry = nextCarry;
    }
}

// Grows seeds both ways along the column.
void fillRuns(const uint64_t* freeBits, uint64_t* seeds, int64_t words, uint64_t* scratchFree,
              uint64_t* scratchSeeds) {
    fillUp(freeBits, seeds, words);
    for (int64_t w = 0; w < words; ++w) {
        scratchFree[w] = reverseBits(freeBits[words - 1 - w]);
        scratchSeeds[w] = reverseBits(seeds[words - 1 - w]);
    }
    fillUp(scratchFree, scratchSeeds, words);
    for (int64_t w = 0; w < words; ++w) seeds[w] = reverseBits(scratchSeeds[words - 1 - w]);
}

} // namespace

BitGrid floodFillInside(const BitGrid& walls) {
    const int64_t W = walls.width(), H = walls.height(), D = walls.depth(), P = walls.wordsPerColumn();
    const uint64_t last = walls.lastWordMask();
    BitGrid outside(W, H, D);
    const auto words = static_cast<size_t>(P);
    std::vector<uint64_t> freeCol(words), seed(words), sf(words), ss(words);
    std::vector<uint8_t> queued(size_t(W * H), 1);
    std::deque<int64_t> work;
    for (int64_t c = 0; c < W * H; ++c) work.push_back(c);

    while (!work.empty()) {
        const int64_t c = work.front();
        work.pop_front();
        queued[size_t(c)] = 0;
        const int64_t x = c % W, y = c / W;
        const bool border = x == 0 || y == 0 || x == W - 1 || y == H - 1;
        const uint64_t* wall = walls.column(c);
        uint64_t* out = outside.column(c);
        const uint64_t* nb[4] = {
            x > 0 ? outside.column(c - 1) : nullptr, x + 1 < W ? outside.column(c + 1) : nullptr,
            y > 0 ? outside.column(c - W) : nullptr, y + 1 < H ? outside.column(c + W) : nullptr};
        for (int64_t w = 0; w < P; ++w) {
            freeCol[size_t(w)] = ~wall[w] & (w == P - 1 ? last : ~uint64_t(0));
            uint64_t s = out[w];
            if (border) s |= ~uint64_t(0);
            for (const uint64_t* n : nb)
                if (n) s |= n[w];
            seed[size_t(w)] = s & freeCol[size_t(w)];
        }
        // Cells at the near and far ends of the column touch the grid border too.
        seed[0] |= freeCol[0] & 1u;
        seed[size_t(P - 1)] |= freeCol[size_t(P - 1)] & (uint64_t(1) << ((D - 1) & 63));
        fillRuns(freeCol.data(), seed.data(), P, sf.data(), ss.data());
        bool grew = false;
        for (int64_t w = 0; w < P; ++w)
            if (seed[size_t(w)] != out[w]) {
                grew = true;
                out[w] = seed[size_t(w)];
            }
        if (!grew) continue;
        const int64_t neighbours[4] = {x > 0 ? c - 1 : -1, x + 1 < W ? c + 1 : -1, y > 0 ? c - W : -1,
                                       y + 1 < H ? c + W : -1};
        for (int64_t n : neighbours)
            if (n >= 0 && !queued[size_t(n)]) {
                queued[size_t(n)] = 1;
                work.push_back(n);
            }
    }
    // Inside (with walls) = not outside.
    uint64_t* o = outside.words();
    parallelFor(0, W * H, 4096, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            for (int64_t w = 0; w < P; ++w) o[c * P + w] = ~o[c * P + w];
            o[c * P + P - 1] &= last;
        }
    });
    return outside;
}

BitGrid majority(const BitGrid& a, const BitGrid& b, const BitGrid& c) {
    VOXFX_CHECK(a.wordCount() == b.wordCount() && a.wordCount() == c.wordCount());
    BitGrid out(a.width(), a.height(), a.depth());
    const uint64_t *pa = a.words(), *pb = b.words(), *pc = c.words();
    uint64_t* po = out.words();
    parallelFor(0, a.wordCount(), int64_t(1) << 16, [&](int64_t s, int64_t e) {
        for (int64_t i = s; i < e; ++i) po[i] = (pa[i] & pb[i]) | (pa[i] & pc[i]) | (pb[i] & pc[i]);
    });
    return out;
}

Frame reframe(const Frame& frame, Axis axis) {
    VoxelGrid probe{frame, {}};
    const Vec3i d = probe.worldDims();
    return Frame::orthographic(frame.box(), axis, d[columnXAxis(axis)], d[columnYAxis(axis)],
                               d[sliceAxis(axis)]);
}

} // namespace voxfx::detail
