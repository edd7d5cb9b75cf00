// voxfx — the renderer's G-buffer: the scene flattened into one mesh, the camera as a perspective
// Frame whose columns are pixels, and the nearest centre-sampled fragment per pixel kept by a
// consumer of the one rasterizer (DESIGN.md: "G-buffer for rendering: keep the nearest"); the
// surface point a pixel shows is reconstructed from it (position from depth, normals by
// barycentric interpolation). Pixel (x, y) has y up; images are y down, flipped on output.
//
// Thread-safety: flattenScene and renderGBuffer may run concurrently (renderGBuffer uses worker
// threads); a GBuffer and a SceneGeometry are values, read by any number of threads.
#pragma once

#include <cstdint>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/types.hpp"

namespace voxfx {

/// All meshes of a scene as one mesh, with per-triangle material and source mesh and per-vertex
/// unit normals: a mesh's given normals (glTF's) as they are; otherwise area-weighted face normals
/// split at creases, the vertex copied (same position) once per distinct normal around it, so a
/// box's faces are flat and a sphere is smooth. The meshes the G-buffer draws come first, in scene
/// order; the meshes of blended materials (Material::blend) follow them.
struct SceneGeometry {
    Mesh mesh;
    std::vector<uint32_t> triangleMaterial, triangleMesh;
    std::vector<Vec3f> normals;
    /// Triangles [0, drawnTriangles) are drawn by the G-buffer; the rest are blended meshes, which
    /// the fragment-list pass draws (they still cast shadows and refract in glass like the others).
    std::size_t drawnTriangles = 0;
};
/// Faces around a vertex whose normals differ by at most `creaseAngle` degrees (0..180) share a
/// smoothed normal; a wider angle is a crease (180: every vertex smooth; 0: flat faces). Cost
/// O(degree^2) per vertex. Throws voxfx::Error for an angle outside [0, 180] or more than 2^32 - 1
/// vertices after the split.
SceneGeometry flattenScene(const Scene& scene, double creaseAngle = kDefaultCreaseAngle);

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
/// The same into `out`, reusing its memory (a renderer's next frame of the same size allocates nothing).
void renderGBuffer(const SceneGeometry& geometry, const Frame& camera, GBuffer& out,
                   Progress* progress = nullptr);

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

} // namespace voxfx
