// voxfx — fuzz target: the NRRD bit-grid reader (io/nrrd.cpp).
#include "fuzz_target.hpp"
#include "io/grid_formats.hpp"

VOXFX_FUZZ_TARGET(nrrd_grid) {
    voxfx::fuzz::expectCleanError([&] {
        const voxfx::VoxelGrid g = voxfx::detail::readNrrd(data);
        voxfx::fuzz::require(g.bits.width() == g.frame.width() && g.bits.height() == g.frame.height() &&
                                 g.bits.depth() == g.frame.depth(),
                             "the grid's bits match its frame");
    });
}
