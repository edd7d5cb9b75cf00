#include "grid_input.hpp"

#include <algorithm>
#include <cctype>
#include <iostream>

#include "cli_common.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx::cli {

void addFitOptions(CLI::App& app, FitArgs& args, const FitChoices& choices) {
    // "Cells along ..." alone, "Mesh input: cells along ..." after a prefix.
    const auto help = [&](std::string text) {
        if (!choices.prefix.empty()) text[0] = char(std::tolower(static_cast<unsigned char>(text[0])));
        return choices.prefix + text;
    };
    auto* res = app.add_option("-r,--resolution", args.resolution,
                               help("Cells along the longest side (default " +
                                    std::to_string(choices.defaultResolution) + ")"))
                    ->check(CLI::Range(int64_t(1), int64_t(1) << 20));
    if (choices.voxelSize) {
        auto* vs =
            app.add_option("--voxel-size", args.voxelSize, help("Edge length of a cubic cell, in mesh units"))
                ->check(CLI::PositiveNumber);
        res->excludes(vs);
    }
    if (choices.dims) {
        auto* dims =
            app.add_option("--dims", args.dims, help("Exact cell counts along x y z (non-cubic cells)"))
                ->expected(3)
                ->check(CLI::Range(int64_t(1), int64_t(1) << 20));
        res->excludes(dims);
        if (CLI::Option* vs = app.get_option_no_throw("--voxel-size")) vs->excludes(dims);
    }
    if (choices.bounds)
        app.add_option("--bounds", args.bounds,
                       help("Box to voxelize instead of the mesh bounds: xmin ymin zmin xmax ymax zmax"))
            ->expected(6);
    app.add_option("--margin", args.margin,
                   choices.defaultMargin >= 0 ? help("Empty cells added on every side (default " +
                                                     std::to_string(choices.defaultMargin) + ")")
                                              : choices.marginHelp)
        ->check(CLI::NonNegativeNumber);
    if (choices.cube) {
        app.add_flag("--cube", args.cube,
                     help("R x R x R cubic cells for -r R, the mesh centred and never stretched (the grids "
                          "learning code stacks)"));
        app.add_option(
               "--padding", args.padding,
               help("Empty cells kept on every side within the resolution: the mesh gets R - 2P cells"))
            ->check(CLI::NonNegativeNumber);
    }
}

FitOptions toFitOptions(const FitArgs& args, const FitChoices& choices, int64_t margin) {
    FitOptions fo;
    fo.resolution = args.resolution;
    fo.voxelSize = args.voxelSize;
    fo.marginCells = margin >= 0        ? margin
                     : args.margin >= 0 ? args.margin
                                        : std::max<int64_t>(choices.defaultMargin, 0);
    if (!args.dims.empty()) fo.dims = {args.dims[0], args.dims[1], args.dims[2]};
    if (!args.bounds.empty()) {
        fo.bounds.lo = {args.bounds[0], args.bounds[1], args.bounds[2]};
        fo.bounds.hi = {args.bounds[3], args.bounds[4], args.bounds[5]};
        if (fo.bounds.empty()) fail("--bounds needs min <= max on every axis");
    }
    if (fo.resolution == 0 && fo.voxelSize == 0 && args.dims.empty())
        fo.resolution = choices.defaultResolution;
    if (args.cube && fo.resolution == 0) fail("--cube needs a resolution (not --voxel-size or --dims)");
    fo.cube = args.cube;
    // --padding P keeps P empty cells inside the resolution, as the Python module's padding does:
    // resolution - 2P cells for the mesh, then P more on every side.
    if (args.padding > 0) {
        if (fo.resolution == 0) fail("--padding needs a resolution (not --voxel-size or --dims)");
        if (fo.resolution <= 2 * args.padding)
            fail("--padding ", args.padding, " needs a resolution above ", 2 * args.padding,
                 " (the cells left for the mesh)");
        fo.resolution -= 2 * args.padding;
        fo.marginCells += args.padding;
    }
    return fo;
}

const FitChoices& voxelizeFitChoices() {
    static const FitChoices choices = [] {
        FitChoices c;
        c.voxelSize = c.dims = c.bounds = true;
        c.cube = true;
        return c;
    }();
    return choices;
}

void addVoxelizeChoiceOptions(CLI::App& app, VoxelizeChoiceArgs& args) {
    app.add_option("-m,--mode", args.mode, enumNameList<VoxelizeMode>(kVoxelizeModeNames, " | "))
        ->default_val("solid");
    app.add_option("--fill", args.fill, enumNameList<Fill>(kFillNames, " | "))->default_val("auto");
    app.add_option("--axis", args.axis, "Slicing axis x | y | z (the result is the same voxels)")
        ->default_val("z");
    app.add_option("--slicing", args.slicing,
                   "uniform | local (ED06 per-column near/far; resampled on export)")
        ->default_val("uniform");
    app.add_flag("--vdb-float", args.vdbFloat,
                 "Write a FloatGrid (fog volume, 1 inside) instead of a BoolGrid");
}

VoxelizeOptions toVoxelizeOptions(const VoxelizeChoiceArgs& args) {
    VoxelizeOptions vo;
    vo.mode = parseVoxelizeMode(args.mode);
    vo.slicing = parseSlicing(args.slicing);
    vo.fill = parseFill(args.fill);
    return vo;
}

void addGridInputOptions(CLI::App& app, GridInput& in, const std::string& marginHelp) {
    app.add_option("INPUT", in.path, "Grid (.binvox .vdb .nrrd) or mesh file")->required();
    in.choices.marginHelp = marginHelp;
    addFitOptions(app, in.fit, in.choices);
    app.add_option("-j,--threads", in.threads, "Worker threads, 0 = all (results are identical)")
        ->check(CLI::NonNegativeNumber)
        ->default_val(0);
    app.add_flag("-q,--quiet", in.quiet, "No summary");
}

VoxelGrid loadGridInput(const GridInput& in, bool uniform, int64_t margin) {
    const FitOptions fit = toFitOptions(in.fit, in.choices, margin);
    VoxelizeOptions vo;
    vo.threads = in.threads;
    vo.fill = Fill::Auto;
    std::string note;
    VoxelGrid grid = loadOrVoxelize(in.path, fit, vo, &note);
    if (!note.empty() && !in.quiet) std::cerr << "voxfx: " << note << "\n";
    if (uniform && grid.frame.slicing() == Slicing::Local) grid = resampleToUniform(grid);
    return grid;
}

double writeGridOutput(const VoxelGrid& grid, const std::string& path, bool vdbFloat) {
    const auto t0 = Clock::now();
    GridWriteOptions wo;
    wo.vdbFloat = vdbFloat;
    writeGrid(grid, path, wo);
    return msSince(t0);
}

void requireExtension(const std::string& path, std::initializer_list<const char*> extensions,
                      const char* what) {
    const std::string ext = fileExtension(path);
    std::string allowed;
    for (const char* e : extensions) {
        if (ext == e) return;
        allowed += allowed.empty() ? e : std::string(" or ") + e;
    }
    fail("'", path, "': a ", what, " is written as ", allowed);
}

} // namespace voxfx::cli
