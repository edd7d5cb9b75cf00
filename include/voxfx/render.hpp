// voxfx — the rasterizing renderer: G-buffer, light loop with shadows, Blinn–Phong shading.
//
// Passes (each separable, so later effects — glass, deep shadow maps — slot in as new passes):
//   1. flattenScene   every SceneMesh into one indexed mesh with per-triangle material and vertex
//                     normals (once per scene); meshes of blended materials last.
//   2. renderGBuffer  the camera is a perspective Frame whose columns are pixels (y up; images are
//                     y down, flipped on output); a consumer of the one rasterizer keeps the
//                     nearest centre-sampled fragment per pixel (depth, triangle). Ties go to the
//                     lower triangle index, so the result does not depend on the thread count.
//   3. shadows        one LightShadow per light (shadow.hpp): standard map, ED06 transmittance,
//                     CHANG absorption, or shadow volumes counted over the G-buffer.
//   4. shade          deferred, tile rows in parallel: ambient + per light Blinn–Phong times the
//                     light's RGB visibility. Surfaces are lit on both sides; the side facing away
//                     from a light receives the light that crosses the surface
//                     (crossingTransmittance: back-lit leaves glow).
//   4b. volumes       scenes with volume objects, Boolean shapes (scene.volumeScene) or meshes of
//                     blended materials: ray casting over fragment lists from the camera, composited
//                     over the shaded image (render/volume_pass): volumes sampled, and the visible
//                     surfaces of opaque and translucent objects (where a Boolean's inside flag
//                     changes) and of blended meshes shaded like meshes and α-blended in depth order.
//   5. resolve        box filter of supersample x supersample pixels.
// Output is linear RGB (writePng encodes sRGB; writePfm keeps HDR). Deterministic for any thread
// count.
//
// EXPERIMENTAL until the renderer issue closes.
// Thread-safety: render calls may run concurrently on one const Scene; each uses worker threads
// (RenderOptions::threads) itself.
#pragma once

#include <cstdint>
#include <vector>

#include "voxfx/environment.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/image.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {

struct RenderOptions {
    int64_t width = 1280, height = 720; ///< output pixels
    int supersample = 1;                ///< k: render k*width x k*height, box-filter down (1..8)
    ShadowOptions shadow;               ///< shadow kind and its resolutions
    Vec3f ambient{0.05f, 0.06f, 0.08f}; ///< ambient irradiance (times albedo)
    Vec3f background{0.60f, 0.72f, 0.90f};
    float exposure = 1; ///< multiplies the linear result (background included)
    GlassOptions glass; ///< refraction through transmissive materials (none: shaded as surfaces)
    /// Radiance around the scene: shown as the background and seen through and in glass. Null: the
    /// flat `background`, and the procedural sky (Environment::sky) where glass needs one. Not owned.
    const Environment* environment = nullptr;
    /// A scene without lights is lit by a sun (the sky's, or SkyOptions' default direction for maps)
    /// and the environment's average radiance as ambient, as glTF viewers do.
    bool defaultLights = true;
    int threads = 0;              ///< 0 = all; output is identical for every value
    Progress* progress = nullptr; ///< polled between tiles of every pass; may cancel
    /// Volume ray casting (scene.volumeScene): sample step in smallest voxel spacings.
    double volumeStep = 1.0;
    /// Volume ray casting: volume bricks the transfer function leaves transparent are not sampled
    /// (EmptySpace, voxfx/volume_scene.hpp); the image is the same either way, only faster.
    bool skipEmptySpace = true;
};

/// Wall-clock time of each pass, milliseconds.
struct RenderTimings {
    double flattenMs = 0, gbufferMs = 0, shadowMapMs = 0, lightVoxelizeMs = 0, shadingMs = 0, resolveMs = 0,
           totalMs = 0;
    double shadowVolumeMs = 0; ///< ShadowKind::Volumes: culling, construction and counting
    double glassPrepareMs = 0; ///< Embree build (exact) or attribute voxelization (voxel methods)
    double glassMs = 0;        ///< tracing the glass pixels
    double volumeMs = 0;       ///< volume ray casting over fragment lists (scenes with volumes)
};

struct RenderResult {
    Image image;
    RenderTimings timings;
    int64_t coveredPixels = 0;         ///< pixels (at the supersampled resolution) showing geometry
    int64_t shadowVolumeFragments = 0; ///< ShadowKind::Volumes: volume fragments, all lights
    /// Per output pixel (row-major, row 0 on top): 1 where any of its samples shows glass, else 0.
    /// Empty when options.glass.kind is None.
    std::vector<uint8_t> glassMask;
    int64_t volumeSamples = 0; ///< volume samples the ray-casting pass took
    DsmStats deepShadowStats;  ///< ShadowKind::Deep: node and memory statistics over all lights' maps
};

/// All meshes of a scene as one mesh, with per-triangle material and source mesh and per-vertex
/// unit normals (given ones, or area-weighted face normals). The meshes the G-buffer draws come
/// first, in scene order; the meshes of blended materials (Material::blend) follow them.
struct SceneGeometry {
    Mesh mesh;
    std::vector<uint32_t> triangleMaterial, triangleMesh;
    std::vector<Vec3f> normals;
    /// Triangles [0, drawnTriangles) are drawn by the G-buffer; the rest are blended meshes, which
    /// the fragment-list pass draws (they still cast shadows and refract in glass like the others).
    std::size_t drawnTriangles = 0;
};
SceneGeometry flattenScene(const Scene& scene);

/// Nearest fragment per pixel. Pixel (x, y) with y up; triangle == kNone where nothing was hit.
struct GBuffer {
    static constexpr uint32_t kNone = 0xffffffffu;
    Frame frame;              ///< the camera's perspective frame (columns = pixels)
    std::vector<float> depth; ///< view distance along the camera axis
    std::vector<uint32_t> triangle;
};
/// The camera's frame for a width x height image.
Frame cameraFrame(const Camera& camera, int64_t width, int64_t height);
GBuffer renderGBuffer(const SceneGeometry& geometry, const Frame& camera, Progress* progress = nullptr);

/// What the shading pass knows about the surface seen through pixel (x, y) (y up).
struct SurfacePoint {
    Vec3d position;        ///< world
    Vec3d normal;          ///< interpolated vertex normal, turned towards the viewer
    Vec3d geometricNormal; ///< face normal, turned towards the viewer
    uint32_t material = 0;
};
/// False for background pixels.
bool surfaceAt(const GBuffer& gbuffer, const SceneGeometry& geometry, int64_t x, int64_t y,
               SurfacePoint& out);

/// Renders the scene as seen by `camera`. Throws voxfx::Error for invalid options (size, supersample)
/// or a scene without triangles; Scene::validate is called first.
RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options);

} // namespace voxfx
