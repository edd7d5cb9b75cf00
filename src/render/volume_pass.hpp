// voxfx — the volume ray-casting pass (internal): volumes of the scene's VolumeScene composited over
// the shaded G-buffer (Bornik et al. §3).
#pragma once

#include <vector>

#include "voxfx/render.hpp"

namespace voxfx::detail {

/// Camera ray casting over fragment lists: the boundary triangles of the scene's volume scene are
/// rasterized into fragment lists over the camera frame; each pixel walks its list front to back,
/// skips segments outside every volume object, samples the volumes inside at steps of
/// `options.volumeStep` smallest voxel spacings up to the G-buffer's depth, composites
/// front to back (sample opacity 1 - (1 - α)^(dl / opacityLength), colour = transfer colour ×
/// (ambient + Σ lights irradiance × shadow visibility / π)), stops when the accumulated opacity
/// reaches 0.999, and blends the result over `shaded` (row-major, y up). Returns the number of
/// volume samples taken. Nothing happens when the scene has no volume objects.
int64_t compositeVolumes(const GBuffer& gbuffer, const Scene& scene, const std::vector<LightShadow>& shadows,
                         const RenderOptions& options, std::vector<Vec3f>& shaded, Progress* progress);

} // namespace voxfx::detail
