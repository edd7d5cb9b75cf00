// voxfx — SparseGrid: occupancy without the dense grid (#23; DESIGN.md: "the sparse container is
// OpenVDB's (leaves for the surface, tiles for uniform regions), with OpenVDB's own tools for what
// they already do on sparse trees").
//
// EXPERIMENTAL until #23 closes.
//
// A SparseGrid is a set of filled cells of the grid of an axis-aligned orthographic frame, held in
// an OpenVDB tree (a BoolGrid: 8^3 leaves where cells are mixed, tiles of 8^3, 128^3 and 4096^3
// cells where they are uniform), so its memory grows with the surface, not the volume. Cells
// are indexed (i, j, k) along world x, y, z whatever the frame's slicing axis; cell (i, j, k)
// covers [lo + (i, j, k) * cell, lo + (i + 1, j + 1, k + 1) * cell] with lo = frame().box().lo
// and cell = frame().cellSize(), as in a VoxelGrid (VoxelGrid::atWorldIndex). Operations may
// create cells outside [0, dims) (a dilation grows past the grid's sides); they stay cells of the
// same lattice.
//
// OpenVDB sits behind the voxfx_vdb module (loaded on first use, as for .vdb files): every
// operation but the accessors of the frame may throw voxfx::Error when the module is missing.
//
// Thread-safety: a SparseGrid is a value (copies are deep). Const members may be called
// concurrently; non-const ones need exclusive access. Operations use worker threads internally
// (OpenVDB's, inside the caller's withThreads limit).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "voxfx/csg.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/tiled.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

/// An inclusive box of cell indices (i, j, k); empty when a lo exceeds its hi.
struct IndexBox {
    Vec3i lo{0, 0, 0}, hi{-1, -1, -1};
    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
};

/// Neighbourhoods of SparseGrid::dilate and erode.
enum class Neighbours : uint8_t {
    Face = 6,  ///< the six cells sharing a face: n steps reach an octahedron of radius n
    Edge = 18, ///< faces and edges
    Box = 26   ///< faces, edges and corners: n steps reach the box of half-size n (morphology.hpp's box)
};

class SparseGrid {
public:
    /// An empty grid without a frame.
    SparseGrid();
    /// An empty grid of `frame`'s cells. Throws voxfx::Error unless the frame is axis-aligned
    /// orthographic with uniform slicing.
    explicit SparseGrid(const Frame& frame);
    ~SparseGrid();
    SparseGrid(const SparseGrid& o);
    SparseGrid& operator=(const SparseGrid& o);
    SparseGrid(SparseGrid&& o) noexcept;
    SparseGrid& operator=(SparseGrid&& o) noexcept;

    /// The filled cells of a dense grid (locally sliced grids are resampled to uniform first).
    /// Cost ~ one pass over the dense grid.
    static SparseGrid fromDense(const VoxelGrid& grid);
    /// The cells [0, dims) as a dense grid in frame() (sliced along its axis). Throws voxfx::Error
    /// when the dense grid needs more memory than is available.
    VoxelGrid toDense() const;
    /// The cells of `box` (any box of indices, inside [0, dims) or not) as a dense grid sliced
    /// along Z whose frame is the box's part of the lattice. Throws as toDense().
    VoxelGrid toDense(const IndexBox& box) const;

    const Frame& frame() const { return frame_; }
    /// Cells along world x, y, z.
    Vec3i dims() const;
    /// Number of filled cells. Cost ~ leaves + tiles.
    int64_t count() const;
    /// The filled cells' bounding box (empty when there are none).
    IndexBox bounds() const;
    /// Whether cell (i, j, k) is filled (any index: outside the grid's box is a cell too).
    bool at(int64_t i, int64_t j, int64_t k) const;
    /// Bytes the tree takes (OpenVDB's memUsage; walks the tree).
    uint64_t memoryBytes() const;
    bool empty() const { return count() == 0; }

    /// Topology operations with a grid of the same frame (voxfx::Error otherwise): OpenVDB's
    /// topologyUnion, topologyIntersection and topologyDifference.
    SparseGrid& unite(const SparseGrid& o);
    SparseGrid& intersect(const SparseGrid& o);
    SparseGrid& subtract(const SparseGrid& o);
    /// OpenVDB's dilateActiveValues / erodeActiveValues: `steps` >= 0 steps over `neighbours`.
    /// Cells outside the grid's box count as empty (erosion eats from the sides; dilation grows
    /// past them). With Neighbours::Box, r steps equal voxfx::morphology's box of radius r.
    SparseGrid& dilate(int steps, Neighbours neighbours = Neighbours::Box);
    SparseGrid& erode(int steps, Neighbours neighbours = Neighbours::Box);
    /// Fills every cell of `box` (OpenVDB's fill: tiles where a whole node is covered).
    SparseGrid& fill(const IndexBox& box);
    /// Empties every cell outside `box` (OpenVDB's clip); an empty box empties the grid.
    SparseGrid& clip(const IndexBox& box);
    /// The cells [0, dims) as a box.
    IndexBox box() const;

    /// The filled cells as (i, j, k) triples of int32 (3 * count() values), without a dense grid:
    /// the cells of each leaf, then of each tile, in the tree's order (the same on every run).
    /// World centre of a cell: frame().box().lo + (ijk + 0.5) * frame().cellSize(). Throws
    /// voxfx::Error when an index does not fit int32 or the array needs more memory than is
    /// available.
    std::vector<int32_t> coordinates() const;

    /// Moves the grid by `offset` (world units): the frame is frame().translated(offset), the
    /// cells keep their indices. Cost O(1).
    void translate(const Vec3d& offset) { frame_ = frame_.translated(offset); }

    /// For io/: the module's handle and the tree index of cell (0, 0, 0).
    const void* handle() const { return tree_; }
    const Vec3i& treeOrigin() const { return origin_; }
    /// For io/ (readSparseGrid): a grid over `frame` owning the module's handle `tree`, whose cell
    /// (0, 0, 0) is tree index `origin`.
    static SparseGrid adopt(const Frame& frame, void* tree, const Vec3i& origin);

private:
    void requireSameFrame(const SparseGrid& o, const char* what) const;
    Frame frame_;
    Vec3i origin_{0, 0, 0};
    void* tree_ = nullptr; // the voxfx_vdb module's grid
};

/// voxfx::morphology on a sparse grid, bit for bit the dense result on the cells [0, dims) (cells
/// outside are dropped first, and after every step, as a dense grid has none): the box of half-size
/// `radius` on every axis is `radius` steps of OpenVDB's 26-neighbour dilation or erosion, and
/// the border is emulated on the tree: Neutral and Filled erosions see filled cells outside where
/// they matter (those within `radius` of a filled cell within `radius` of a side), a Filled
/// dilation fills the cells within `radius` of a side. Memory grows with the surface (and, for
/// Filled dilation, the sides). Throws voxfx::Error for a negative radius or one over 2^20.
SparseGrid morphology(const SparseGrid& grid, MorphOp op, int64_t radius,
                      MorphBorder border = MorphBorder::Neutral);

/// Evaluates a CSG expression (voxfx/csg.hpp) on sparse grids with OpenVDB's topology union,
/// intersection and difference (xor as (a | b) - (a & b)); the leaves must share one frame
/// (voxfx::Error otherwise). Bit for bit voxfx::evaluateCsg on the leaves' dense grids.
SparseGrid evaluateCsg(const CsgNode& node, const std::function<SparseGrid(const std::string&)>& leaf);

/// Voxelizes `mesh` into `frame` as a sparse grid, tile by tile (voxfx/tiled.hpp): the dense grid
/// is never built and memory grows with the surface. The cells are those of voxelize(mesh, frame,
/// options) bit for bit; Fill::Auto is decided as voxelize() decides it (resolveFill, which writes
/// options.report). Fills that need the whole grid (flood, vote: wholeGridReason) voxelize
/// the dense grid and convert it when it fits in tiles.memoryBytes (default: the memory
/// available), else throw voxfx::Error naming the fill and the memory it needs; so do locally
/// sliced requests. The tree is checked against the same budget as it grows (voxfx::Error with
/// the bytes it reached). options.device is ignored (bricks run on the CPU) and the note says so.
SparseGrid voxelizeSparse(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& options = {},
                          const TileOptions& tiles = {});

} // namespace voxfx
