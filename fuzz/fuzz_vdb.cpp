// voxfx — fuzz target: .vdb input (readGrid and loadVolume through the voxfx_vdb module and OpenVDB).
#include "fuzz_target.hpp"
#include "fuzz_volume.hpp"
#include "voxfx/grid_io.hpp"

VOXFX_FUZZ_TARGET(vdb) {
    static const std::string path = voxfx::fuzz::scratchPath("grid.vdb");
    voxfx::fuzz::writeFile(path, data);
    int64_t voxels = -1;
    voxfx::fuzz::expectCleanError([&] {
        const voxfx::VoxelGrid g = voxfx::readGrid(path);
        voxfx::fuzz::require(g.bits.width() == g.frame.width() && g.bits.height() == g.frame.height() &&
                                 g.bits.depth() == g.frame.depth(),
                             "the grid's bits match its frame");
        voxels = g.frame.width() * g.frame.height() * g.frame.depth();
    });
    // The same bytes as a dense volume, when the grid's box is small: a few bytes can place two
    // voxels far apart, and a dense box of gigabytes (which the memory check allows) would be
    // reported as the fuzzer's out-of-memory.
    if (voxels >= 0 && voxels <= (int64_t(1) << 22))
        voxfx::fuzz::expectCleanError([&] { voxfx::fuzz::checkVolume(voxfx::loadVolume(path)); });
}
