// voxfx — density maps and normals of solid bit grids (GI08 §6).
//
// The density map of level L counts, for every block of 2^L x 2^L x 2^L cells of a BitGrid, how
// many are filled (0 .. 8^L). Level 1 is GI08's 2x2x2 box filter, computed bit-parallel: pairwise
// sums of neighbouring depth bits with masks (SWAR, so sums never spill into the next lane), then
// sums over the 2 x 2 neighbour columns. Level L+1 repeats the same step on the counts of level L
// (GI08: "larger power-of-two kernels by repetition"). Occupancy = count / 8^L is a smooth field
// in [0, 1] that behaves like a local distance field; its gradient gives normals.
//
// DensityGrid layout (the BitGrid layout with b-bit lanes instead of bits):
//
//   cells:   W' x H' x D' = ceil(W / 2^L) x ceil(H / 2^L) x ceil(D / 2^L); cell (X, Y, S) counts
//            the filled fine cells (x, y, s) with x / 2^L = X, y / 2^L = Y, s / 2^L = S. Blocks
//            cut by the grid's border count only the cells that exist.
//   lanes:   b = 2^(L+1) bits per cell: L=1: 4 bits (max 8), L=2: 8 (64), L=3: 16 (512),
//            L=4: 32 (4096), L=5: 64 (32768). Levels 1..5 (kernels 2 .. 32).
//   columns: row-major, column c = Y * W' + X, each wordsPerColumn() = ceil(D' * b / 64) words;
//            cell S is lane (S mod 64/b) of word S / (64/b), lane 0 in the lowest bits.
//   level 1, word k of a column (16 cells of 4 bits):
//            bit  63..60   59..56  ...   7..4    3..0
//            cell 16k+15   16k+14  ...   16k+1   16k
//   Lanes of cells >= D' (padding) are always zero.
//
// Density-grid coordinates: cell (X, Y, S) covers [X, X+1) x [Y, Y+1) x [S, S+1) and its centre
// is (X + 0.5, Y + 0.5, S + 0.5); a point g in the fine grid's coordinates is g / 2^L here.
// Axes are the grid's (column x, column y, slice); worldFromGridNormal turns normals into world
// directions for orthographic frames.
// Thread-safety: calls may run concurrently on shared const inputs (no global state); each
// computing function spreads its work over worker threads (`threads`), the samplers are
// single-threaded and read-only.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/math.hpp"

namespace voxfx {

/// Counts of filled cells per 2^L block, packed in b-bit lanes (see the file comment).
class DensityGrid {
public:
    DensityGrid() = default;
    /// A zeroed density grid of level `level` (1..5) with W' x H' x D' cells. Throws voxfx::Error
    /// for a level outside 1..5 or a non-positive dimension.
    DensityGrid(int level, int64_t w, int64_t h, int64_t d);

    int level() const { return level_; }
    /// Kernel edge in fine cells: 2^level.
    int64_t kernel() const { return int64_t(1) << level_; }
    /// Bits per cell: 2^(level+1).
    int laneBits() const { return 2 << level_; }
    int64_t lanesPerWord() const { return 64 / laneBits(); }
    /// Largest count a cell can hold: 8^level (a full block).
    uint64_t maxCount() const { return uint64_t(1) << (3 * level_); }

    int64_t width() const { return w_; }
    int64_t height() const { return h_; }
    int64_t depth() const { return d_; }
    int64_t wordsPerColumn() const { return wpc_; }
    int64_t columnCount() const { return w_ * h_; }
    int64_t cellCount() const { return w_ * h_ * d_; }
    int64_t wordCount() const { return w_ * h_ * wpc_; }
    uint64_t byteCount() const { return uint64_t(wordCount()) * 8; }
    bool empty() const { return storage_.empty(); }

    uint64_t* words() { return storage_.words(); }
    const uint64_t* words() const { return storage_.words(); }
    uint64_t* column(int64_t x, int64_t y) { return storage_.words() + (y * w_ + x) * wpc_; }
    const uint64_t* column(int64_t x, int64_t y) const { return storage_.words() + (y * w_ + x) * wpc_; }

    /// Count of cell (x, y, s), 0 .. maxCount(). Preconditions checked in debug builds.
    uint64_t count(int64_t x, int64_t y, int64_t s) const {
        VOXFX_DCHECK(x >= 0 && x < w_ && y >= 0 && y < h_ && s >= 0 && s < d_);
        // 2^(5 - level) lanes of 2^(level + 1) bits per word: shifts, no division.
        const int lanesLog2 = 5 - level_, bitsLog2 = level_ + 1;
        const uint64_t word = column(x, y)[s >> lanesLog2];
        const int shift = int(s & ((int64_t(1) << lanesLog2) - 1)) << bitsLog2;
        return level_ == 5 ? word : (word >> shift) & ((uint64_t(1) << (2 << level_)) - 1);
    }
    /// Count of cell (x, y, s), or 0 outside the grid (any integer coordinates).
    uint64_t countOrZero(int64_t x, int64_t y, int64_t s) const {
        return (x < 0 || y < 0 || s < 0 || x >= w_ || y >= h_ || s >= d_) ? 0 : count(x, y, s);
    }
    /// count / maxCount, in [0, 1].
    float occupancy(int64_t x, int64_t y, int64_t s) const {
        return float(count(x, y, s)) / float(maxCount());
    }
    /// Sum of all counts (= filled cells of the source grid).
    uint64_t total() const;
    bool operator==(const DensityGrid& o) const = default;

private:
    int level_ = 0;
    int64_t w_ = 0, h_ = 0, d_ = 0, wpc_ = 0;
    // The words live in a BitGrid of wordCount() one-word columns: the same zeroed, 64-byte
    // aligned, huge-page mapped memory as the grids themselves (fresh 4 KiB pages fault slowly).
    BitGrid storage_;
};

struct DensityOptions {
    /// Kernel 2^level, 1..5.
    int level = 1;
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
};

/// The density map of `grid` (see the file comment). Level 1 reads every grid word once and
/// writes half as many bytes; each further level costs a pass over the previous level's counts
/// (8x fewer cells, 2x wider lanes). Throws voxfx::Error for a level outside 1..5. An empty
/// grid gives an empty density grid.
DensityGrid computeDensity(const BitGrid& grid, const DensityOptions& options = {});

/// The same into a caller-owned density grid, reused when it already has the right level and
/// size (no allocation for level 1; higher levels allocate their intermediate levels).
void computeDensity(const BitGrid& grid, DensityGrid& out, const DensityOptions& options = {});

/// The next level (kernel doubled) from a density grid of level L < 5: every output cell sums
/// the 2 x 2 x 2 input cells of its block (missing border cells count 0).
DensityGrid coarsenDensity(const DensityGrid& density, int threads = 0);

/// Occupancy (count / 8^L) of every cell as floats, in cell order (Y * W' + X) * D' + S, the
/// layout of the column words. `out` must hold density.cellCount() values (voxfx::Error
/// otherwise). The vector form allocates exactly that.
void occupancyField(const DensityGrid& density, std::span<float> out);
std::vector<float> occupancyField(const DensityGrid& density);

/// Gradient of the counts at cell (x, y, s) by central differences over the six face
/// neighbours (cells outside the grid count 0), in counts per cell: each component is
/// (count(+1) - count(-1)) / 2, so within [-maxCount / 2, maxCount / 2].
Vec3f densityGradient(const DensityGrid& density, int64_t x, int64_t y, int64_t s);

/// Outward unit normal at cell (x, y, s): -gradient / |gradient|, pointing from filled towards
/// empty space; the zero vector where the gradient vanishes (inside a solid or far from it).
Vec3f densityNormal(const DensityGrid& density, int64_t x, int64_t y, int64_t s);

/// Occupancy at any point p (density-grid coordinates) by trilinear interpolation between cell
/// centres; 0 outside the grid. Non-finite p gives 0.
float sampleOccupancy(const DensityGrid& density, const Vec3d& p);

/// Outward unit normal at any point p (density-grid coordinates): the trilinear interpolation of
/// the eight surrounding cells' central-difference gradients, negated and normalized; the zero
/// vector where it vanishes or p is not finite. Cost: 48 count lookups.
Vec3f sampleNormal(const DensityGrid& density, const Vec3d& p);

/// Compact normals: octahedral encoding in 16 bits (8 bits per coordinate of the octahedron's
/// unfolding, 0..254 with 127 = 0). Angular error <= 1 degree for unit input. The zero vector
/// (and non-finite input) encodes as kNoNormal and decodes to the zero vector.
constexpr uint16_t kNoNormal = 0xFFFF;
uint16_t encodeNormalOct16(const Vec3f& n);
Vec3f decodeNormalOct16(uint16_t code);

/// densityNormal of every cell, octahedrally encoded, in cell order (Y * W' + X) * D' + S.
/// `out` must hold density.cellCount() values (voxfx::Error otherwise).
void quantizedNormals(const DensityGrid& density, std::span<uint16_t> out, int threads = 0);
std::vector<uint16_t> quantizedNormals(const DensityGrid& density, int threads = 0);

/// The orthographic, uniformly sliced frame whose cells are the density cells of `fine` at
/// `level`: same lower corner and axis, cells 2^level times larger, W' x H' x D' of them (the
/// box grows past the fine box when a dimension is not a multiple of 2^level). Throws
/// voxfx::Error for perspective or locally sliced frames.
Frame densityFrame(const Frame& fine, int level);

/// World direction of a normal given in grid axes (column x, column y, slice) of an orthographic
/// frame: component i is divided by the cell size along that axis (normals transform with the
/// inverse transpose), then normalized. Zero stays zero.
Vec3d worldFromGridNormal(const Frame& frame, const Vec3d& gridNormal);

} // namespace voxfx
