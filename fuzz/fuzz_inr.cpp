// voxfx — fuzz target: the INRIMAGE-4 reader (io/volume_inr.cpp), plain and gzipped.
#include "fuzz_volume.hpp"

VOXFX_FUZZ_TARGET(inr) {
    voxfx::fuzz::expectCleanError([&] {
        voxfx::VolumeLoadReport report;
        voxfx::fuzz::checkVolume(voxfx::detail::readInr(data, voxfx::fuzz::kNowhere + ".inr", report));
    });
}
