// voxfx — deep shadow maps (Bornik et al. 2012, after Lokovic & Veach 2000): per texel of a light
// view, a piecewise-linear visibility function V(z), the fraction of light left at depth z along
// the texel's ray, compressed on the fly so that it never leaves the ε-band around the exact one.
//
// Visibility function: nodes (z, v) sorted by depth, V(0) = 1, non-increasing. Before the first
// node V is the first node's value (1 for built functions); after the last node, the last value; between two
// nodes V interpolates linearly. A surface of opacity α is a step: two nodes at the SAME depth (the value
// before and after V *= 1 - α), as in the paper. V is left-continuous at a step: V(z_step) is the value
// before the step, so a surface does not shadow its own depth (the standard shadow map's "lit when z <=
// stored depth"), and any z > z_step sees the value after. A volume segment is a ramp: one node at its start,
// then one per sample with V *= exp(-σ·dz), linear in between.
//
// Compression (Lokovic & Veach §4.1): walk the nodes from the current segment origin, keep the
// interval of slopes whose line from the origin stays within ε of every node seen (slopes are also
// capped at 0, so the result stays non-increasing); when a node empties the interval, end the
// segment at the previous node's depth (value on the line, inside that node's band) and restart
// from there. A node at the origin's depth that lies outside the band is a step: a node at the
// same depth. Segment ends lie on depths of original nodes, so between two consecutive original
// depths both functions are linear and the ε bound at the nodes (both one-sided limits of steps)
// holds everywhere. ε = 0 keeps every node (up to float rounding of the stored values).
//
// Storage of a W x H map: DsmFixed (N nodes per texel, sized up front; a texel needing more is
// rebuilt with a doubled ε until it fits, and counted) and DsmChunked (chunks of 64 nodes linked
// per 8x8 tile; each tile fills its own chunk list, and the lists are placed in tile order, so the
// chunk layout does not depend on the thread count). Both report the bytes they hold.
//
// Lookups on the plain views (DsmFixedView, DsmChunkedView) are VOXFX_HOSTDEV: no allocation, no
// exceptions. EXPERIMENTAL until the renderer wires them in (`voxfx render --shadows deep`).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/shadow_options.hpp"
#include "voxfx/types.hpp"

namespace voxfx {

/// One node of a visibility function: depth along the light ray and the visibility there.
struct DsmNode {
    float z = 0;
    float v = 1;
};

/// Evaluates the piecewise-linear function of `count` nodes (sorted by depth) at depth z, with the
/// conventions of the file comment (left-continuous at steps, constant outside). Binary search.
VOXFX_HOSTDEV inline float evalVisibility(const DsmNode* nodes, int64_t count, float z) {
    if (count <= 0) return 1.0f;
    if (z <= nodes[0].z) return nodes[0].v;
    if (z > nodes[count - 1].z) return nodes[count - 1].v;
    // First node with depth >= z (exists, index >= 1).
    int64_t lo = 1, hi = count - 1;
    while (lo < hi) {
        const int64_t mid = lo + (hi - lo) / 2;
        if (nodes[mid].z < z)
            lo = mid + 1;
        else
            hi = mid;
    }
    const DsmNode a = nodes[lo - 1], b = nodes[lo];
    if (b.z == z || b.z <= a.z) return b.v;
    const float t = (z - a.z) / (b.z - a.z);
    return a.v + t * (b.v - a.v);
}

/// Streaming ε-compressor (Lokovic & Veach): push the exact nodes in depth order, then finish().
/// Output goes to the vector given at construction (appended).
class DsmCompressor {
public:
    DsmCompressor(double epsilon, std::vector<DsmNode>& out);
    void push(double z, double v);
    /// Emits the pending segment end; the compressor can then be reset() and reused.
    void finish();
    void reset(double epsilon, std::vector<DsmNode>& out);

private:
    void emit(double z, double v);
    void closeSegment();
    std::vector<DsmNode>* out_;
    int64_t emitted_ = 0;
    double eps_;
    bool started_ = false;
    double zo_ = 0, vo_ = 1;                // segment origin (already emitted)
    double lo_ = 0, hi_ = 0;                // feasible slopes
    bool open_ = false;                     // at least one node accepted since the origin, at zl_ > zo_
    double zl_ = 0, vlMin_ = 0, vlMax_ = 0; // last accepted depth and the band there
};

/// Builds one texel's visibility from events fed in depth order, compressing on the fly.
class VisibilityBuilder {
public:
    /// Compressed output appended to `out`; epsilon < 0 keeps the exact function (no compression).
    VisibilityBuilder(double epsilon, std::vector<DsmNode>& out);
    /// A surface of opacity alpha in [0, 1] at depth z: a step (two nodes at depth z).
    void surface(double z, double alpha);
    /// Starts a volume segment at depth z: a node with the current visibility.
    void volumeBegin(double z);
    /// One volume sample ending at depth z, of extinction sigma over the step dz: V *= exp(-sigma*dz),
    /// reached linearly from the previous node.
    void volumeSample(double z, double sigma, double dz);
    /// Multiplies the visibility by `factor` in [0, 1], reached linearly from the previous node.
    void ramp(double z, double factor);
    /// Current (exact) visibility; 0 means nothing further changes it (early termination).
    double visibility() const { return v_; }
    /// Completes the function (must be called once, after the last event).
    void finish();

private:
    void node(double z, double v);
    DsmCompressor comp_;
    std::vector<DsmNode>* out_;
    bool exact_;
    double v_ = 1;
    double lastZ_ = 0;
    bool any_ = false;
};

/// An event along a light ray, for building from an unsorted list (buildVisibility).
struct DsmEvent {
    enum class Kind : uint8_t { Surface, Volume };
    Kind kind = Kind::Surface;
    float z0 = 0;        ///< surface depth, or start of the volume segment
    float z1 = 0;        ///< end of the volume segment (z1 >= z0)
    float alpha = 1;     ///< surface opacity
    float sigma = 0;     ///< volume extinction per depth unit
    int32_t samples = 1; ///< volume samples, evenly spaced, the last one at z1
};

/// Sorts the events' elementary attenuations by depth (ties: ramps before steps, then input
/// order) and builds the visibility function into `out` (cleared), ε-compressed (epsilon < 0:
/// exact). Overlapping volume segments multiply. Throws voxfx::Error on invalid events.
void buildVisibility(std::span<const DsmEvent> events, double epsilon, std::vector<DsmNode>& out);

/// Texel (x, y) in [0, W) x [0, H): feed its events into the builder in depth order (do not call
/// finish). Must be deterministic; the map may call it more than once for a texel (fixed storage
/// rebuilding with a larger ε) and from several threads at once for different texels.
using DsmTexelFunction = std::function<void(int64_t x, int64_t y, VisibilityBuilder& builder)>;

/// Plain view of a fixed-size map: texel i = y * width + x holds counts[i] nodes at nodes[i * n].
struct DsmFixedView {
    const DsmNode* nodes = nullptr;
    const uint16_t* counts = nullptr;
    int64_t width = 0, height = 0;
    int32_t n = 0;

    VOXFX_HOSTDEV float visibility(int64_t x, int64_t y, float z) const {
        const int64_t i = y * width + x;
        return evalVisibility(nodes + i * n, counts[i], z);
    }
    /// Bilinear over the four texels around light-space (u, v) in texel units (texel (x, y) covers
    /// [x, x+1) x [y, y+1), its centre at x + 0.5); clamped at the border.
    VOXFX_HOSTDEV float visibilityBilinear(float u, float v, float z) const;
};

/// One chunk of the chunked storage: 64 nodes and the index of the next chunk (-1: none).
inline constexpr int kDsmChunkNodes = 64;
struct DsmChunk {
    DsmNode nodes[kDsmChunkNodes];
    int32_t next = -1;
};
/// Where a texel's nodes start: chunk index and entry, and how many there are.
struct DsmTexelHead {
    int32_t chunk = -1;
    uint32_t entry = 0;
    uint32_t count = 0;
};

/// Plain view of a chunked map: a texel's nodes run from (chunk, entry) on, following `next` at
/// the end of a chunk. Lookups walk them linearly (as the paper does).
struct DsmChunkedView {
    const DsmChunk* chunks = nullptr;
    const DsmTexelHead* heads = nullptr;
    int64_t width = 0, height = 0;

    VOXFX_HOSTDEV float visibility(int64_t x, int64_t y, float z) const;
    VOXFX_HOSTDEV float visibilityBilinear(float u, float v, float z) const;
};

namespace detail {
/// Bilinear weights and the clamped texel indices around (u, v) (see DsmFixedView).
struct DsmBilinear {
    int64_t x0, x1, y0, y1;
    float tx, ty;
};
VOXFX_HOSTDEV inline int64_t dsmFloor(float f) {
    const int64_t i = int64_t(f);
    return float(i) > f ? i - 1 : i;
}
VOXFX_HOSTDEV inline DsmBilinear dsmBilinear(float u, float v, int64_t w, int64_t h) {
    // Clamp before converting (NaN -> the first texel; far outside -> the border texel).
    float fx = u == u ? u - 0.5f : 0.0f, fy = v == v ? v - 0.5f : 0.0f;
    fx = fx < -1.0f ? -1.0f : (fx > float(w) ? float(w) : fx);
    fy = fy < -1.0f ? -1.0f : (fy > float(h) ? float(h) : fy);
    const int64_t bx = dsmFloor(fx), by = dsmFloor(fy);
    const auto clampi = [](int64_t i, int64_t n) { return i < 0 ? int64_t(0) : (i >= n ? n - 1 : i); };
    DsmBilinear b{};
    b.tx = fx - float(bx);
    b.ty = fy - float(by);
    b.x0 = clampi(bx, w);
    b.x1 = clampi(bx + 1, w);
    b.y0 = clampi(by, h);
    b.y1 = clampi(by + 1, h);
    return b;
}
} // namespace detail

VOXFX_HOSTDEV inline float DsmFixedView::visibilityBilinear(float u, float v, float z) const {
    const detail::DsmBilinear b = detail::dsmBilinear(u, v, width, height);
    const float a = visibility(b.x0, b.y0, z) * (1 - b.tx) + visibility(b.x1, b.y0, z) * b.tx;
    const float c = visibility(b.x0, b.y1, z) * (1 - b.tx) + visibility(b.x1, b.y1, z) * b.tx;
    return a * (1 - b.ty) + c * b.ty;
}

VOXFX_HOSTDEV inline float DsmChunkedView::visibility(int64_t x, int64_t y, float z) const {
    const DsmTexelHead h = heads[y * width + x];
    if (h.count == 0) return 1.0f;
    int32_t c = h.chunk;
    uint32_t e = h.entry;
    DsmNode prev = chunks[c].nodes[e];
    if (z <= prev.z) return prev.v;
    for (uint32_t i = 1; i < h.count; ++i) {
        if (++e == kDsmChunkNodes) {
            c = chunks[c].next;
            e = 0;
        }
        const DsmNode cur = chunks[c].nodes[e];
        if (cur.z >= z) {
            if (cur.z == z || cur.z <= prev.z) return cur.v;
            const float t = (z - prev.z) / (cur.z - prev.z);
            return prev.v + t * (cur.v - prev.v);
        }
        prev = cur;
    }
    return prev.v;
}

VOXFX_HOSTDEV inline float DsmChunkedView::visibilityBilinear(float u, float v, float z) const {
    const detail::DsmBilinear b = detail::dsmBilinear(u, v, width, height);
    const float a = visibility(b.x0, b.y0, z) * (1 - b.tx) + visibility(b.x1, b.y0, z) * b.tx;
    const float c = visibility(b.x0, b.y1, z) * (1 - b.tx) + visibility(b.x1, b.y1, z) * b.tx;
    return a * (1 - b.ty) + c * b.ty;
}

/// Options for building a map.
struct DsmBuildOptions {
    double epsilon = 0.05;
    /// DsmFixed: nodes per texel (at least 2), or 0: sized by the worst texel (the paper's fixed
    /// layout: every texel is compressed once, then copied; none is rebuilt).
    int32_t fixedNodes = 32;
};

class DsmChunked;

/// Fixed storage: N nodes per texel.
class DsmFixed {
public:
    static DsmFixed build(int64_t width, int64_t height, const DsmTexelFunction& texel,
                          const DsmBuildOptions& options);
    DsmFixedView view() const { return {nodes_.data(), counts_.data(), width_, height_, n_}; }
    const DsmStats& stats() const { return stats_; }
    /// The nodes of texel (x, y).
    std::span<const DsmNode> texel(int64_t x, int64_t y) const;
    /// The fixed layout of a chunked map, N = its largest texel (at least 2).
    static DsmFixed fromChunked(const DsmChunked& chunked);

private:
    int64_t width_ = 0, height_ = 0;
    int32_t n_ = 0;
    std::vector<DsmNode> nodes_;
    std::vector<uint16_t> counts_;
    DsmStats stats_;
};

/// Chunked storage: chunks of 64 nodes, filled per 8x8 tile.
class DsmChunked {
public:
    static constexpr int64_t kTile = 8;
    static DsmChunked build(int64_t width, int64_t height, const DsmTexelFunction& texel, double epsilon);
    DsmChunkedView view() const { return {chunks_.data(), heads_.data(), width_, height_}; }
    const DsmStats& stats() const { return stats_; }
    /// The nodes of texel (x, y), gathered across chunks.
    std::vector<DsmNode> texel(int64_t x, int64_t y) const;
    int64_t chunkCount() const { return int64_t(chunks_.size()); }
    int64_t width() const { return width_; }
    int64_t height() const { return height_; }

private:
    int64_t width_ = 0, height_ = 0;
    std::vector<DsmChunk> chunks_;
    std::vector<DsmTexelHead> heads_;
    DsmStats stats_;
};

const char* toString(DsmStorage s);
/// Parses fixed | chunked (any case); throws voxfx::Error listing them otherwise.
DsmStorage parseDsmStorage(const std::string& name);

const char* toString(DsmFilter f);
/// Parses bilinear | none (any case); throws voxfx::Error listing them otherwise.
DsmFilter parseDsmFilter(const std::string& name);

namespace detail {
/// The texel holding light-space (u, v) (texel units), clamped at the border (NaN: the first).
VOXFX_HOSTDEV inline int64_t dsmNearest(float u, int64_t n) {
    if (!(u == u) || u < 0.0f) return 0;
    if (u >= float(n)) return n - 1;
    const int64_t i = int64_t(u);
    return i >= n ? n - 1 : i;
}
} // namespace detail

/// A plain view of either storage, for lookups that choose at run time (`--dsm-storage`).
struct DsmView {
    DsmStorage storage = DsmStorage::Chunked;
    DsmFixedView fixed;
    DsmChunkedView chunked;

    VOXFX_HOSTDEV float visibility(int64_t x, int64_t y, float z) const {
        return storage == DsmStorage::Fixed ? fixed.visibility(x, y, z) : chunked.visibility(x, y, z);
    }
    VOXFX_HOSTDEV float visibilityBilinear(float u, float v, float z) const {
        return storage == DsmStorage::Fixed ? fixed.visibilityBilinear(u, v, z)
                                            : chunked.visibilityBilinear(u, v, z);
    }
    /// The texel (u, v) falls in (texel units, clamped at the border), unfiltered.
    VOXFX_HOSTDEV float visibilityNearest(float u, float v, float z) const {
        const int64_t w = storage == DsmStorage::Fixed ? fixed.width : chunked.width;
        const int64_t h = storage == DsmStorage::Fixed ? fixed.height : chunked.height;
        return visibility(detail::dsmNearest(u, w), detail::dsmNearest(v, h), z);
    }
    VOXFX_HOSTDEV float visibilityFiltered(DsmFilter f, float u, float v, float z) const {
        return f == DsmFilter::None ? visibilityNearest(u, v, z) : visibilityBilinear(u, v, z);
    }
};

/// One deep shadow map in the storage chosen at build time.
class DeepShadowMap {
public:
    static DeepShadowMap build(int64_t width, int64_t height, const DsmTexelFunction& texel,
                               DsmStorage storage, const DsmBuildOptions& options);
    DsmStorage storage() const {
        return std::holds_alternative<DsmFixed>(map_) ? DsmStorage::Fixed : DsmStorage::Chunked;
    }
    DsmView view() const;
    const DsmStats& stats() const;
    /// The nodes of texel (x, y).
    std::vector<DsmNode> texel(int64_t x, int64_t y) const;

private:
    std::variant<DsmChunked, DsmFixed> map_;
};

} // namespace voxfx
