// voxfx — flood fill of the outside (robust fill for open meshes) and three-axis parity vote.
#include "voxelize/fill.hpp"

#include <algorithm>
#include <deque>
#include <vector>

#include "voxfx/parallel.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx::detail {

namespace {

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

// Grows seeds downward (towards lower slices) through runs of free bits: a Kogge–Stone smear
// inside each word (six shift steps, p = "free for the next 2^k bits"), words from the top down,
// the lowest bit of a word seeding the top bit of the word below.
void fillDown(const uint64_t* freeBits, uint64_t* seeds, int64_t words) {
    uint64_t carry = 0;
    for (int64_t w = words - 1; w >= 0; --w) {
        uint64_t p = freeBits[w];
        uint64_t g = (seeds[w] | (carry << 63)) & p;
        g |= p & (g >> 1);
        p &= p >> 1;
        g |= p & (g >> 2);
        p &= p >> 2;
        g |= p & (g >> 4);
        p &= p >> 4;
        g |= p & (g >> 8);
        p &= p >> 8;
        g |= p & (g >> 16);
        p &= p >> 16;
        g |= p & (g >> 32);
        seeds[w] = g;
        carry = g & 1;
    }
}

} // namespace

BitGrid floodFillInside(const BitGrid& walls) {
    const int64_t W = walls.width(), H = walls.height(), D = walls.depth(), P = walls.wordsPerColumn();
    const uint64_t last = walls.lastWordMask();
    BitGrid outside(W, H, D);
    const auto words = static_cast<size_t>(P);
    std::vector<uint64_t> freeCol(words), seed(words);
    // A column is saturated once every free cell of it is outside: nothing can grow it again,
    // so it is neither processed nor queued any more (most columns of a grid are empty).
    std::vector<uint8_t> queued(size_t(W * H), 1), saturated(size_t(W * H), 0);
    std::deque<int64_t> work;
    for (int64_t c = 0; c < W * H; ++c) work.push_back(c);

    while (!work.empty()) {
        const int64_t c = work.front();
        work.pop_front();
        queued[size_t(c)] = 0;
        if (saturated[size_t(c)]) continue;
        const int64_t x = c % W, y = c / W;
        const bool border = x == 0 || y == 0 || x == W - 1 || y == H - 1;
        const uint64_t* wall = walls.column(c);
        uint64_t* out = outside.column(c);
        uint64_t anyWall = 0;
        for (int64_t w = 0; w < P; ++w) {
            freeCol[size_t(w)] = ~wall[w];
            anyWall |= wall[w];
        }
        freeCol[size_t(P - 1)] &= last;
        if (border || anyWall == 0) {
            // Every cell of a border column touches the grid border, and so do both ends of every
            // column: a column on the border or without walls is outside wherever it is free.
            std::copy(freeCol.begin(), freeCol.end(), seed.begin());
        } else {
            const uint64_t *n0 = outside.column(c - 1), *n1 = outside.column(c + 1),
                           *n2 = outside.column(c - W), *n3 = outside.column(c + W);
            for (int64_t w = 0; w < P; ++w)
                seed[size_t(w)] = (out[w] | n0[w] | n1[w] | n2[w] | n3[w]) & freeCol[size_t(w)];
            // Cells at the near and far ends of the column touch the grid border too.
            seed[0] |= freeCol[0] & 1u;
            seed[size_t(P - 1)] |= freeCol[size_t(P - 1)] & (uint64_t(1) << ((D - 1) & 63));
            fillUp(freeCol.data(), seed.data(), P);
            fillDown(freeCol.data(), seed.data(), P);
        }
        bool grew = false, full = true;
        for (int64_t w = 0; w < P; ++w) {
            if (seed[size_t(w)] != out[w]) {
                grew = true;
                out[w] = seed[size_t(w)];
            }
            full &= seed[size_t(w)] == freeCol[size_t(w)];
        }
        saturated[size_t(c)] = full;
        if (!grew) continue;
        const int64_t neighbours[4] = {x > 0 ? c - 1 : -1, x + 1 < W ? c + 1 : -1, y > 0 ? c - W : -1,
                                       y + 1 < H ? c + W : -1};
        for (int64_t n : neighbours)
            if (n >= 0 && !queued[size_t(n)] && !saturated[size_t(n)]) {
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
