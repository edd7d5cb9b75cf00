// voxfx — counting and traversal on bit grids: column popcounts, rays through the grid (3D DDA)
// and volume. These are the lookups the shadow and refraction effects call per pixel, so they are
// exact and allocation-free (GI08 §6 "counting"; Amanatides & Woo 1987 for the traversal).
//
// Coordinates. "Grid coordinates" are the frame's (gx, gy, depth) of an orthographic, uniformly
// sliced grid: cell (x, y, s) is the box [x, x+1) x [y, y+1) x [s, s+1), so the whole grid is
// [0, W] x [0, H] x [0, D]. World coordinates go through Frame::gridFromWorld. For perspective
// frames a column already is a ray from the light or eye, so countColumnRange is the lookup.
// Thread-safety: every query is read-only and may run concurrently on one grid; filledVolume,
// filledCellIndices, filledCellCenters and filledAt use worker threads, the per-column and
// per-segment lookups run on the calling thread.
#pragma once

#include <cstdint>
#include <span>

#include "voxfx/bitgrid.hpp"
#include "voxfx/math.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx {

/// Filled cells of column (x, y) among slices [s0, s1). The range is clamped to [0, D); an empty
/// or inverted range gives 0. Cost: one popcount per 64 slices of the range, masks at both ends,
/// no branches per bit. Preconditions: 0 <= x < W and 0 <= y < H (checked in debug builds).
int64_t countColumnRange(const BitGrid& grid, int64_t x, int64_t y, int64_t s0, int64_t s1);

/// Same as countColumnRange on one column given as `words` (the slicemap layout of BitGrid),
/// `depth` slices long. For callers that already hold a column pointer.
int64_t countColumnRange(const uint64_t* words, int64_t depth, int64_t s0, int64_t s1);

/// World volume of the filled cells.
///   orthographic, uniform slicing: count * cell volume;
///   orthographic, local slicing:   per column, count * cell area * slice thickness of that column;
///   perspective:                   per cell, the exact volume of its frustum piece: a pixel
///                                  covers (2 z tanX / W) (2 z tanY / H) at view depth z, so the
///                                  cell between depths z0 and z1 holds 4 tanX tanY (z1^3 - z0^3)
///                                  / (3 W H).
/// Cost: one pass of popcounts over the grid (perspective: per filled cell). Empty grid: 0.
double filledVolume(const VoxelGrid& grid);

/// World-axis indices (i, j, k) (cells along x, y, z) of every filled cell of an axis-aligned
/// orthographic, uniformly sliced grid, in the order of i, then j, then k: the C order of an
/// array indexed [x, y, z], as numpy.argwhere lists them. Cell n goes to out[3n], out[3n + 1],
/// out[3n + 2]; `out` holds exactly 3 * grid.bits.count() values (sizes before data: count
/// first). Cost: one popcount pass and one pass over the filled cells' words, over worker
/// threads (`threads`, 0 = all; the result does not depend on it); a grid sliced along x or y is
/// resliced along z first (one transpose pass, a copy of the grid). No dense array. Throws
/// voxfx::Error for perspective, oriented or locally sliced grids, more than 2^31 - 1 cells along
/// an axis, or a size mismatch.
void filledCellIndices(const VoxelGrid& grid, std::span<int32_t> out, int threads = 0);

/// World-space centres of the same cells in the same order: box.lo + (index + 0.5) * cellSize()
/// per axis, computed in double (then rounded once for float). Same cost, sizes and errors.
void filledCellCenters(const VoxelGrid& grid, std::span<double> out, int threads = 0);
void filledCellCenters(const VoxelGrid& grid, std::span<float> out, int threads = 0);

/// out[i] = 1 when the cell holding points[i] is filled: cells are half-open (a point on the
/// face between two cells belongs to the one above), points outside the grid or not finite give
/// 0. Any orthographic, axis-aligned grid (uniform or local slicing). Sizes must match. Cost:
/// one lookup per point, over worker threads. Throws voxfx::Error for perspective or oriented
/// grids or a size mismatch.
void filledAt(const VoxelGrid& grid, std::span<const Vec3d> points, std::span<uint8_t> out, int threads = 0);

/// What a segment crosses. Lengths are in the units of the space the segment was given in.
struct SegmentHits {
    int64_t cellsVisited = 0; ///< grid cells the segment passes through with positive length
    int64_t filledCells = 0;  ///< of those, the filled ones
    double filledLength = 0;  ///< summed length of the pieces of the segment inside filled cells
    double length = 0;        ///< length of the whole segment (inside and outside the grid)
    /// Fraction of the segment inside filled cells, in [0, 1] (0 for a zero-length segment).
    double filledFraction() const { return length > 0 ? filledLength / length : 0.0; }
};

/// Walks the segment a -> b (grid coordinates) through the grid with Amanatides & Woo's DDA and
/// reports the cells it crosses. The segment is clipped to the grid box first; parts outside
/// count in `length` only. Cell entry and exit parameters are recomputed exactly from the
/// endpoints at every step (no accumulated increments), so the summed lengths match a per-cell
/// box clip to rounding. A segment running exactly inside a plane between cells is assigned to
/// the cell above the plane (cells are half-open). Non-finite endpoints or a zero-length
/// segment give all zeros. Cost: O(cells crossed), no allocation.
SegmentHits traceSegmentGrid(const BitGrid& grid, const Vec3d& a, const Vec3d& b);

/// traceSegmentGrid for world-space endpoints of an orthographic, uniformly sliced grid; lengths
/// come back in world units (the world-to-grid map is affine, so length fractions carry over).
/// Throws voxfx::Error for perspective or locally sliced frames (use countColumnRange).
SegmentHits traceSegment(const VoxelGrid& grid, const Vec3d& aWorld, const Vec3d& bWorld);

} // namespace voxfx
