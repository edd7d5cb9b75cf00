// voxfx — reading environment maps (voxfx/environment.hpp) from image files.
// Thread-safety: loadEnvironment may run concurrently; it runs on the calling thread.
#pragma once

#include <string>

#include "voxfx/environment.hpp"

namespace voxfx {

/// Loads an environment map by extension: .exr (OpenEXR, through the exr module), .pfm, .hdr
/// (Radiance RGBE, flat or run-length encoded), .png (sRGB, decoded to linear). The string "sky"
/// gives the default procedural sky. Throws voxfx::Error naming the file.
Environment loadEnvironment(const std::string& path);

} // namespace voxfx
