// voxfx — the renderer's glass pass (internal): replaces the shading of the pixels that show glass
// with the light that comes through them (voxfx/glass.hpp).
#pragma once

#include "render/frame_state.hpp"

namespace voxfx::detail {

/// With a glass method other than none: shades the glass samples of frame.shaded with it, marks them
/// in frame.glassSamples (one entry per sample) and records the method's times in frame.result.glass.
void shadeGlass(FrameState& frame);

} // namespace voxfx::detail
