// voxfx volume-info VOLUME [--tf TF.json] [--grid NAME] — what a scalar volume file holds: format, type,
// dimensions, placement and value range; with a transfer function, how much of it is visible.
#include <iostream>

#include "cli_common.hpp"
#include "voxfx/transfer_function.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx::cli {
namespace {

std::string vecString(const Vec3d& v) {
    return "(" + fmt(v.x, 6) + ", " + fmt(v.y, 6) + ", " + fmt(v.z, 6) + ")";
}

int runVolumeInfo(const std::string& path, const std::string& tfPath, const std::string& grid) {
    // Everything that can fail is read before anything is printed.
    TransferFunction tf;
    if (!tfPath.empty()) tf = loadTransferFunction(tfPath);
    const auto t0 = Clock::now();
    VolumeLoadReport report;
    VolumeLoadOptions options;
    options.vdbGrid = grid;
    const Volume v = loadVolume(path, options, &report);
    const double loadMs = msSince(t0);

    double sum = 0;
    int64_t nonzero = 0, visible = 0;
    for (const float x : v.values()) {
        sum += x;
        nonzero += x != 0;
        if (!tfPath.empty()) visible += tf.opacity(x) > 0;
    }
    const Vec3i d = v.dims();
    std::cout << "file:       " << path << " (" << toString(report.format) << (report.gzip ? ", gzip" : "")
              << ", " << withCommas(int64_t(report.fileBytes)) << " bytes, loaded in " << fmtMs(loadMs)
              << ")\n";
    if (report.format == VolumeFormat::Vdb)
        std::cout << "grid:       '" << report.gridName << "' (" << report.gridClass << ")\n";
    std::cout << "type:       " << toString(v.sourceType()) << "\n";
    std::cout << "dims:       " << d.x << " x " << d.y << " x " << d.z << " (" << withCommas(v.voxelCount())
              << " voxels)\n";
    std::cout << "spacing:    " << vecString(v.spacing()) << "\n";
    if (!v.axisAligned())
        std::cout << "axes:       i " << vecString(v.axis(0)) << ", j " << vecString(v.axis(1)) << ", k "
                  << vecString(v.axis(2)) << " (turned; bounds are the box around it)\n";
    std::cout << "bounds:     " << boxString(v.box()) << "\n";
    std::cout << "values:     min " << fmt(v.minValue(), 6) << ", max " << fmt(v.maxValue(), 6) << ", mean "
              << fmt(sum / double(v.voxelCount()), 6) << ", " << withCommas(nonzero) << " non-zero\n";
    if (!tfPath.empty())
        std::cout << "transfer:   " << tfPath << " (" << tf.colorPoints().size() << " colour, "
                  << tf.opacityPoints().size() << " opacity points over [" << fmt(tf.minValue(), 6) << ", "
                  << fmt(tf.maxValue(), 6) << "]): " << withCommas(visible) << " voxels with opacity > 0\n";
    return 0;
}

const Command kVolumeInfo{
    "volume-info",
    "Print a scalar volume's type, dimensions, placement and value range (INR, NRRD, raw+JSON, OpenVDB)",
    [](CLI::App& app) {
        auto path = std::make_shared<std::string>();
        auto tf = std::make_shared<std::string>();
        auto grid = std::make_shared<std::string>();
        app.add_option("VOLUME", *path, "Volume file (.inr, .inr.gz, .nrrd, .nhdr, .json, .vdb)")->required();
        app.add_option("--tf", *tf, "Transfer function (JSON) to check against the volume");
        app.add_option("--grid", *grid,
                       "Grid of a .vdb file to read (default: the first float or double grid)");
        return std::function<int()>([path, tf, grid] { return runVolumeInfo(*path, *tf, *grid); });
    }};

} // namespace
} // namespace voxfx::cli
