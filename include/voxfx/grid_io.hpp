// voxfx — reading and writing voxel grids: binvox, OpenVDB (.vdb), NRRD (.nrrd), and a mesh of
// the filled voxels (.ply, .obj) to look at in any mesh viewer.
//
// World placement: every format carries the grid's world box so tools line voxels up with the
// source mesh. Voxel (i, j, k) (indices along world x, y, z) covers
// [lo + (i, j, k) * cell, lo + (i+1, j+1, k+1) * cell] and its centre is lo + (i + 0.5) * cell.
//   binvox: translate = lo, scale = longest world extent of the grid (binvox's convention),
//           data order x-major, then z, then y fastest (as binvox writes it).
//   vdb:    a BoolGrid (or FloatGrid 0/1) named "voxels" (default), class fog volume for float,
//           index-to-world transform = scale(cell) then translate(lo + cell/2), so index (i,j,k)
//           maps to the voxel centre (OpenVDB's cell-centred convention).
//   nrrd:   uint8 0/1, x fastest, "space origin" = centre of voxel (0,0,0), "space directions"
//           = cell sizes; raw encoding.
//   ply/obj: the exposed faces of filled voxels as quads (ply binary little endian).
// All writers are atomic: they write a temporary file beside the target and rename it, so a
// failure leaves no partial output and an existing file untouched.
#pragma once

#include <string>

#include "voxfx/voxel_grid.hpp"

namespace voxfx {

enum class GridFormat : uint8_t { Binvox, Vdb, Nrrd, Ply, Obj };

/// Format from the file extension; throws voxfx::Error listing the allowed extensions.
GridFormat gridFormatFromPath(const std::string& path);
const char* toString(GridFormat f);

struct GridWriteOptions {
    bool vdbFloat = false; ///< vdb: FloatGrid with 1.0 in filled voxels instead of BoolGrid
    std::string gridName = "voxels";
};

/// Writes an orthographic grid (locally sliced grids are resampled to uniform first).
void writeGrid(const VoxelGrid& grid, const std::string& path, const GridWriteOptions& options = {});
/// Reads binvox, vdb (first bool/float/double grid, active or > 0 voxels) or nrrd (nonzero voxels)
/// into an orthographic grid sliced along Z. Throws voxfx::Error on unreadable, malformed or
/// truncated files.
VoxelGrid readGrid(const std::string& path);

} // namespace voxfx
