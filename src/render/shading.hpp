// voxfx — the deferred shading pass (internal): Blinn–Phong per light times the light's shadow.
#pragma once

#include <vector>

#include "voxfx/render.hpp"

namespace voxfx::detail {

/// Irradiance the light delivers at p without shadow (spot cone and 1/d^2 falloff included), and the
/// unit direction from p towards the light.
Vec3f lightIrradiance(const Light& light, const Vec3d& p, Vec3d& toLight);

/// Linear radiance of one surface point seen from `eye` (ambient + every light).
Vec3f shadePoint(const SurfacePoint& s, const Scene& scene, const std::vector<LightShadow>& shadows,
                 const RenderOptions& options, const Vec3d& eye);
/// The same with material `m` instead of scene.materials[s.material] (the volume pass's objects).
Vec3f shadePoint(const SurfacePoint& s, const Material& m, const Scene& scene,
                 const std::vector<LightShadow>& shadows, const RenderOptions& options, const Vec3d& eye);

/// Shades every pixel of the G-buffer (row-major, y up, background where nothing was hit), rows in
/// parallel; `progress` is polled between row blocks.
std::vector<Vec3f> shadeGBuffer(const GBuffer& gbuffer, const SceneGeometry& geometry, const Scene& scene,
                                const std::vector<LightShadow>& shadows, const RenderOptions& options,
                                Progress* progress);

} // namespace voxfx::detail
