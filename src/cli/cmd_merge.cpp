// voxfx merge REGIONS... -o OUT — the regions of one grid (the .vdb files a cluster's tasks wrote,
// voxfx.dask.voxelize_regions) united into one grid file.
#include <algorithm>
#include <filesystem>
#include <iostream>

#include "cli_common.hpp"

namespace voxfx::cli {
namespace {

struct MergeArgs {
    std::vector<std::string> inputs;
    std::string output;
    bool quiet = false;
};

// The region files: each input file as given, each folder's *.vdb files in name order.
std::vector<std::string> regionFiles(const std::vector<std::string>& inputs) {
    std::vector<std::string> files;
    for (const std::string& in : inputs) {
        std::error_code ec;
        if (!std::filesystem::is_directory(in, ec)) {
            if (!std::filesystem::exists(in, ec)) fail("cannot read '", in, "': no such file or folder");
            files.push_back(in);
            continue;
        }
        std::vector<std::string> found;
        for (const auto& e : std::filesystem::directory_iterator(in, ec))
            if (e.is_regular_file() && e.path().extension() == ".vdb" &&
                e.path().filename().string()[0] != '.')
                found.push_back(e.path().string());
        if (ec) fail("cannot list '", in, "': ", ec.message());
        if (found.empty()) fail("'", in, "' holds no .vdb region");
        std::sort(found.begin(), found.end());
        files.insert(files.end(), found.begin(), found.end());
    }
    return files;
}

int runMerge(const MergeArgs& a) {
    const auto t0 = Clock::now();
    const std::vector<std::string> files = regionFiles(a.inputs);
    ProgressLine progress("merge", !a.quiet);
    SparseGrid grid = readSparseGrid(files[0]);
    for (std::size_t i = 1; i < files.size(); ++i) {
        progress.update(double(i) / double(files.size()));
        const SparseGrid region = readSparseGrid(files[i]);
        if (!(region.frame().box().lo == grid.frame().box().lo) || !(region.dims() == grid.dims()) ||
            !(region.frame().cellSize() == grid.frame().cellSize()))
            fail("'", files[i], "' is a region of another grid than '", files[0], "' (", region.dims().x,
                 " x ", region.dims().y, " x ", region.dims().z, " cells against ", grid.dims().x, " x ",
                 grid.dims().y, " x ", grid.dims().z, ", or another placement)");
        grid.unite(region);
    }
    const double mergeMs = msSince(t0);
    const auto tw = Clock::now();
    writeGrid(grid, a.output);
    progress.done();
    if (!a.quiet) {
        const Vec3i d = grid.dims();
        std::cout << files.size() << " regions -> " << d.x << " x " << d.y << " x " << d.z << " grid, "
                  << withCommas(grid.count()) << " filled voxels\n"
                  << "time: read + unite " << fmtMs(mergeMs) << ", write " << fmtMs(msSince(tw)) << " -> "
                  << a.output << "\n";
    }
    return 0;
}

const char* kMergeHelp = R"(
The regions are the .vdb files of one grid written piece by piece, as the tasks of
`voxfx voxelize MESH -o GRID.vdb --scheduler ADDRESS` (voxfx.dask.voxelize_regions) write them
into GRID.regions/: each holds the cells of its columns in the whole grid's frame. A folder
stands for the .vdb files in it. They are united with OpenVDB's topology union (the result's
memory grows with the surface, not the volume) and written as one grid: .vdb from the tree,
.binvox and .nrrd streamed in slabs. Regions of different grids are refused.

  voxfx merge bunny.regions -o bunny.vdb)";

const Command kMerge{
    "merge", "Unite the .vdb regions of one grid into one grid file", [](CLI::App& app) {
        auto a = std::make_shared<MergeArgs>();
        app.add_option("REGIONS", a->inputs, ".vdb region files, or folders of them")->required();
        app.add_option("-o,--output", a->output, "Output grid: .vdb .binvox .nrrd")->required();
        app.add_flag("-q,--quiet", a->quiet, "No summary and no progress line");
        app.footer(kMergeHelp);
        return std::function<int()>([a] { return runMerge(*a); });
    }};

} // namespace
} // namespace voxfx::cli
