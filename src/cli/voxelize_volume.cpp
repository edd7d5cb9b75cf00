// voxfx command line — `voxfx voxelize VOLUME --threshold T` (GI08 §7, Eisemann & Décoret 2008:
// scanned volumes as bit grids); see voxelize_volume.hpp.
#include "voxelize_volume.hpp"

#include <iostream>

#include "cli_common.hpp"
#include "voxfx/threshold.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx::cli {

void refuseMeshOnlyOptions(const FitArgs& fit, const VoxelizeChoiceArgs& choice, const std::string& device) {
    const char* given = fit.resolution > 0                    ? "-r/--resolution"
                        : fit.voxelSize > 0                   ? "--voxel-size"
                        : !fit.dims.empty()                   ? "--dims"
                        : !fit.bounds.empty()                 ? "--bounds"
                        : fit.margin >= 0                     ? "--margin"
                        : choice.mode != "solid"              ? "--mode"
                        : choice.fill != "auto"               ? "--fill"
                        : choice.slicing != "uniform"         ? "--slicing"
                        : device != "cpu" && device != "auto" ? "--device"
                                                              : nullptr;
    if (given)
        fail(given, " does not apply with --threshold: the grid is the volume's own lattice, a cell "
                    "filled where its sample is >= the threshold");
}

int runVoxelizeVolume(const VolumeThresholdArgs& a) {
    const auto t0 = Clock::now();
    const GridFormat format = gridFormatFromPath(a.output); // a bad output name fails before the work
    ThresholdOptions to;
    to.axis = parseAxis(a.axis);
    to.threads = a.threads;
    VolumeLoadReport report;
    const Volume volume = loadVolume(a.input, &report);
    const double loadMs = msSince(t0);

    ProgressLine progress("thresholding", !a.quiet);
    to.progress = &progress;
    const auto tt = Clock::now();
    const VoxelGrid grid = thresholdVolume(volume, a.threshold, to);
    const double thresholdMs = msSince(tt);
    progress.done();
    const double writeMs = writeGridOutput(grid, a.output, a.vdbFloat);

    if (!a.quiet) {
        const Vec3i n = volume.dims(), d = grid.worldDims();
        const Vec3d cell = volume.spacing();
        std::cout << a.input << ": " << n.x << " x " << n.y << " x " << n.z << " "
                  << toString(volume.sourceType()) << " volume (" << toString(report.format)
                  << "), threshold " << fmt(a.threshold, 6) << " -> " << d.x << " x " << d.y << " x " << d.z
                  << " grid (cell " << fmt(cell.x, 4);
        if (cell.y != cell.x || cell.z != cell.x)
            std::cout << " x " << fmt(cell.y, 4) << " x " << fmt(cell.z, 4);
        std::cout << ", axis " << toString(grid.frame.axis()) << "), " << withCommas(grid.bits.count())
                  << " filled voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", threshold " << fmtMs(thresholdMs) << ", write "
                  << fmtMs(writeMs) << ", total " << fmtMs(msSince(t0)) << " -> " << a.output << " ("
                  << toString(format) << ")\n";
    }
    return 0;
}

} // namespace voxfx::cli
