// voxfx view — the window (internal to cli/): SDL2 when the build found it (window_sdl.cpp), else a
// stand-in that says what is missing (window_none.cpp).
#pragma once

#include "session.hpp"

namespace voxfx::cli::viewer {

/// Opens the window on `setup` and runs until it is closed (Esc, Q, the window's close button);
/// returns the exit code. Throws voxfx::Error when there is no window to open: a build without
/// SDL2, no display ($DISPLAY and $WAYLAND_DISPLAY unset), or SDL failing to start.
int runViewer(ViewSetup setup);

} // namespace voxfx::cli::viewer
