// voxfx — attribute voxelization (CHANG §2: per-voxel write count, normal sum, material absorption,
// material id, refraction index and attenuation; the channels a use asks for).
//
// A consumer of the one rasterizer. Centre coverage reproduces CHANG's slab clipping (per triangle
// and covered column centre, the slices whose slab, widened by slabOverlap, holds the triangle's
// depth there); conservative coverage writes every voxel the triangle's exact depth span in the
// column touches (widened the same way). Each tile owns its rows and visits triangles in index
// order, so the float sums are deterministic.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "voxelize/consumers.hpp"
#include "voxfx/attribute_grid.hpp"

namespace voxfx {

namespace {

// The slices written for a centre fragment at `depth`: those whose slab [s - w, s + 1 + w) (slice
// units, the last one closed at the far plane) holds it; w = 0 gives the one slice of the depth.
bool attributeCentreSlices(const FrameView& frame, int64_t column, double depth, double w, int64_t& s0,
                           int64_t& s1) {
    if (w == 0) {
        s0 = s1 = detail::fragmentSlice(frame, column, depth);
        return s0 >= 0;
    }
    const double t = frame.depthToSlice(column)(depth);
    const int64_t D = frame.depth;
    if (!(t >= -w && t <= double(D) + w)) return false;
    s0 = std::clamp<int64_t>(int64_t(std::floor(t - 1 - w)) + 1, 0, D - 1);
    s1 = std::clamp<int64_t>(int64_t(std::floor(t + w)), 0, D - 1);
    return s0 <= s1;
}

// The slices written for a conservative span: spanSlices on the span widened by w slices.
bool attributeSpanSlices(const FrameView& frame, int64_t column, double depthMin, double depthMax, double w,
                         int64_t& s0, int64_t& s1) {
    if (w == 0) return detail::spanSlices(frame, column, depthMin, depthMax, s0, s1);
    const DepthToSlice m = frame.depthToSlice(column);
    const double t0 = m(depthMin) - detail::kConservativeSlack - w;
    const double t1 = m(depthMax) + detail::kConservativeSlack + w;
    const int64_t D = frame.depth;
    if (!(t1 >= 0 && t0 <= double(D))) return false;
    s0 = std::max<int64_t>(0, int64_t(std::ceil(std::max(t0, -1.0))) - 1);
    s1 = std::min<int64_t>(D - 1, int64_t(std::floor(std::min(t1, double(D)))));
    return s0 <= s1;
}

// Per triangle, what interpolating its vertex normals at a point needs: a corner, the two edges,
// their Gram matrix inverted (barycentric weights of a point's projection), the three normals.
struct SmoothNormals {
    struct Triangle {
        Vec3d a, e1, e2;
        double i11, i12, i22; // inverse of [[e1.e1, e1.e2], [e1.e2, e2.e2]]
        Vec3d n[3];
        bool degenerate;
    };
    std::vector<Triangle> triangles;

    SmoothNormals(const MeshView& mesh, std::span<const Vec3f> vertexNormals) {
        triangles.resize(mesh.triangleCount);
        for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
            Triangle& tr = triangles[t];
            tr.a = mesh.vertex(mesh.index(t, 0));
            tr.e1 = mesh.vertex(mesh.index(t, 1)) - tr.a;
            tr.e2 = mesh.vertex(mesh.index(t, 2)) - tr.a;
            const double g11 = dot(tr.e1, tr.e1), g12 = dot(tr.e1, tr.e2), g22 = dot(tr.e2, tr.e2);
            const double det = g11 * g22 - g12 * g12;
            tr.degenerate = !(det > 1e-30 * std::max(1.0, g11 * g22));
            tr.i11 = tr.degenerate ? 0 : g22 / det;
            tr.i12 = tr.degenerate ? 0 : -g12 / det;
            tr.i22 = tr.degenerate ? 0 : g11 / det;
            for (int k = 0; k < 3; ++k) tr.n[k] = Vec3d(vertexNormals[mesh.index(t, k)]);
        }
    }
    // The unit normal of triangle t at the point nearest p (or `face` where it has no direction).
    Vec3f at(uint32_t t, const Vec3d& p, const Vec3f& face) const {
        const Triangle& tr = triangles[t];
        double w1 = 1.0 / 3, w2 = 1.0 / 3;
        if (!tr.degenerate) {
            const Vec3d q = p - tr.a;
            const double b1 = dot(q, tr.e1), b2 = dot(q, tr.e2);
            w1 = tr.i11 * b1 + tr.i12 * b2;
            w2 = tr.i12 * b1 + tr.i22 * b2;
        }
        double w0 = 1 - w1 - w2;
        w0 = std::max(w0, 0.0), w1 = std::max(w1, 0.0), w2 = std::max(w2, 0.0);
        const Vec3d n = tr.n[0] * w0 + tr.n[1] * w1 + tr.n[2] * w2;
        const double len = length(n);
        return len > 1e-12 ? Vec3f(n / len) : face;
    }
};

struct AttributeConsumer {
    const Frame& frame;
    AttributeGrid& grid;
    std::span<const float> absorption;          // empty when the absorption channel is off
    const std::vector<Vec3f>& faceNormals;      // empty when normals are off
    const SmoothNormals* smooth;                // vertex normals to interpolate, or null
    std::span<const uint32_t> triangleMaterial; // empty when no material channel is stored
    std::span<const AttributeMaterial> materials;
    double overlap;
    bool attenuationMarksFirst; // the attenuation channel alone tells first writes (sentinel -1)

    struct Sink {
        AttributeConsumer& c;
        FrameView frame;
        void write(int64_t column, int64_t s, uint32_t triangle) {
            AttributeGrid& g = c.grid;
            const auto i = size_t(column * c.frame.depth() + s);
            if (!c.triangleMaterial.empty()) {
                // The first write sets the material channels (triangles arrive in index order).
                const bool first = !g.material.empty() ? g.material[i] == AttributeGrid::kNoMaterial
                                   : !g.ior.empty()    ? g.ior[i] == 0
                                   : !g.count.empty() && !c.attenuationMarksFirst ? g.count[i] == 0
                                                                                  : g.attenuation[i].x < 0;
                if (first) {
                    const uint32_t m = c.triangleMaterial[triangle];
                    if (!g.material.empty()) g.material[i] = m;
                    if (!g.ior.empty()) g.ior[i] = c.materials[m].ior;
                    if (!g.attenuation.empty()) g.attenuation[i] = c.materials[m].attenuation;
                }
            }
            if (!g.count.empty() && g.count[i] != 0xffff) ++g.count[i];
            if (!c.absorption.empty()) g.absorption[i] += c.absorption[triangle];
            if (!c.faceNormals.empty()) {
                if (c.smooth) {
                    const int64_t W = c.frame.width();
                    g.normalSum[i] += c.smooth->at(triangle, c.frame.cellCenter(column % W, column / W, s),
                                                   c.faceNormals[triangle]);
                } else {
                    g.normalSum[i] += c.faceNormals[triangle];
                }
            }
        }
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool) {
            const int64_t column = y * c.frame.width() + x;
            int64_t s0, s1;
            if (!attributeCentreSlices(frame, column, depth, c.overlap, s0, s1)) return;
            for (int64_t s = s0; s <= s1; ++s) write(column, s, triangle);
        }
        void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t triangle) {
            const int64_t column = y * c.frame.width() + x;
            int64_t s0, s1;
            if (!attributeSpanSlices(frame, column, depthMin, depthMax, c.overlap, s0, s1)) return;
            for (int64_t s = s0; s <= s1; ++s) write(column, s, triangle);
        }
        void finish() {}
    };
    Sink tile(const Tile&) { return {*this, frame.view()}; }
};

// Sparse writes: each tile collects (column, slice, triangle) entries in visiting order, then sorts
// them stably by (column, slice) and merges equal keys, so the sums follow triangle order as in the
// dense consumer.
struct ColumnWritesConsumer {
    const Frame& frame;
    std::span<const float> absorption;
    double overlap;
    struct Entry {
        int64_t column;
        int64_t slice;
        uint32_t triangle;
    };
    struct TileOut {
        std::vector<int64_t> column, slice;
        std::vector<uint16_t> count;
        std::vector<float> absorption;
    };
    std::vector<TileOut>& out;

    struct Sink {
        ColumnWritesConsumer& c;
        FrameView frame;
        TileOut& out;
        std::vector<Entry> entries;
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool) {
            const int64_t column = y * c.frame.width() + x;
            int64_t s0, s1;
            if (!attributeCentreSlices(frame, column, depth, c.overlap, s0, s1)) return;
            for (int64_t s = s0; s <= s1; ++s) entries.push_back({column, s, triangle});
        }
        void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t triangle) {
            const int64_t column = y * c.frame.width() + x;
            int64_t s0, s1;
            if (!attributeSpanSlices(frame, column, depthMin, depthMax, c.overlap, s0, s1)) return;
            for (int64_t s = s0; s <= s1; ++s) entries.push_back({column, s, triangle});
        }
        void finish() {
            std::stable_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
                return a.column != b.column ? a.column < b.column : a.slice < b.slice;
            });
            for (std::size_t i = 0; i < entries.size();) {
                const Entry& e = entries[i];
                uint32_t n = 0;
                float sum = 0;
                for (; i < entries.size() && entries[i].column == e.column && entries[i].slice == e.slice;
                     ++i) {
                    ++n;
                    if (!c.absorption.empty()) sum += c.absorption[entries[i].triangle];
                }
                out.column.push_back(e.column);
                out.slice.push_back(e.slice);
                out.count.push_back(uint16_t(std::min<uint32_t>(n, 0xffff)));
                out.absorption.push_back(sum);
            }
            entries = {};
        }
    };
    Sink tile(const Tile& t) { return {*this, frame.view(), out[size_t(t.index)], {}}; }
};

void checkAbsorption(const MeshView& mesh, std::span<const float> triangleAbsorption,
                     const AttributeOptions& options) {
    if (!triangleAbsorption.empty() && triangleAbsorption.size() != mesh.triangleCount)
        fail("attribute voxelization: ", triangleAbsorption.size(), " absorption values for ",
             mesh.triangleCount, " triangles");
    if (!options.vertexNormals.empty() && options.vertexNormals.size() != mesh.vertexCount)
        fail("attribute voxelization: ", options.vertexNormals.size(), " vertex normals for ",
             mesh.vertexCount, " vertices");
    if (!(options.slabOverlap >= 0 && std::isfinite(options.slabOverlap)))
        fail("attribute voxelization: slab overlap must be finite and >= 0, got ", options.slabOverlap);
}

// What is stored: the channels asked for whose inputs are given.
AttributeChannels storedChannels(const MeshView& mesh, std::span<const float> triangleAbsorption,
                                 const AttributeOptions& options) {
    AttributeChannels c = options.channels;
    c.absorption = c.absorption && !triangleAbsorption.empty();
    const bool needTable = c.ior || c.attenuation;
    if ((needTable || (c.material && !options.triangleMaterial.empty())) &&
        options.triangleMaterial.size() != mesh.triangleCount)
        fail("attribute voxelization: ", options.triangleMaterial.size(), " material indices for ",
             mesh.triangleCount, " triangles");
    c.material = c.material && !options.triangleMaterial.empty();
    if (needTable)
        for (const uint32_t m : options.triangleMaterial)
            if (m >= options.materials.size())
                fail("attribute voxelization: material id ", m, " outside the table of ",
                     options.materials.size(), " materials (the ior and attenuation channels read it)");
    return c;
}

// ED06 fig. 2: each column's slices spread over the depth range its geometry spans.
Frame slicedFrame(const MeshView& mesh, const Frame& in, const AttributeOptions& options) {
    Frame frame = in;
    if (options.slicing != Slicing::Local) return frame;
    std::vector<double> nearDepth(size_t(frame.columnCount()), std::numeric_limits<double>::infinity());
    std::vector<double> farDepth(size_t(frame.columnCount()), -std::numeric_limits<double>::infinity());
    detail::DepthRangeConsumer range{frame.width(), nearDepth, farDepth};
    RasterOptions rr;
    rr.coverage = options.coverage;
    rasterize(frame, mesh, rr, range);
    frame.setLocalSlicing(nearDepth, farDepth);
    return frame;
}

} // namespace

Vec3f AttributeGrid::normal(int64_t i) const {
    if (normalSum.empty()) return {};
    return normalize(normalSum[size_t(i)]);
}

BitGrid AttributeGrid::occupancy() const {
    if (voxelCount() > 0 && count.empty() && material.empty() && ior.empty())
        fail("attribute grid occupancy needs the count, material or ior channel");
    BitGrid bits(frame.width(), frame.height(), frame.depth());
    const int64_t D = frame.depth();
    parallelFor(0, frame.columnCount(), 1024, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            uint64_t* col = bits.column(c);
            for (int64_t s = 0; s < D; ++s)
                if (written(c * D + s)) col[s >> 6] |= uint64_t(1) << (s & 63);
        }
    });
    return bits;
}

int64_t AttributeGrid::writeCount() const {
    int64_t total = 0;
    for (const uint16_t n : count) total += n;
    return total;
}

uint64_t AttributeChannels::bytesPerVoxel() const {
    return (count ? sizeof(uint16_t) : 0) + (absorption ? sizeof(float) : 0) + (normals ? sizeof(Vec3f) : 0) +
           (material ? sizeof(uint32_t) : 0) + (ior ? sizeof(float) : 0) + (attenuation ? sizeof(Vec3f) : 0);
}

AttributeChannels AttributeGrid::channels() const {
    return {!count.empty(),    !absorption.empty(), !normalSum.empty(),
            !material.empty(), !ior.empty(),        !attenuation.empty()};
}

uint64_t AttributeGrid::bytes() const {
    return count.size() * sizeof(uint16_t) + absorption.size() * sizeof(float) +
           normalSum.size() * sizeof(Vec3f) + material.size() * sizeof(uint32_t) +
           ior.size() * sizeof(float) + attenuation.size() * sizeof(Vec3f);
}

uint64_t attributeGridBytes(const Frame& frame, const AttributeChannels& channels) {
    return uint64_t(frame.columnCount()) * uint64_t(frame.depth()) * channels.bytesPerVoxel();
}

AttributeGrid voxelizeAttributes(const MeshView& mesh, const Frame& inFrame,
                                 std::span<const float> triangleAbsorption, const AttributeOptions& options) {
    validateMesh(mesh, "mesh");
    checkAbsorption(mesh, triangleAbsorption, options);
    const AttributeChannels ch = storedChannels(mesh, triangleAbsorption, options);
    AttributeGrid grid;
    withThreads(options.threads, [&] {
        const Frame frame = slicedFrame(mesh, inFrame, options);
        checkMemory(attributeGridBytes(frame, ch), "attribute voxelization at this resolution");
        grid.frame = frame;
        const auto voxels = size_t(grid.voxelCount());
        if (ch.count) grid.count.assign(voxels, 0);
        if (ch.absorption) grid.absorption.assign(voxels, 0.0f);
        std::vector<Vec3f> faceNormals;
        if (ch.normals) {
            grid.normalSum.assign(voxels, Vec3f{});
            faceNormals.resize(mesh.triangleCount);
            for (size_t t = 0; t < mesh.triangleCount; ++t) {
                const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                            c = mesh.vertex(mesh.index(t, 2));
                faceNormals[t] = Vec3f(normalize(cross(b - a, c - a)));
            }
        }
        if (ch.material) grid.material.assign(voxels, AttributeGrid::kNoMaterial);
        if (ch.ior) grid.ior.assign(voxels, 0.0f);
        // Without a material, ior or count channel, -1 marks the attenuation of unwritten voxels.
        const bool attenuationMarksFirst = ch.attenuation && !ch.material && !ch.ior && !ch.count;
        if (ch.attenuation) {
            const float unset = attenuationMarksFirst ? -1.0f : 0.0f;
            grid.attenuation.assign(voxels, Vec3f{unset, unset, unset});
        }
        RasterOptions ro;
        ro.coverage = options.coverage;
        ro.progress = options.progress;
        const bool anyMaterial = ch.material || ch.ior || ch.attenuation;
        std::optional<SmoothNormals> smooth;
        if (ch.normals && !options.vertexNormals.empty()) smooth.emplace(mesh, options.vertexNormals);
        AttributeConsumer consumer{grid.frame,
                                   grid,
                                   ch.absorption ? triangleAbsorption : std::span<const float>{},
                                   faceNormals,
                                   smooth ? &*smooth : nullptr,
                                   anyMaterial ? options.triangleMaterial : std::span<const uint32_t>{},
                                   options.materials,
                                   options.slabOverlap,
                                   attenuationMarksFirst};
        rasterize(grid.frame, mesh, ro, consumer);
        if (attenuationMarksFirst)
            for (Vec3f& a : grid.attenuation)
                if (a.x < 0) a = Vec3f{};
    });
    return grid;
}

AttributeColumns voxelizeAttributeColumns(const MeshView& mesh, const Frame& inFrame,
                                          std::span<const float> triangleAbsorption,
                                          const AttributeOptions& options) {
    validateMesh(mesh, "mesh");
    checkAbsorption(mesh, triangleAbsorption, options);
    AttributeColumns out;
    withThreads(options.threads, [&] {
        out.frame = slicedFrame(mesh, inFrame, options);
        const int64_t H = out.frame.height();
        RasterOptions ro;
        ro.coverage = options.coverage;
        ro.progress = options.progress;
        ro.rowsPerTile = std::max<int64_t>(1, (H + 63) / 64);
        std::vector<ColumnWritesConsumer::TileOut> tiles(size_t((H + ro.rowsPerTile - 1) / ro.rowsPerTile));
        ColumnWritesConsumer consumer{out.frame, triangleAbsorption, options.slabOverlap, tiles};
        rasterize(out.frame, mesh, ro, consumer);
        // Tiles own consecutive row ranges, so their column-sorted entries concatenate in order.
        std::size_t total = 0;
        for (const auto& t : tiles) total += t.slice.size();
        out.slice.reserve(total);
        out.count.reserve(total);
        out.absorption.reserve(total);
        out.offsets.assign(size_t(out.frame.columnCount()) + 1, 0);
        for (const auto& t : tiles) {
            for (std::size_t i = 0; i < t.slice.size(); ++i) {
                ++out.offsets[size_t(t.column[i]) + 1];
                out.slice.push_back(uint32_t(t.slice[i]));
            }
            out.count.insert(out.count.end(), t.count.begin(), t.count.end());
            out.absorption.insert(out.absorption.end(), t.absorption.begin(), t.absorption.end());
        }
        for (std::size_t c = 1; c < out.offsets.size(); ++c) out.offsets[c] += out.offsets[c - 1];
    });
    return out;
}

} // namespace voxfx
