#include "grid_input.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx::cli {

void addGridInputOptions(CLI::App& app, GridInput& in, const std::string& marginHelp) {
    app.add_option("INPUT", in.path, "Grid (.binvox .vdb .nrrd) or mesh file")->required();
    app.add_option("-r,--resolution", in.resolution,
                   "Mesh input: cells along the longest side (default " + std::to_string(in.resolution) + ")")
        ->check(CLI::Range(int64_t(1), int64_t(1) << 20))
        ->default_val(in.resolution);
    if (in.margin >= 0)
        app.add_option("--margin", in.margin,
                       "Mesh input: empty cells on every side (default " + std::to_string(in.margin) + ")")
            ->check(CLI::NonNegativeNumber)
            ->default_val(in.margin);
    else
        app.add_option("--margin", in.margin, marginHelp)->check(CLI::NonNegativeNumber);
    app.add_option("-j,--threads", in.threads, "Worker threads, 0 = all (results are identical)")
        ->check(CLI::NonNegativeNumber)
        ->default_val(0);
    app.add_flag("-q,--quiet", in.quiet, "No summary");
}

VoxelGrid loadGridInput(const GridInput& in, bool uniform, int64_t margin) {
    FitOptions fit;
    fit.resolution = in.resolution;
    fit.marginCells = margin >= 0 ? margin : std::max<int64_t>(in.margin, 0);
    VoxelizeOptions vo;
    vo.threads = in.threads;
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
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    std::string allowed;
    for (const char* e : extensions) {
        if (ext == e) return;
        allowed += allowed.empty() ? e : std::string(" or ") + e;
    }
    fail("'", path, "': a ", what, " is written as ", allowed);
}

} // namespace voxfx::cli
