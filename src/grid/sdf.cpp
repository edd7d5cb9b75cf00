// voxfx — signed distance fields (see voxfx/sdf.hpp).
//
// Exact narrow-band distance fields as OpenVDB's level sets (Museth, "VDB: High-resolution sparse
// volumes with dynamic topology", ACM TOG 32(3), 2013, §5: narrow band, background = band width),
// computed differently from OpenVDB's meshToVolume: instead of propagating closest-triangle
// indices outwards from the intersecting voxels (approximate past the first voxels), every band
// voxel takes the minimum over the triangles its block gathered from the hierarchy, which holds
// every triangle within the band width (exact). The sign comes from the solid voxelization (GI08
// parity and its tie rule), as voxfx/sdf.hpp explains, brick by brick from the tiled voxelizer
// where the fill allows it (sdf_detail.hpp), so no grid of the whole volume is made.
//
// The builder consumes slabs of slices along z (solid bits of the slab, conservative surface bits
// of the slab and of kz slices on either side) and processes layers of 8^3 blocks: per column the
// surface bits dilated along z by kz, then along x and y by kx, ky (separable box dilation) give the
// candidate voxels of each block, in OpenVDB's leaf mask order.
#include "voxfx/sdf.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <mutex>

#include "core/progress_range.hpp"
#include "grid/sdf_detail.hpp"
#include "grid/triangle_bvh.hpp"
#include "voxfx/error.hpp"
#include "voxfx/tiled.hpp"

namespace voxfx {

namespace detail {

/// The bits of one slab of a grid sliced along z: column (x, y) = words + (y * width + x) *
/// wordsPerColumn, bit s of it = slice firstSlice + s; columns are offset by (x0, y0) from the
/// grid's (a surface grid grown by the dilation's margin has x0 = kx, y0 = ky).
struct SlabBits {
    const uint64_t* words = nullptr;
    int64_t width = 0, wordsPerColumn = 0;
    int64_t firstSlice = 0, slices = 0;
    int64_t x0 = 0, y0 = 0;
    /// No words: every bit of the slab is `value` (a uniform tile of a tiled voxelization).
    bool uniform = false;
    bool value = false;

    const uint64_t* column(int64_t x, int64_t y) const {
        return words + ((y + y0) * width + x + x0) * wordsPerColumn;
    }
    /// Bits [lo, lo + n) (grid slices, n <= 64) of column (x, y), bit 0 = slice lo; slices outside
    /// the slab read as 0.
    uint64_t window(int64_t x, int64_t y, int64_t lo, int n) const {
        const int64_t b = std::max(lo, firstSlice), e = std::min(lo + n, firstSlice + slices);
        if (uniform || !words) {
            // A uniform slab is all `value`; a slab without words (and not uniform) is empty.
            if (!uniform || !value || b >= e) return 0;
            const uint64_t ones = e - b == 64 ? ~uint64_t(0) : (uint64_t(1) << (e - b)) - 1;
            return ones << (b - lo);
        }
        const uint64_t* col = column(x, y);
        uint64_t out = 0;
        for (int64_t s = b; s < e;) {
            const int64_t local = s - firstSlice, w = local >> 6, bit = local & 63;
            const int64_t take = std::min<int64_t>(64 - bit, e - s);
            uint64_t chunk = col[w] >> bit;
            if (take < 64) chunk &= (uint64_t(1) << take) - 1;
            out |= chunk << (s - lo);
            s += take;
        }
        return out;
    }
    /// Whether any bit of slices [lo, hi) of column (x, y) is set.
    bool any(int64_t x, int64_t y, int64_t lo, int64_t hi) const {
        for (int64_t s = lo; s < hi; s += 64)
            if (window(x, y, s, int(std::min<int64_t>(64, hi - s)))) return true;
        return false;
    }
};

/// One tile of the grid (see SdfBuilder::tile): the voxels [lo, hi) (lo a multiple of 8 on every
/// axis, hi too or the grid's size), their solid bits, and the conservative surface bits of the
/// tile grown by the dilation (kx, ky, kz) on every side (surface outside the grid included), both
/// addressed by the grid's own column and slice indices.
struct SdfTile {
    Vec3i lo, hi;
    SlabBits solid;
    SlabBits surface; ///< empty (no words, not uniform): no surface near the tile
};

/// What a tile made: its leaves and inside runs, each in (z, y, x) order.
struct SdfPiece {
    std::vector<SdfLeaf> leaves;
    std::vector<SdfInsideRun> runs;
};

struct SdfParams {
    Vec3i dims;          ///< voxels along x, y, z
    Vec3d lo, cell;      ///< voxel (i, j, k) centre: lo + (i + 0.5) * cell
    double width = 0;    ///< band width W (background)
    int64_t brick = 128; ///< brick edge (SdfOptions::brickSize)
    bool full = false;
    Vec3i dilation; ///< kx, ky, kz
};

namespace {

constexpr int kLeafDim = 8;
// A cube with more candidates than this splits into eight (down to cubes of kSmallestSplit / 2):
// smaller lists per voxel against the cost of making them (measured on the bunny, 75K and 1.2M
// triangles, at 256^3 and 512^3).
constexpr std::size_t kSplitCandidates = 64;
constexpr int kSmallestSplit = 2;

/// The triangles a block gathered, prepared once for all its voxels (the root list), or a part of
/// a parent list (indices into the root's prepared triangles); the boxes in structure-of-arrays
/// form, so that the per-voxel box test runs four candidates per instruction.
struct Candidates {
    std::vector<uint32_t> index; ///< root: tree order (filled by TriangleBvh::gather); part: root slots
    std::vector<DistanceTriangle> prepared; ///< root only
    const DistanceTriangle* tris = nullptr; ///< the root's prepared triangles
    std::vector<uint32_t> slot;             ///< candidate -> index into tris
    std::vector<double> lox, loy, loz, hix, hiy, hiz;
    std::vector<double> lb; ///< scratch: squared box distances to the current point

    std::size_t size() const { return slot.size(); }
    void resizeBoxes(std::size_t n) {
        for (std::vector<double>* v : {&lox, &loy, &loz, &hix, &hiy, &hiz, &lb}) v->resize(n);
    }
    /// The root list: triangles and boxes of `index`.
    void prepare(const TriangleBvh& bvh) {
        const std::size_t n = index.size();
        prepared.resize(n);
        slot.resize(n);
        resizeBoxes(n);
        for (std::size_t c = 0; c < n; ++c) {
            prepared[c] = bvh.triangle(index[c]);
            slot[c] = uint32_t(c);
            const Vec3d a = bvh.corner(index[c], 0), b = bvh.corner(index[c], 1), d = bvh.corner(index[c], 2);
            const Vec3d lo = min(min(a, b), d), hi = max(max(a, b), d);
            lox[c] = lo.x;
            loy[c] = lo.y;
            loz[c] = lo.z;
            hix[c] = hi.x;
            hiy[c] = hi.y;
            hiz[c] = hi.z;
        }
        tris = prepared.data();
    }
    /// The candidates of `from` whose box lies within `radius` of the box [lo, hi].
    void subset(Candidates& from, const Vec3d& lo, const Vec3d& hi, double radius) {
        tris = from.tris;
        const std::size_t m = from.size();
        // Box-to-box distances in one vectorized pass (into the parent's scratch), then the copy.
        {
            const double *__restrict x0 = from.lox.data(), *__restrict y0 = from.loy.data(),
                         *__restrict z0 = from.loz.data();
            const double *__restrict x1 = from.hix.data(), *__restrict y1 = from.hiy.data(),
                         *__restrict z1 = from.hiz.data();
            double* __restrict out = from.lb.data();
            for (std::size_t c = 0; c < m; ++c) {
                double dx = x0[c] - hi.x > lo.x - x1[c] ? x0[c] - hi.x : lo.x - x1[c];
                double dy = y0[c] - hi.y > lo.y - y1[c] ? y0[c] - hi.y : lo.y - y1[c];
                double dz = z0[c] - hi.z > lo.z - z1[c] ? z0[c] - hi.z : lo.z - z1[c];
                dx = dx > 0 ? dx : 0;
                dy = dy > 0 ? dy : 0;
                dz = dz > 0 ? dz : 0;
                out[c] = dx * dx + dy * dy + dz * dz;
            }
        }
        slot.resize(m);
        resizeBoxes(m);
        const double r2 = radius * radius;
        std::size_t n = 0;
        for (std::size_t c = 0; c < m; ++c) {
            if (from.lb[c] > r2) continue;
            slot[n] = from.slot[c];
            lox[n] = from.lox[c];
            loy[n] = from.loy[c];
            loz[n] = from.loz[c];
            hix[n] = from.hix[c];
            hiy[n] = from.hiy[c];
            hiz[n] = from.hiz[c];
            ++n;
        }
        slot.resize(n);
    }
    /// The smallest squared distance from p to the candidates below `cap2`, or cap2 when none is
    /// nearer; `hint` (a slot of the root list, or -1) is tried first and receives the nearest one.
    double nearest2(const Vec3d& p, double cap2, int& hint) {
        const std::size_t n = size();
        // Box distances first, in one pass the compiler vectorizes; then the kernel where a box
        // is nearer than the best so far.
        const double* __restrict x0 = lox.data(), * __restrict y0 = loy.data(), * __restrict z0 = loz.data();
        const double* __restrict x1 = hix.data(), * __restrict y1 = hiy.data(), * __restrict z1 = hiz.data();
        double* __restrict out = lb.data();
        const double px = p.x, py = p.y, pz = p.z;
        for (std::size_t c = 0; c < n; ++c) {
            const double ax = x0[c] - px, bx = px - x1[c], ay = y0[c] - py, by = py - y1[c];
            const double az = z0[c] - pz, bz = pz - z1[c];
            double dx = ax > bx ? ax : bx, dy = ay > by ? ay : by, dz = az > bz ? az : bz;
            dx = dx > 0 ? dx : 0;
            dy = dy > 0 ? dy : 0;
            dz = dz > 0 ? dz : 0;
            out[c] = dx * dx + dy * dy + dz * dz;
        }
        double best = cap2;
        int bestSlot = -1;
        double u, v;
        // The hint (a slot of the root list) need not be in this part: any triangle's distance
        // bounds the minimum from above, and the part holds every triangle that can attain it.
        if (hint >= 0) {
            const double d2 = triangleDistance2(tris[hint], p, u, v);
            if (d2 < best) {
                best = d2;
                bestSlot = hint;
            }
        }
        for (std::size_t c = 0; c < n; ++c) {
            if (lb[c] >= best) continue;
            const double d2 = triangleDistance2(tris[slot[c]], p, u, v);
            if (d2 < best) {
                best = d2;
                bestSlot = int(slot[c]);
            }
        }
        if (bestSlot >= 0) hint = bestSlot;
        return best;
    }
};

} // namespace

/// Builds a signed distance field tile by tile (see the file comment). Immutable: tiles may be
/// processed on several threads at once, each writing its own piece.
class SdfBuilder {
public:
    SdfBuilder(const SdfParams& params, const TriangleBvh& bvh) : p_(params), bvh_(bvh) {}

    /// The blocks of `t`, 64 slices at a time, into `out`.
    void tile(const SdfTile& t, SdfPiece& out) const;

private:
    using Bits = std::array<uint64_t, 8>; ///< one bit per voxel of a block, OpenVDB's leaf order
    /// Candidate lists per depth of the cube recursion (8^3, 4^3, 2^3, 1), reused block after block.
    using Scratch = std::array<Candidates, 4>;
    /// Per column of a tile, 64 slices: solid bits and candidate bits (see candidateWords).
    struct Words {
        Vec3i lo, hi;
        int64_t z0 = 0;
        std::vector<uint64_t> solid, mask;
        std::size_t at(int64_t x, int64_t y) const {
            return std::size_t((y - lo.y) * (hi.x - lo.x) + x - lo.x);
        }
    };
    void candidateWords(const SdfTile& t, Words& w) const;
    void blockRow(int64_t by, int64_t bz, const Words& w, SdfPiece& row) const;
    bool solveBlock(SdfLeaf& leaf, const Bits& todo, const Bits& inside, Scratch& scratch) const;
    void solveCube(SdfLeaf& leaf, const Vec3i& b, int size, int depth, Scratch& scratch, const Bits& todo,
                   const Bits& inside, bool& any, int& hint) const;
    Vec3d centre(int64_t i, int64_t j, int64_t k) const {
        return {p_.lo.x + (double(i) + 0.5) * p_.cell.x, p_.lo.y + (double(j) + 0.5) * p_.cell.y,
                p_.lo.z + (double(k) + 0.5) * p_.cell.z};
    }
    void setValue(SdfLeaf& leaf, int n, double d2, bool active, bool inside) const {
        const float d = active ? float(std::sqrt(d2)) : float(p_.width);
        leaf.values[std::size_t(n)] = inside ? -d : d;
        if (active) leaf.active[std::size_t(n >> 6)] |= uint64_t(1) << (n & 63);
    }

    SdfParams p_;
    const TriangleBvh& bvh_;
};

// Per column of the tile, for the 64 slices from w.z0 (8 layers of blocks, bit s = slice z0 + s):
// the solid bits and the candidate bits (surface dilated by kz along the column, then by kx, ky
// across columns, reading the surface's grown columns around the tile).
void SdfBuilder::candidateWords(const SdfTile& t, Words& w) const {
    const int64_t kx = p_.dilation.x, ky = p_.dilation.y, kz = p_.dilation.z, z0 = w.z0;
    const int64_t nx = t.hi.x - t.lo.x, ny = t.hi.y - t.lo.y;
    const int n = int(std::min<int64_t>(64, t.hi.z - z0));
    const uint64_t keep = n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1;
    w.solid.assign(std::size_t(nx * ny), 0);
    w.mask.assign(std::size_t(nx * ny), 0);
    parallelFor(t.lo.y, t.hi.y, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = t.lo.x; x < t.hi.x; ++x)
                w.solid[w.at(x, y)] = t.solid.window(x, y, z0, 64) & keep;
    });
    if (p_.full || (!t.surface.words && !t.surface.uniform)) return;
    // Surface bits of column (x, y), dilated along z, for the tile's columns grown by (kx, ky).
    const int64_t gx = nx + 2 * kx, gy = ny + 2 * ky;
    std::vector<uint64_t> along(std::size_t(gx * gy)), xy(std::size_t(nx * gy));
    parallelFor(0, gy, 8, [&](int64_t r0, int64_t r1) {
        for (int64_t r = r0; r < r1; ++r)
            for (int64_t c = 0; c < gx; ++c) {
                uint64_t d = 0;
                for (int64_t s = -kz; s <= kz; ++s)
                    d |= t.surface.window(t.lo.x - kx + c, t.lo.y - ky + r, z0 + s, 64);
                along[std::size_t(r * gx + c)] = d & keep;
            }
    });
    parallelFor(0, gy, 8, [&](int64_t r0, int64_t r1) {
        for (int64_t r = r0; r < r1; ++r)
            for (int64_t c = 0; c < nx; ++c) {
                uint64_t a = 0;
                for (int64_t dx = 0; dx <= 2 * kx; ++dx) a |= along[std::size_t(r * gx + c + dx)];
                xy[std::size_t(r * nx + c)] = a;
            }
    });
    parallelFor(0, ny, 8, [&](int64_t r0, int64_t r1) {
        for (int64_t r = r0; r < r1; ++r)
            for (int64_t c = 0; c < nx; ++c) {
                uint64_t a = 0;
                for (int64_t dy = 0; dy <= 2 * ky; ++dy) a |= xy[std::size_t((r + dy) * nx + c)];
                w.mask[std::size_t(r * nx + c)] = a;
            }
    });
}

void SdfBuilder::tile(const SdfTile& t, SdfPiece& out) const {
    Words w;
    w.lo = t.lo;
    w.hi = t.hi;
    const int64_t rows = (t.hi.y - t.lo.y + kLeafDim - 1) / kLeafDim;
    for (w.z0 = t.lo.z; w.z0 < t.hi.z; w.z0 += 64) {
        candidateWords(t, w);
        for (int64_t bz = w.z0 / kLeafDim; bz * kLeafDim < std::min(w.z0 + 64, t.hi.z); ++bz) {
            std::vector<SdfPiece> pieces{std::size_t(rows)};
            parallelFor(0, rows, 1, [&](int64_t b, int64_t e) {
                for (int64_t r = b; r < e; ++r)
                    blockRow(t.lo.y / kLeafDim + r, bz, w, pieces[std::size_t(r)]);
            });
            for (SdfPiece& piece : pieces) {
                for (SdfLeaf& l : piece.leaves) out.leaves.push_back(std::move(l));
                out.runs.insert(out.runs.end(), piece.runs.begin(), piece.runs.end());
            }
        }
    }
}

// The tile's blocks (bx, by, bz) along x: each becomes a leaf (band voxels, or signs that differ),
// a run of inside blocks, or nothing (outside, the background).
void SdfBuilder::blockRow(int64_t by, int64_t bz, const Words& w, SdfPiece& row) const {
    const int64_t W = p_.dims.x, H = p_.dims.y, D = p_.dims.z;
    const int shift = int(bz * kLeafDim - w.z0);
    SdfLeaf leaf;
    Scratch scratch;
    for (int64_t bx = w.lo.x / kLeafDim; bx * kLeafDim < w.hi.x; ++bx) {
        // Word i is column x = 8 bx + i, byte j of it column y = 8 by + j: OpenVDB's leaf order.
        Bits m{}, in{}, valid{};
        const int nz = int(std::min<int64_t>(kLeafDim, D - bz * kLeafDim));
        const uint8_t zValid = uint8_t((1u << nz) - 1);
        for (int i = 0; i < kLeafDim; ++i) {
            const int64_t x = bx * kLeafDim + i;
            if (x >= W) break;
            for (int j = 0; j < kLeafDim; ++j) {
                const int64_t y = by * kLeafDim + j;
                if (y >= H) break;
                const std::size_t c = w.at(x, y);
                m[std::size_t(i)] |= ((w.mask[c] >> shift) & 0xFF) << (8 * j);
                in[std::size_t(i)] |= ((w.solid[c] >> shift) & 0xFF) << (8 * j);
                valid[std::size_t(i)] |= uint64_t(zValid) << (8 * j);
            }
        }
        bool anyInside = false, allInside = true;
        for (int i = 0; i < 8; ++i) {
            anyInside = anyInside || in[std::size_t(i)];
            allInside = allInside && in[std::size_t(i)] == ~uint64_t(0);
        }
        leaf.origin = {bx * kLeafDim, by * kLeafDim, bz * kLeafDim};
        leaf.active.fill(0);
        Bits todo;
        for (int i = 0; i < 8; ++i)
            todo[std::size_t(i)] = (p_.full ? ~uint64_t(0) : m[std::size_t(i)]) & valid[std::size_t(i)];
        bool active = false;
        if (todo != Bits{}) active = solveBlock(leaf, todo, in, scratch);
        if (active || (anyInside && !allInside)) {
            // Band voxels, or signs that differ (a gwn fill's inside ending at a hole) or a block
            // cut by the grid's border: a leaf, so that every voxel keeps its value and sign.
            if (!active)
                for (int n = 0; n < 512; ++n)
                    setValue(leaf, n, 0, false, (in[std::size_t(n >> 6)] >> (n & 63)) & 1);
            row.leaves.push_back(leaf);
        } else if (allInside) {
            // Blocks wholly in the grid and inside: runs of tiles at -background.
            if (!row.runs.empty() && row.runs.back().x1 == int32_t(bx))
                ++row.runs.back().x1;
            else
                row.runs.push_back({int32_t(bx), int32_t(bx + 1), int32_t(by), int32_t(bz)});
        }
    }
}

// A block's voxels to compute (band: the candidates; full: all in the grid): each takes the
// distance to the triangles gathered within the band width of them (band), or to those that can
// be nearest to a voxel of the block (full); the others the background with their sign. Returns
// whether a voxel is active.
bool SdfBuilder::solveBlock(SdfLeaf& leaf, const Bits& todo, const Bits& inside, Scratch& scratch) const {
    for (int n = 0; n < 512; ++n) setValue(leaf, n, 0, false, (inside[std::size_t(n >> 6)] >> (n & 63)) & 1);
    bool any = false;
    int hint = -1;
    solveCube(leaf, {0, 0, 0}, kLeafDim, 0, scratch, todo, inside, any, hint);
    return any;
}

// The voxels of `todo` in the cube [b, b + size)^3 of the leaf. The triangles that matter lie
// within a radius of the box of those voxels' centres: the band width, or (full) d + h, d the
// distance at the box's centre and h its half diagonal, since d(v) <= d + |v - centre|. While they
// are many, the cube splits into eight, each keeping the part of the list within its own radius.
void SdfBuilder::solveCube(SdfLeaf& leaf, const Vec3i& b, int size, int depth, Scratch& scratch,
                           const Bits& todo, const Bits& inside, bool& any, int& hint) const {
    Candidates* parent = depth ? &scratch[std::size_t(depth - 1)] : nullptr;
    // The box of the cube's voxels to compute.
    int lo[3] = {8, 8, 8}, hi[3] = {-1, -1, -1};
    const uint64_t zBits = ((uint64_t(1) << size) - 1) << b.z;
    for (int64_t i = b.x; i < b.x + size; ++i)
        for (int64_t j = b.y; j < b.y + size; ++j) {
            const uint64_t bits = (todo[std::size_t(i)] >> (8 * j)) & zBits;
            if (!bits) continue;
            lo[0] = std::min(lo[0], int(i));
            hi[0] = std::max(hi[0], int(i));
            lo[1] = std::min(lo[1], int(j));
            hi[1] = std::max(hi[1], int(j));
            lo[2] = std::min(lo[2], std::countr_zero(bits));
            hi[2] = std::max(hi[2], 63 - std::countl_zero(bits));
        }
    if (hi[0] < 0) return;
    const Vec3i o = leaf.origin;
    const Vec3d boxLo = centre(o.x + lo[0], o.y + lo[1], o.z + lo[2]);
    const Vec3d boxHi = centre(o.x + hi[0], o.y + hi[1], o.z + hi[2]);
    double radius = p_.width;
    if (p_.full) {
        const Vec3d mid = (boxLo + boxHi) * 0.5;
        int midHint = hint;
        const double d =
            std::sqrt(parent ? parent->nearest2(mid, std::numeric_limits<double>::infinity(), midHint)
                             : bvh_.nearest(mid).distance2);
        // Rounding of d, h and the box distances stays far below this relative slack.
        radius = (d + length(boxHi - boxLo) * 0.5) * (1 + 1e-12) + 1e-300;
    }
    Candidates& cand = scratch[std::size_t(depth)];
    if (parent) {
        cand.subset(*parent, boxLo, boxHi, radius);
    } else {
        cand.index.clear();
        bvh_.gather(boxLo, boxHi, radius, cand.index);
        cand.prepare(bvh_);
    }
    if (!cand.size()) return;
    if (cand.size() > kSplitCandidates && size > kSmallestSplit) {
        const int half = size / 2;
        for (int q = 0; q < 8; ++q)
            solveCube(leaf, b + Vec3i{(q & 1) * half, ((q >> 1) & 1) * half, (q >> 2) * half}, half,
                      depth + 1, scratch, todo, inside, any, hint);
        return;
    }
    const double cap2 = p_.full ? std::numeric_limits<double>::infinity() : p_.width * p_.width;
    for (int64_t i = lo[0]; i <= hi[0]; ++i)
        for (int64_t j = lo[1]; j <= hi[1]; ++j)
            for (int64_t k = lo[2]; k <= hi[2]; ++k) {
                const int n = int((i << 6) | (j << 3) | k);
                const std::size_t w = std::size_t(n >> 6);
                const uint64_t bit = uint64_t(1) << (n & 63);
                if (!(todo[w] & bit)) continue;
                const double d2 = cand.nearest2(centre(o.x + i, o.y + j, o.z + k), cap2, hint);
                if (d2 >= cap2) continue;
                any = true;
                setValue(leaf, n, d2, true, inside[w] & bit);
            }
}

// The conservative surface of the triangles within the band of tile [lo, hi), in the tile grown by
// the dilation on every side (surface outside the grid included): those triangles are the ones
// that can be nearest to a band voxel of the tile (their boxes lie within the band width of it).
VoxelGrid tileSurface(const SdfParams& p, const TriangleBvh& bvh, const Vec3i& lo, const Vec3i& hi) {
    const auto centreOf = [&](const Vec3i& i) { return p.lo + p.cell * (Vec3d(i) + Vec3d{0.5, 0.5, 0.5}); };
    std::vector<uint32_t> near;
    bvh.gather(centreOf(lo), centreOf(hi - Vec3i{1, 1, 1}), p.width * (1 + 1e-9), near);
    if (near.empty()) return {};
    Mesh part;
    part.positions.reserve(3 * near.size());
    for (const uint32_t t : near)
        for (int k = 0; k < 3; ++k) {
            part.indices.push_back(uint32_t(part.positions.size()));
            part.positions.push_back(Vec3f(bvh.corner(t, k))); // exact: the corners are floats
        }
    const Vec3i glo = lo - p.dilation, ghi = hi + p.dilation, gd = ghi - glo;
    const Box3d box{p.lo + p.cell * Vec3d(glo), p.lo + p.cell * Vec3d(ghi)};
    VoxelizeOptions co;
    co.mode = VoxelizeMode::Conservative;
    return voxelize(part.view(), Frame::orthographic(box, Axis::Z, gd.x, gd.y, gd.z), co);
}

// A tile whose solid bits are uniform and that no triangle's band reaches (no surface): outside,
// nothing; inside, what SdfBuilder::tile makes of it without looking at a column: runs of the
// blocks wholly in the grid, and leaves at -W inside the grid and +W beyond it for the blocks the
// grid's border cuts (their bits outside the grid are 0, so they are not all inside).
void uniformTile(const SdfParams& p, const SdfTile& t, SdfPiece& out) {
    if (!t.solid.value) return;
    const Vec3i d = p.dims;
    for (int64_t bz = t.lo.z / kLeafDim; bz * kLeafDim < t.hi.z; ++bz)
        for (int64_t by = t.lo.y / kLeafDim; by * kLeafDim < t.hi.y; ++by)
            for (int64_t bx = t.lo.x / kLeafDim; bx * kLeafDim < t.hi.x; ++bx) {
                const Vec3i o{bx * kLeafDim, by * kLeafDim, bz * kLeafDim};
                if (o.x + kLeafDim <= d.x && o.y + kLeafDim <= d.y && o.z + kLeafDim <= d.z) {
                    if (!out.runs.empty() && out.runs.back().x1 == int32_t(bx) &&
                        out.runs.back().y == int32_t(by) && out.runs.back().z == int32_t(bz))
                        ++out.runs.back().x1;
                    else
                        out.runs.push_back({int32_t(bx), int32_t(bx + 1), int32_t(by), int32_t(bz)});
                    continue;
                }
                SdfLeaf leaf;
                leaf.origin = o;
                for (int n = 0; n < 512; ++n) {
                    const bool in = o.x + (n >> 6) < d.x && o.y + ((n >> 3) & 7) < d.y && o.z + (n & 7) < d.z;
                    leaf.values[std::size_t(n)] = in ? -float(p.width) : float(p.width);
                }
                out.leaves.push_back(leaf);
            }
}

// One brick [lo, hi) with its solid bits: the surface of its own triangles (tileSurface), then its
// blocks into `out`.
void sdfBrick(const SdfParams& p, const TriangleBvh& bvh, const SdfBuilder& builder, const Vec3i& lo,
              const Vec3i& hi, const SlabBits& solid, SdfPiece& out) {
    SdfTile t;
    t.lo = lo;
    t.hi = hi;
    t.solid = solid;
    VoxelGrid surface;
    if (!p.full) surface = tileSurface(p, bvh, t.lo, t.hi);
    if (surface.bits.empty() && solid.uniform && !p.full) return uniformTile(p, t, out);
    if (!surface.bits.empty())
        t.surface = {surface.bits.words(),  surface.bits.width(), surface.bits.wordsPerColumn(),
                     t.lo.z - p.dilation.z, surface.bits.depth(), p.dilation.x - t.lo.x,
                     p.dilation.y - t.lo.y};
    builder.tile(t, out);
}

namespace {

// A brick's piece to the sink (if any), then freed: with a sink the pieces are not kept.
void sdfDeliver(SdfPiece& piece, SdfSink* sink) {
    if (!sink) return;
    sink->add(piece.leaves, piece.runs);
    piece = {};
}

/// The grid's bricks of p.brick^3 voxels: n of them along each axis, brick i at (i % n.x,
/// (i / n.x) % n.y, i / (n.x n.y)), one piece each.
struct Bricks {
    Vec3i n;
    int64_t brick = 0;
    explicit Bricks(const SdfParams& p)
        : n((p.dims + Vec3i{p.brick - 1, p.brick - 1, p.brick - 1}) / p.brick), brick(p.brick) {}
    int64_t count() const { return n.x * n.y * n.z; }
    int64_t index(const Vec3i& lo) const {
        const Vec3i b = lo / brick;
        return (b.z * n.y + b.y) * n.x + b.x;
    }
};

// The pieces joined in (z, y, x) order, runs that meet at a brick's side made one.
std::pair<std::vector<SdfLeaf>, std::vector<SdfInsideRun>> joinPieces(std::vector<SdfPiece>& pieces) {
    std::vector<SdfLeaf> leaves;
    std::vector<SdfInsideRun> runs;
    // Reserved, so that the result is not copied as it grows (it is most of the memory).
    std::size_t count = 0;
    for (const SdfPiece& piece : pieces) count += piece.leaves.size();
    leaves.reserve(count);
    for (SdfPiece& piece : pieces) {
        for (SdfLeaf& l : piece.leaves) leaves.push_back(std::move(l));
        runs.insert(runs.end(), piece.runs.begin(), piece.runs.end());
        piece = {};
    }
    const auto zyx = [](const Vec3i& a, const Vec3i& b) {
        return a.z != b.z ? a.z < b.z : (a.y != b.y ? a.y < b.y : a.x < b.x);
    };
    std::sort(leaves.begin(), leaves.end(),
              [&](const SdfLeaf& a, const SdfLeaf& b) { return zyx(a.origin, b.origin); });
    std::sort(runs.begin(), runs.end(), [&](const SdfInsideRun& a, const SdfInsideRun& b) {
        return zyx({a.x0, a.y, a.z}, {b.x0, b.y, b.z});
    });
    std::vector<SdfInsideRun> merged;
    for (const SdfInsideRun& r : runs)
        if (!merged.empty() && merged.back().z == r.z && merged.back().y == r.y && merged.back().x1 == r.x0)
            merged.back().x1 = r.x1;
        else
            merged.push_back(r);
    return {std::move(leaves), std::move(merged)};
}

} // namespace

// The whole grid in bricks of p.brick^3 voxels, on worker threads (one owner per brick), each with
// the solid bits of `solid` (a dense voxelization of the grid) and the surface of its own
// triangles; the pieces joined in (z, y, x) order.
std::pair<std::vector<SdfLeaf>, std::vector<SdfInsideRun>>
sdfTiles(const SdfParams& p, const TriangleBvh& bvh, const SdfBuilder& builder, const SlabBits& solid,
         Progress* progress, SdfSink* sink) {
    const Bricks bricks(p);
    std::vector<SdfPiece> pieces{std::size_t(bricks.count())};
    ProgressSteps steps(progress, bricks.count());
    parallelFor(0, bricks.count(), 1, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e && !steps.cancelled(); ++i) {
            const Vec3i lo =
                Vec3i{i % bricks.n.x, (i / bricks.n.x) % bricks.n.y, i / (bricks.n.x * bricks.n.y)} * p.brick;
            sdfBrick(p, bvh, builder, lo, min(lo + Vec3i{p.brick, p.brick, p.brick}, p.dims), solid,
                     pieces[std::size_t(i)]);
            sdfDeliver(pieces[std::size_t(i)], sink);
            steps.step();
        }
    });
    if (steps.cancelled()) fail("cancelled");
    return joinPieces(pieces);
}

// The same bricks with their solid bits from a tiled voxelization (voxfx/tiled.hpp), so that no
// grid of the whole volume is made: each brick the voxelizer visits (p.brick^3, or 2 p.brick a
// side where the gwn fill needs a multiple of 16) is cut into the field's bricks, computed on the
// thread that visits it. The bits are the dense voxelization's, so the field is the same.
std::pair<std::vector<SdfLeaf>, std::vector<SdfInsideRun>>
sdfTilesStreamed(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& vo, const SdfParams& p,
                 const TriangleBvh& bvh, const SdfBuilder& builder, Progress* progress,
                 uint64_t* workingBytes, SdfSink* sink) {
    const Bricks bricks(p);
    std::vector<SdfPiece> pieces{std::size_t(bricks.count())};
    ProgressSteps steps(progress, bricks.count());
    TileOptions to;
    to.brickSize = vo.fill == Fill::Gwn && p.brick % 16 ? 2 * p.brick : p.brick;
    to.workingBytes = workingBytes;
    VoxelizeOptions tiled = vo;
    tiled.progress = nullptr; // the field's bricks report, below
    voxelizeTiles(mesh, frame, tiled, to, [&](const GridTile& g) {
        SlabBits solid;
        solid.firstSlice = g.s0;
        solid.slices = g.depth;
        if (g.uniform) {
            solid.uniform = true;
            solid.value = g.value;
        } else {
            solid.words = g.bits.words;
            solid.width = g.width;
            solid.wordsPerColumn = g.bits.wordsPerColumn;
            solid.x0 = -g.x0;
            solid.y0 = -g.y0;
        }
        const Vec3i end{g.x0 + g.width, g.y0 + g.height, g.s0 + g.depth};
        for (int64_t z = g.s0; z < end.z; z += p.brick)
            for (int64_t y = g.y0; y < end.y; y += p.brick)
                for (int64_t x = g.x0; x < end.x; x += p.brick) {
                    // The voxelizer stops at the first exception and rethrows it.
                    if (steps.cancelled()) fail("cancelled");
                    const Vec3i lo{x, y, z};
                    SdfPiece& piece = pieces[std::size_t(bricks.index(lo))];
                    sdfBrick(p, bvh, builder, lo, min(lo + Vec3i{p.brick, p.brick, p.brick}, end), solid,
                             piece);
                    sdfDeliver(piece, sink);
                    steps.step();
                }
    });
    if (steps.cancelled()) fail("cancelled");
    return joinPieces(pieces);
}

} // namespace detail

// ---- the field ---------------------------------------------------------------------------------

Vec3i SignedDistanceField::dims() const { return {frame.width(), frame.height(), frame.depth()}; }

int64_t SignedDistanceField::activeCount() const {
    int64_t n = 0;
    for (const SdfLeaf& l : leaves)
        for (const uint64_t w : l.active) n += std::popcount(w);
    return n;
}

float SignedDistanceField::value(int64_t i, int64_t j, int64_t k) const {
    const Vec3i d = dims();
    if (i < 0 || j < 0 || k < 0 || i >= d.x || j >= d.y || k >= d.z)
        fail("voxel (", i, ", ", j, ", ", k, ") is outside the ", d.x, " x ", d.y, " x ", d.z, " field");
    const Vec3i o{i & ~7, j & ~7, k & ~7};
    const auto before = [](const Vec3i& a, const Vec3i& b) {
        return a.z != b.z ? a.z < b.z : (a.y != b.y ? a.y < b.y : a.x < b.x);
    };
    const auto it = std::lower_bound(leaves.begin(), leaves.end(), o,
                                     [&](const SdfLeaf& l, const Vec3i& v) { return before(l.origin, v); });
    if (it != leaves.end() && it->origin == o)
        return it->values[std::size_t(((i & 7) << 6) | ((j & 7) << 3) | (k & 7))];
    const int32_t bx = int32_t(i >> 3), by = int32_t(j >> 3), bz = int32_t(k >> 3);
    const auto run =
        std::lower_bound(insideRuns.begin(), insideRuns.end(), SdfInsideRun{0, 0, by, bz},
                         [](const SdfInsideRun& a, const SdfInsideRun& b) {
                             return a.z != b.z ? a.z < b.z : (a.y != b.y ? a.y < b.y : a.x1 <= b.x0);
                         });
    for (auto r = run; r != insideRuns.end() && r->z == bz && r->y == by; ++r)
        if (bx >= r->x0 && bx < r->x1) return float(-background);
    return float(background);
}

std::vector<float> SignedDistanceField::dense() const {
    const Vec3i d = dims();
    checkMemory(uint64_t(d.x * d.y * d.z) * sizeof(float), "the dense distance field");
    std::vector<float> out(std::size_t(d.x * d.y * d.z), float(background));
    const auto at = [&](int64_t i, int64_t j, int64_t k) -> float& {
        return out[std::size_t((k * d.y + j) * d.x + i)];
    };
    for (const SdfInsideRun& r : insideRuns)
        for (int64_t k = 8 * int64_t(r.z); k < 8 * int64_t(r.z) + 8; ++k)
            for (int64_t j = 8 * int64_t(r.y); j < 8 * int64_t(r.y) + 8; ++j)
                for (int64_t i = 8 * int64_t(r.x0); i < 8 * int64_t(r.x1); ++i)
                    at(i, j, k) = float(-background);
    parallelFor(0, int64_t(leaves.size()), 64, [&](int64_t b, int64_t e) {
        for (int64_t l = b; l < e; ++l) {
            const SdfLeaf& leaf = leaves[std::size_t(l)];
            for (int n = 0; n < 512; ++n) {
                const int64_t i = leaf.origin.x + (n >> 6), j = leaf.origin.y + ((n >> 3) & 7),
                              k = leaf.origin.z + (n & 7);
                if (i < d.x && j < d.y && k < d.z) at(i, j, k) = leaf.values[std::size_t(n)];
            }
        }
    });
    return out;
}

void SignedDistanceField::activeVoxels(std::vector<std::array<int32_t, 3>>& indices,
                                       std::vector<float>& values) const {
    indices.clear();
    values.clear();
    indices.reserve(std::size_t(activeCount()));
    values.reserve(std::size_t(activeCount()));
    for (const SdfLeaf& leaf : leaves)
        for (int n = 0; n < 512; ++n)
            if ((leaf.active[std::size_t(n >> 6)] >> (n & 63)) & 1) {
                indices.push_back({int32_t(leaf.origin.x + (n >> 6)), int32_t(leaf.origin.y + ((n >> 3) & 7)),
                                   int32_t(leaf.origin.z + (n & 7))});
                values.push_back(leaf.values[std::size_t(n)]);
            }
}

SignedDistanceField signedDistanceField(const MeshView& mesh, const Frame& frame, const SdfOptions& options) {
    return detail::signedDistanceField(mesh, frame, options, detail::SdfSign::Auto);
}

SignedDistanceField detail::signedDistanceField(const MeshView& mesh, const Frame& frame,
                                                const SdfOptions& options, SdfSign sign,
                                                SdfSignReport* report, SdfSink* sink) {
    validateMesh(mesh, "signed distance field");
    if (frame.isPerspective() || frame.isOriented())
        fail("signed distance fields need an axis-aligned orthographic frame");
    if (!options.full && !(options.bandVoxels >= 1 && std::isfinite(options.bandVoxels)))
        fail("signed distance field: the band must be at least 1 voxel wide, got ", options.bandVoxels);
    if (options.brickSize < 8 || options.brickSize % 8)
        fail("signed distance field: the brick size must be a positive multiple of 8, got ",
             options.brickSize);
    // World-axis dimensions, sliced along z.
    Vec3i dims;
    dims[columnXAxis(frame.axis())] = frame.width();
    dims[columnYAxis(frame.axis())] = frame.height();
    dims[sliceAxis(frame.axis())] = frame.depth();
    SignedDistanceField f;
    f.frame = Frame::orthographic(frame.box(), Axis::Z, dims.x, dims.y, dims.z);
    f.full = options.full;
    f.fill = options.fill != Fill::Auto ? options.fill
                                        : (analyzeTopology(mesh).closed() ? Fill::Parity : Fill::Gwn);
    const Vec3d cell = f.frame.cellSize();
    const double maxCell = std::max({cell.x, cell.y, cell.z});
    f.bandVoxels = options.full ? 0.0 : options.bandVoxels;
    f.background = options.full ? length(f.frame.box().extent()) : options.bandVoxels * maxCell;

    detail::SdfParams p;
    p.dims = dims;
    p.lo = f.frame.box().lo;
    p.cell = cell;
    p.width = f.background;
    p.full = options.full;
    // A brick larger than the grid is the grid: clamped (to a multiple of 16, the gwn fill's
    // tiles), so that the tiled voxelizer's bricks are not sized for voxels that do not exist.
    // The field is the same for every brick size.
    p.brick = std::min(options.brickSize, (std::max({dims.x, dims.y, dims.z}) + 15) / 16 * 16);
    // Every voxel of a full field costs a distance query: bricks of 32^3 keep the polls between
    // bricks (Ctrl-C, a progress callback) a few milliseconds apart instead of seconds.
    if (options.full) p.brick = std::min<int64_t>(p.brick, 32);
    // A centre closer than W to the surface is within ceil(W / cell + 1/2) - 1 cells of the
    // conservative cell holding its nearest point (the relative 1e-9 absorbs rounding).
    for (int a = 0; a < 3 && !options.full; ++a)
        p.dilation[a] = int64_t(std::ceil(0.5 + f.background / cell[a] * (1 + 1e-9))) - 1;

    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Solid;
    vo.fill = f.fill;
    vo.threads = options.threads;
    // Tiled where the fill allows it: the sign brick by brick, no grid of the whole volume.
    const bool tiled = sign == SdfSign::Auto && wholeGridReason(f.frame, vo).empty();
    SdfSignReport used;
    used.tiled = tiled;
    if (sink) sink->begin(f);
    const auto run = [&] {
        const detail::TriangleBvh bvh(mesh);
        const detail::SdfBuilder builder(p, bvh);
        if (tiled) {
            auto [leaves, runs] = detail::sdfTilesStreamed(mesh, f.frame, vo, p, bvh, builder,
                                                           options.progress, &used.workingBytes, sink);
            f.leaves = std::move(leaves);
            f.insideRuns = std::move(runs);
            return;
        }
        // The solid voxelization is quick next to the distances: a tenth of the progress.
        detail::ProgressRange solidProgress(options.progress, 0.0, 0.1),
            brickProgress(options.progress, 0.1, 1.0);
        vo.progress = solidProgress.get();
        const VoxelGrid solid = voxelize(mesh, f.frame, vo);
        used.workingBytes = solid.bits.byteCount();
        const detail::SlabBits solidBits{
            solid.bits.words(), dims.x, solid.bits.wordsPerColumn(), 0, dims.z, 0, 0};
        auto [leaves, runs] = detail::sdfTiles(p, bvh, builder, solidBits, brickProgress.get(), sink);
        f.leaves = std::move(leaves);
        f.insideRuns = std::move(runs);
    };
    withThreads(options.threads, run);
    if (report) *report = used;
    return f;
}

} // namespace voxfx
