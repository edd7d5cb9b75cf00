// voxfx — VoxelGrid: a BitGrid together with the Frame that places it in the world.
// Thread-safety: VoxelGrid is a value: concurrent reads are fine, writes need exclusive access.
// reslice and resampleToUniform use worker threads.
#pragma once

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"

namespace voxfx {

/// A voxelization result: bits in the slicemap layout plus the frame they live in.
struct VoxelGrid {
    Frame frame;
    BitGrid bits;

    /// Occupancy of the voxel with world-axis indices (i, j, k) = (along x, along y, along z) of
    /// an orthographic, uniformly sliced grid, whatever its slicing axis.
    bool atWorldIndex(int64_t i, int64_t j, int64_t k) const;
    /// Dimensions in world-axis order (cells along x, y, z) of an orthographic frame.
    Vec3i worldDims() const;
};

/// Re-slices an orthographic, uniformly sliced grid along another axis (bit-matrix transposes,
/// cost ~ a few passes over the grid's bytes). Result holds the same voxels.
VoxelGrid reslice(const VoxelGrid& grid, Axis axis);

/// Resamples a locally sliced orthographic grid to its frame's uniform slicing: each uniform cell
/// takes the bit of the local cell its centre falls in (empty outside the column's range).
VoxelGrid resampleToUniform(const VoxelGrid& grid);

} // namespace voxfx
