// voxfx — reading environment maps (voxfx/environment.hpp) from image files, and the one a scene
// renders under.
// Thread-safety: loadEnvironment may run concurrently; it runs on the calling thread.
#pragma once

#include <memory>
#include <string>

#include "voxfx/environment.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {

/// Loads an environment map by extension: .exr (OpenEXR, through the exr module), .pfm, .hdr
/// (Radiance RGBE, flat or run-length encoded), .png (sRGB, decoded to linear). The string "sky"
/// gives the default procedural sky. Throws voxfx::Error naming the file.
Environment loadEnvironment(const std::string& path);

/// The environment `scene` renders under with `options` (what `voxfx render` and Python's render
/// use): `requested` if not empty ("sky" or a file), else the scene file's environmentMap; null
/// otherwise (render then uses its own: the procedural sky, or the flat background with
/// RenderOptions::sky = flat). The environment is what the background shows, what glass sees and
/// the ambient light. Throws voxfx::Error as loadEnvironment does.
std::shared_ptr<const Environment> loadSceneEnvironment(const Scene& scene, const RenderOptions& options,
                                                        const std::string& requested = {});

} // namespace voxfx
