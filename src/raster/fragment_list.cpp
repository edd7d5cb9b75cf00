// voxfx — fragment lists: a consumer of the one rasterizer that keeps every centre-sampled
// fragment, then sorts each column by depth (see voxfx/fragment_list.hpp).
#include "voxfx/fragment_list.hpp"

#include <algorithm>

#include "voxfx/raster.hpp"

namespace voxfx {

namespace {

struct FragmentListEntry {
    int64_t x;
    ListFragment f;
};

// Each tile owns its rows: sinks append to the row vectors of their tile without locks.
struct FragmentListConsumer {
    std::vector<std::vector<FragmentListEntry>>* rows;
    struct Sink {
        std::vector<std::vector<FragmentListEntry>>* rows;
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool front) {
            (*rows)[std::size_t(y)].push_back({x, {depth, triangle, front}});
        }
        void finish() {}
    };
    Sink tile(const Tile&) const { return {rows}; }
};

} // namespace

FragmentLists FragmentLists::build(const Frame& frame, const MeshView& mesh, Progress* progress) {
    FragmentLists out;
    out.width_ = frame.width();
    out.height_ = frame.height();
    std::vector<std::vector<FragmentListEntry>> rows(std::size_t(out.height_));
    FragmentListConsumer consumer{&rows};
    RasterOptions ro;
    ro.progress = progress;
    rasterize<Coverage::Center>(frame, mesh, ro, consumer);

    // Sort every row by (column, depth, triangle): a total order, whatever the tiling.
    parallelFor(0, out.height_, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            std::sort(rows[std::size_t(y)].begin(), rows[std::size_t(y)].end(),
                      [](const FragmentListEntry& a, const FragmentListEntry& b) {
                          if (a.x != b.x) return a.x < b.x;
                          if (a.f.depth != b.f.depth) return a.f.depth < b.f.depth;
                          return a.f.triangle < b.f.triangle;
                      });
    });
    out.offsets_.assign(std::size_t(out.width_ * out.height_ + 1), 0);
    for (int64_t y = 0; y < out.height_; ++y)
        for (const FragmentListEntry& e : rows[std::size_t(y)])
            ++out.offsets_[std::size_t(y * out.width_ + e.x + 1)];
    for (std::size_t c = 1; c < out.offsets_.size(); ++c) out.offsets_[c] += out.offsets_[c - 1];
    out.fragments_.resize(std::size_t(out.offsets_.back()));
    parallelFor(0, out.height_, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y) {
            const auto& row = rows[std::size_t(y)];
            if (row.empty()) continue;
            ListFragment* dst = out.fragments_.data() + out.offsets_[std::size_t(y * out.width_)];
            for (const FragmentListEntry& e : row) *dst++ = e.f;
        }
    });
    return out;
}

int64_t FragmentLists::maxPerColumn() const {
    int64_t m = 0;
    for (std::size_t c = 0; c + 1 < offsets_.size(); ++c) m = std::max(m, offsets_[c + 1] - offsets_[c]);
    return m;
}

} // namespace voxfx
