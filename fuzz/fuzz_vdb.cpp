// voxfx — fuzz target: .vdb input, in memory (readGrid's path for .vdb and loadVolume's: the
// voxfx_vdb module checks the bytes, then OpenVDB reads them as a stream from memory).
#include "fuzz_target.hpp"
#include "fuzz_volume.hpp"
#include "io/grid_formats.hpp"

VOXFX_FUZZ_TARGET(vdb) {
    int64_t voxels = -1;
    voxfx::fuzz::expectCleanError([&] {
        const voxfx::VoxelGrid g = voxfx::detail::readVdb(data);
        voxfx::fuzz::require(g.bits.width() == g.frame.width() && g.bits.height() == g.frame.height() &&
                                 g.bits.depth() == g.frame.depth(),
                             "the grid's bits match its frame");
        voxels = g.frame.width() * g.frame.height() * g.frame.depth();
    });
    // The same bytes as a dense volume, when the grid's box is small: a few bytes can place two
    // voxels far apart, and a dense box of gigabytes (which the memory check allows) would be
    // reported as the fuzzer's out-of-memory.
    if (voxels >= 0 && voxels <= (int64_t(1) << 22))
        voxfx::fuzz::expectCleanError([&] {
            voxfx::VolumeLoadReport report;
            voxfx::fuzz::checkVolume(voxfx::detail::readVdbVolume(data, voxfx::fuzz::kNowhere, "", report));
        });
}
