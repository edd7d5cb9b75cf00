// voxfx — rasterizer set-up and binning (the per-triangle kernels are templates in raster_impl.hpp).
#include "voxfx/raster.hpp"

#include <algorithm>
#include <cmath>

namespace voxfx {

const char* toString(Coverage c) { return enumName(c, kCoverageNames); }

Coverage parseCoverage(const std::string& name) {
    return parseEnum<Coverage>(name, "coverage", kCoverageNames);
}

} // namespace voxfx

namespace voxfx::detail {

namespace {
// Triangles per chunk in the binning passes; chunks are counted and filled in index order.
constexpr int64_t kBinChunk = 16384;
} // namespace

RasterSetup prepareVertices(const Frame& frame, const MeshView& mesh) {
    RasterSetup s;
    s.frame = frame.view();
    s.mesh = &mesh;
    s.vertices.resize(mesh.vertexCount);
    s.clipDepth = clipDepthOf(frame);
    Vec3d* out = s.vertices.data();
    const Projection pr = frame.projection();
    parallelFor(0, int64_t(mesh.vertexCount), 65536, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i) out[i] = projectVertex(pr, mesh.vertex(size_t(i)));
    });
    return s;
}

TileBins binTriangles(const RasterSetup& setup, Coverage coverage, int64_t rowsPerTile) {
    const int64_t H = setup.frame.height;
    const double W = double(setup.frame.width);
    TileBins bins;
    bins.rowsPerTile = rowsPerTile;
    bins.tileCount = (H + rowsPerTile - 1) / rowsPerTile;
    const int64_t T = int64_t(setup.mesh->triangleCount);
    const int64_t chunks = (T + kBinChunk - 1) / kBinChunk;
    const auto tiles = size_t(bins.tileCount);

    // Tile range [first, last] of triangle t (union over its pieces); empty when last < first.
    // Centre coverage also drops triangles whose bounding box holds no column centre (same exact
    // arithmetic as rasterizeCenter): on dense meshes (a million triangles at 512^3) most
    // triangles are smaller than a cell and never reach a tile.
    const bool center = coverage == Coverage::Center;
    auto tileRange = [&](int64_t t, int64_t& first, int64_t& last) {
        first = bins.tileCount;
        last = -1;
        setup.triangle(size_t(t), [&](const RasterTriangle& r) {
            const double xlo = std::min({r.x[0], r.x[1], r.x[2]}), xhi = std::max({r.x[0], r.x[1], r.x[2]});
            if (!(xhi >= -1.0 && xlo <= W + 1.0)) return; // entirely left or right of the columns
            if (center && std::ceil(xlo - 0.5) > std::floor(xhi - 0.5)) return;
            int64_t r0, r1;
            coveredRows(r, coverage, H, r0, r1);
            if (r0 > r1) return;
            first = std::min(first, r0 / rowsPerTile);
            last = std::max(last, r1 / rowsPerTile);
        });
    };

    // Pass 1: each triangle's tile range (set up once, kept for pass 2) and counts per
    // (chunk, tile).
    std::vector<int32_t> ranges(size_t(2 * T));
    std::vector<int64_t> counts(size_t(chunks) * tiles, 0);
    parallelFor(0, chunks, 1, [&](int64_t cb, int64_t ce) {
        for (int64_t c = cb; c < ce; ++c) {
            int64_t* row = counts.data() + size_t(c) * tiles;
            for (int64_t t = c * kBinChunk, e = std::min(T, t + kBinChunk); t < e; ++t) {
                int64_t f, l;
                tileRange(t, f, l);
                ranges[size_t(2 * t)] = int32_t(f);
                ranges[size_t(2 * t + 1)] = int32_t(l);
                for (int64_t k = f; k <= l; ++k) ++row[k];
            }
        }
    });
    // Exclusive prefix sums: tile-major, then chunk order, so each tile lists triangles in order.
    bins.offsets.assign(tiles + 1, 0);
    std::vector<int64_t> cursor(size_t(chunks) * tiles, 0);
    int64_t total = 0;
    for (size_t k = 0; k < tiles; ++k) {
        bins.offsets[k] = total;
        for (int64_t c = 0; c < chunks; ++c) {
            cursor[size_t(c) * tiles + k] = total;
            total += counts[size_t(c) * tiles + k];
        }
    }
    bins.offsets[tiles] = total;
    bins.entries.resize(size_t(total));
    // Pass 2: fill.
    parallelFor(0, chunks, 1, [&](int64_t cb, int64_t ce) {
        for (int64_t c = cb; c < ce; ++c) {
            int64_t* cur = cursor.data() + size_t(c) * tiles;
            for (int64_t t = c * kBinChunk, e = std::min(T, t + kBinChunk); t < e; ++t)
                for (int64_t k = ranges[size_t(2 * t)]; k <= ranges[size_t(2 * t + 1)]; ++k)
                    bins.entries[size_t(cur[k]++)] = uint32_t(t);
        }
    });
    return bins;
}

} // namespace voxfx::detail
