// voxfx — fuzz target: the NRRD scalar-volume reader (io/volume_nrrd.cpp), attached data.
#include "fuzz_volume.hpp"

VOXFX_FUZZ_TARGET(nrrd_volume) {
    voxfx::fuzz::expectCleanError([&] {
        voxfx::VolumeLoadReport report;
        voxfx::fuzz::checkVolume(
            voxfx::detail::readScalarNrrd(data, voxfx::fuzz::kNowhere + ".nrrd", report));
    });
}
