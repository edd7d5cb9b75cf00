// voxfx — rasterizer set-up and binning (the per-triangle kernels are templates in raster_impl.hpp).
#include "voxfx/raster.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "core/scratch.hpp"

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

double clipDepthOf(const Frame& frame, const MeshView& mesh, bool fullLine) {
    if (!frame.isPerspective() || !fullLine) return clipDepthOf(frame);
    // The squared distance from the eye to the nearest triangle's bounding box: a lower bound of
    // its distance to the mesh (the minimum does not depend on the order of the chunks).
    const Vec3d eye = frame.eye();
    const double inf = std::numeric_limits<double>::infinity();
    const double nearest2 = parallelReduce(
        int64_t(0), int64_t(mesh.triangleCount), int64_t(16384), inf,
        [&](int64_t b, int64_t e) {
            double m = inf;
            for (int64_t t = b; t < e; ++t) {
                const Vec3d p = mesh.vertex(mesh.index(size_t(t), 0)),
                            q = mesh.vertex(mesh.index(size_t(t), 1)),
                            r = mesh.vertex(mesh.index(size_t(t), 2));
                double d2 = 0;
                for (int a = 0; a < 3; ++a) {
                    const double lo = std::min({p[a], q[a], r[a]}), hi = std::max({p[a], q[a], r[a]});
                    const double d = eye[a] < lo ? lo - eye[a] : (eye[a] > hi ? eye[a] - hi : 0.0);
                    d2 += d * d;
                }
                m = std::min(m, d2);
            }
            return m;
        },
        [](double x, double y) { return std::min(x, y); });
    // A point on a column's line at camera depth z lies within |z| sqrt(1 + tanX^2 + tanY^2) of
    // the eye.
    const Projection& pr = frame.projection();
    const double spread = std::sqrt(1.0 + pr.tanX * pr.tanX + pr.tanY * pr.tanY);
    const double standard = clipDepthOf(frame);
    return -std::clamp(0.5 * std::sqrt(nearest2) / spread, frame.nearDepth() * 1e-9, standard);
}

RasterSetup prepareVertices(const Frame& frame, const MeshView& mesh, bool fullLine) {
    RasterSetup s;
    s.frame = frame.view();
    s.mesh = &mesh;
    s.vertices = Scratch<Vec3d>::take(mesh.vertexCount); // memory of an earlier call: no page faults
    s.vertices.resize(mesh.vertexCount);
    s.clipDepth = clipDepthOf(frame, mesh, fullLine);
    Vec3d* out = s.vertices.data();
    const Projection pr = frame.projection();
    parallelFor(0, int64_t(mesh.vertexCount), 8192, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i) out[i] = projectVertex(pr, mesh.vertex(size_t(i)));
    });
    return s;
}

namespace {

// The tiles of one triangle: rows [r0, r1] and columns [c0, c1] of the tiling (empty when r1 < r0).
struct TileSpan {
    int32_t r0, r1, c0, c1;
    int64_t count() const { return r1 < r0 ? 0 : int64_t(r1 - r0 + 1) * int64_t(c1 - c0 + 1); }
};

class Binner {
public:
    Binner(const RasterSetup& setup, Coverage coverage, int64_t rowsPerTile, int64_t colsPerTile,
           int64_t grow)
        : setup_(setup), center_(coverage == Coverage::Center), coverage_(coverage), grow_(grow),
          rows_(rowsPerTile), cols_(colsPerTile > 0 ? colsPerTile : std::max<int64_t>(1, setup.frame.width)),
          tileRows_((setup.frame.height + rows_ - 1) / rows_),
          tileColumns_((setup.frame.width + cols_ - 1) / cols_) {}

    int64_t tileRows() const { return tileRows_; }
    int64_t tileColumns() const { return tileColumns_; }
    int64_t cols() const { return cols_; }

    // Tile range of triangle t (union over its pieces). Centre coverage also drops triangles
    // whose bounding box holds no column centre (same exact arithmetic as rasterizeCenter): on
    // dense meshes (a million triangles at 512^3) most triangles are smaller than a cell and
    // never reach a tile.
    TileSpan span(int64_t t) const {
        const int64_t H = setup_.frame.height, W = setup_.frame.width;
        int64_t r0 = H, r1 = -1, x0 = W, x1 = -1;
        setup_.triangle(size_t(t), [&](const RasterTriangle& r) {
            const double xlo = std::min({r.x[0], r.x[1], r.x[2]}), xhi = std::max({r.x[0], r.x[1], r.x[2]});
            if (!(xhi >= -1.0 && xlo <= double(W) + 1.0)) return; // entirely left or right of the columns
            if (center_ && std::ceil(xlo - 0.5) > std::floor(xhi - 0.5)) return;
            int64_t f, l;
            coveredRows(r, coverage_, H, f, l);
            if (f > l) return;
            r0 = std::min(r0, f);
            r1 = std::max(r1, l);
            if (tileColumns_ == 1) return; // one tile column (the whole-grid raster): rows suffice
            // Columns as coveredRows finds rows (clamped in floating point first).
            const double cf = center_ ? std::ceil(xlo - 0.5) : std::ceil(xlo - kConservativeSlack) - 1.0;
            const double cl = center_ ? std::floor(xhi - 0.5) : std::floor(xhi + kConservativeSlack);
            x0 = std::min(x0, int64_t(std::clamp(cf, 0.0, double(W - 1))));
            x1 = std::max(x1, int64_t(std::clamp(cl, 0.0, double(W - 1))));
        });
        if (r1 < r0 || (tileColumns_ > 1 && x1 < x0)) return {0, -1, 0, -1};
        if (tileColumns_ == 1) x0 = x1 = 0;
        // A shift for the usual power-of-two tiles: this runs once per triangle and tiling.
        auto tile = [](int64_t v, int64_t size, int64_t count) {
            const int64_t index = (size & (size - 1)) == 0 ? v >> std::countr_zero(uint64_t(size)) : v / size;
            return int32_t(std::clamp<int64_t>(v < 0 ? -1 : index, 0, count - 1));
        };
        return {tile(r0 - grow_, rows_, tileRows_), tile(r1 + grow_, rows_, tileRows_),
                tile(x0 - grow_, cols_, tileColumns_), tile(x1 + grow_, cols_, tileColumns_)};
    }

private:
    const RasterSetup& setup_;
    bool center_;
    Coverage coverage_;
    int64_t grow_, rows_, cols_, tileRows_, tileColumns_;
};

} // namespace

TileBins binTriangles(const RasterSetup& setup, Coverage coverage, int64_t rowsPerTile, int64_t colsPerTile,
                      int64_t grow, const std::function<void(int64_t entries)>& counted) {
    const Binner binner(setup, coverage, rowsPerTile, colsPerTile, grow);
    TileBins bins;
    bins.rowsPerTile = rowsPerTile;
    bins.colsPerTile = binner.cols();
    bins.tileColumns = binner.tileColumns();
    bins.tileCount = binner.tileRows() * binner.tileColumns();
    const int64_t T = int64_t(setup.mesh->triangleCount);
    const int64_t chunks = (T + kBinChunk - 1) / kBinChunk;
    const auto tiles = size_t(bins.tileCount);
    const int64_t TC = bins.tileColumns;

    // Pass 1: each triangle's tile range (set up once, kept for pass 2) and counts per
    // (chunk, tile).
    PageVector<TileSpan> spans = Scratch<TileSpan>::take(size_t(T));
    spans.resize(static_cast<size_t>(T));
    PageVector<int64_t> counts = Scratch<int64_t>::take(size_t(chunks) * tiles);
    counts.assign(size_t(chunks) * tiles, 0);
    parallelFor(0, chunks, 1, [&](int64_t cb, int64_t ce) {
        for (int64_t c = cb; c < ce; ++c) {
            int64_t* row = counts.data() + size_t(c) * tiles;
            for (int64_t t = c * kBinChunk, e = std::min(T, t + kBinChunk); t < e; ++t) {
                const TileSpan sp = binner.span(t);
                spans[size_t(t)] = sp;
                for (int64_t r = sp.r0; r <= sp.r1; ++r)
                    for (int64_t k = sp.c0; k <= sp.c1; ++k) ++row[r * TC + k];
            }
        }
    });
    // Exclusive prefix sums: tile-major, then chunk order, so each tile lists triangles in order.
    bins.offsets = Scratch<int64_t>::take(tiles + 1);
    bins.offsets.assign(tiles + 1, 0);
    PageVector<int64_t> cursor = Scratch<int64_t>::take(size_t(chunks) * tiles);
    cursor.assign(size_t(chunks) * tiles, 0);
    int64_t total = 0;
    for (size_t k = 0; k < tiles; ++k) {
        bins.offsets[k] = total;
        for (int64_t c = 0; c < chunks; ++c) {
            cursor[size_t(c) * tiles + k] = total;
            total += counts[size_t(c) * tiles + k];
        }
    }
    bins.offsets[tiles] = total;
    if (counted) counted(total);
    bins.entries = Scratch<uint32_t>::take(size_t(total));
    bins.entries.resize(size_t(total));
    // Pass 2: fill.
    parallelFor(0, chunks, 1, [&](int64_t cb, int64_t ce) {
        for (int64_t c = cb; c < ce; ++c) {
            int64_t* cur = cursor.data() + size_t(c) * tiles;
            for (int64_t t = c * kBinChunk, e = std::min(T, t + kBinChunk); t < e; ++t) {
                const TileSpan sp = spans[size_t(t)];
                for (int64_t r = sp.r0; r <= sp.r1; ++r)
                    for (int64_t k = sp.c0; k <= sp.c1; ++k)
                        bins.entries[size_t(cur[r * TC + k]++)] = uint32_t(t);
            }
        }
    });
    Scratch<TileSpan>::give(std::move(spans));
    Scratch<int64_t>::give(std::move(counts));
    Scratch<int64_t>::give(std::move(cursor));
    return bins;
}

void recycle(RasterSetup& setup, TileBins* bins) {
    Scratch<Vec3d>::give(std::move(setup.vertices));
    if (!bins) return;
    Scratch<int64_t>::give(std::move(bins->offsets));
    Scratch<uint32_t>::give(std::move(bins->entries));
}

} // namespace voxfx::detail
