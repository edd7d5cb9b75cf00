// voxfx — the volume of the intersection of two solids, in world units, with a stated error
// bound (GI08 §7 "object intersection": both solids in one grid, combined by AND and counted,
// "useful for collision detection and haptic feedback").
//
// The estimate counts the cells whose centre lies in both solids and adds their world volumes
// (filledVolume: count x cell volume on orthographic uniform grids). Its error is bounded per
// cell (CsgBounds, voxfx/csg.hpp): a cell that lies wholly inside the intersection or wholly
// outside it is counted exactly, so only the cells a surface passes through can be off, each by
// at most its own volume:
//     |volume - exact| <= errorBound = volume of the cells of upper & ~lower.
// For meshes the bound is rigorous (the conservative surface holds every cell a triangle
// touches); it shrinks like the surface area times the cell size, so halving the cell roughly
// halves it. Grids are taken as the union of their cells, which have no error of their own.
// Thread-safety: re-entrant; voxelization and counting use worker threads (options.threads).
#pragma once

#include <cstdint>

#include "voxfx/csg.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

/// A volume estimate and its error bound, world units cubed.
struct VolumeEstimate {
    double volume = 0;          ///< world volume of the cells counted
    int64_t cells = 0;          ///< cells counted (centre inside the solid)
    double errorBound = 0;      ///< |volume - exact volume| <= errorBound
    int64_t uncertainCells = 0; ///< cells a surface passes through (upper & ~lower)
    double lowerVolume = 0;     ///< volume of the cells wholly inside: exact volume >= this
    double upperVolume = 0;     ///< volume of the cells meeting the solid: exact volume <= this
};

/// The estimate for a cell-centre grid `centres` whose solid `bounds` bounds (bounds in the same
/// frame): volume = filledVolume(centres), errorBound = filledVolume(upper & ~lower). Throws
/// voxfx::Error when the sizes differ.
VolumeEstimate estimateVolume(const VoxelGrid& centres, const CsgBounds& bounds);

/// The intersection of two grids of one frame (Frame::sameGrid; voxfx::Error otherwise), each
/// the union of its filled cells: the common cells' volume, exact (errorBound 0). Cost: one pass
/// over both grids' words.
VolumeEstimate intersectionVolume(const VoxelGrid& a, const VoxelGrid& b);

/// The intersection of a grid (the union of its filled cells) and the solid of a closed mesh
/// placed by `worldFromMesh` (an affine map; positions are mapped in double and stored as
/// float), voxelized into the grid's frame with `options` (mode ignored; fill as given, Auto
/// picks parity for a closed mesh). The error comes from the mesh's surface only. Cost: two
/// voxelizations of the mesh in the grid's frame (solid and conservative) and a few passes over
/// the grid's words.
VolumeEstimate intersectionVolume(const VoxelGrid& grid, const MeshView& mesh, const Mat4d& worldFromMesh,
                                  const VoxelizeOptions& options = {});

/// The intersection of the solids of two closed meshes, each placed by its affine map, in an
/// orthographic frame fitted by `fit` to the overlap of their world bounds (fit.bounds, when
/// set, replaces the overlap; the intersection lies inside the overlap, so no cell is spent
/// elsewhere). Boxes that do not overlap give all zeros without voxelizing. Cost: four
/// voxelizations (solid and conservative per mesh) in the fitted frame.
VolumeEstimate intersectionVolume(const MeshView& a, const Mat4d& worldFromA, const MeshView& b,
                                  const Mat4d& worldFromB, const FitOptions& fit,
                                  const VoxelizeOptions& options = {});

} // namespace voxfx
