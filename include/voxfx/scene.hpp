// voxfx — scenes: meshes with materials, lights and cameras (read from files by voxfx/scene_io.hpp).
//
// The scene model is independent of any file format: everything is in world space (node transforms
// applied), units are the file's (glTF: metres), angles are radians, colours are linear RGB. What
// the loaders read:
//
//   glTF 2.0 (.gltf, .glb)  meshes under their node transforms (a mesh used by two nodes becomes two
//                           SceneMeshes), cameras, KHR_lights_punctual (point, spot, directional),
//                           materials: baseColorFactor, alphaMode/alpha, doubleSided, roughness,
//                           KHR_materials_transmission, _diffuse_transmission, _ior, _volume.
//                           Geometry, node transforms,
//                           cameras and lights come through Assimp; the material extensions and the
//                           lights' exact parameters are read from the file's JSON (Assimp 5.2 does
//                           not expose KHR_materials_ior nor the volume attenuation).
//   JSON wrapper (.json)    what glTF cannot say: effect settings, grid resolution, extra meshes in
//                           other formats (OFF, OBJ, PLY, STL ... with a transform and a material),
//                           extra lights and cameras, meshes that only receive shadows, an
//                           environment map. Format: see loadScene (voxfx/scene_io.hpp).
//   other mesh formats      one mesh with a default material, no lights or cameras.
//
// EXPERIMENTAL: the scene model will grow (textures, volumes for DSM) until the renderer issue closes.
// Thread-safety: a Scene is a value: concurrent reads are fine.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"

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
    /// KHR_materials_diffuse_transmission diffuseTransmissionFactor, [0, 1]: the fraction of the
    /// diffuse response that passes through the surface instead of being reflected. With
    /// transmission 0, opacity 1 and no blend, a material with diffuseTransmission > 0 is a
    /// translucent solid (isTranslucent: jade, wax, marble; GI08 §7): its diffuse reflection is
    /// scaled by 1 - diffuseTransmission, light from a light on its far side passes with
    /// diffuseTransmissionColor times the light's shadow visibility (with `--shadows translucency`:
    /// Beer-Lambert over the matter the light crossed), and the camera sees what lies behind it
    /// through the solid, attenuated by beerLambert(attenuationCoefficient(), matter along the ray)
    /// (KHR_materials_volume's attenuationDistance and attenuationColor; the render pass
    /// "translucency", voxfx/render.hpp). Glass (transmission > 0) keeps its own path.
    float diffuseTransmission = 0;
    Vec3f diffuseTransmissionColor{1, 1, 1}; ///< KHR_materials_diffuse_transmission, linear RGB

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
    /// A translucent solid: diffuseTransmission > 0, not glass, opacity 1 and not blended (see
    /// diffuseTransmission). Shadow methods other than translucency treat it as opaque.
    bool isTranslucent() const;
    /// What one crossing passes for the shadow methods that multiply crossings (transmittance,
    /// absorption, deep shadow maps). A sheet: crossingTransmittance. Glass, crossed twice per
    /// passage: each crossing passes 1 - F0 (Fresnel at normal incidence, ((ior - 1) / (ior + 1))^2)
    /// and half the tint (its square root); the methods pair a crossing that enters with the next
    /// that leaves and multiply by beerLambert(shadowAttenuationCoefficient(), chord), so that a
    /// passage gives what ExactShadow gives at normal incidence (`thickness` is not used: the chord
    /// is the glass's own). Absorption, transmittance and deep shadows replace 1 - F0 by the
    /// crossing's own 1 - fresnelDielectric(cos, 1, ior), cos between the light's ray and the crossed
    /// triangle's normal, as ExactShadow does at every angle.
    Vec3f shadowCrossingTransmittance() const;
    /// Glass: attenuationCoefficient (Beer–Lambert over the chord between paired crossings); a sheet
    /// or an opaque material: zero (its crossings are all it does to light).
    Vec3f shadowAttenuationCoefficient() const;
};

/// KHR_materials_volume's attenuation coefficient of `m`: sigma = -ln(attenuationColor) /
/// attenuationDistance per channel, per world unit (zero when the distance is infinite or not > 0).
Vec3f attenuationCoefficient(const Material& m);
/// Beer–Lambert: exp(-sigma * length) per channel. The one glass attenuation of every shadow
/// method (ExactShadow over the traced chord, the light grids and deep shadow maps over the chord
/// between paired crossings) and of the glass tracers.
Vec3f beerLambert(const Vec3f& sigma, double length);
/// Exact unpolarized dielectric Fresnel reflectance for cos(incidence) cosI in [0, 1] from a medium of
/// index etaI into etaT; 1 under total internal reflection. The glass tracers' Fresnel, and that of
/// every glass crossing of the shadows (voxfx/glass_optics.hpp).
double fresnelDielectric(double cosI, double etaI, double etaT);

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

    /// Spot and point lights are at a position; a directional light is at infinity.
    bool positioned() const { return type != LightType::Directional; }
    /// Towards the light from world point p: for a directional light the unit vector against its
    /// direction; for a spot or point light position - p, not normalized (its length is the
    /// distance to the light).
    Vec3d towards(const Vec3d& p) const { return positioned() ? position - p : -normalize(direction); }
};

struct Camera {
    std::string name;
    Vec3d position{0, 0, 5}, target{0, 0, 0}, up{0, 1, 0};
    double fovY = 0.8;       ///< vertical field of view, radians, in (0, pi)
    double nearDepth = 0.01; ///< view distance of the near plane (world units, > 0)
    double farDepth = 1.0e4; ///< far plane (geometry beyond it is still drawn: the depth is exact)
};

/// What a scene file says about how to render it: the JSON wrapper's "render" settings, by name
/// ("shadows", "glass", and the names voxfx/render.hpp's setRenderOption takes, such as
/// "gridResolution" or "ambient"; renderOptionsFor applies them, the techniques first), and its
/// environment map. Nothing is given where the file says nothing: the defaults are the options
/// structs' own.
struct SceneSettings {
    std::vector<std::pair<std::string, OptionValue>> render;
    std::string environmentMap; ///< path of an environment map (resolved against the scene file), or empty
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

/// A camera looking at the whole scene from the front-above (used when a scene has no camera).
Camera defaultCamera(const Scene& scene, double aspect);

/// The scene's camera `index`; for a scene without cameras, index 0 is defaultCamera(scene,
/// aspect). Throws voxfx::Error naming the cameras there are otherwise.
Camera sceneCamera(const Scene& scene, int index, double aspect);

} // namespace voxfx
