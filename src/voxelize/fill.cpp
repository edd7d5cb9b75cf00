// voxfx — flood fill of the outside (robust fill for open meshes) and three-axis parity vote.
#include "voxelize/fill.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <memory>
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

// Grows seeds downward (towards lower slices) through runs of free bits, words from the top down,
// the lowest bit of a word seeding the top bit of the word below. A word needs work only where a
// free cell not reached lies right below a reached one (after fillUp, only below the lowest seed
// of a run); there a Kogge-Stone smear (six shift steps, p = "free for the next 2^k bits") fills
// the rest of the run inside the word.
void fillDown(const uint64_t* freeBits, uint64_t* seeds, int64_t words) {
    uint64_t carry = 0;
    for (int64_t w = words - 1; w >= 0; --w) {
        uint64_t p = freeBits[w];
        uint64_t g = (seeds[w] | (carry << 63)) & p;
        if ((p & ~g & (g >> 1)) != 0) {
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
        }
        seeds[w] = g;
        carry = g & 1;
    }
}

} // namespace

namespace {

// The outside flood. First each band settles what needs no neighbour (border columns,
// columns without walls, and the cells below each column's lowest wall and above its highest);
// only free cells between those walls can still be undecided, and each column keeps the range
// of words that hold its undecided cells (it only shrinks: a free run holding an undecided cell
// is undecided as a whole, so no run crosses the range's ends). Then row sweeps spread the
// outside sideways: a column is looked at when it is dirty (never looked at, or a neighbour grew
// since), its seeds (free undecided cells that are outside in a neighbour) run through its free
// runs, and when it grows its neighbours become dirty. Rows are swept in order, each row left to
// right and then right to left, forward then backward, so one sweep carries the outside across
// many columns (a FIFO worklist moved it one column per visit). Bands of rows sweep in parallel,
// even bands then odd ones, so a band reads the rows of its neighbours while they stand still.
// The outside is the unique fixpoint, so the result does not depend on the order of work or the
// number of threads. The grid kept is the inside (walls and free cells not known to be outside).
class Flood {
public:
    explicit Flood(const BitGrid& walls)
        : walls_(walls), inside_(walls.width(), walls.height(), walls.depth()), W_(walls.width()),
          H_(walls.height()), P_(walls.wordsPerColumn()), last_(walls.lastWordMask()),
          dirty_(std::make_unique_for_overwrite<uint8_t[]>(size_t(W_ * H_))),
          saturated_(std::make_unique_for_overwrite<uint8_t[]>(size_t(W_ * H_))),
          lo_(std::make_unique_for_overwrite<int32_t[]>(size_t(W_ * H_))),
          hi_(std::make_unique_for_overwrite<int32_t[]>(size_t(W_ * H_))) {
        // Fixed bands (never from the thread count), at least 2 rows so that the bands that sweep
        // at the same time never mark the same row of the band between them.
        bandRows_ = std::max<int64_t>(8, (H_ + 15) / 16);
        bands_ = (H_ + bandRows_ - 1) / bandRows_;
        pending_ = std::make_unique<std::atomic<uint8_t>[]>(size_t(bands_));
        for (int64_t b = 0; b < bands_; ++b) pending_[size_t(b)].store(1, std::memory_order_relaxed);
    }

    BitGrid run() {
        for (bool again = true, first = true; again; first = false) {
            again = false;
            for (int64_t parity = 0; parity < 2; ++parity) {
                std::atomic<bool> marked{false};
                parallelFor(0, (bands_ + 1 - parity) / 2, 1, [&](int64_t k0, int64_t k1) {
                    Scratch s(P_);
                    for (int64_t k = k0; k < k1; ++k) {
                        const int64_t b = 2 * k + parity;
                        if (first) seedBand(b);
                        if (pending_[size_t(b)].exchange(0, std::memory_order_relaxed) && sweepBand(b, s))
                            marked.store(true, std::memory_order_relaxed);
                    }
                });
                // Marks from the odd bands make even bands pending again: one more round.
                if (parity == 1 && marked.load()) again = true;
            }
        }
        return std::move(inside_);
    }

private:
    struct Scratch {
        explicit Scratch(int64_t words) : freeCol(size_t(words)), seed(size_t(words)) {}
        std::vector<uint64_t> freeCol, seed;
    };

    int64_t band(int64_t y) const { return y / bandRows_; }

    // Each band settles its rows right before its first sweep, which then finds them in cache
    // (the grid is far larger than the caches: after a separate pass over all of it, the first
    // sweep loaded every row back from memory). A sweep reads the row on each side of its band
    // too, so an even band settles its rows and those two, an odd band the rest of its rows.
    void seedBand(int64_t b) {
        int64_t y0 = b * bandRows_, y1 = std::min(H_, y0 + bandRows_);
        if (b % 2 == 0) {
            y0 = std::max<int64_t>(y0 - 1, 0);
            y1 = std::min(y1 + 1, H_);
        } else {
            y0 += 1;
            if (b + 1 < bands_) y1 -= 1;
        }
        seedColumns(y0 * W_, y1 * W_);
    }

    // The outside that needs no neighbour, writing only the words that hold inside cells (the
    // new grid is zero): every free cell of a border column or of a column without walls (both
    // ends of a column touch the grid border), and elsewhere the cells below the column's lowest
    // wall and above its highest (free runs from the ends). Each column's outside is then a union
    // of whole free runs, as the flood keeps it. A column whose free cells are all outside is
    // saturated; the others are dirty (not looked at yet).
    void seedColumns(int64_t c0, int64_t c1) {
        for (int64_t c = c0; c < c1; ++c) {
            const uint64_t* wall = walls_.column(c);
            uint64_t* in = inside_.column(c);
            const int64_t x = c % W_, y = c / W_;
            int64_t lo = 0, hi = P_ - 1;
            while (lo < P_ && wall[lo] == 0) ++lo;
            if (lo == P_ || x == 0 || y == 0 || x == W_ - 1 || y == H_ - 1) {
                for (int64_t w = lo; w < P_; ++w) in[w] = wall[w];
                saturated_[size_t(c)] = 1;
                dirty_[size_t(c)] = 0;
                continue;
            }
            while (wall[hi] == 0) --hi;
            for (int64_t w = lo; w <= hi; ++w) in[w] = ~uint64_t(0);
            in[lo] &= ~((wall[lo] & (~wall[lo] + 1)) - 1);                       // below the lowest wall
            in[hi] &= ~(~uint64_t(0) << (63 - std::countl_zero(wall[hi])) << 1); // above the highest
            if (hi == P_ - 1) in[hi] &= last_;
            // Free cells between the lowest and the highest wall: not decided yet.
            uint64_t open = (~wall[lo] & in[lo]) | (~wall[hi] & in[hi]);
            for (int64_t w = lo + 1; w < hi; ++w) open |= ~wall[w];
            saturated_[size_t(c)] = open == 0;
            dirty_[size_t(c)] = open != 0;
            lo_[size_t(c)] = int32_t(lo);
            hi_[size_t(c)] = int32_t(hi);
        }
    }

    // Looks at a dirty column: gathers over its undecided words the free cells and the seeds
    // (free cells outside here or in a neighbour), runs the seeds through the free runs and
    // stores the result. When the column grew, its neighbours that can still grow become dirty
    // (marking a row of another band makes that band pending). Returns whether it grew.
    bool visit(int64_t c, Scratch& s, int64_t yLo, int64_t yHi, bool& markedOtherBand) {
        dirty_[size_t(c)] = 0;
        const int64_t lo = lo_[size_t(c)], n = hi_[size_t(c)] - lo + 1;
        const uint64_t* wall = walls_.column(c) + lo;
        uint64_t* in = inside_.column(c) + lo;
        const uint64_t *n0 = inside_.column(c - 1) + lo, *n1 = inside_.column(c + 1) + lo;
        const uint64_t *n2 = inside_.column(c - W_) + lo, *n3 = inside_.column(c + W_) + lo;
        // First only whether a free undecided cell is outside in a neighbour (loads and ORs, no
        // stores): the common case when a neighbour's growth was elsewhere is no news, and the
        // column's outside is closed under the run fill already, so it cannot grow.
        uint64_t news = 0;
        for (int64_t w = 0; w < n; ++w) news |= ~(n0[w] & n1[w] & n2[w] & n3[w]) & ~wall[w] & in[w];
        if (news == 0) return false;
        for (int64_t w = 0; w < n; ++w) {
            const uint64_t f = ~wall[w];
            s.freeCol[size_t(w)] = f;
            s.seed[size_t(w)] = ~(in[w] & n0[w] & n1[w] & n2[w] & n3[w]) & f;
        }
        // Padding bits of the last word are never free nor seeds.
        if (lo + n == P_) {
            s.freeCol[size_t(n - 1)] &= last_;
            s.seed[size_t(n - 1)] &= last_;
        }
        fillUp(s.freeCol.data(), s.seed.data(), n);
        fillDown(s.freeCol.data(), s.seed.data(), n);
        // Inside = walls and the free cells not reached: everything but the seeds. The undecided
        // range shrinks to the words that still hold a free cell not reached.
        int64_t first = -1, lastOpen = -1;
        for (int64_t w = 0; w < n; ++w) {
            const uint64_t v = ~s.seed[size_t(w)] & (lo + w == P_ - 1 ? last_ : ~uint64_t(0));
            in[w] = v;
            if ((s.freeCol[size_t(w)] & v) != 0) {
                if (first < 0) first = w;
                lastOpen = w;
            }
        }
        if (first < 0) {
            saturated_[size_t(c)] = 1;
        } else {
            lo_[size_t(c)] = int32_t(lo + first);
            hi_[size_t(c)] = int32_t(lo + lastOpen);
        }
        const int64_t y = c / W_;
        const int64_t nb[4] = {c - 1, c + 1, c - W_, c + W_};
        for (int k = 0; k < 4; ++k) {
            const int64_t d = nb[k];
            if (saturated_[size_t(d)] || dirty_[size_t(d)]) continue;
            dirty_[size_t(d)] = 1;
            if ((k == 2 && y - 1 < yLo) || (k == 3 && y + 1 >= yHi)) {
                pending_[size_t(band(d / W_))].store(1, std::memory_order_relaxed);
                markedOtherBand = true;
            }
        }
        return true;
    }

    // Visits the dirty columns of one row, left to right, then right to left.
    bool sweepRow(int64_t y, Scratch& s, int64_t yLo, int64_t yHi, bool& marked) {
        bool grew = false;
        const int64_t row = y * W_;
        for (int64_t x = 1; x < W_ - 1; ++x)
            if (dirty_[size_t(row + x)]) grew |= visit(row + x, s, yLo, yHi, marked);
        for (int64_t x = W_ - 2; x >= 1; --x)
            if (dirty_[size_t(row + x)]) grew |= visit(row + x, s, yLo, yHi, marked);
        return grew;
    }

    // Sweeps the rows of band b forward and backward until none of its columns is dirty.
    // Returns whether it marked a column of another band.
    bool sweepBand(int64_t b, Scratch& s) {
        const int64_t yLo = b * bandRows_, yHi = std::min(H_, yLo + bandRows_);
        const int64_t y0 = std::max<int64_t>(yLo, 1), y1 = std::min(yHi, H_ - 1);
        bool marked = false;
        for (bool grew = true; grew;) {
            grew = false;
            for (int64_t y = y0; y < y1; ++y) grew |= sweepRow(y, s, yLo, yHi, marked);
            if (!grew) break;
            grew = false;
            for (int64_t y = y1 - 1; y >= y0; --y) grew |= sweepRow(y, s, yLo, yHi, marked);
        }
        return marked;
    }

    const BitGrid& walls_;
    BitGrid inside_; ///< walls and the free cells not (yet) known to be outside
    int64_t W_, H_, P_;
    uint64_t last_;
    // Per column, every entry written by the first pass (no clearing pass before it); lo_ and
    // hi_ are read for columns that are not saturated only.
    std::unique_ptr<uint8_t[]> dirty_, saturated_;
    std::unique_ptr<int32_t[]> lo_, hi_; ///< words holding the column's undecided cells
    int64_t bandRows_ = 1, bands_ = 1;
    std::unique_ptr<std::atomic<uint8_t>[]> pending_;
};

} // namespace

BitGrid floodFillInside(const BitGrid& walls) { return Flood(walls).run(); }

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
