// voxfx — scene files: glTF 2.0 (.gltf, .glb), the JSON wrapper (.json) and single meshes read
// into a Scene (voxfx/scene.hpp), and scenes written as glTF.
//
// Thread-safety: loadScene, parseSceneJson and writeGltf of different paths may run concurrently;
// they run on the calling thread.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "voxfx/options.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {

/// Loads a scene by extension:
///   .gltf .glb   glTF 2.0 (see the file comment);
///   .json        the wrapper:
///     { "gltf": "tree.glb",                       optional, relative to the JSON file
///       "scene": "base.json",                     or: any scene file (glTF, wrapper, mesh) this
///                                                 one adds to; its cameras come after this file's,
///                                                 its "render" settings give way to this file's
///       "meshes": [ { "file": "bunny.off", "name": "bunny",
///                     "translate": [x,y,z], "scale": s or [sx,sy,sz],
///                     "rotate": [ax,ay,az, degrees],
///                     "material": { "name": "fur", "baseColor": [r,g,b], "opacity": 1,
///                                   "transmission": 0, "ior": 1.5, "specular": 0.2,
///                                   "shininess": 32,
///                                   "diffuseTransmission": 0, "diffuseTransmissionColor": [r,g,b],
///                                   "attenuationDistance": d, "attenuationColor": [r,g,b] },
///                     (diffuseTransmission > 0: a translucent solid, Material::diffuseTransmission)
///                     "castsShadow": true } ],
///       "lights":  [ { "type": "directional|spot|point", "name": "sun", "position": [..],
///                      "direction": [..], "target": [..] (instead of direction),
///                      "color": [..], "intensity": 3, "innerConeDegrees": 20,
///                      "outerConeDegrees": 30 } ],
///       "cameras": [ { "position": [..], "target": [..], "up": [..], "fovYDegrees": 45,
///                      (or "fovY": radians), "near": 0.01, "far": 1e4 } ],
///       "receiversOnly": [ "Ground" ],             mesh names that cast no shadow
///       "render":  { "shadows": "transmittance", "width": 1280, "height": 720,
///                    "supersample": 2, "gridResolution": 256, "gridDepth": 256,
///                    "shadowMapResolution": 2048, "slicing": "local",
///                    "voxelMode": "surface", "ambient": [..], "background": [..] },
///       "environmentMap": "sky.pfm" }              ("sky": the procedural sky)
///   anything loadMesh reads: one mesh, default material.
/// Throws voxfx::Error naming the file for a missing or unreadable file, an unknown extension (with
/// the allowed list), malformed JSON (with the position), unknown keys or light types, a light
/// without a usable direction, a wrapper that includes itself through "scene", and everything
/// Scene::validate rejects.
Scene loadScene(const std::string& path);

/// The JSON wrapper from text, as loadScene reads it from a .json file: `path` names the text in
/// messages and is the file its relative names are resolved against (it is not read itself).
/// Throws voxfx::Error as loadScene does.
Scene parseSceneJson(std::string_view json, const std::string& path);

/// Writes a scene as glTF 2.0: .gltf (JSON with the buffer embedded as a base64 data URI) or .glb
/// (binary container). Materials with their extensions, lights (KHR_lights_punctual) and cameras are
/// written as nodes; meshes are written in world space under identity nodes. Per-vertex normals are
/// written when present. Atomic (temporary file, then rename). Throws voxfx::Error.
void writeGltf(const Scene& scene, const std::string& path);

/// A JSON wrapper that adds cameras and render settings to another scene file: how a viewer saves
/// a view (`voxfx view`) so that `voxfx render` of the file reproduces its frame.
struct SceneView {
    /// "scene": the scene file it adds to, as it is written (a relative path is taken relative to
    /// the folder of the JSON file, as loadScene reads it).
    std::string scene;
    /// "cameras": they come first in the loaded scene (camera 0 is cameras[0]); the field of view is
    /// written in radians ("fovY"), so every number reads back bit for bit.
    std::vector<Camera> cameras;
    /// "render": settings by name (voxfx/view.hpp's renderSettings gives every one of a
    /// RenderOptions), in this order.
    std::vector<std::pair<std::string, OptionValue>> render;
    /// "environmentMap" when not empty, as it is written ("sky": the procedural sky).
    std::string environmentMap;
};

/// Writes `view` as a JSON wrapper (.json) that loadScene reads; numbers are written so that they
/// read back bit for bit. Atomic (temporary file, then rename). Throws voxfx::Error for another
/// extension, a non-finite number, or a failed write.
void writeSceneView(const SceneView& view, const std::string& path);

} // namespace voxfx
