// voxfx — fuzz target: .vdb input (readGrid's path for .vdb: the voxfx_vdb module checks the bytes,
// then OpenVDB reads them as a stream from memory).
#include "fuzz_target.hpp"
#include "io/grid_formats.hpp"

VOXFX_FUZZ_TARGET(vdb) {
    voxfx::fuzz::expectCleanError([&] {
        const voxfx::VoxelGrid g = voxfx::detail::readVdb(data);
        voxfx::fuzz::require(g.bits.width() == g.frame.width() && g.bits.height() == g.frame.height() &&
                                 g.bits.depth() == g.frame.depth(),
                             "the grid's bits match its frame");
    });
}
