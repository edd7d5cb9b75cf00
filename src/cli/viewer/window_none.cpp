// voxfx view — the stand-in for a build without SDL2 (viewer.hpp).
#include "viewer.hpp"

namespace voxfx::cli::viewer {

int runViewer(ViewSetup) {
    fail("voxfx view needs SDL2, which this build of voxfx did not find: install it (Debian: "
         "libsdl2-dev, which scripts/install-deps.sh installs) and build again");
}

} // namespace voxfx::cli::viewer
