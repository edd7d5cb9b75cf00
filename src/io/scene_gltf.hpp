// voxfx — glTF 2.0 scenes (internal): loading through Assimp plus the file's JSON, and writing.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "voxfx/scene.hpp"

namespace voxfx::detail {

/// The JSON document of a .gltf file or of a .glb container's JSON chunk. Throws voxfx::Error naming
/// the file for an unreadable file, a bad GLB header or chunk, and malformed JSON (with the byte).
nlohmann::json readGltfJson(const std::string& path, bool binary);

/// Loads a .gltf / .glb file (see scene.hpp). Validation is left to the caller.
Scene loadGltfScene(const std::string& path);

/// Whole file as a string; voxfx::Error naming the file (and `what` it is) when it cannot be read.
std::string readTextFile(const std::string& path, const char* what);

/// directional | spot | point (glTF KHR_lights_punctual and the JSON wrapper spell them alike);
/// voxfx::Error starting with `where` and listing the allowed names otherwise.
LightType parseLightType(const std::string& type, const std::string& where);

} // namespace voxfx::detail
