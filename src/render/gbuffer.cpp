// voxfx — the G-buffer: the camera is a perspective Frame whose columns are pixels, and a consumer
// of the one rasterizer keeps the nearest centre-sampled fragment per pixel (DESIGN.md: "G-buffer
// for rendering: keep the nearest"). Also the scene flattening and surface reconstruction the
// shading pass reads (position from depth, normals by barycentric interpolation).
#include "voxfx/gbuffer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/raster.hpp"

namespace voxfx {

namespace {

struct NearestFragmentConsumer {
    int64_t width;
    double nearDepth;
    GBuffer& g;
    struct Sink {
        int64_t width;
        double nearDepth;
        GBuffer& g;
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool) {
            if (!(depth >= nearDepth)) return; // the rasterizer keeps geometry in front of near
            const auto i = size_t(y * width + x);
            const float d = float(depth);
            // Ties go to the lower triangle index: independent of the visiting order.
            if (d < g.depth[i] || (d == g.depth[i] && triangle < g.triangle[i])) {
                g.depth[i] = d;
                g.triangle[i] = triangle;
            }
        }
        void finish() {}
    };
    Sink tile(const Tile&) const { return {width, nearDepth, g}; }
};

} // namespace

SceneGeometry flattenScene(const Scene& scene) {
    SceneGeometry g;
    std::size_t vertices = 0, triangles = 0;
    for (const SceneMesh& m : scene.meshes) {
        vertices += m.mesh.positions.size();
        triangles += m.mesh.triangleCount();
    }
    if (vertices > 0xffffffffu) fail("the scene has ", vertices, " vertices, more than 32-bit indices allow");
    g.mesh.positions.reserve(vertices);
    g.mesh.indices.reserve(3 * triangles);
    g.normals.reserve(vertices);
    g.triangleMaterial.reserve(triangles);
    g.triangleMesh.reserve(triangles);
    // The G-buffer draws a prefix of the triangles: meshes of blended materials go last.
    auto blended = [&](const SceneMesh& m) {
        return m.material < scene.materials.size() && scene.materials[m.material].blend;
    };
    std::vector<std::size_t> order;
    order.reserve(scene.meshes.size());
    for (int pass = 0; pass < 2; ++pass)
        for (std::size_t k = 0; k < scene.meshes.size(); ++k)
            if (blended(scene.meshes[k]) == (pass == 1)) order.push_back(k);
    for (const std::size_t k : order) {
        const SceneMesh& m = scene.meshes[k];
        if (!blended(m)) g.drawnTriangles += m.mesh.triangleCount();
        const auto base = uint32_t(g.mesh.positions.size());
        g.mesh.positions.insert(g.mesh.positions.end(), m.mesh.positions.begin(), m.mesh.positions.end());
        for (const uint32_t i : m.mesh.indices) g.mesh.indices.push_back(base + i);
        g.triangleMaterial.insert(g.triangleMaterial.end(), m.mesh.triangleCount(), m.material);
        g.triangleMesh.insert(g.triangleMesh.end(), m.mesh.triangleCount(), uint32_t(k));
        if (!m.normals.empty()) {
            g.normals.insert(g.normals.end(), m.normals.begin(), m.normals.end());
            continue;
        }
        // Area-weighted face normals (the cross product's length is twice the area).
        std::vector<Vec3d> sum(m.mesh.positions.size());
        for (std::size_t t = 0; t < m.mesh.triangleCount(); ++t) {
            const uint32_t a = m.mesh.indices[3 * t], b = m.mesh.indices[3 * t + 1],
                           c = m.mesh.indices[3 * t + 2];
            const Vec3d pa(m.mesh.positions[a]), pb(m.mesh.positions[b]), pc(m.mesh.positions[c]);
            const Vec3d n = cross(pb - pa, pc - pa);
            sum[a] += n;
            sum[b] += n;
            sum[c] += n;
        }
        for (const Vec3d& n : sum) g.normals.push_back(Vec3f(normalize(n)));
    }
    return g;
}

Frame cameraFrame(const Camera& camera, int64_t width, int64_t height) {
    const double far = std::max(camera.farDepth, camera.nearDepth * 2);
    return Frame::perspective(camera.position, camera.target, camera.up, camera.fovY, width, height,
                              camera.nearDepth, far, 1);
}

GBuffer renderGBuffer(const SceneGeometry& geometry, const Frame& camera, Progress* progress) {
    GBuffer g;
    g.frame = camera;
    g.depth.assign(size_t(camera.columnCount()), std::numeric_limits<float>::infinity());
    g.triangle.assign(size_t(camera.columnCount()), GBuffer::kNone);
    if (geometry.drawnTriangles == 0) return g;
    NearestFragmentConsumer consumer{camera.width(), camera.nearDepth(), g};
    RasterOptions ro;
    ro.progress = progress;
    MeshView drawn = geometry.mesh.view();
    drawn.triangleCount = geometry.drawnTriangles;
    rasterize(camera, drawn, ro, consumer);
    return g;
}

bool surfaceAt(const GBuffer& gbuffer, const SceneGeometry& geometry, int64_t x, int64_t y,
               SurfacePoint& out) {
    const auto i = size_t(y * gbuffer.frame.width() + x);
    const uint32_t t = gbuffer.triangle[i];
    if (t == GBuffer::kNone) return false;
    const uint32_t ia = geometry.mesh.indices[3 * size_t(t)], ib = geometry.mesh.indices[3 * size_t(t) + 1],
                   ic = geometry.mesh.indices[3 * size_t(t) + 2];
    const Vec3d a(geometry.mesh.positions[ia]), b(geometry.mesh.positions[ib]),
        c(geometry.mesh.positions[ic]);
    // The pixel ray meets the triangle's plane where the interpolated depth says.
    const Vec3d p = gbuffer.frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, double(gbuffer.depth[i])});
    Vec3d ng = cross(b - a, c - a);
    const double area2 = dot(ng, ng);
    // Barycentrics of p (sub-triangle areas over the whole), clamped against rounding.
    double wa = 1.0 / 3, wb = 1.0 / 3, wc = 1.0 / 3;
    if (area2 > 0) {
        wa = std::max(0.0, dot(cross(b - p, c - p), ng) / area2);
        wb = std::max(0.0, dot(cross(c - p, a - p), ng) / area2);
        wc = std::max(0.0, 1.0 - wa - wb);
    }
    ng = normalize(ng);
    Vec3d n = normalize(Vec3d(geometry.normals[ia]) * wa + Vec3d(geometry.normals[ib]) * wb +
                        Vec3d(geometry.normals[ic]) * wc);
    if (!(length(n) > 0)) n = ng;
    // Both sides are visible: turn the normals towards the viewer.
    const Vec3d toEye = gbuffer.frame.eye() - p;
    if (dot(ng, toEye) < 0) ng = -ng;
    if (dot(n, ng) < 0) n = -n;
    out.position = p;
    out.normal = n;
    out.geometricNormal = ng;
    out.material = geometry.triangleMaterial[t];
    return true;
}

} // namespace voxfx
