// voxfx — the renderer's glass pass (internal): replaces the shading of the pixels that show
// transmissive materials with the light that comes through them (voxfx/glass.hpp).
#pragma once

#include <vector>

#include "voxfx/render.hpp"

namespace voxfx::detail {

/// Shades the glass pixels of `shaded` (the G-buffer's samples, y up) with options.glass.kind, marks
/// them in `sampleMask` (one entry per sample), adds the pass's times to `timings`.
void shadeGlass(const GBuffer& gbuffer, const SceneGeometry& geometry, const Scene& scene,
                const std::vector<LightShadow>& shadows, const RenderOptions& options,
                const Environment& environment, std::vector<Vec3f>& shaded, std::vector<uint8_t>& sampleMask,
                RenderTimings& timings);

} // namespace voxfx::detail
