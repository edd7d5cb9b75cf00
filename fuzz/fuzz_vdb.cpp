// voxfx — fuzz target: .vdb input (readGrid through the voxfx_vdb module and OpenVDB).
#include "fuzz_target.hpp"
#include "voxfx/grid_io.hpp"

VOXFX_FUZZ_TARGET(vdb) {
    static const std::string path = voxfx::fuzz::scratchPath("grid.vdb");
    voxfx::fuzz::writeFile(path, data);
    voxfx::fuzz::expectCleanError([&] {
        const voxfx::VoxelGrid g = voxfx::readGrid(path);
        voxfx::fuzz::require(g.bits.width() == g.frame.width() && g.bits.height() == g.frame.height() &&
                                 g.bits.depth() == g.frame.depth(),
                             "the grid's bits match its frame");
    });
}
