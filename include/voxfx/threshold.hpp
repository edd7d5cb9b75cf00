// voxfx — a scalar volume thresholded into a bit grid (GI08 §7 "volume visualization": level
// sets of large scanned data sets kept as bit grids, so that the toolkit's density, morphology,
// CSG and surface extraction run on CT data).
//
// The grid is the volume's own lattice: voxel (i, j, k) of the volume becomes cell (i, j, k) of
// an orthographic, uniformly sliced grid whose box is the volume's (lo to lo + dims * spacing,
// non-cubic cells when the spacing is), so each cell's centre is the volume voxel's centre and
// the grid lines up with the scan in every output format. A turned volume (Volume::setAxes) gets
// an oriented orthographic frame along its axes (Volume::frame). A cell is filled when its sample is >= the
// threshold (the samples as loaded, float whatever type the file stored, compared with the threshold in
// double: exactly "sample >= T" for any T).
// Thread-safety: re-entrant; uses worker threads (`threads`), results identical for any count.
#pragma once

#include <cstdint>

#include "voxfx/frame.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/volume.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx {

struct ThresholdOptions {
    /// Slicing axis of the grid (its columns run along the other two); the filled cells are the
    /// same for every axis.
    Axis axis = Axis::Z;
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
    /// Polled between rows of columns; returning false cancels (voxfx::Error "cancelled").
    Progress* progress = nullptr;
};

/// Cells whose sample is >= `threshold`, in volume.frame(options.axis) (see the file comment).
/// Throws voxfx::Error for a threshold that is not finite, an empty or mirrored volume, a grid
/// that would not fit in memory (checked before allocating) or a cancelled progress.
/// Cost: one pass over the samples, 1 bit of output per sample.
VoxelGrid thresholdVolume(const Volume& volume, double threshold, const ThresholdOptions& options = {});

} // namespace voxfx
