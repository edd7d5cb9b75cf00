// voxfx command line — the "grid or mesh" input shared by density, mesh, morph and particles:
// its options (-r, --margin, -j, -q) and loading it (a grid file is read, a mesh is voxelized as
// a solid with voxfx::loadOrVoxelize).
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>

#include <CLI/CLI.hpp>

#include "voxfx/voxel_grid.hpp"

namespace voxfx::cli {

struct GridInput {
    /// The defaults of -r and --margin for this command.
    explicit GridInput(int64_t defaultResolution = 256, int64_t defaultMargin = 1)
        : resolution(defaultResolution), margin(defaultMargin) {}
    std::string path;
    int64_t resolution; ///< mesh input: cells along the longest side
    int64_t margin;     ///< mesh input: empty cells on every side (< 0: the command decides)
    int threads = 0;
    bool quiet = false;
};

/// Adds INPUT, -r/--resolution, --margin, -j/--threads and -q/--quiet. The defaults shown are
/// `in`'s current values; a negative in.margin adds --margin without a default, described by
/// `marginHelp`.
void addGridInputOptions(CLI::App& app, GridInput& in, const std::string& marginHelp = "");

/// Reads the grid, or voxelizes the mesh (margin `margin`, or in.margin when `margin` < 0),
/// printing the fill note on stderr unless quiet. With `uniform`, a locally sliced grid is
/// resampled to uniform slicing. Throws voxfx::Error.
VoxelGrid loadGridInput(const GridInput& in, bool uniform, int64_t margin = -1);

/// Writes a grid result (writeGrid; a FloatGrid for .vdb with `vdbFloat`) and returns the
/// milliseconds it took.
double writeGridOutput(const VoxelGrid& grid, const std::string& path, bool vdbFloat);

/// Throws voxfx::Error unless `path` ends in one of `extensions` (any case): checked before the
/// work starts, so a misspelt output fails at once. `what` names the file ("density map").
void requireExtension(const std::string& path, std::initializer_list<const char*> extensions,
                      const char* what);

} // namespace voxfx::cli
