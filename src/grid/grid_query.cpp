// voxfx — counting and traversal: column popcounts (GI08 §6, "counting"), filled volume, and
// segment queries walked with the one 3D DDA (voxfx/dda.hpp, Amanatides & Woo 1987).
#include "voxfx/grid_query.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <vector>

#include "core/bitops.hpp"
#include "voxfx/dda.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace {

// Calls emit(n, i, j, k) for the n-th filled cell in the order of i, then j, then k (world axes)
// of an axis-aligned, uniformly sliced grid: counts per i (a popcount pass over the columns
// (i, j) of a grid sliced along z), prefix sums, then each i fills its own range of n.
template <class Emit>
void forEachFilledCell(const VoxelGrid& grid, std::size_t values, int threads, Emit emit) {
    const Frame& f = grid.frame;
    if (f.isPerspective() || f.isOriented() || f.slicing() != Slicing::Uniform)
        fail("filled cells need an axis-aligned orthographic grid with uniform slicing (resample a locally "
             "sliced one first)");
    const Vec3i dims = grid.worldDims();
    for (int a = 0; a < 3; ++a)
        if (dims[a] > int64_t(std::numeric_limits<int32_t>::max()))
            fail("filled cells: ", dims[a], " cells along ", toString(Axis(a)), " do not fit 32-bit indices");
    const VoxelGrid resliced = f.axis() == Axis::Z ? VoxelGrid{} : reslice(grid, Axis::Z);
    const BitGrid& bits = f.axis() == Axis::Z ? grid.bits : resliced.bits;
    const int64_t W = bits.width(), H = bits.height(), P = bits.wordsPerColumn();
    withThreads(threads, [&] {
        std::vector<int64_t> start(std::size_t(W) + 1, 0);
        parallelFor(0, W, 1, [&](int64_t b, int64_t e) {
            for (int64_t x = b; x < e; ++x) {
                int64_t n = 0;
                for (int64_t y = 0; y < H; ++y) {
                    const uint64_t* col = bits.column(x, y);
                    for (int64_t w = 0; w < P; ++w) n += std::popcount(col[w]);
                }
                start[std::size_t(x) + 1] = n;
            }
        });
        for (std::size_t x = 1; x < start.size(); ++x) start[x] += start[x - 1];
        if (values != 3 * std::size_t(start.back()))
            fail("filled cells: room for ", values, " values, but ", start.back(), " cells need ",
                 3 * start.back());
        parallelFor(0, W, 1, [&](int64_t b, int64_t e) {
            for (int64_t x = b; x < e; ++x) {
                int64_t n = start[std::size_t(x)];
                for (int64_t y = 0; y < H; ++y) {
                    const uint64_t* col = bits.column(x, y);
                    for (int64_t w = 0; w < P; ++w)
                        for (uint64_t word = col[w]; word; word &= word - 1)
                            emit(n++, x, y, w * 64 + std::countr_zero(word));
                }
            }
        });
    });
}

template <class T> void filledCellCentersAs(const VoxelGrid& grid, std::span<T> out, int threads) {
    const Vec3d lo = grid.frame.box().lo, cell = grid.frame.cellSize();
    forEachFilledCell(grid, out.size(), threads, [&](int64_t n, int64_t i, int64_t j, int64_t k) {
        T* o = out.data() + 3 * n;
        o[0] = T(lo.x + (double(i) + 0.5) * cell.x);
        o[1] = T(lo.y + (double(j) + 0.5) * cell.y);
        o[2] = T(lo.z + (double(k) + 0.5) * cell.z);
    });
}

} // namespace

void filledCellIndices(const VoxelGrid& grid, std::span<int32_t> out, int threads) {
    forEachFilledCell(grid, out.size(), threads, [&](int64_t n, int64_t i, int64_t j, int64_t k) {
        int32_t* o = out.data() + 3 * n;
        o[0] = int32_t(i);
        o[1] = int32_t(j);
        o[2] = int32_t(k);
    });
}

void filledCellCenters(const VoxelGrid& grid, std::span<double> out, int threads) {
    filledCellCentersAs(grid, out, threads);
}
void filledCellCenters(const VoxelGrid& grid, std::span<float> out, int threads) {
    filledCellCentersAs(grid, out, threads);
}

void filledAt(const VoxelGrid& grid, std::span<const Vec3d> points, std::span<uint8_t> out, int threads) {
    const Frame& f = grid.frame;
    if (f.isPerspective() || f.isOriented()) fail("filledAt needs an axis-aligned orthographic grid");
    if (points.size() != out.size()) fail("filledAt: ", points.size(), " points but room for ", out.size());
    const int64_t W = f.width(), H = f.height(), D = f.depth();
    withThreads(threads, [&] {
        parallelFor(0, int64_t(points.size()), 4096, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) {
                const Vec3d g = f.gridFromWorld(points[std::size_t(i)]);
                uint8_t answer = 0;
                // Comparisons first: NaN fails them all, and no out-of-range double is converted.
                if (g.x >= 0 && g.x < double(W) && g.y >= 0 && g.y < double(H)) {
                    const auto x = int64_t(g.x), y = int64_t(g.y);
                    const double s = f.depthToSlice(y * W + x)(g.z);
                    if (s >= 0 && s < double(D)) answer = grid.bits.get(x, y, int64_t(s)) ? 1 : 0;
                }
                out[std::size_t(i)] = answer;
            }
        });
    });
}

int64_t countColumnRange(const uint64_t* words, int64_t depth, int64_t s0, int64_t s1) {
    s0 = std::max<int64_t>(s0, 0);
    s1 = std::min<int64_t>(s1, depth);
    if (s1 <= s0) return 0;
    const int64_t w0 = s0 >> 6, w1 = (s1 - 1) >> 6;
    // Masks keep bits [s0 % 64, 64) of the first word and [0, (s1 - 1) % 64] of the last:
    //   first = ~0 << (s0 & 63)          last = ~0 >> (63 - ((s1 - 1) & 63))
    const uint64_t first = ~uint64_t(0) << (s0 & 63);
    const uint64_t last = ~uint64_t(0) >> (63 - ((s1 - 1) & 63));
    if (w0 == w1) return std::popcount(words[w0] & first & last);
    int64_t n = std::popcount(words[w0] & first) + std::popcount(words[w1] & last);
    for (int64_t w = w0 + 1; w < w1; ++w) n += std::popcount(words[w]);
    return n;
}

int64_t countColumnRange(const BitGrid& grid, int64_t x, int64_t y, int64_t s0, int64_t s1) {
    VOXFX_DCHECK(x >= 0 && x < grid.width() && y >= 0 && y < grid.height());
    return countColumnRange(grid.column(x, y), grid.depth(), s0, s1);
}

double filledVolume(const VoxelGrid& grid) {
    const Frame& f = grid.frame;
    const BitGrid& bits = grid.bits;
    if (bits.empty()) return 0.0;
    if (bits.width() != f.width() || bits.height() != f.height() || bits.depth() != f.depth())
        fail("volume: the grid's bits (", bits.width(), " x ", bits.height(), " x ", bits.depth(),
             ") do not match its frame (", f.width(), " x ", f.height(), " x ", f.depth(), ")");
    const int64_t columns = bits.columnCount(), P = bits.wordsPerColumn(), D = bits.depth();
    // Fixed-order sums (parallelReduce): the result does not depend on the thread count.
    const int64_t grain = 4096;
    if (!f.isPerspective()) {
        const Vec3d cell = f.cellSize();
        if (f.slicing() == Slicing::Uniform) return double(bits.count()) * (cell.x * cell.y * cell.z);
        // Local slicing: a column's D slices span 1 / scale uniform slices each.
        const double total = parallelReduce(
            0, columns, grain, 0.0,
            [&](int64_t b, int64_t e) {
                double sum = 0;
                for (int64_t c = b; c < e; ++c)
                    sum += double(countColumnRange(bits.column(c), D, 0, D)) / f.depthToSlice(c).scale;
                return sum;
            },
            std::plus<>());
        return total * cell.x * cell.y * cell.z;
    }
    // Footprint of one pixel at view depth 1: its area scales with depth squared, so the
    // cell between depths z0 and z1 holds area1 * (z1^3 - z0^3) / 3.
    const Vec3d o = f.worldFromGrid({0, 0, 1});
    const double area1 = length(f.worldFromGrid({1, 0, 1}) - o) * length(f.worldFromGrid({0, 1, 1}) - o);
    return parallelReduce(
        0, columns, grain, 0.0,
        [&](int64_t b, int64_t e) {
            double sum = 0;
            for (int64_t c = b; c < e; ++c) {
                const DepthToSlice m = f.depthToSlice(c);
                const uint64_t* col = bits.column(c);
                for (int64_t w = 0; w < P; ++w)
                    for (uint64_t bitsLeft = col[w]; bitsLeft; bitsLeft &= bitsLeft - 1) {
                        const int64_t s = w * 64 + std::countr_zero(bitsLeft);
                        const double z0 = m.near + double(s) / m.scale, z1 = m.near + double(s + 1) / m.scale;
                        sum += (z1 * z1 * z1 - z0 * z0 * z0) / 3.0;
                    }
            }
            return sum * area1;
        },
        std::plus<>());
}

namespace {

// Segment running along the slice axis only (d.x = d.y = 0): popcounts instead of stepping.
void traceAlongColumn(const BitGrid& grid, int64_t x, int64_t y, double lo, double hi, SegmentHits& r) {
    const int64_t D = grid.depth();
    // Clamp defensively: lo and hi come from a clip to [0, D] and may round past it.
    const int64_t k0 = std::clamp<int64_t>(int64_t(std::floor(lo)), 0, D - 1);
    const int64_t k1 = std::clamp<int64_t>(int64_t(std::ceil(hi)) - 1, k0, D - 1);
    const uint64_t* col = grid.column(x, y);
    auto filled = [&](int64_t s) { return (col[s >> 6] >> (s & 63)) & 1u; };
    if (k0 == k1) {
        r.cellsVisited = 1;
        if (filled(k0)) {
            r.filledCells = 1;
            r.filledLength = hi - lo;
        }
        return;
    }
    // First and last cells are partial, the ones between are crossed over their full unit depth.
    const double firstLen = double(k0 + 1) - lo, lastLen = hi - double(k1);
    const int64_t middle = countColumnRange(col, D, k0 + 1, k1);
    r.cellsVisited = k1 - k0 + 1;
    r.filledCells = middle + int64_t(filled(k0)) + int64_t(filled(k1));
    r.filledLength = double(middle) + (filled(k0) ? firstLen : 0.0) + (filled(k1) ? lastLen : 0.0);
}

} // namespace

SegmentHits traceSegmentGrid(const BitGrid& grid, const Vec3d& a, const Vec3d& b) {
    SegmentHits r;
    if (!isFinite(a) || !isFinite(b)) return r;
    const Vec3d d = b - a;
    r.length = length(d);
    if (!(r.length > 0) || grid.empty()) return r;
    const int64_t dims[3] = {grid.width(), grid.height(), grid.depth()};

    // Clip the parameter range [0, 1] to the grid box. A segment inside a plane parallel to an
    // axis belongs to the half-open cell range [0, n).
    const DdaClip clip = clipToGrid(a, d, dims);
    if (clip.empty()) return r;
    const double t0 = clip.t0, t1 = clip.t1;

    if (d.x == 0 && d.y == 0) {
        const int64_t x = std::clamp<int64_t>(int64_t(std::floor(a.x)), 0, dims[0] - 1);
        const int64_t y = std::clamp<int64_t>(int64_t(std::floor(a.y)), 0, dims[1] - 1);
        const double za = a.z + t0 * d.z, zb = a.z + t1 * d.z;
        traceAlongColumn(grid, x, y, std::min(za, zb), std::max(za, zb), r);
        // Lengths along the column are in slice units, which are grid units here.
        return r;
    }

    Dda walk = Dda::start(a, d, dims, t0);
    const int64_t W = grid.width(), P = grid.wordsPerColumn();
    const uint64_t* words = grid.words();
    const uint64_t* col = words + (walk.cell[1] * W + walk.cell[0]) * P;
    double t = t0, filledT = 0;
    int64_t visited = 0, filledCells = 0;
    for (;;) {
        const int axis = walk.nextAxis();
        const double tNext = walk.tMax[axis];
        const double len = std::min(tNext, t1) - t;
        if (len > 0) {
            ++visited;
            const int64_t s = walk.cell[2];
            if ((col[s >> 6] >> (s & 63)) & 1u) {
                ++filledCells;
                filledT += len;
            }
        }
        if (tNext >= t1) break;
        if (!walk.advance(axis)) break; // rounding at the exit face
        if (axis != 2) col = words + (walk.cell[1] * W + walk.cell[0]) * P;
        t = std::max(t, tNext);
    }
    r.cellsVisited = visited;
    r.filledCells = filledCells;
    r.filledLength = filledT * r.length;
    return r;
}

SegmentHits traceSegment(const VoxelGrid& grid, const Vec3d& aWorld, const Vec3d& bWorld) {
    if (grid.frame.isPerspective() || grid.frame.slicing() != Slicing::Uniform)
        fail("segment traversal needs an orthographic, uniformly sliced grid (for perspective or locally "
             "sliced grids count along columns with countColumnRange)");
    SegmentHits r =
        traceSegmentGrid(grid.bits, grid.frame.gridFromWorld(aWorld), grid.frame.gridFromWorld(bWorld));
    const double worldLength = isFinite(aWorld) && isFinite(bWorld) ? length(bWorld - aWorld) : 0.0;
    if (r.length > 0) r.filledLength = r.filledLength / r.length * worldLength;
    r.length = worldLength;
    return r;
}

} // namespace voxfx
