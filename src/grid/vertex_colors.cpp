// voxfx — per-vertex colours voxelized (see voxfx/vertex_colors.hpp): a consumer of the one
// rasterizer with attribute voxelization's writes (CHANG §2, slab overlap 0), adding each write's
// interpolated colour into its voxel; then the mean per voxel.
#include "voxfx/vertex_colors.hpp"

#include <algorithm>
#include <cmath>

#include "voxelize/consumers.hpp"
#include "voxfx/bitgrid.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

namespace {

// Per triangle, what the colour at a point needs: a corner, the two edges, their Gram matrix
// inverted (barycentric weights of a point's projection onto the plane) and the corner colours.
struct ColorTriangle {
    Vec3d a, e1, e2;
    double i11, i12, i22;
    Vec3d color[3];
    bool degenerate;

    /// The colour at the projection of p, weights clamped to >= 0 and renormalized (the corners'
    /// mean on a degenerate triangle).
    Vec3f at(const Vec3d& p) const {
        double w1 = 1.0 / 3, w2 = 1.0 / 3;
        if (!degenerate) {
            const Vec3d q = p - a;
            const double b1 = dot(q, e1), b2 = dot(q, e2);
            w1 = i11 * b1 + i12 * b2;
            w2 = i12 * b1 + i22 * b2;
        }
        double w0 = std::max(1 - w1 - w2, 0.0);
        w1 = std::max(w1, 0.0);
        w2 = std::max(w2, 0.0);
        const double sum = w0 + w1 + w2; // >= 1: at most two weights were negative
        return Vec3f((color[0] * w0 + color[1] * w1 + color[2] * w2) / sum);
    }
};

std::vector<ColorTriangle> colorTriangles(const MeshView& mesh, std::span<const Vec3f> colors) {
    std::vector<ColorTriangle> out(mesh.triangleCount);
    parallelFor(0, int64_t(mesh.triangleCount), 8192, [&](int64_t b, int64_t e) {
        for (int64_t t = b; t < e; ++t) {
            ColorTriangle& tr = out[std::size_t(t)];
            const auto T = std::size_t(t);
            tr.a = mesh.vertex(mesh.index(T, 0));
            tr.e1 = mesh.vertex(mesh.index(T, 1)) - tr.a;
            tr.e2 = mesh.vertex(mesh.index(T, 2)) - tr.a;
            const double g11 = dot(tr.e1, tr.e1), g12 = dot(tr.e1, tr.e2), g22 = dot(tr.e2, tr.e2);
            const double det = g11 * g22 - g12 * g12;
            tr.degenerate = !(det > 1e-30 * std::max(1.0, g11 * g22));
            tr.i11 = tr.degenerate ? 0 : g22 / det;
            tr.i12 = tr.degenerate ? 0 : -g12 / det;
            tr.i22 = tr.degenerate ? 0 : g11 / det;
            for (int k = 0; k < 3; ++k) tr.color[k] = Vec3d(colors[mesh.index(T, k)]);
        }
    });
    return out;
}

struct ColorConsumer {
    const Frame& frame;
    ColorGrid& grid;
    const std::vector<ColorTriangle>& triangles;

    struct Sink {
        ColorConsumer& c;
        FrameView view;
        void write(int64_t column, int64_t s, uint32_t triangle) {
            const auto i = std::size_t(column * view.depth + s);
            ++c.grid.count[i];
            const int64_t W = view.width;
            c.grid.color[i] += c.triangles[triangle].at(c.frame.cellCenter(column % W, column / W, s));
        }
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool) {
            const int64_t column = y * view.width + x;
            const int64_t s = detail::fragmentSlice(view, column, depth);
            if (s >= 0) write(column, s, triangle);
        }
        void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t triangle) {
            const int64_t column = y * view.width + x;
            int64_t s0, s1;
            if (!detail::spanSlices(view, column, depthMin, depthMax, s0, s1)) return;
            for (int64_t s = s0; s <= s1; ++s) write(column, s, triangle);
        }
        void finish() {}
    };
    Sink tile(const Tile&) { return {*this, frame.view()}; }
};

} // namespace

ColorGrid voxelizeVertexColors(const MeshView& mesh, std::span<const Vec3f> vertexColors, const Frame& frame,
                               const VertexColorOptions& options) {
    validateMesh(mesh, "mesh");
    if (vertexColors.size() != mesh.vertexCount)
        fail("vertex colour voxelization: ", vertexColors.size(), " colours for ", mesh.vertexCount,
             " vertices");
    for (std::size_t t = 0; t < mesh.triangleCount; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = mesh.index(t, k);
            if (!isFinite(vertexColors[v]))
                fail("vertex colour voxelization: vertex ", v, " (of triangle ", t,
                     ") has a non-finite colour");
        }
    if (frame.isPerspective()) fail("vertex colour voxelization needs an orthographic frame");
    ColorGrid grid;
    grid.frame = frame;
    const uint64_t voxels = uint64_t(frame.columnCount()) * uint64_t(frame.depth());
    checkMemory(voxels * (sizeof(uint32_t) + sizeof(Vec3f)), "vertex colour voxelization at this resolution");
    withThreads(options.threads, [&] {
        grid.count.assign(voxels, 0);
        grid.color.assign(voxels, Vec3f{});
        const std::vector<ColorTriangle> triangles = colorTriangles(mesh, vertexColors);
        RasterOptions ro;
        ro.coverage = options.coverage;
        ro.progress = options.progress;
        ColorConsumer consumer{grid.frame, grid, triangles};
        rasterize(grid.frame, mesh, ro, consumer);
        parallelFor(0, int64_t(voxels), 1 << 16, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i)
                if (const uint32_t n = grid.count[std::size_t(i)]; n > 1)
                    grid.color[std::size_t(i)] = grid.color[std::size_t(i)] / float(n);
        });
    });
    return grid;
}

} // namespace voxfx
