// voxfx — the deferred shading pass (internal): Blinn–Phong per light times the light's shadow.
#pragma once

#include <vector>

#include "render/frame_state.hpp"

namespace voxfx::detail {

/// Irradiance the light delivers at p without shadow (spot cone and 1/d^2 falloff included), and the
/// unit direction from p towards the light.
Vec3f lightIrradiance(const Light& light, const Vec3d& p, Vec3d& toLight);

/// Linear radiance of one surface point of frame.lit seen from `eye` (ambient + every light, each
/// times its shadow's visibility).
Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Vec3d& eye);
/// The same with material `m` instead of lit.materials[s.material] (the volume pass's objects).
Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Material& m, const Vec3d& eye);

/// The shading pass: every pixel of the G-buffer into frame.shaded (background where nothing was
/// hit, or the environment along the pixel's ray when one was given), rows in parallel; `progress`
/// is polled between row blocks.
void shadeGBuffer(FrameState& frame, Progress* progress);

} // namespace voxfx::detail
