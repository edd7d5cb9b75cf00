// voxfx — fuzz target: the JSON scene wrapper (loadScene on a .json). The files it names are
// resolved next to a scratch file in a folder of its own, so relative names are not found.
#include "fuzz_target.hpp"
#include "voxfx/scene.hpp"

VOXFX_FUZZ_TARGET(scene_json) {
    static const std::string path = voxfx::fuzz::scratchPath("scene.json");
    voxfx::fuzz::writeFile(path, data);
    voxfx::fuzz::expectCleanError([&] { (void)voxfx::loadScene(path); });
}
