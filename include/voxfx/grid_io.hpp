// voxfx — reading and writing voxel grids: binvox, OpenVDB (.vdb), NRRD (.nrrd), and a mesh of
// the filled voxels (.ply, .obj) to look at in any mesh viewer; writing density maps (NRRD, VDB);
// and the grid tools' input, "a grid file or a mesh to voxelize" (loadOrVoxelize).
//
// World placement: every format carries the grid's world box so tools line voxels up with the
// source mesh. Voxel (i, j, k) (indices along world x, y, z) covers
// [lo + (i, j, k) * cell, lo + (i+1, j+1, k+1) * cell] and its centre is lo + (i + 0.5) * cell.
//   binvox: translate = lo, scale = longest world extent of the grid (binvox's convention),
//           data order x-major, then z, then y fastest (as binvox writes it). "dim" lists the
//           counts in data order, slowest first: nx nz ny (how read_binvox.cc and binvox-rw-py
//           decode it; classic readers want cubic grids, d d d). binvox has one scale, so
//           reading gives cubic cells of scale / max(dims): non-cubic cells do not survive.
//   vdb:    a BoolGrid (or FloatGrid 0/1) named "voxels" (default), class fog volume for float,
//           index-to-world transform = scale(cell) then translate(lo + cell/2), so index (i,j,k)
//           maps to the voxel centre (OpenVDB's cell-centred convention). Filled 8^3 blocks are
//           stored as tiles; the dimensions go in Vec3i metadata "voxfx_dims".
//   nrrd:   uint8 0/1, x fastest, "space origin" = centre of voxel (0,0,0), "space directions"
//           = cell sizes; raw encoding; "space: right-anterior-superior".
//   ply/obj: the exposed faces of filled voxels (between a filled voxel and an empty one or the
//           grid border) as quads, counter-clockwise seen from outside, in world coordinates
//           (ply binary little endian, float x y z, list uchar int). Corners are shared: each
//           lattice point is one vertex. Cost ~ a few passes over the grid plus the output.
//   npy:    (for NumPy, write-only) the occupancy as a bool array (nx, ny, nz) indexed [x, y, z], C
//           order: np.load(path) equals the Python module's grid.to_numpy().
//   npz:    (write-only) a zip archive as np.savez_compressed writes it (deflate): "occupancy" (the
//           .npy array), "origin" (world corner of voxel (0, 0, 0)) and "cell_size", float64 (3,).
//           Below 4 GiB (no zip64).
// All writers are atomic: they write a temporary file beside the target and rename it, so a
// failure leaves no partial output and an existing file untouched.
// Thread-safety: reads and writes of different paths may run concurrently (OpenVDB's one-time
// initialization is guarded); writing one path from two calls at once is undefined. NRRD and
// voxel-mesh writing use worker threads internally.
#pragma once

#include <string>

#include "voxfx/density.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

enum class GridFormat : uint8_t { Binvox, Vdb, Nrrd, Ply, Obj, Npy, Npz };
inline constexpr EnumName<GridFormat> kGridFormatNames[] = {
    {"binvox", GridFormat::Binvox}, {"vdb", GridFormat::Vdb}, {"nrrd", GridFormat::Nrrd},
    {"ply", GridFormat::Ply},       {"obj", GridFormat::Obj}, {"npy", GridFormat::Npy},
    {"npz", GridFormat::Npz}};

/// Format from the file extension; throws voxfx::Error listing the allowed extensions.
GridFormat gridFormatFromPath(const std::string& path);
const char* toString(GridFormat f);

/// Loads what reading or writing `path`'s format needs (the OpenVDB module for .vdb: tens of
/// milliseconds; nothing for the other formats or an unknown extension), so that a missing module
/// is reported before other work and the write does not pay the load. `background`: start the
/// load on another thread and return at once (failures are then reported by the next call that
/// needs the module); a later call without it waits for that load.
void prepareGridFormat(const std::string& path, bool background = false);

struct GridWriteOptions {
    bool vdbFloat = false; ///< vdb: FloatGrid with 1.0 in filled voxels instead of BoolGrid
    std::string gridName = "voxels";
    /// Sparse grids to .binvox and .nrrd: bytes of one dense slab of the streamed write (0: an
    /// eighth of the memory available, at least one slab of cells).
    uint64_t slabBytes = 0;
};

/// Writes an orthographic grid (locally sliced grids are resampled to uniform first); throws
/// voxfx::Error naming the path for perspective grids and failed writes.
void writeGrid(const VoxelGrid& grid, const std::string& path, const GridWriteOptions& options = {});
/// Reads binvox, vdb (first bool/float/double grid, active or > 0 voxels) or nrrd (nonzero voxels)
/// into an orthographic grid sliced along Z. Throws voxfx::Error on unreadable, malformed or
/// truncated files, naming the path. Limits: vdb needs an axis-aligned scale + translate
/// transform and no level sets (its grid spans "voxfx_dims" when present, else the active
/// voxels' box); nrrd needs uchar/signed char samples, raw encoding (gzip is rejected) and
/// diagonal space directions, read as world coordinates whatever the named space.
/// .ply/.obj are write-only.
VoxelGrid readGrid(const std::string& path);

class SparseGrid;
/// Writes a sparse grid (voxfx/sparse_grid.hpp), the dense grid never built: .vdb straight from
/// its tree (same conventions as above, "voxfx_dims" = its dims; cells outside [0, dims) are
/// kept); .binvox and .nrrd streamed in slabs of options.slabBytes along the format's slowest
/// axis (x for binvox, z for nrrd), byte for byte the dense writer's file; .ply and .obj through
/// toDense(), which must fit in memory. Throws voxfx::Error naming the path.
void writeGrid(const SparseGrid& grid, const std::string& path, const GridWriteOptions& options = {});
/// Reads a grid file as a sparse grid: .vdb without a dense grid (the same grids and checks as
/// readGrid; the frame spans "voxfx_dims" or the filled voxels' box), .binvox and .nrrd through
/// the dense grid. Throws voxfx::Error naming the path.
SparseGrid readSparseGrid(const std::string& path);

// ---- Density maps (voxfx/density.hpp) ----

/// Writes a density map placed in the world by `fineFrame` (the frame of the grid it was computed
/// from; orthographic and uniform), by extension:
///   .nrrd  counts as uchar (levels 1-2) or ushort (levels 3-5), x fastest in world axes,
///          "space origin" = centre of density cell (0, 0, 0), directions = density cell sizes;
///   .vdb   a FloatGrid "density" (fog volume) holding the occupancy count / 8^L, active where
///          the count is nonzero, index (i, j, k) at the density cell's centre.
/// Atomic (temporary file, then rename). Throws voxfx::Error for other extensions or I/O errors.
void writeDensity(const DensityGrid& density, const Frame& fineFrame, const std::string& path);

/// Writes the outward normals of every density cell as a NRRD of 3-vectors of float (world
/// directions, x fastest; zero where the gradient vanishes), placed like writeDensity's .nrrd.
void writeDensityNormalsNrrd(const DensityGrid& density, const Frame& fineFrame, const std::string& path);

// ---- A grid or a mesh ----

/// True for the extensions readGrid reads (.binvox .vdb .nrrd, any case).
bool isGridFile(const std::string& path);

/// For tools that accept "a grid or a mesh": a grid file (isGridFile) is read with readGrid;
/// any other file is loaded as a mesh, fitted with `fit` and voxelized with `options` (with
/// Fill::Auto, voxelize() picks parity or flood). `note`, if given, receives "<path>: <why>" when
/// Auto chose flood (VoxelizeReport::fillNote), else it is cleared. Throws voxfx::Error.
VoxelGrid loadOrVoxelize(const std::string& path, const FitOptions& fit, const VoxelizeOptions& options = {},
                         std::string* note = nullptr);

} // namespace voxfx
