// voxfx — the G-buffer: the camera is a perspective Frame whose columns are pixels, and a consumer
// of the one rasterizer keeps the nearest centre-sampled fragment per pixel (DESIGN.md: "G-buffer
// for rendering: keep the nearest"). Also the scene flattening and surface reconstruction the
// shading pass reads (position from depth, normals by barycentric interpolation).
#include "voxfx/gbuffer.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#ifdef __AVX2__
#include <immintrin.h>
#endif

#include "render/antialias.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {

namespace {

struct NearestFragmentConsumer {
    int64_t width;
    double nearDepth;
    GBuffer& g;
    const std::function<void(int64_t, int64_t)>* rowsDone; ///< called on each tile's rows when done, or null
    struct Sink {
        int64_t width;
        double nearDepth;
        GBuffer& g;
        const std::function<void(int64_t, int64_t)>* rowsDone;
        int64_t y0, y1; ///< the tile's rows
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
#ifdef __AVX2__
        // Four neighbours of a row at once, branch-free: lane k is fragment(x + k, ...)'s test
        // and writes (the depth as float, the same comparisons). A tile is whole rows (Tile), so
        // the four are read and written back whole (a lane it does not cover keeps its value); at
        // the row's end, masked to the covered lanes (nothing past the row is touched).
        void fragments(int64_t x, int64_t y, const double* depth, unsigned bits, uint32_t triangle, bool) {
            const __m256d d = _mm256_loadu_pd(depth);
            // !(depth >= nearDepth) leaves the lane (NaN too: an ordered comparison).
            bits &= unsigned(_mm256_movemask_pd(_mm256_cmp_pd(d, _mm256_set1_pd(nearDepth), _CMP_GE_OQ)));
            if (bits == 0) return;
            const __m128i lane = _mm_setr_epi32(1, 2, 4, 8);
            const __m128i mask = _mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(int(bits)), lane), lane);
            const auto i = size_t(y * width + x);
            float* depthAt = g.depth.data() + i;
            auto* triangleAt = reinterpret_cast<__m128i*>(g.triangle.data() + i);
            const bool whole = x + 4 <= width;
            const __m128 f = _mm256_cvtpd_ps(d); // float(depth), rounded to nearest as the cast
            const __m128 old = whole ? _mm_loadu_ps(depthAt) : _mm_maskload_ps(depthAt, mask);
            const __m128i oldTriangle = whole ? _mm_loadu_si128(triangleAt)
                                              : _mm_maskload_epi32(reinterpret_cast<int*>(triangleAt), mask);
            const __m128i t = _mm_set1_epi32(int(triangle));
            // triangle < old triangle, unsigned: a signed comparison with the sign bits flipped.
            const __m128i sign = _mm_set1_epi32(int(0x80000000u));
            const __m128i lower = _mm_cmpgt_epi32(_mm_xor_si128(oldTriangle, sign), _mm_xor_si128(t, sign));
            const __m128i nearer =
                _mm_or_si128(_mm_castps_si128(_mm_cmp_ps(f, old, _CMP_LT_OQ)),
                             _mm_and_si128(_mm_castps_si128(_mm_cmp_ps(f, old, _CMP_EQ_OQ)), lower));
            const __m128i write = _mm_and_si128(mask, nearer);
            if (whole) { // stored whatever the test gave: no branch on it (as good as random)
                _mm_storeu_ps(depthAt, _mm_blendv_ps(old, f, _mm_castsi128_ps(write)));
                _mm_storeu_si128(triangleAt, _mm_blendv_epi8(oldTriangle, t, write));
            } else {
                _mm_maskstore_ps(depthAt, write, f);
                _mm_maskstore_epi32(reinterpret_cast<int*>(triangleAt), write, t);
            }
        }
#endif
        void finish() {
            if (rowsDone) (*rowsDone)(y0, y1);
        }
    };
    Sink tile(const Tile& t) const { return {width, nearDepth, g, rowsDone, t.y0, t.y1}; }
};

} // namespace

namespace {

// Appends `m` to `g` with vertex normals split at creases: the normal of a corner is the
// area-weighted sum of the face normals around its vertex that are within the crease angle
// (cos >= cosCrease) of its own face's; the corners of a vertex with equal normals share one copy
// of it. Positions are copied exactly, so the split changes no surface, only its shading. A vertex
// whose faces all lie within half the angle of their mean costs O(degree), others O(degree^2).
void appendCreased(SceneGeometry& g, const Mesh& m, double cosCrease, double cosHalf) {
    const std::size_t V = m.positions.size(), T = m.triangleCount();
    std::vector<Vec3d> face(T), unit(T);
    for (std::size_t t = 0; t < T; ++t) {
        const Vec3d a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]),
            c(m.positions[m.indices[3 * t + 2]]);
        face[t] = cross(b - a, c - a); // twice the area
        const double len = length(face[t]);
        unit[t] = len > 0 ? face[t] / len : Vec3d{0, 0, 0};
    }
    // The corners around each vertex, in corner order (so sums run in a fixed order).
    std::vector<std::size_t> start(V + 1, 0), around(3 * T);
    for (const uint32_t i : m.indices) ++start[i + 1];
    for (std::size_t v = 0; v < V; ++v) start[v + 1] += start[v];
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t c = 0; c < 3 * T; ++c) around[fill[m.indices[c]]++] = c;
    std::vector<uint32_t> index(3 * T);
    std::vector<std::pair<Vec3d, uint32_t>> made;
    for (std::size_t v = 0; v < V; ++v) {
        made.clear();
        if (start[v] == start[v + 1]) { // unused: kept, so the scene's bounds do not change
            g.mesh.positions.push_back(m.positions[v]);
            g.normals.push_back(Vec3f{0, 0, 0});
        }
        // Every face within half the angle of the mean: every pair within the angle, so every
        // corner has the whole sum (the common case, O(degree)).
        Vec3d all{0, 0, 0};
        for (std::size_t k = start[v]; k < start[v + 1]; ++k) all += face[around[k] / 3];
        bool smooth = length(all) > 0;
        const Vec3d mean = smooth ? normalize(all) : all;
        for (std::size_t k = start[v]; k < start[v + 1] && smooth; ++k)
            smooth = dot(unit[around[k] / 3], mean) >= cosHalf;
        for (std::size_t j = start[v]; j < start[v + 1]; ++j) {
            const Vec3d& own = unit[around[j] / 3];
            const bool degenerate = dot(own, own) == 0; // takes the smooth normal
            Vec3d n = smooth ? all : Vec3d{0, 0, 0};
            for (std::size_t k = start[v]; k < start[v + 1] && !smooth; ++k)
                if (degenerate || dot(unit[around[k] / 3], own) >= cosCrease) n += face[around[k] / 3];
            auto same = std::find_if(made.begin(), made.end(), [&](const auto& e) { return e.first == n; });
            if (same == made.end()) {
                if (g.mesh.positions.size() >= 0xffffffffu)
                    fail("the scene's vertices, split at creases, are more than 32-bit indices allow");
                same = made.insert(made.end(), {n, uint32_t(g.mesh.positions.size())});
                g.mesh.positions.push_back(m.positions[v]);
                g.normals.push_back(length(n) > 0 ? Vec3f(normalize(n)) : Vec3f{0, 0, 0});
            }
            index[around[j]] = same->second;
        }
    }
    g.mesh.indices.insert(g.mesh.indices.end(), index.begin(), index.end());
}

} // namespace

SceneGeometry flattenScene(const Scene& scene, double creaseAngle) {
    if (!(creaseAngle >= 0 && creaseAngle <= 180))
        fail("crease angle ", creaseAngle, " outside [0, 180] degrees");
    // Faces whose normals are within the angle are smoothed together (a tolerance keeps coplanar
    // faces together at 0 despite rounding).
    const double radians = creaseAngle * (3.14159265358979323846 / 180);
    const double cosCrease = std::cos(radians) - 1e-12;
    // The shortcut's bound, kept on the safe side of rounding (a pair it lets through is within the
    // angle by a margin far above the tolerance).
    const double cosHalf = std::cos(radians / 2) + 1e-9;
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
        g.triangleMaterial.insert(g.triangleMaterial.end(), m.mesh.triangleCount(), m.material);
        g.triangleMesh.insert(g.triangleMesh.end(), m.mesh.triangleCount(), uint32_t(k));
        if (m.normals.empty()) {
            appendCreased(g, m.mesh, cosCrease, cosHalf);
            continue;
        }
        // Given normals (glTF's) are kept as they are.
        const auto base = uint32_t(g.mesh.positions.size());
        g.mesh.positions.insert(g.mesh.positions.end(), m.mesh.positions.begin(), m.mesh.positions.end());
        for (const uint32_t i : m.mesh.indices) g.mesh.indices.push_back(base + i);
        g.normals.insert(g.normals.end(), m.normals.begin(), m.normals.end());
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
    renderGBuffer(geometry, camera, g, progress);
    return g;
}

namespace {

// renderGBuffer, in tiles of a multiple of rowAlign rows (0: the rasterizer's choice) when rowsDone
// is given (detail::renderGBufferTiles).
void renderInto(const SceneGeometry& geometry, const Frame& camera, GBuffer& g, Progress* progress,
                int64_t rowAlign, const std::function<void(int64_t, int64_t)>* rowsDone) {
    g.frame = camera;
    // Cleared in parallel: 8 bytes a sample, 30 MB at 1280x720 with 2x2 samples per pixel.
    const auto n = size_t(camera.columnCount());
    g.depth.resize(n);
    g.triangle.resize(n);
    parallelFor(0, int64_t(n), int64_t(1) << 16, [&](int64_t i0, int64_t i1) {
        std::fill(g.depth.begin() + i0, g.depth.begin() + i1, std::numeric_limits<float>::infinity());
        std::fill(g.triangle.begin() + i0, g.triangle.begin() + i1, GBuffer::kNone);
    });
    if (geometry.drawnTriangles == 0) {
        if (rowsDone) (*rowsDone)(0, camera.height());
        return;
    }
    NearestFragmentConsumer consumer{camera.width(), camera.nearDepth(), g, rowsDone};
    RasterOptions ro;
    ro.progress = progress;
    if (rowAlign > 1) {
        // The rasterizer's own choice (about 64 tiles), rounded up to whole multiples of rowAlign.
        const int64_t rows = std::max<int64_t>(1, (camera.height() + 63) / 64);
        ro.rowsPerTile = (rows + rowAlign - 1) / rowAlign * rowAlign;
    }
    MeshView drawn = geometry.mesh.view();
    drawn.triangleCount = geometry.drawnTriangles;
    rasterize(camera, drawn, ro, consumer);
}

} // namespace

void renderGBuffer(const SceneGeometry& geometry, const Frame& camera, GBuffer& g, Progress* progress) {
    renderInto(geometry, camera, g, progress, 0, nullptr);
}

namespace detail {

void renderGBufferTiles(const SceneGeometry& geometry, const Frame& camera, GBuffer& out, int64_t rowAlign,
                        Progress* progress, const std::function<void(int64_t, int64_t)>& rowsDone) {
    renderInto(geometry, camera, out, progress, rowAlign, &rowsDone);
}

} // namespace detail

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
