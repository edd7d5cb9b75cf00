// voxfx — flood fill of the outside (robust fill for open meshes) and three-axis parity vote.
#include "voxelize/fill.hpp"

#include <algorithm>
#include <bit>
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

namespace {

// The outside flood. First one parallel pass settles what needs no neighbour (border columns,
// columns without walls, and the cells below each column's lowest wall and above its highest);
// only the free cells between those walls (the column's wall span) can still be undecided.
// Then a column worklist per band of rows, seeded with the undecided columns a neighbour's
// outside reaches, spreads the outside sideways and along the span's free runs. Bands run in
// parallel and only read columns of their own rows; between rounds a serial pass over the seams
// between bands lets the outside cross them. The outside is the unique fixpoint, so the result
// does not depend on the order of work or the number of threads. The grid kept is the inside
// (walls and free cells not known to be outside), so no inversion pass is needed at the end.
class Flood {
public:
    explicit Flood(const BitGrid& walls)
        : walls_(walls), inside_(walls.width(), walls.height(), walls.depth()), W_(walls.width()),
          H_(walls.height()), P_(walls.wordsPerColumn()), last_(walls.lastWordMask()),
          noOutside_(size_t(P_), ~uint64_t(0)), queued_(size_t(W_ * H_), 0), saturated_(size_t(W_ * H_), 0),
          spanLo_(size_t(W_ * H_), 0), spanHi_(size_t(W_ * H_), 0) {
        // Fixed bands (never from the thread count): at least 8 rows, at most 32 bands.
        bandRows_ = std::max<int64_t>(8, (H_ + 31) / 32);
        bands_ = (H_ + bandRows_ - 1) / bandRows_;
        queues_.resize(size_t(bands_));
    }

    BitGrid run() {
        seedFromColumnEnds();
        queueSeededColumns();
        for (;;) {
            parallelFor(0, bands_, 1, [&](int64_t b0, int64_t b1) {
                Scratch s(P_);
                for (int64_t b = b0; b < b1; ++b) drain(b, s);
            });
            if (!crossSeams()) break;
        }
        return std::move(inside_);
    }

private:
    struct Scratch {
        explicit Scratch(int64_t words) : freeCol(size_t(words)), seed(size_t(words)) {}
        std::vector<uint64_t> freeCol, seed;
    };

    int64_t band(int64_t y) const { return y / bandRows_; }

    // The outside that needs no neighbour, in one parallel pass writing every word once: every
    // free cell of a border column or of a column without walls (both ends of a column touch the
    // grid border), and elsewhere the cells below the column's lowest wall and above its highest
    // (free runs from the ends). Each column's outside is then a union of whole free runs, as the
    // flood keeps it. A column whose free cells are all outside is saturated.
    void seedFromColumnEnds() {
        parallelFor(0, W_ * H_, 2048, [&](int64_t c0, int64_t c1) {
            for (int64_t c = c0; c < c1; ++c) {
                const uint64_t* wall = walls_.column(c);
                uint64_t* in = inside_.column(c);
                const int64_t x = c % W_, y = c / W_;
                int64_t lo = 0, hi = P_ - 1;
                while (lo < P_ && wall[lo] == 0) ++lo;
                if (lo == P_ || x == 0 || y == 0 || x == W_ - 1 || y == H_ - 1) {
                    for (int64_t w = 0; w < P_; ++w) in[w] = wall[w];
                    saturated_[size_t(c)] = 1;
                    continue;
                }
                while (wall[hi] == 0) --hi;
                for (int64_t w = 0; w < lo; ++w) in[w] = 0;
                for (int64_t w = lo; w <= hi; ++w) in[w] = ~uint64_t(0);
                for (int64_t w = hi + 1; w < P_; ++w) in[w] = 0;
                in[lo] &= ~((wall[lo] & (~wall[lo] + 1)) - 1);                       // below the lowest wall
                in[hi] &= ~(~uint64_t(0) << (63 - std::countl_zero(wall[hi])) << 1); // above the highest
                in[P_ - 1] &= last_;
                // Free cells between the lowest and the highest wall: not decided yet.
                uint64_t open = 0;
                for (int64_t w = lo; w <= hi; ++w) open |= ~wall[w] & in[w];
                saturated_[size_t(c)] = open == 0;
                spanLo_[size_t(c)] = int32_t(lo);
                spanHi_[size_t(c)] = int32_t(hi);
            }
        });
    }

    // Queues, band by band, the undecided columns that a neighbour's outside reaches. Read-only
    // on the grids, so the bands run in parallel; each band's queue is in column order.
    void queueSeededColumns() {
        parallelFor(0, bands_, 1, [&](int64_t b0, int64_t b1) {
            for (int64_t b = b0; b < b1; ++b) {
                const int64_t yLo = b * bandRows_, yHi = std::min(H_, yLo + bandRows_);
                for (int64_t y = std::max<int64_t>(yLo, 1); y < std::min(yHi, H_ - 1); ++y)
                    for (int64_t x = 1; x < W_ - 1; ++x) {
                        const int64_t c = y * W_ + x;
                        if (saturated_[size_t(c)]) continue;
                        // Only the span can be undecided: outside it every free cell is outside.
                        const int64_t lo = spanLo_[size_t(c)], n = spanHi_[size_t(c)] - lo + 1;
                        const uint64_t *wall = walls_.column(c) + lo, *in = inside_.column(c) + lo;
                        const uint64_t *n0 = inside_.column(c - 1) + lo, *n1 = inside_.column(c + 1) + lo;
                        const uint64_t *n2 = inside_.column(c - W_) + lo, *n3 = inside_.column(c + W_) + lo;
                        uint64_t news = 0; // free, undecided here, outside in a neighbour
                        for (int64_t w = 0; w < n; ++w)
                            news |= ~(n0[w] & n1[w] & n2[w] & n3[w]) & ~wall[w] & in[w];
                        if (news != 0) {
                            queued_[size_t(c)] = 1;
                            queues_[size_t(b)].push_back(c);
                        }
                    }
            }
        });
    }

    // Gathers, over the words [lo, lo + n) of an undecided column c (its wall span), the free
    // cells and the seeds: free cells that are outside in c or in a neighbour (the neighbours'
    // inside; n2, n3: the rows above and below, or noOutside_). Returns whether any seed is new.
    bool gather(int64_t c, Scratch& s, const uint64_t* n2, const uint64_t* n3) const {
        const int64_t lo = spanLo_[size_t(c)], n = spanHi_[size_t(c)] - lo + 1;
        const uint64_t* wall = walls_.column(c) + lo;
        const uint64_t* in = inside_.column(c) + lo;
        const uint64_t *n0 = inside_.column(c - 1) + lo, *n1 = inside_.column(c + 1) + lo;
        n2 += lo;
        n3 += lo;
        uint64_t news = 0;
        for (int64_t w = 0; w < n; ++w) {
            const uint64_t f = ~wall[w];
            const uint64_t seed = ~(in[w] & n0[w] & n1[w] & n2[w] & n3[w]) & f;
            s.freeCol[size_t(w)] = f;
            s.seed[size_t(w)] = seed;
            news |= seed & in[w];
        }
        // Padding bits of the last word are never free nor seeds (news has none: in's are zero).
        if (lo + n == P_) {
            s.freeCol[size_t(n - 1)] &= last_;
            s.seed[size_t(n - 1)] &= last_;
        }
        return news != 0;
    }

    // Runs the gathered seeds through the free runs of the span and stores them, and says whether
    // the column grew (and whether it is now saturated: every free cell outside). The span is
    // bounded by walls, so no free run crosses its ends: the words outside it are settled.
    bool store(int64_t c, Scratch& s) {
        const int64_t lo = spanLo_[size_t(c)], n = spanHi_[size_t(c)] - lo + 1;
        fillUp(s.freeCol.data(), s.seed.data(), n);
        fillDown(s.freeCol.data(), s.seed.data(), n);
        uint64_t* in = inside_.column(c) + lo;
        bool grew = false, full = true;
        for (int64_t w = 0; w < n; ++w) {
            // Inside = walls and the free cells not reached: everything but the seeds.
            const uint64_t v = ~s.seed[size_t(w)] & (lo + w == P_ - 1 ? last_ : ~uint64_t(0));
            if (v != in[w]) {
                grew = true;
                in[w] = v;
            }
            full &= s.seed[size_t(w)] == s.freeCol[size_t(w)];
        }
        saturated_[size_t(c)] = full;
        return grew;
    }

    // Queues the neighbours of c inside rows [yLo, yHi) that can still grow.
    void queueNeighbours(int64_t c, int64_t yLo, int64_t yHi, std::deque<int64_t>& q) {
        const int64_t x = c % W_, y = c / W_;
        const int64_t n[4] = {x > 0 ? c - 1 : -1, x + 1 < W_ ? c + 1 : -1, y > yLo ? c - W_ : -1,
                              y + 1 < yHi ? c + W_ : -1};
        for (int64_t k : n)
            if (k >= 0 && !queued_[size_t(k)] && !saturated_[size_t(k)]) {
                queued_[size_t(k)] = 1;
                q.push_back(k);
            }
    }

    // Columns that are not saturated are inner columns with walls (seedFromColumnEnds).
    void drain(int64_t b, Scratch& s) {
        const int64_t yLo = b * bandRows_, yHi = std::min(H_, yLo + bandRows_);
        std::deque<int64_t>& q = queues_[size_t(b)];
        while (!q.empty()) {
            const int64_t c = q.front();
            q.pop_front();
            queued_[size_t(c)] = 0;
            if (saturated_[size_t(c)]) continue;
            const int64_t y = c / W_;
            const uint64_t* n2 = y > yLo ? inside_.column(c - W_) : noOutside_.data();
            const uint64_t* n3 = y + 1 < yHi ? inside_.column(c + W_) : noOutside_.data();
            // The column's outside is closed under the run fill already: without a new seed it
            // cannot grow (the common case when a column is queued again).
            if (!gather(c, s, n2, n3)) continue;
            if (store(c, s)) queueNeighbours(c, yLo, yHi, q);
        }
    }

    // Lets the outside cross every seam between bands, both ways; queues what grew. Serial.
    bool crossSeams() {
        bool changed = false;
        Scratch s(P_);
        for (int64_t b = 1; b < bands_; ++b) {
            const int64_t yBelow = b * bandRows_; // first row of band b; row yBelow - 1 is band b - 1
            for (int64_t x = 0; x < W_; ++x) {
                const int64_t pairs[2][2] = {{yBelow * W_ + x, (yBelow - 1) * W_ + x},
                                             {(yBelow - 1) * W_ + x, yBelow * W_ + x}};
                for (const auto& [c, other] : pairs) {
                    if (saturated_[size_t(c)]) continue;
                    if (!gather(c, s, inside_.column(other), noOutside_.data())) continue;
                    store(c, s);
                    changed = true;
                    const int64_t bc = band(c / W_);
                    queueNeighbours(c, bc * bandRows_, std::min(H_, (bc + 1) * bandRows_),
                                    queues_[size_t(bc)]);
                }
            }
        }
        return changed;
    }

    const BitGrid& walls_;
    BitGrid inside_; ///< walls and the free cells not (yet) known to be outside
    int64_t W_, H_, P_;
    uint64_t last_;
    std::vector<uint64_t> noOutside_; ///< a column that is all inside: stands for rows of other bands
    std::vector<uint8_t> queued_, saturated_;
    std::vector<int32_t> spanLo_, spanHi_; ///< words holding the lowest and highest wall
    int64_t bandRows_ = 1, bands_ = 1;
    std::vector<std::deque<int64_t>> queues_;
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
