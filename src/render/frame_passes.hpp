// voxfx — passes of the renderer's frame (internal) that have a file of their own and nothing else
// to declare; renderer.cpp lists them in order with the rest.
#pragma once

#include "render/frame_state.hpp"

namespace voxfx::detail {

/// render/occlusion_pass.cpp: the ambient light's occlusion (RenderOptions::ambientOcclusion):
/// nothing where it is off or there is no ambient light; its setup (opaque triangles, region,
/// radius) and, for the field method, the field (voxfx/ambient_occlusion.hpp), both kept in the
/// cache (f.occlusion); for the screen method, GTAO (render/screen_space_ao.hpp) over the
/// G-buffer's cells, one sample each (the one the shading pass shades), up to the upsample, which the
/// shading pass does (f.cellOcclusion, filling f.screenOcclusion).
void occlusionPass(FrameState& f, Progress* progress);

/// render/resolve_pass.cpp: box filter of the k x k (times adaptive) samples of each pixel, each
/// tone-mapped first (so an edge against a bright sky keeps its coverage), and flip: frame rows
/// run up, image rows down. Then the post-process anti-aliasing on the pixels adaptive sampling
/// did not refine (nor touch), and the glass mask.
void resolvePass(FrameState& f, Progress* progress);

} // namespace voxfx::detail
