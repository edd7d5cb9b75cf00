// voxfx command line — the grid-fitting options of every command that voxelizes (-r, --voxel-size,
// --dims, --bounds, --margin), and the "grid or mesh" input shared by density, mesh, morph and
// particles: its options and loading it (a grid file is read, a mesh is voxelized as a solid
// with voxfx::loadOrVoxelize).
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "voxfx/grid_io.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx::cli {

/// Which of the grid-fitting options a command offers, and their defaults.
struct FitChoices {
    int64_t defaultResolution = 256; ///< -r when neither --voxel-size nor --dims is given
    int64_t defaultMargin = 0;       ///< < 0: --margin has no default; `marginHelp` says what happens
    bool voxelSize = false, dims = false, bounds = false;
    bool cube = false;      ///< --cube and --padding (the grids learning code stacks)
    std::string prefix;     ///< help prefix, e.g. "Mesh input: "
    std::string marginHelp; ///< help of --margin when defaultMargin < 0
};

/// The fitting options as given on the command line (0, empty or negative: not given).
struct FitArgs {
    int64_t resolution = 0;
    double voxelSize = 0;
    std::vector<int64_t> dims;
    std::vector<double> bounds;
    int64_t margin = -1;
    bool cube = false;
    int64_t padding = 0;
};

/// Adds -r/--resolution, --margin and, as `choices` says, --voxel-size, --dims and --bounds
/// (the first three exclude each other). The one place these options are declared.
void addFitOptions(CLI::App& app, FitArgs& args, const FitChoices& choices);

/// voxfx::FitOptions from what was given: the default resolution unless --voxel-size or --dims
/// is; the margin `margin` when >= 0, else the given one, else the default (0 when none).
/// Throws voxfx::Error for --bounds with min > max on an axis.
FitOptions toFitOptions(const FitArgs& args, const FitChoices& choices, int64_t margin = -1);

/// The fitting choices of `voxfx voxelize` and `voxfx batch` (resolution 256, --voxel-size,
/// --dims, --bounds, margin 0): one definition, so both fit the same frames.
const FitChoices& voxelizeFitChoices();

/// The voxelization choices besides fitting, as `voxfx voxelize` and `voxfx batch` take them.
struct VoxelizeChoiceArgs {
    std::string mode = "solid", fill = "auto", axis = "z", slicing = "uniform";
    bool vdbFloat = false;
};

/// Adds -m/--mode, --fill, --axis, --slicing and --vdb-float.
void addVoxelizeChoiceOptions(CLI::App& app, VoxelizeChoiceArgs& args);

/// Mode, slicing and (unless auto) fill parsed; throws voxfx::Error for unknown names.
VoxelizeOptions toVoxelizeOptions(const VoxelizeChoiceArgs& args);

struct GridInput {
    /// The defaults of -r and --margin for this command (margin < 0: the command decides).
    explicit GridInput(int64_t defaultResolution = 256, int64_t defaultMargin = 1) {
        choices.defaultResolution = defaultResolution;
        choices.defaultMargin = defaultMargin;
        choices.prefix = "Mesh input: ";
    }
    std::string path;
    FitArgs fit;
    FitChoices choices;
    int threads = 0;
    bool quiet = false;
};

/// Adds INPUT, -r/--resolution, --margin, -j/--threads and -q/--quiet. A negative default margin
/// adds --margin without a default, described by `marginHelp`.
void addGridInputOptions(CLI::App& app, GridInput& in, const std::string& marginHelp = "");

/// Reads the grid, or voxelizes the mesh (margin `margin`, or the given one when `margin` < 0),
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
