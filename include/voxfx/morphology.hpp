// voxfx — mathematical morphology on bit grids with a box structuring element (GI08 §6).
//
// Dilation sets a cell when any cell of the box [x-rx, x+rx] x [y-ry, y+ry] x [s-rz, s+rz]
// around it is set; erosion keeps a cell when all of them are set. Opening = dilation of the
// erosion (removes parts thinner than the box), closing = erosion of the dilation (fills gaps
// narrower than the box). The box is separable, and each axis is a sliding OR/AND window:
//   along x and y: whole column words of neighbour columns combined word by word;
//   along depth:   shifts of the column's words (bits move between neighbouring words).
// Radii are in cells along the grid's axes (column x, column y, slice); 0 leaves an axis alone.
//
// Border: what cells outside the grid count as.
//   Neutral (default)  outside cells are ignored: dilation ORs and erosion ANDs only the part of
//                      the box inside the grid. Then closing(X) contains X and opening(X) is
//                      contained in X everywhere, borders included (the box always holds its
//                      centre), and erosion never eats from the grid's faces.
//   Empty              outside is empty: erosion removes cells within r of a face.
//   Filled             outside is filled: dilation fills cells within r of a face.
// Results are identical for any thread count and keep the padding bits zero.
// Thread-safety: calls may run concurrently on shared const inputs (no global state); each
// operation spreads its work over worker threads (`threads`).
#pragma once

#include <cstdint>
#include <string>

#include "voxfx/bitgrid.hpp"
#include "voxfx/device.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx {

enum class MorphOp : uint8_t { Erode, Dilate, Open, Close };
inline constexpr EnumName<MorphOp> kMorphOpNames[] = {
    {"erode", MorphOp::Erode},        {"dilate", MorphOp::Dilate},       {"open", MorphOp::Open},
    {"close", MorphOp::Close},        {"erosion", MorphOp::Erode, true}, {"dilation", MorphOp::Dilate, true},
    {"opening", MorphOp::Open, true}, {"closing", MorphOp::Close, true}};
enum class MorphBorder : uint8_t { Neutral, Empty, Filled };
inline constexpr EnumName<MorphBorder> kMorphBorderNames[] = {
    {"neutral", MorphBorder::Neutral}, {"empty", MorphBorder::Empty}, {"filled", MorphBorder::Filled}};

const char* toString(MorphOp op);
const char* toString(MorphBorder border);
/// "erode", "dilate", "open", "close" (also erosion, dilation, opening, closing); throws
/// voxfx::Error listing the allowed names otherwise.
MorphOp parseMorphOp(const std::string& name);
/// "neutral", "empty", "filled"; throws voxfx::Error listing the allowed names otherwise.
MorphBorder parseMorphBorder(const std::string& name);

struct MorphologyOptions {
    /// Box half-sizes in cells along column x, column y and slices (>= 0; voxfx::Error otherwise).
    int64_t rx = 1, ry = 1, rz = 1;
    MorphBorder border = MorphBorder::Neutral;
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
};

/// One morphological operation. x and depth are fused into one pass over the grid, a row at a
/// time: along x ~log2(2 rx + 1) doubling passes over the row (from cache); along depth, for
/// rz <= 3 the 2 rz shifted copies of each word, for rz < 64 ~log2(2 rz + 1) shift-ORs of a word
/// with its two neighbours, else ~log2(2 rz + 1) passes over the column padded with the fill.
/// y is a second pass reading 2 ry + 1 rows from cache. A pass is skipped when its radii are 0,
/// so a depth-only operation is one read and one write of the grid. Opening and closing cost
/// twice that. Extra memory: one grid when both passes run. An empty grid stays empty.
BitGrid morphology(const BitGrid& grid, MorphOp op, const MorphologyOptions& options = {});

/// The same into caller-owned grids, for repeated operations without allocation: `out` receives
/// the result and `scratch` holds the intermediate pass; each is reallocated only when its
/// dimensions differ from `grid`'s (its previous bits are overwritten). `out` and `scratch` must
/// be distinct from `grid` and from each other (voxfx::Error otherwise).
void morphology(const BitGrid& grid, MorphOp op, const MorphologyOptions& options, BitGrid& out,
                BitGrid& scratch);

inline BitGrid erode(const BitGrid& g, const MorphologyOptions& o = {}) {
    return morphology(g, MorphOp::Erode, o);
}
inline BitGrid dilate(const BitGrid& g, const MorphologyOptions& o = {}) {
    return morphology(g, MorphOp::Dilate, o);
}
inline BitGrid opening(const BitGrid& g, const MorphologyOptions& o = {}) {
    return morphology(g, MorphOp::Open, o);
}
inline BitGrid closing(const BitGrid& g, const MorphologyOptions& o = {}) {
    return morphology(g, MorphOp::Close, o);
}

/// Morphology of a grid with radii given along world x, y, z (mapped onto the grid's axes by its
/// frame's slicing axis); options.rx/ry/rz are ignored. The frame is kept.
VoxelGrid morphology(const VoxelGrid& grid, MorphOp op, const Vec3i& worldRadii,
                     const MorphologyOptions& options = {});

/// morphology on the GPU (voxfx/device.hpp), bit for bit the CPU's (options.threads is ignored);
/// voxfx::Error when no GPU can be used.
CudaGrid morphology(const CudaGrid& grid, MorphOp op, const MorphologyOptions& options);

} // namespace voxfx
