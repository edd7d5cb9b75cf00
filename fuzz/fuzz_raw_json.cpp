// voxfx — fuzz target: the JSON header of raw volumes (io/volume_raw.cpp). The raw file it names
// is looked up next to a path that does not exist, so the header's checks are what is fuzzed.
#include "fuzz_volume.hpp"

VOXFX_FUZZ_TARGET(raw_json) {
    voxfx::fuzz::expectCleanError([&] {
        voxfx::VolumeLoadReport report;
        voxfx::fuzz::checkVolume(voxfx::detail::readRawJson(data, voxfx::fuzz::kNowhere + ".json", report));
    });
}
