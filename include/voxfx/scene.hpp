// voxfx — scenes: meshes with materials, lights and cameras, loaded from glTF 2.0 or a JSON wrapper.
//
// The scene model is independent of any file format: everything is in world space (node transforms
// applied), units are the file's (glTF: metres), angles are radians, colours are linear RGB.
//
//   glTF 2.0 (.gltf, .glb)  meshes under their node transforms (a mesh used by two nodes becomes two
//                           SceneMeshes), cameras, KHR_lights_punctual (point, spot, directional),
//                           materials: baseColorFactor, alphaMode/alpha, doubleSided, roughness,
//                           KHR_materials_transmission, _ior, _volume. Geometry, node transforms,
//                           cameras and lights come through Assimp; the material extensions and the
//                           lights' exact parameters are read from the file's JSON (Assimp 5.2 does
//                           not expose KHR_materials_ior nor the volume attenuation).
//   JSON wrapper (.json)    what glTF cannot say: effect settings, grid resolution, extra meshes in
//                           other formats (OFF, OBJ, PLY, STL ... with a transform and a material),
//                           extra lights and cameras, meshes that only receive shadows, an
//                           environment map. Format: see loadScene below.
//   other mesh formats      one mesh with a default material, no lights or cameras.
//
// EXPERIMENTAL: the scene model will grow (textures, volumes for DSM) until the renderer issue closes.
// Thread-safety: a Scene is a value: concurrent reads are fine. loadScene/writeGltf of different
// paths may run concurrently; they run on the calling thread.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx {

struct VolumeScene; // voxfx/volume_scene.hpp

enum class LightType : uint8_t { Directional, Spot, Point };
inline constexpr EnumName<LightType> kLightTypeNames[] = {
    {"directional", LightType::Directional}, {"spot", LightType::Spot}, {"point", LightType::Point}};
const char* toString(LightType t);

/// A surface material. Partial occluders (leaves, glass) are surfaces that let a fraction of the
/// light through at every crossing; see crossingTransmittance.
struct Material {
    std::string name;
    Vec3f baseColor{0.8f, 0.8f, 0.8f}; ///< linear RGB albedo (glTF baseColorFactor.rgb)
    /// Fraction of the light a crossing of the surface stops, in [0, 1] (glTF baseColorFactor.a when
    /// alphaMode is BLEND or MASK, else 1). A leaf with gaps between its cells: 0.5–0.8.
    float opacity = 1;
    float transmission = 0;          ///< KHR_materials_transmission transmissionFactor, [0, 1]
    float ior = 1.5f;                ///< KHR_materials_ior, >= 1
    float thickness = 0;             ///< KHR_materials_volume thicknessFactor (world units)
    Vec3f attenuationColor{1, 1, 1}; ///< KHR_materials_volume
    float attenuationDistance = std::numeric_limits<float>::infinity(); ///< KHR_materials_volume
    float specular = 0.2f;    ///< Blinn–Phong specular weight (glTF: from roughness)
    float shininess = 32;     ///< Blinn–Phong exponent (glTF: 2 / roughness^4 - 2, clamped to [1, 1000])
    bool doubleSided = false; ///< glTF doubleSided (informative: the renderer lights both sides)
    /// The camera sees through the surface: it is drawn blended by its opacity over what lies behind
    /// it (glTF alphaMode BLEND; the fragment-list pass draws it, depth-sorted with the volumes).
    /// False: the camera sees a solid surface even when opacity < 1 (foliage: a leaf whose gaps pass
    /// light to the shadows but which the eye sees as a leaf; glTF alphaMode MASK). Shadows are the
    /// same either way.
    bool blend = false;

    /// RGB fraction of the light that passes one crossing of the surface:
    ///   (1 - opacity) + opacity * transmission * baseColor
    /// (light through the gaps passes unchanged; light through the tissue or glass is filtered by
    /// its colour). All zero for an opaque surface.
    Vec3f crossingTransmittance() const;
    /// True when no light passes a crossing (crossingTransmittance is zero in every channel).
    bool isOpaque() const;
    /// Glass: a dielectric volume that refracts the camera's rays and whose crossings pass
    /// 1 - Fresnel (transmission > 0 on a surface without gaps, opacity 1). A surface with gaps
    /// (opacity < 1) and transmission, such as a leaf, is a sheet: light passes its gaps and its
    /// tissue unbent.
    bool isGlass() const;
    /// What one crossing passes for the shadow methods that multiply crossings (transmittance,
    /// absorption, deep shadow maps). A sheet: crossingTransmittance. Glass, crossed twice per
    /// passage: each crossing passes 1 - F0 (Fresnel at normal incidence, ((ior - 1) / (ior + 1))^2),
    /// half the tint (its square root) and half the Beer–Lambert loss over `thickness`
    /// (KHR_materials_volume's typical thickness; none when 0), so that a passage gives what
    /// ExactShadow gives at normal incidence through that thickness.
    Vec3f shadowCrossingTransmittance() const;
};

/// One mesh in world space with one material.
struct SceneMesh {
    std::string name;
    Mesh mesh;
    /// Per-vertex normals (one per mesh.positions entry), or empty: the renderer then averages the
    /// face normals around each vertex (area-weighted).
    std::vector<Vec3f> normals;
    uint32_t material = 0;
    /// False for meshes that only receive shadows (a ground plane): light frames are not fitted to
    /// them and shadow grids do not hold them.
    bool castsShadow = true;
};

struct Light {
    LightType type = LightType::Directional;
    std::string name;
    Vec3d position{0, 0, 0};   ///< spot, point: world position
    Vec3d direction{0, 0, -1}; ///< directional, spot: unit direction the light travels
    Vec3f color{1, 1, 1};      ///< linear RGB
    /// Directional: irradiance on a surface facing the light. Spot and point: intensity; the
    /// irradiance at distance d is intensity / d^2 (glTF KHR_lights_punctual units).
    float intensity = 1;
    double innerConeAngle = 0;        ///< spot: full intensity inside this angle (radians)
    double outerConeAngle = M_PI / 4; ///< spot: no light outside this angle, in (0, pi/2]
    double range = 0;                 ///< 0 = unlimited (glTF range: smooth cut-off, informative)
};

struct Camera {
    std::string name;
    Vec3d position{0, 0, 5}, target{0, 0, 0}, up{0, 1, 0};
    double fovY = 0.8;       ///< vertical field of view, radians, in (0, pi)
    double nearDepth = 0.01; ///< view distance of the near plane (world units, > 0)
    double farDepth = 1.0e4; ///< far plane (geometry beyond it is still drawn: the depth is exact)
};

/// What the JSON wrapper adds to a scene; zero / empty means "not given" (the caller's default).
struct SceneSettings {
    std::string shadows; ///< none | map | transmittance | absorption
    int64_t width = 0, height = 0;
    int supersample = 0;
    int64_t gridResolution = 0; ///< light grid columns per side
    int64_t gridDepth = 0;      ///< light grid slices
    int64_t shadowMapResolution = 0;
    std::string slicing;        ///< uniform | local
    std::string voxelMode;      ///< surface | conservative
    std::string environmentMap; ///< path of an environment map (kept for the glass renderer)
    Vec3f ambient{-1, -1, -1};  ///< negative = not given
    Vec3f background{-1, -1, -1};
};

struct Scene {
    std::vector<Material> materials;
    std::vector<SceneMesh> meshes;
    std::vector<Light> lights;
    std::vector<Camera> cameras;
    SceneSettings settings;
    /// Volume objects and Boolean shapes (voxfx/volume_scene.hpp): deep shadows, and drawn by the
    /// renderer's ray casting over fragment lists; null when the scene has none.
    std::shared_ptr<const VolumeScene> volumeScene;
    std::string source; ///< file it was loaded from (for messages)
    /// What a loader understood but could not use (orthographic cameras, textures, non-triangle
    /// primitives ...), one line each; `voxfx scene-info` prints them.
    std::vector<std::string> warnings;

    /// Adds a material and returns its index.
    uint32_t addMaterial(const Material& m);
    /// Bounds of every mesh, or of the shadow casters only.
    Box3d bounds(bool castersOnly = false) const;
    std::size_t triangleCount() const;
    /// Checks what the renderer relies on; throws voxfx::Error naming the mesh, light or camera:
    /// material index out of range, invalid mesh (validateMesh), normals of the wrong count, light
    /// with a zero or non-finite direction (directional, spot), non-positive or NaN intensity,
    /// spot cone outside (0, pi/2] or inner > outer, camera with eye == target, fov outside (0, pi),
    /// near <= 0. Loaders call it; call it after editing a scene by hand.
    void validate() const;
};

/// Loads a scene by extension:
///   .gltf .glb   glTF 2.0 (see the file comment);
///   .json        the wrapper:
///     { "gltf": "tree.glb",                       optional, relative to the JSON file
///       "meshes": [ { "file": "bunny.off", "name": "bunny",
///                     "translate": [x,y,z], "scale": s or [sx,sy,sz],
///                     "rotate": [ax,ay,az, degrees],
///                     "material": { "name": "fur", "baseColor": [r,g,b], "opacity": 1,
///                                   "transmission": 0, "ior": 1.5, "specular": 0.2,
///                                   "shininess": 32 },
///                     "castsShadow": true } ],
///       "lights":  [ { "type": "directional|spot|point", "name": "sun", "position": [..],
///                      "direction": [..], "target": [..] (instead of direction),
///                      "color": [..], "intensity": 3, "innerConeDegrees": 20,
///                      "outerConeDegrees": 30 } ],
///       "cameras": [ { "position": [..], "target": [..], "up": [..], "fovYDegrees": 45,
///                      "near": 0.01 } ],
///       "receiversOnly": [ "Ground" ],             mesh names that cast no shadow
///       "render":  { "shadows": "transmittance", "width": 1280, "height": 720,
///                    "supersample": 2, "gridResolution": 256, "gridDepth": 256,
///                    "shadowMapResolution": 2048, "slicing": "local",
///                    "voxelMode": "surface", "ambient": [..], "background": [..] },
///       "environmentMap": "sky.pfm" }
///   anything loadMesh reads: one mesh, default material.
/// Throws voxfx::Error naming the file for a missing or unreadable file, an unknown extension (with
/// the allowed list), malformed JSON (with the position), unknown keys or light types, a light
/// without a usable direction, and everything Scene::validate rejects.
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

/// A camera looking at the whole scene from the front-above (used when a scene has no camera).
Camera defaultCamera(const Scene& scene, double aspect);

} // namespace voxfx
