// voxfx density INPUT -o OUT — the GI08 density map (filled cells per 2^L block) of a grid or a
// mesh, as NRRD counts or a VDB fog volume, optionally with its normals.
#include <iostream>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/density.hpp"
#include "voxfx/grid_io.hpp"

namespace voxfx::cli {
namespace {

struct DensityArgs {
    GridInput in;
    std::string output, normals;
    int level = 1;
};

int runDensity(const DensityArgs& a) {
    requireExtension(a.output, {".nrrd", ".vdb"}, "density map");
    if (!a.normals.empty()) requireExtension(a.normals, {".nrrd"}, "normal map");
    const auto t0 = Clock::now();
    const VoxelGrid grid = loadGridInput(a.in, /*uniform=*/true);
    const double loadMs = msSince(t0);

    const auto td = Clock::now();
    DensityOptions d;
    d.level = a.level;
    d.threads = a.in.threads;
    const DensityGrid density = computeDensity(grid.bits, d);
    const double densityMs = msSince(td);

    const auto tw = Clock::now();
    writeDensity(density, grid.frame, a.output);
    if (!a.normals.empty()) writeDensityNormalsNrrd(density, grid.frame, a.normals);
    const double writeMs = msSince(tw);

    if (!a.in.quiet) {
        std::cout << a.in.path << ": " << grid.bits.width() << " x " << grid.bits.height() << " x "
                  << grid.bits.depth() << " grid, " << withCommas(grid.bits.count()) << " filled -> level "
                  << a.level << " density (" << density.kernel() << "^3 blocks) " << density.width() << " x "
                  << density.height() << " x " << density.depth() << ", " << density.laneBits()
                  << " bits per cell, " << withCommas(int64_t(density.byteCount())) << " bytes\n";
        std::cout << "time: input " << fmtMs(loadMs) << ", density " << fmtMs(densityMs) << ", write "
                  << fmtMs(writeMs) << " -> " << a.output << (a.normals.empty() ? "" : " + " + a.normals)
                  << "\n";
    }
    return 0;
}

const char* kDensityHelp = R"(
The density map counts the filled cells of every 2^L x 2^L x 2^L block (GI08): level 1 gives
counts 0..8 per 2x2x2 block, computed bit-parallel on the slicemap words; each further level
doubles the kernel. Occupancy = count / 8^L behaves like a local distance field.

Input: a grid (.binvox .vdb .nrrd) or a mesh (voxelized as a solid with -r, parity when closed,
flood fill otherwise).
Output: .nrrd (uint8 counts for levels 1-2, uint16 for 3-5) or .vdb (FloatGrid "density",
occupancy in [0, 1], fog volume). Voxel (i, j, k) is centred on its 2^L block.
--normals FILE.nrrd also writes the outward normals (-gradient of the counts, central
differences) as float 3-vectors in world axes.)";

const Command kDensity{
    "density", "Density map (filled cells per 2^L block) of a grid or mesh -> .nrrd / .vdb",
    [](CLI::App& app) {
        app.footer(kDensityHelp);
        auto a = std::make_shared<DensityArgs>();
        app.add_option("-o,--output", a->output, "Density map: .nrrd (counts) or .vdb (occupancy)")
            ->required();
        app.add_option("-l,--level", a->level, "Kernel 2^level, 1..5 (default 1: 2x2x2)")
            ->check(CLI::Range(1, 5))
            ->default_val(1);
        app.add_option("--normals", a->normals,
                       "Also write the outward normals as a NRRD of float 3-vectors");
        addGridInputOptions(app, a->in);
        return std::function<int()>([a] { return runDensity(*a); });
    }};

} // namespace
} // namespace voxfx::cli
