// voxfx — the two storages of a deep shadow map: fixed nodes per texel, and chunks of 64 nodes
// filled per 8x8 tile (Bornik et al. §4.3). Tiles are built in parallel, each by one thread that
// owns its texels; per-tile results are combined in tile order, so nothing depends on the
// thread count.
#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/dsm.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {
namespace {

constexpr int64_t kTile = DsmChunked::kTile;

void checkMap(int64_t width, int64_t height, double epsilon) {
    if (width <= 0 || height <= 0 || width > (int64_t(1) << 20) || height > (int64_t(1) << 20))
        fail("deep shadow map: size ", width, " x ", height, " is not in 1..1048576 per side");
    if (!std::isfinite(epsilon) || epsilon < 0)
        fail("deep shadow map: epsilon ", epsilon, " is not a finite value >= 0");
}

struct TileStats {
    int64_t nodes = 0, maxNodes = 0, overflow = 0;
    double maxEpsilon = 0;
};

void buildTexel(const DsmTexelFunction& texel, int64_t x, int64_t y, double epsilon,
                std::vector<DsmNode>& out) {
    out.clear();
    VisibilityBuilder builder(epsilon, out);
    texel(x, y, builder);
    builder.finish();
}

// Tiles in row-major order; tile t covers texels [x0, x1) x [y0, y1).
struct TileGrid {
    int64_t width, height, tilesX, tilesY;
    TileGrid(int64_t w, int64_t h)
        : width(w), height(h), tilesX((w + kTile - 1) / kTile), tilesY((h + kTile - 1) / kTile) {}
    int64_t count() const { return tilesX * tilesY; }
    template <class F> void forEachTexel(int64_t t, F&& f) const {
        const int64_t x0 = (t % tilesX) * kTile, y0 = (t / tilesX) * kTile;
        const int64_t x1 = std::min(width, x0 + kTile), y1 = std::min(height, y0 + kTile);
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x) f(x, y);
    }
};

DsmStats combine(const std::vector<TileStats>& tiles, int64_t texels, double epsilon) {
    DsmStats s;
    s.texels = texels;
    s.maxEpsilon = epsilon;
    for (const TileStats& t : tiles) {
        s.nodes += t.nodes;
        s.maxNodes = std::max(s.maxNodes, t.maxNodes);
        s.overflowTexels += t.overflow;
        s.maxEpsilon = std::max(s.maxEpsilon, t.maxEpsilon);
    }
    return s;
}

} // namespace

DsmFixed DsmFixed::build(int64_t width, int64_t height, const DsmTexelFunction& texel,
                         const DsmBuildOptions& options) {
    checkMap(width, height, options.epsilon);
    if (options.fixedNodes == 0) return fromChunked(DsmChunked::build(width, height, texel, options.epsilon));
    if (options.fixedNodes < 2 || options.fixedNodes > std::numeric_limits<uint16_t>::max())
        fail("deep shadow map: fixed storage needs 2..65535 nodes per texel (or 0: sized by the worst "
             "texel), not ",
             options.fixedNodes);
    DsmFixed m;
    m.width_ = width;
    m.height_ = height;
    m.n_ = options.fixedNodes;
    const int64_t n = m.n_;
    m.nodes_.assign(size_t(width * height * n), DsmNode{});
    m.counts_.assign(size_t(width * height), 0);
    const TileGrid grid(width, height);
    std::vector<TileStats> stats(size_t(grid.count()));
    parallelFor(0, grid.count(), 1, [&](int64_t b, int64_t e) {
        std::vector<DsmNode> buf;
        for (int64_t t = b; t < e; ++t) {
            TileStats& ts = stats[size_t(t)];
            grid.forEachTexel(t, [&](int64_t x, int64_t y) {
                double eps = options.epsilon;
                buildTexel(texel, x, y, eps, buf);
                if (int64_t(buf.size()) > n) {
                    // Degrade gracefully: rebuild with a doubled ε until the texel fits. With
                    // ε >= 1 every function fits in two nodes (a flat line at its first value).
                    ++ts.overflow;
                    eps = std::max(eps, 1.0 / 1024);
                    while (int64_t(buf.size()) > n) {
                        eps = std::min(1.0, 2 * eps);
                        buildTexel(texel, x, y, eps, buf);
                    }
                    ts.maxEpsilon = std::max(ts.maxEpsilon, eps);
                }
                const int64_t i = y * width + x;
                std::copy(buf.begin(), buf.end(), m.nodes_.begin() + i * n);
                m.counts_[size_t(i)] = uint16_t(buf.size());
                ts.nodes += int64_t(buf.size());
                ts.maxNodes = std::max(ts.maxNodes, int64_t(buf.size()));
            });
        }
    });
    m.stats_ = combine(stats, width * height, options.epsilon);
    m.stats_.bytes = int64_t(m.nodes_.size() * sizeof(DsmNode) + m.counts_.size() * sizeof(uint16_t));
    return m;
}

DsmFixed DsmFixed::fromChunked(const DsmChunked& chunked) {
    const DsmStats& cs = chunked.stats();
    if (cs.maxNodes > std::numeric_limits<uint16_t>::max())
        fail("deep shadow map: a texel has ", cs.maxNodes, " nodes, more than fixed storage holds (65535)");
    DsmFixed m;
    m.width_ = chunked.width();
    m.height_ = chunked.height();
    m.n_ = int32_t(std::max<int64_t>(2, cs.maxNodes));
    const int64_t n = m.n_, width = m.width_;
    m.nodes_.assign(size_t(m.width_ * m.height_ * n), DsmNode{});
    m.counts_.assign(size_t(m.width_ * m.height_), 0);
    parallelFor(0, m.height_, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < width; ++x) {
                const std::vector<DsmNode> nodes = chunked.texel(x, y);
                std::copy(nodes.begin(), nodes.end(), m.nodes_.begin() + (y * width + x) * n);
                m.counts_[size_t(y * width + x)] = uint16_t(nodes.size());
            }
    });
    m.stats_ = cs;
    m.stats_.bytes = int64_t(m.nodes_.size() * sizeof(DsmNode) + m.counts_.size() * sizeof(uint16_t));
    return m;
}

std::span<const DsmNode> DsmFixed::texel(int64_t x, int64_t y) const {
    VOXFX_CHECK(x >= 0 && x < width_ && y >= 0 && y < height_);
    const int64_t i = y * width_ + x;
    return {nodes_.data() + i * n_, counts_[size_t(i)]};
}

DsmChunked DsmChunked::build(int64_t width, int64_t height, const DsmTexelFunction& texel, double epsilon) {
    checkMap(width, height, epsilon);
    DsmChunked m;
    m.width_ = width;
    m.height_ = height;
    m.heads_.assign(size_t(width * height), DsmTexelHead{});
    const TileGrid grid(width, height);
    // Each tile appends its texels' nodes, in texel order, to its own chain of chunks (the paper's
    // per-block chunk list, without atomics: one thread per tile). Chunk indices are tile-local
    // until the chains are placed one after another in tile order.
    std::vector<std::vector<DsmChunk>> tileChunks(size_t(grid.count()));
    std::vector<TileStats> stats(size_t(grid.count()));
    parallelFor(0, grid.count(), 1, [&](int64_t b, int64_t e) {
        std::vector<DsmNode> buf;
        for (int64_t t = b; t < e; ++t) {
            std::vector<DsmChunk>& chunks = tileChunks[size_t(t)];
            TileStats& ts = stats[size_t(t)];
            uint32_t fill = kDsmChunkNodes; // entries used in the last chunk
            grid.forEachTexel(t, [&](int64_t x, int64_t y) {
                buildTexel(texel, x, y, epsilon, buf);
                if (buf.size() > std::numeric_limits<uint32_t>::max())
                    fail("deep shadow map: texel (", x, ", ", y, ") has too many nodes");
                DsmTexelHead& head = m.heads_[size_t(y * width + x)];
                head.count = uint32_t(buf.size());
                for (size_t k = 0; k < buf.size(); ++k) {
                    if (fill == kDsmChunkNodes) {
                        if (!chunks.empty()) chunks.back().next = int32_t(chunks.size());
                        chunks.emplace_back();
                        fill = 0;
                    }
                    if (k == 0) {
                        head.chunk = int32_t(chunks.size() - 1);
                        head.entry = fill;
                    }
                    chunks.back().nodes[fill++] = buf[k];
                }
                ts.nodes += int64_t(buf.size());
                ts.maxNodes = std::max(ts.maxNodes, int64_t(buf.size()));
            });
        }
    });
    std::vector<int64_t> offset(size_t(grid.count()) + 1, 0);
    for (int64_t t = 0; t < grid.count(); ++t)
        offset[size_t(t) + 1] = offset[size_t(t)] + int64_t(tileChunks[size_t(t)].size());
    if (offset.back() > std::numeric_limits<int32_t>::max())
        fail("deep shadow map: too many chunks (", offset.back(), ")");
    m.chunks_.resize(size_t(offset.back()));
    parallelFor(0, grid.count(), 1, [&](int64_t b, int64_t e) {
        for (int64_t t = b; t < e; ++t) {
            const int32_t off = int32_t(offset[size_t(t)]);
            std::vector<DsmChunk>& chunks = tileChunks[size_t(t)];
            for (size_t c = 0; c < chunks.size(); ++c) {
                DsmChunk& dst = m.chunks_[size_t(off) + c];
                dst = chunks[c];
                if (dst.next >= 0) dst.next += off;
            }
            std::vector<DsmChunk>().swap(chunks);
            grid.forEachTexel(t, [&](int64_t x, int64_t y) {
                DsmTexelHead& head = m.heads_[size_t(y * width + x)];
                if (head.chunk >= 0) head.chunk += off;
            });
        }
    });
    m.stats_ = combine(stats, width * height, epsilon);
    m.stats_.bytes = int64_t(m.chunks_.size() * sizeof(DsmChunk) + m.heads_.size() * sizeof(DsmTexelHead));
    return m;
}

std::vector<DsmNode> DsmChunked::texel(int64_t x, int64_t y) const {
    VOXFX_CHECK(x >= 0 && x < width_ && y >= 0 && y < height_);
    const DsmTexelHead h = heads_[size_t(y * width_ + x)];
    std::vector<DsmNode> out;
    out.reserve(h.count);
    int32_t c = h.chunk;
    uint32_t e = h.entry;
    for (uint32_t i = 0; i < h.count; ++i) {
        if (e == kDsmChunkNodes) {
            c = chunks_[size_t(c)].next;
            e = 0;
        }
        out.push_back(chunks_[size_t(c)].nodes[e++]);
    }
    return out;
}

const char* toString(DsmStorage s) { return enumName(s, kDsmStorageNames); }

DsmStorage parseDsmStorage(const std::string& name) {
    return parseEnum<DsmStorage>(name, "deep shadow map storage", kDsmStorageNames);
}

const char* toString(DsmFilter f) { return enumName(f, kDsmFilterNames); }

DsmFilter parseDsmFilter(const std::string& name) {
    return parseEnum<DsmFilter>(name, "deep shadow map filter", kDsmFilterNames);
}

DeepShadowMap DeepShadowMap::build(int64_t width, int64_t height, const DsmTexelFunction& texel,
                                   DsmStorage storage, const DsmBuildOptions& options) {
    DeepShadowMap m;
    if (storage == DsmStorage::Fixed)
        m.map_ = DsmFixed::build(width, height, texel, options);
    else
        m.map_ = DsmChunked::build(width, height, texel, options.epsilon);
    return m;
}

DsmView DeepShadowMap::view() const {
    DsmView v;
    if (const auto* f = std::get_if<DsmFixed>(&map_)) {
        v.storage = DsmStorage::Fixed;
        v.fixed = f->view();
    } else {
        v.storage = DsmStorage::Chunked;
        v.chunked = std::get<DsmChunked>(map_).view();
    }
    return v;
}

const DsmStats& DeepShadowMap::stats() const {
    return std::visit([](const auto& m) -> const DsmStats& { return m.stats(); }, map_);
}

std::vector<DsmNode> DeepShadowMap::texel(int64_t x, int64_t y) const {
    if (const auto* f = std::get_if<DsmFixed>(&map_)) {
        const auto s = f->texel(x, y);
        return {s.begin(), s.end()};
    }
    return std::get<DsmChunked>(map_).texel(x, y);
}

} // namespace voxfx
