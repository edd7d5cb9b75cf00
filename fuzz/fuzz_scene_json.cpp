// voxfx — fuzz target: the JSON scene wrapper (parseSceneJson, what loadScene reads from a .json).
// The text is named by a path in a folder that does not exist, so the relative file names it
// holds are never found (absolute names still are, which is what a hostile file can do too).
#include "fuzz_target.hpp"
#include "voxfx/scene_io.hpp"

VOXFX_FUZZ_TARGET(scene_json) {
    voxfx::fuzz::expectCleanError([&] {
        (void)voxfx::parseSceneJson(voxfx::fuzz::asText(data), "/nonexistent-voxfx-fuzz/scene.json");
    });
}
