// voxfx — attribute voxelization (CHANG §2: per-voxel write count, normal sum, material absorption).
//
// A consumer of the one rasterizer. Centre coverage reproduces CHANG's slab clipping (one write per
// triangle and covered column centre, in the slice of the triangle's depth there); conservative
// coverage writes every voxel the triangle's exact depth span in the column touches. Each tile owns
// its rows and visits triangles in index order, so the float sums are deterministic.
#include <algorithm>
#include <cmath>
#include <limits>

#include "voxelize/consumers.hpp"
#include "voxfx/attribute_grid.hpp"

namespace voxfx {

namespace {

struct AttributeConsumer {
    const Frame& frame;
    AttributeGrid& grid;
    std::span<const float> absorption;
    const std::vector<Vec3f>& faceNormals;      // empty when normals are off
    std::span<const uint32_t> triangleMaterial; // empty when the material channel is off

    struct Sink {
        AttributeConsumer& c;
        FrameView frame;
        void write(int64_t column, int64_t s, uint32_t triangle) {
            const auto i = size_t(column * c.frame.depth() + s);
            uint16_t& n = c.grid.count[i];
            if (n != 0xffff) ++n;
            if (!c.absorption.empty()) c.grid.absorption[i] += c.absorption[triangle];
            if (!c.faceNormals.empty()) c.grid.normalSum[i] += c.faceNormals[triangle];
            if (!c.triangleMaterial.empty() && c.grid.material[i] == AttributeGrid::kNoMaterial)
                c.grid.material[i] = c.triangleMaterial[triangle];
        }
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool) {
            const int64_t column = y * c.frame.width() + x;
            const int64_t s = detail::fragmentSlice(frame, column, depth);
            if (s >= 0) write(column, s, triangle);
        }
        void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t triangle) {
            const int64_t column = y * c.frame.width() + x;
            int64_t s0, s1;
            if (!detail::spanSlices(frame, column, depthMin, depthMax, s0, s1)) return;
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
            const int64_t s = detail::fragmentSlice(frame, column, depth);
            if (s >= 0) entries.push_back({column, s, triangle});
        }
        void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t triangle) {
            const int64_t column = y * c.frame.width() + x;
            int64_t s0, s1;
            if (!detail::spanSlices(frame, column, depthMin, depthMax, s0, s1)) return;
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

void checkAbsorption(const MeshView& mesh, std::span<const float> triangleAbsorption) {
    if (!triangleAbsorption.empty() && triangleAbsorption.size() != mesh.triangleCount)
        fail("attribute voxelization: ", triangleAbsorption.size(), " absorption values for ",
             mesh.triangleCount, " triangles");
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
    BitGrid bits(frame.width(), frame.height(), frame.depth());
    const int64_t D = frame.depth();
    parallelFor(0, frame.columnCount(), 1024, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            uint64_t* col = bits.column(c);
            const uint16_t* n = count.data() + c * D;
            for (int64_t s = 0; s < D; ++s)
                if (n[s]) col[s >> 6] |= uint64_t(1) << (s & 63);
        }
    });
    return bits;
}

int64_t AttributeGrid::writeCount() const {
    int64_t total = 0;
    for (const uint16_t n : count) total += n;
    return total;
}

uint64_t attributeGridBytes(const Frame& frame, bool normals, bool materials) {
    const uint64_t voxels = uint64_t(frame.columnCount()) * uint64_t(frame.depth());
    return voxels * (sizeof(uint16_t) + sizeof(float) + (normals ? sizeof(Vec3f) : 0) +
                     (materials ? sizeof(uint32_t) : 0));
}

AttributeGrid voxelizeAttributes(const MeshView& mesh, const Frame& inFrame,
                                 std::span<const float> triangleAbsorption, const AttributeOptions& options) {
    validateMesh(mesh, "mesh");
    checkAbsorption(mesh, triangleAbsorption);
    AttributeGrid grid;
    withThreads(options.threads, [&] {
        const Frame frame = slicedFrame(mesh, inFrame, options);
        if (!options.triangleMaterial.empty() && options.triangleMaterial.size() != mesh.triangleCount)
            fail("attribute voxelization: ", options.triangleMaterial.size(), " material indices for ",
                 mesh.triangleCount, " triangles");
        checkMemory(attributeGridBytes(frame, options.normals, !options.triangleMaterial.empty()),
                    "attribute voxelization at this resolution");
        grid.frame = frame;
        const auto voxels = size_t(grid.voxelCount());
        grid.count.assign(voxels, 0);
        grid.absorption.assign(voxels, 0.0f);
        std::vector<Vec3f> faceNormals;
        if (options.normals) {
            grid.normalSum.assign(voxels, Vec3f{});
            faceNormals.resize(mesh.triangleCount);
            for (size_t t = 0; t < mesh.triangleCount; ++t) {
                const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                            c = mesh.vertex(mesh.index(t, 2));
                faceNormals[t] = Vec3f(normalize(cross(b - a, c - a)));
            }
        }
        RasterOptions ro;
        ro.coverage = options.coverage;
        ro.progress = options.progress;
        if (!options.triangleMaterial.empty()) grid.material.assign(voxels, AttributeGrid::kNoMaterial);
        AttributeConsumer consumer{grid.frame, grid, triangleAbsorption, faceNormals,
                                   options.triangleMaterial};
        rasterize(grid.frame, mesh, ro, consumer);
    });
    return grid;
}

AttributeColumns voxelizeAttributeColumns(const MeshView& mesh, const Frame& inFrame,
                                          std::span<const float> triangleAbsorption,
                                          const AttributeOptions& options) {
    validateMesh(mesh, "mesh");
    checkAbsorption(mesh, triangleAbsorption);
    AttributeColumns out;
    withThreads(options.threads, [&] {
        out.frame = slicedFrame(mesh, inFrame, options);
        const int64_t H = out.frame.height();
        RasterOptions ro;
        ro.coverage = options.coverage;
        ro.progress = options.progress;
        ro.rowsPerTile = std::max<int64_t>(1, (H + 63) / 64);
        std::vector<ColumnWritesConsumer::TileOut> tiles(size_t((H + ro.rowsPerTile - 1) / ro.rowsPerTile));
        ColumnWritesConsumer consumer{out.frame, triangleAbsorption, tiles};
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
