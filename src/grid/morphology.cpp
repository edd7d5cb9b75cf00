// voxfx — erosion, dilation, opening and closing with a box structuring element (Eisemann &
// Décoret, "Single-Pass GPU Solid Voxelization for Real-Time Applications", GI 2008, §6
// "Morphology": separable box filters, shifts along the column and AND/OR across columns).
// Along depth the window of 2r + 1 slices is built by doubling (van den Boomgaard & van Balen's
// logarithmic decomposition of a line segment): ~log2(2r + 1) shift-ORs, of a word with its two
// neighbours for r < 64, else of the whole column padded with the fill; along x the same
// doubling over whole columns of a row.
#include "voxfx/morphology.hpp"

#include <algorithm>
#include <cctype>
#include <type_traits>
#include <vector>

#include "voxfx/parallel.hpp"

namespace voxfx {

const char* toString(MorphOp op) { return enumName(op, kMorphOpNames); }

const char* toString(MorphBorder border) { return enumName(border, kMorphBorderNames); }

MorphOp parseMorphOp(const std::string& name) {
    return parseEnum<MorphOp>(name, "morphology operation", kMorphOpNames);
}

MorphBorder parseMorphBorder(const std::string& name) {
    return parseEnum<MorphBorder>(name, "morphology border", kMorphBorderNames);
}

namespace {

// The combining operation of a window: OR for dilation, AND for erosion.
template <bool And> inline uint64_t combine(uint64_t a, uint64_t b) { return And ? (a & b) : (a | b); }

// Window along depth for any radius r (used for r >= 64), from column `src` to column `dst`
// (P words each), with two scratch buffers of P + 2Q words, Q = r / 64 + 2. The column goes into
// the middle of the buffer with Q words of fill on each side (and its padding bits set to the
// fill): a stream in which the window of every real slice lies inside the buffer. The window of
// length L = 2r + 1 ending at each bit is built by doubling (y op= y shifted up by `step` bits,
// steps 1, 2, 4, ... summing to L - 1), each step one vectorizable pass from one buffer to the
// other; the output is that stream shifted down by r. A stream bit depends only on the L bits
// below it, so the words below the first step's reach (left as they are) never matter.
template <bool And>
void depthWindowLarge(const uint64_t* src, uint64_t* dst, int64_t P, int64_t r, uint64_t lastMask,
                      uint64_t fillWord, uint64_t* bufA, uint64_t* bufB) {
    const int64_t Q = (r >> 6) + 2, n = P + 2 * Q;
    std::fill(bufA, bufA + Q, fillWord);
    std::copy(src, src + P, bufA + Q);
    bufA[Q + P - 1] = (src[P - 1] & lastMask) | (fillWord & ~lastMask);
    std::fill(bufA + Q + P, bufA + n, fillWord);
    uint64_t *a = bufA, *b = bufB;
    const int64_t length = 2 * r + 1;
    for (int64_t len = 1; len < length;) {
        const int64_t step = std::min(len, length - len);
        const int64_t q = step >> 6;
        const int sh = int(step & 63);
        const uint64_t* __restrict in = a;
        uint64_t* __restrict out = b;
        const int64_t first = std::min(n, q + 1);
        std::copy(in, in + first, out);
        if (sh)
            for (int64_t w = first; w < n; ++w)
                out[w] = combine<And>(in[w], (in[w - q] << sh) | (in[w - q - 1] >> (64 - sh)));
        else
            for (int64_t w = first; w < n; ++w) out[w] = combine<And>(in[w], in[w - q]);
        std::swap(a, b);
        len += step;
    }
    // Output slice s is stream bit 64 Q + s + r.
    const int64_t u = Q + (r >> 6);
    const int sh = int(r & 63);
    if (sh)
        for (int64_t j = 0; j < P; ++j) dst[j] = (a[u + j] >> sh) | (a[u + j + 1] << (64 - sh));
    else
        std::copy(a + u, a + u + P, dst);
    dst[P - 1] &= lastMask;
}

// Window along depth for 0 < r < 64. Every output word depends on three input words only (the
// window reaches less than a word each way), so the doubling runs on the 192-bit stream
// (lo, mid, hi) in registers, independently for every output word (so the loop over words
// vectorizes). The window of length L = 2r + 1 ending at each bit is built by doubling:
//   y |= y << step (carrying across the three words), steps 1, 2, 4, ... summing to L - 1,
// and the output word is that stream shifted down by r: bits r .. r + 63 of (mid, hi). The bits
// used depend only on stream bits 64 - r .. 128 + r, so what shifts in below lo never reaches
// them. Words outside the column and the padding bits read as the fill: this is the window of
// the column extended by the fill on both sides. sh[0 .. NS) are the steps, sh[NS] = r.
template <bool And, int NS> inline uint64_t window3(uint64_t lo, uint64_t mid, uint64_t hi, const int* sh) {
    if constexpr (NS < 0) {
        // Radius -NS <= 3: the 2r shifted copies directly (6 r operations, fewer than doubling).
        uint64_t out = mid;
        for (int k = 1; k <= -NS; ++k) {
            out = combine<And>(out, (mid << k) | (lo >> (64 - k)));
            out = combine<And>(out, (mid >> k) | (hi << (64 - k)));
        }
        return out;
    } else {
        for (int i = 0; i < NS; ++i) {
            const uint64_t h = combine<And>(hi, (hi << sh[i]) | (mid >> (64 - sh[i])));
            const uint64_t m = combine<And>(mid, (mid << sh[i]) | (lo >> (64 - sh[i])));
            lo = combine<And>(lo, lo << sh[i]);
            hi = h;
            mid = m;
        }
        return (mid >> sh[NS]) | (hi << (64 - sh[NS]));
    }
}

template <bool And, int NS>
void depthColumn(const uint64_t* __restrict src, uint64_t* __restrict dst, int64_t P, const int* shifts,
                 uint64_t lastMask, uint64_t fillWord) {
    int sh[8];
    for (int i = 0; i < 8; ++i) sh[i] = shifts[i];
    const uint64_t last = (src[P - 1] & lastMask) | (fillWord & ~lastMask);
    if (P == 1) {
        dst[0] = window3<And, NS>(fillWord, last, fillWord, sh) & lastMask;
        return;
    }
    dst[0] = window3<And, NS>(fillWord, src[0], P == 2 ? last : src[1], sh);
    for (int64_t w = 1; w + 2 < P; ++w) dst[w] = window3<And, NS>(src[w - 1], src[w], src[w + 1], sh);
    if (P >= 3) dst[P - 2] = window3<And, NS>(src[P - 3], src[P - 2], last, sh);
    dst[P - 1] = window3<And, NS>(src[P - 2], last, fillWord, sh) & lastMask;
}

// The doubling steps of a depth window of radius 0 < r < 64 (window3), computed once per pass:
// shifts[0 .. steps) build the window of length 2r + 1, shifts[steps] = r; steps = -r for the
// direct form of radii up to 3.
struct DepthPlan {
    int shifts[8] = {};
    int steps = 0;
    int r = 0;
    explicit DepthPlan(int64_t radius) : r(int(std::min<int64_t>(radius, 63))) {
        const int length = 2 * r + 1;
        for (int len = 1, step; len < length; len += step)
            shifts[steps++] = step = std::min(len, length - len);
        shifts[steps] = r;
        if (r <= 3) steps = -r;
    }
};

// Calls f(std::integral_constant<int, NS>) for NS = steps (-3..-1 direct, 1..7 doubling): the
// loops unrolled.
template <class F> void withSteps(int steps, F&& f) {
    switch (steps) {
    case -1:
        return f(std::integral_constant<int, -1>{});
    case -2:
        return f(std::integral_constant<int, -2>{});
    case -3:
        return f(std::integral_constant<int, -3>{});
    case 1:
        return f(std::integral_constant<int, 1>{});
    case 2:
        return f(std::integral_constant<int, 2>{});
    case 3:
        return f(std::integral_constant<int, 3>{});
    case 4:
        return f(std::integral_constant<int, 4>{});
    case 5:
        return f(std::integral_constant<int, 5>{});
    case 6:
        return f(std::integral_constant<int, 6>{});
    default:
        return f(std::integral_constant<int, 7>{});
    }
}

template <bool And>
void depthWindowSmall(const uint64_t* src, uint64_t* dst, int64_t P, const DepthPlan& plan, uint64_t lastMask,
                      uint64_t fillWord) {
    withSteps(plan.steps, [&](auto ns) {
        depthColumn<And, decltype(ns)::value>(src, dst, P, plan.shifts, lastMask, fillWord);
    });
}

// Depth-only window over whole rows of columns (rx = 0, 0 < r < 64): one long vectorized loop
// over the row's words treats the row as a single column, which is right everywhere except at
// each column's first and last words (and the one before the last when the column has padding
// bits); those are then recomputed with the fill. Cuts the per-column overhead of short columns.
template <bool And, int NS>
void depthRows(const uint64_t* __restrict src, uint64_t* __restrict dst, int64_t W, int64_t P, int64_t y0,
               int64_t y1, const int* shifts, uint64_t lastMask, uint64_t fillWord) {
    int sh[8];
    for (int i = 0; i < 8; ++i) sh[i] = shifts[i];
    const int64_t rowWords = W * P;
    for (int64_t y = y0; y < y1; ++y) {
        const uint64_t* rs = src + y * rowWords;
        uint64_t* rd = dst + y * rowWords;
        for (int64_t i = 1; i + 1 < rowWords; ++i) rd[i] = window3<And, NS>(rs[i - 1], rs[i], rs[i + 1], sh);
        for (int64_t x = 0; x < W; ++x) {
            const uint64_t* cs = rs + x * P;
            uint64_t* cd = rd + x * P;
            const uint64_t last = (cs[P - 1] & lastMask) | (fillWord & ~lastMask);
            cd[0] = window3<And, NS>(fillWord, cs[0], P == 2 ? last : cs[1], sh);
            if (P >= 3 && lastMask != ~uint64_t(0))
                cd[P - 2] = window3<And, NS>(cs[P - 3], cs[P - 2], last, sh);
            cd[P - 1] = window3<And, NS>(cs[P - 2], last, fillWord, sh) & lastMask;
        }
    }
}

// The steps of a doubling that builds a window of `length` items: a window of len items combined
// with itself shifted by step <= len covers len + step.
int doublingSteps(int64_t length, int64_t* steps) {
    int n = 0;
    for (int64_t len = 1, step; len < length; len += step) steps[n++] = step = std::min(len, length - len);
    return n;
}

// Window along x of one row of W columns of P words into ext[0 .. W P): column x becomes the
// combination of columns x - R .. x + R, those outside the row reading as the fill. ext holds
// (W + 2R) P words: R fill columns, the row, R fill columns; each doubling step combines every
// column with the one `step` columns further, in place (ascending: it reads only columns not yet
// updated), so column x ends as the window [x, x + 2R] of ext = [x - R, x + R] of the row.
// ~log2(2R + 1) vectorized passes over the row, whatever R.
template <bool And>
void xWindowRow(const uint64_t* row, uint64_t* ext, int64_t W, int64_t P, int64_t R, const int64_t* steps,
                int nSteps, uint64_t fillWord) {
    const int64_t n = (W + 2 * R) * P;
    std::fill(ext, ext + R * P, fillWord);
    std::copy(row, row + W * P, ext + R * P);
    std::fill(ext + (R + W) * P, ext + n, fillWord);
    int64_t valid = n; // words whose window is complete
    for (int i = 0; i < nSteps; ++i) {
        const int64_t off = steps[i] * P;
        valid -= off;
        for (int64_t k = 0; k < valid; ++k) ext[k] = combine<And>(ext[k], ext[k + off]);
    }
}

// Pass A: window along x (neighbour columns of the same row), then along depth, a row at a time.
// Rows are independent, so each output row has one owner.
template <bool And> void passXZ(const BitGrid& in, BitGrid& out, int64_t rx, int64_t rz, uint64_t fillWord) {
    const int64_t W = in.width(), P = in.wordsPerColumn(), rowWords = W * P;
    const uint64_t lastMask = in.lastWordMask();
    const uint64_t* src = in.words();
    uint64_t* dst = out.words();
    const DepthPlan plan(rz);
    // Beyond W every window already holds a column outside the row: the same result.
    const int64_t R = std::min(rx, W);
    int64_t xSteps[64];
    const int nxSteps = doublingSteps(2 * R + 1, xSteps);
    parallelFor(0, in.height(), std::max<int64_t>(1, 512 / W), [&](int64_t b, int64_t e) {
        std::vector<uint64_t> ext(R > 0 ? size_t((W + 2 * R) * P) : 0);
        // Scratch of depthWindowLarge (rz >= 64).
        const int64_t largeWords = rz >= 64 ? P + 2 * ((rz >> 6) + 2) : 0;
        std::vector<uint64_t> large(size_t(2 * largeWords));
        for (int64_t y = b; y < e; ++y) {
            const uint64_t* rowIn = src + y * rowWords;
            uint64_t* rowOut = dst + y * rowWords;
            if (R > 0) {
                xWindowRow<And>(rowIn, ext.data(), W, P, R, xSteps, nxSteps, fillWord);
                rowIn = ext.data();
            }
            if (rz == 0) {
                // An absorbing fill of ones reaches the padding bits: clear them.
                std::copy(rowIn, rowIn + rowWords, rowOut);
                for (int64_t x = 0; x < W; ++x) rowOut[x * P + P - 1] &= lastMask;
            } else if (rz < 64 && P >= 2) {
                withSteps(plan.steps, [&](auto ns) {
                    depthRows<And, decltype(ns)::value>(rowIn, rowOut, W, P, 0, 1, plan.shifts, lastMask,
                                                        fillWord);
                });
            } else {
                for (int64_t x = 0; x < W; ++x) {
                    const uint64_t* ci = rowIn + x * P;
                    uint64_t* co = rowOut + x * P;
                    if (rz < 64) {
                        depthWindowSmall<And>(ci, co, P, plan, lastMask, fillWord);
                    } else {
                        depthWindowLarge<And>(ci, co, P, rz, lastMask, fillWord, large.data(),
                                              large.data() + largeWords);
                    }
                }
            }
        }
    });
}

// Pass B: window along y, whole rows at a time, in blocks of words that stay in L1.
template <bool And> void passY(const BitGrid& in, BitGrid& out, int64_t ry, uint64_t fillWord) {
    const int64_t W = in.width(), H = in.height(), P = in.wordsPerColumn();
    const int64_t rowWords = W * P;
    const uint64_t lastMask = in.lastWordMask();
    const uint64_t* src = in.words();
    uint64_t* dst = out.words();
    parallelFor(0, H, 2, [&](int64_t b, int64_t e) {
        constexpr int64_t kBlock = 512;
        for (int64_t y = b; y < e; ++y) {
            const bool clipped = (y - ry < 0) || (y + ry > H - 1);
            const int64_t lo = std::max<int64_t>(0, y - ry), hi = std::min<int64_t>(H - 1, y + ry);
            uint64_t* o = dst + y * rowWords;
            for (int64_t i0 = 0; i0 < rowWords; i0 += kBlock) {
                const int64_t i1 = std::min(rowWords, i0 + kBlock);
                const uint64_t* first = src + lo * rowWords;
                for (int64_t i = i0; i < i1; ++i)
                    o[i] = clipped ? combine<And>(first[i], fillWord) : first[i];
                for (int64_t n = lo + 1; n <= hi; ++n) {
                    const uint64_t* row = src + n * rowWords;
                    for (int64_t i = i0; i < i1; ++i) o[i] = combine<And>(o[i], row[i]);
                }
            }
            // An absorbing fill of ones reaches the padding bits: clear them again.
            if (clipped && fillWord)
                for (int64_t x = 0; x < W; ++x) o[x * P + P - 1] &= lastMask;
        }
    });
}

// Gives g the dimensions of `like` unless it already has them (its bits are then overwritten).
void ensureSize(BitGrid& g, const BitGrid& like) {
    if (g.width() != like.width() || g.height() != like.height() || g.depth() != like.depth())
        g = BitGrid(like.width(), like.height(), like.depth());
}

template <bool And> uint64_t fillWordOf(const MorphologyOptions& o) {
    // Fill bit of the cells outside: the operation's identity for Neutral, else the border's.
    const bool fill = o.border == MorphBorder::Filled || (o.border == MorphBorder::Neutral && And);
    return fill ? ~uint64_t(0) : 0;
}

// One operation from `src` into `out`, with `spare` for the intermediate pass. `out` may be
// `src` (the operation then runs in place); `spare` is distinct from both.
template <bool And> void apply(const BitGrid& src, BitGrid& out, BitGrid& spare, const MorphologyOptions& o) {
    const uint64_t fillWord = fillWordOf<And>(o);
    const bool doXZ = o.rx > 0 || o.rz > 0, doY = o.ry > 0;
    if (!doXZ && !doY) {
        if (&out != &src) {
            ensureSize(out, src);
            std::copy(src.words(), src.words() + src.wordCount(), out.words());
        }
        return;
    }
    const bool inPlace = &out == &src;
    if (doXZ && doY) {
        ensureSize(spare, src);
        passXZ<And>(src, spare, o.rx, o.rz, fillWord);
        ensureSize(out, src);
        passY<And>(spare, out, o.ry, fillWord); // reads only `spare`, so out may be src
        return;
    }
    BitGrid& target = inPlace ? spare : out;
    ensureSize(target, src);
    if (doXZ)
        passXZ<And>(src, target, o.rx, o.rz, fillWord);
    else
        passY<And>(src, target, o.ry, fillWord);
    if (inPlace) std::swap(out, spare);
}

} // namespace

void morphology(const BitGrid& grid, MorphOp op, const MorphologyOptions& options, BitGrid& out,
                BitGrid& scratch) {
    if (options.rx < 0 || options.ry < 0 || options.rz < 0)
        fail("morphology radii must be >= 0, got ", options.rx, ", ", options.ry, ", ", options.rz);
    if (&out == &grid || &scratch == &grid || &out == &scratch)
        fail("morphology: the output and scratch grids must be distinct from the input and from each other");
    if (grid.empty()) {
        out = BitGrid();
        return;
    }
    // A radius of the grid's size already reaches every cell of the line and one beyond each end,
    // whatever the cell: a larger one gives the same result, but would cost time and scratch
    // memory in proportion to it (along depth: 2^30 slices took a minute and half a gigabyte).
    MorphologyOptions o = options;
    o.rx = std::min(o.rx, grid.width());
    o.ry = std::min(o.ry, grid.height());
    o.rz = std::min(o.rz, grid.depth());
    withThreads(o.threads, [&] {
        switch (op) {
        case MorphOp::Erode:
            apply<true>(grid, out, scratch, o);
            break;
        case MorphOp::Dilate:
            apply<false>(grid, out, scratch, o);
            break;
        case MorphOp::Open:
            apply<true>(grid, out, scratch, o);
            apply<false>(out, out, scratch, o);
            break;
        case MorphOp::Close:
            apply<false>(grid, out, scratch, o);
            apply<true>(out, out, scratch, o);
            break;
        }
    });
}

BitGrid morphology(const BitGrid& grid, MorphOp op, const MorphologyOptions& options) {
    BitGrid out, scratch;
    morphology(grid, op, options, out, scratch);
    return out;
}

VoxelGrid morphology(const VoxelGrid& grid, MorphOp op, const Vec3i& worldRadii,
                     const MorphologyOptions& options) {
    MorphologyOptions o = options;
    const Axis a = grid.frame.axis();
    o.rx = worldRadii[columnXAxis(a)];
    o.ry = worldRadii[columnYAxis(a)];
    o.rz = worldRadii[sliceAxis(a)];
    return {grid.frame, morphology(grid.bits, op, o)};
}

} // namespace voxfx
