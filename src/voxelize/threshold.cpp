// voxfx — a scalar volume thresholded into a bit grid (Eisemann & Décoret, "Single-Pass GPU Solid
// Voxelization for Real-Time Applications", GI 2008, §7 "volume visualization": level sets of
// scanned volumes kept as bit grids). See voxfx/threshold.hpp.
#include "voxfx/threshold.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

#include "voxfx/error.hpp"

namespace voxfx {

VoxelGrid thresholdVolume(const Volume& volume, double threshold, const ThresholdOptions& options) {
    if (!std::isfinite(threshold)) fail("threshold must be a finite number, got ", threshold);
    VoxelGrid out;
    out.frame = volume.frame(options.axis); // fails for an empty or mirrored volume
    const Frame& f = out.frame;
    checkMemory(BitGrid::requiredBytes(f.width(), f.height(), f.depth()), "the thresholded grid");
    out.bits = BitGrid(f.width(), f.height(), f.depth());

    // Grid (x, y, s) is volume voxel index[columnXAxis] = x, [columnYAxis] = y, [axis] = s: the
    // sample's offset is x * stride[cx] + y * stride[cy] + s * stride[cs].
    const Vec3i n = volume.dims();
    const int64_t stride[3] = {1, n.x, n.x * n.y};
    const int64_t sx = stride[columnXAxis(options.axis)], sy = stride[columnYAxis(options.axis)],
                  ss = stride[sliceAxis(options.axis)];
    const int64_t W = f.width(), H = f.height(), D = f.depth();
    const float* values = volume.values().data();
    BitGrid& bits = out.bits;

    ProgressSteps rows(options.progress, H);
    withThreads(options.threads, [&] {
        // One owner per row of columns. Slices outermost and columns inside, so that along z
        // (the default) each pass reads one contiguous row of samples.
        parallelFor(0, H, 1, [&](int64_t yb, int64_t ye) {
            for (int64_t y = yb; y < ye && !rows.cancelled(); ++y) {
                for (int64_t s = 0; s < D; ++s) {
                    const float* row = values + y * sy + s * ss;
                    const uint64_t bit = uint64_t(1) << (s & 63);
                    for (int64_t x = 0; x < W; ++x)
                        if (double(row[x * sx]) >= threshold) bits.column(x, y)[s >> 6] |= bit;
                }
                rows.step();
            }
        });
    });
    if (rows.cancelled()) fail("cancelled");
    return out;
}

} // namespace voxfx
