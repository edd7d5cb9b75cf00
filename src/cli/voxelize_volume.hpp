// voxfx command line — `voxfx voxelize VOLUME --threshold T`: a scalar volume (CT data) into a bit
// grid on its own lattice (GI08 §7, voxfx/threshold.hpp), the input-stage branch of voxelize.
#pragma once

#include <string>

#include "grid_input.hpp"

namespace voxfx::cli {

struct VolumeThresholdArgs {
    std::string input, output;
    double threshold = 0;
    std::string axis = "z";
    bool vdbFloat = false;
    int threads = 0;
    bool quiet = false;
};

/// Throws voxfx::Error naming the first option given that only applies to meshes (the grid is
/// the volume's own lattice, filled by the threshold): fitting, mode, fill, slicing, device.
void refuseMeshOnlyOptions(const FitArgs& fit, const VoxelizeChoiceArgs& choice, const std::string& device);

/// Loads the volume, thresholds it, writes the grid and prints the summary (unless quiet).
int runVoxelizeVolume(const VolumeThresholdArgs& args);

} // namespace voxfx::cli
