// voxfx — tiled voxelization: grids of any size in bounded memory (#23; DESIGN.md: "Grids larger
// than memory are voxelized tile by tile (parity carried along the columns from tile to tile)").
//
// EXPERIMENTAL until #23 closes: the signature of voxelizeTiles and GridTile is meant to stay.
//
// The grid of an axis-aligned orthographic frame with uniform slicing is cut into *bricks*, boxes of
// B x B x B cells (B = TileOptions::brickSize) in the frame's own index space (column x, row y,
// slice s), the last ones along each axis clipped to the grid:
//
//   brick (bx, by, bs) holds cells x in [bx B, bx B + B), y in [by B, by B + B), s in [bs B, bs B + B)
//
// A *stack* is the bricks sharing their columns (bx, by), in slice order. Each brick is voxelized
// on its own into a slicemap of the brick's size (voxfx/bitgrid.hpp's layout: columns x, y of the
// brick, slices along the frame's axis) and handed to the caller's `visit`; the inside modes carry
// each column's state from one brick of its stack to the next (parity: whether an odd number of
// crossings lie in front; winding: the winding number so far), so no brick needs more than its
// own cells. The bits of every brick are exactly the bits of those cells in the dense voxelize()
// result, for every mode and for the parity, winding and gwn fills (the same rasterizer kernels
// over a window of columns, the same tie rule, the same slice mapping).
//
// Uniform bricks: a brick that no triangle reaches and whose columns all carry the same state in
// is uniform: `visit` gets GridTile::uniform with its value and no bits. At large resolutions
// nearly all bricks are uniform, so the cost grows with the surface (bricks the mesh reaches),
// not with the volume.
//
// Fills: parity and winding run per column; gwn runs the dense fill's block rule on each brick
// (its blocks of 16 cells are the dense ones when B is a multiple of 16), with the conservative
// surface of a one-cell halo around the brick. Flood and vote need the whole grid (a flood
// crosses bricks any number of times; vote slices along all three axes): voxelizeTiles refuses
// them (voxfx::Error naming the fill). wholeGridFillReason() says so in advance.
//
// Memory: per worker thread, a brick (two for the solid-conservative, interior and gwn modes:
// B^3 / 8 bytes each, 256 KiB at 128) and the fragments of one stack; plus the triangles' bins
// (one entry per triangle and stack it reaches) and the mesh's projected vertices (24 bytes each).
// The bins are counted first and checked against TileOptions::memoryBytes.
//
// Thread-safety: `visit` is called from worker threads, concurrently for bricks of different
// stacks; the bricks of one stack are visited in slice order on one thread. Each call owns its
// brick (the bits are valid during the call only and must not be written). Which thread visits
// which stack depends on scheduling, the bits do not: a visitor that writes each brick's result
// to the brick's own place is deterministic for any thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

struct TileOptions {
    /// Brick edge B in cells: a positive multiple of 8 (OpenVDB's leaf edge), or 0 for 128 (the
    /// cells of one node of OpenVDB's lowest internal level, so a brick is one node of a sparse
    /// tree). The gwn fill needs a multiple of 16. Results are the same for every value.
    int64_t brickSize = 0;
    /// Bytes the tiling may hold at once (bins, bricks, fragments); 0 = availableMemoryBytes()
    /// (the machine's available memory, or VOXFX_MEMORY_LIMIT when smaller).
    uint64_t memoryBytes = 0;
    /// When given, receives the bytes the tiling holds (the bins, the projected vertices, the bricks
    /// and fragments of every worker thread) before the first brick is visited: what a caller that
    /// keeps results (a sparse tree) has left of its budget. Not owned.
    uint64_t* workingBytes = nullptr;
    /// Only the stacks (bx, by) with stackX0 <= bx < stackX1 and stackY0 <= by < stackY1 are
    /// voxelized and visited: one piece of the grid (a task of voxfx.dask.voxelize_grid). A stack's
    /// bricks depend on the stack alone (its parity starts empty in front of its first brick), so
    /// the pieces of a grid, run anywhere in any order, are the bricks of the whole run. Clipped to
    /// the grid's stacks; the default (-1 ends) is every stack.
    int64_t stackX0 = 0, stackY0 = 0, stackX1 = -1, stackY1 = -1;
};

/// One brick as `visit` sees it. Cell (x, y, s) of the brick is cell (x0 + x, y0 + y, s0 + s) of
/// the frame (column x, row y, slice s along the frame's axis).
struct GridTile {
    int64_t x0 = 0, y0 = 0, s0 = 0;
    int64_t width = 0, height = 0, depth = 0; ///< the brick's size (B, clipped to the grid)
    /// Every cell of the brick has `value`; `bits` is then empty (null words).
    bool uniform = false;
    bool value = false;
    /// width x height x depth cells in the slicemap layout (read only; valid during the call).
    BitGridView bits;
};

/// Why `options` cannot be voxelized tile by tile in `frame` (the fill needs the whole grid, the
/// frame is perspective, oriented or locally sliced), or an empty string when it can. Fill::Auto
/// is taken as Parity: ask with resolveFill(mesh, frame, options) for a mesh that may be open.
std::string wholeGridReason(const Frame& frame, const VoxelizeOptions& options);

/// Voxelizes `mesh` into `frame` brick by brick and calls visit(tile) once per brick (uniform
/// ones included), as described in the file comment. Fill::Auto is decided as voxelize() decides
/// it (resolveFill; options.report receives it). options.slicing must be Uniform and
/// options.device is ignored (bricks run on the CPU); options.threads, progress and rasterPath
/// apply. Validates the mesh first. Throws voxfx::Error for what wholeGridReason() names, a
/// brick size that is not a positive multiple of 8 (16 for gwn), bins larger than the memory
/// budget (the message gives the bytes needed), cancellation, and whatever `visit` throws (the
/// first exception stops the work and is rethrown on the calling thread).
/// Cost: O(triangles x stacks they reach + fragments + B^3 / 64 words per brick the mesh reaches
/// + one step per uniform brick).
void voxelizeTiles(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& options,
                   const TileOptions& tiles, const std::function<void(const GridTile&)>& visit);

} // namespace voxfx
