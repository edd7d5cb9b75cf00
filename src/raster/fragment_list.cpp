// voxfx — fragment lists: a consumer of the one rasterizer that keeps every centre-sampled
// fragment, then sorts each column by depth (see voxfx/fragment_list.hpp).
#include "voxfx/fragment_list.hpp"

#include <algorithm>

#include "voxfx/error.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {

namespace {

// The lists' order: depth, then triangle (a total order: a triangle has one fragment per column).
bool before(const ListFragment& u, const ListFragment& v) {
    return u.depth != v.depth ? u.depth < v.depth : u.triangle < v.triangle;
}

// Sorts one column. Most hold a few fragments, which an insertion sort orders without std::sort's
// dispatch; the order is total, so any sort gives the same column.
void sortColumn(ListFragment* b, ListFragment* e) {
    if (e - b < 2) return;
    if (e - b > 16) {
        std::sort(b, e, before);
        return;
    }
    for (ListFragment* i = b + 1; i < e; ++i) {
        const ListFragment v = *i;
        ListFragment* j = i;
        for (; j > b && before(v, j[-1]); --j) *j = j[-1];
        *j = v;
    }
}

// Each tile owns its rows: sinks append to the row vectors of their tile without locks.
template <class Entry> struct FragmentListConsumer {
    std::vector<std::vector<Entry>>* rows;
    struct Sink {
        std::vector<std::vector<Entry>>* rows;
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool front) {
            (*rows)[std::size_t(y)].push_back({depth, triangle, uint32_t(x) << 1 | uint32_t(front)});
        }
        void finish() {}
    };
    Sink tile(const Tile&) const { return {rows}; }
};

} // namespace

FragmentLists FragmentLists::build(const Frame& frame, const MeshView& mesh, Progress* progress) {
    FragmentLists out;
    out.rebuild(frame, mesh, progress);
    out.rows_ = {};
    return out;
}

void FragmentLists::rebuild(const Frame& frame, const MeshView& mesh, Progress* progress) {
    // A row entry keeps the column in 31 bits (RowEntry::columnFront).
    if (frame.width() >= int64_t(1) << 31) throw Error("FragmentLists: the frame is too wide");
    width_ = frame.width();
    height_ = frame.height();
    std::vector<std::vector<RowEntry>>& rows = rows_;
    rows.resize(std::size_t(height_));
    for (auto& row : rows) row.clear();
    FragmentListConsumer<RowEntry> consumer{&rows};
    RasterOptions ro;
    ro.progress = progress;
    rasterize<Coverage::Center>(frame, mesh, ro, consumer);

    // Pack the rows in order, then each row's fragments by column (a counting sort, in place of
    // sorting the row) and each column by (depth, triangle): a total order, whatever the tiling.
    const std::size_t W = std::size_t(width_);
    if (W == 0 || height_ == 0) {
        offsets_.assign(1, 0);
        fragments_.clear();
        return;
    }
    offsets_.resize(W * std::size_t(height_) + 1);
    int64_t total = 0;
    for (int64_t y = 0; y < height_; ++y) {
        offsets_[std::size_t(y) * W] = total;
        total += int64_t(rows[std::size_t(y)].size());
    }
    offsets_.back() = total;
    fragments_.resize(std::size_t(total));
    parallelFor(0, height_, 8, [&](int64_t y0, int64_t y1) {
        std::vector<int64_t> cursor(W);
        for (int64_t y = y0; y < y1; ++y) {
            const auto& row = rows[std::size_t(y)];
            // off[0]: the row's start; off[W]: the next row's (the end), neither written here.
            int64_t* off = offsets_.data() + std::size_t(y) * W;
            if (row.empty()) { // every column empty: each starts where the row does
                std::fill(off + 1, off + W, off[0]);
                continue;
            }
            std::fill(off + 1, off + W, int64_t(0));
            for (const RowEntry& e : row)
                if (e.x() + 1 < int64_t(W)) ++off[e.x() + 1];
            for (std::size_t c = 1; c < W; ++c) off[c] += off[c - 1];
            std::copy(off, off + W, cursor.begin());
            for (const RowEntry& e : row)
                fragments_[std::size_t(cursor[std::size_t(e.x())]++)] = e.fragment();
            // Every column's end is the next one's start (the last's: off[W]), which the cursors
            // now hold.
            for (std::size_t c = 0; c < W; ++c)
                sortColumn(fragments_.data() + off[c], fragments_.data() + cursor[c]);
        }
    });
}

int64_t FragmentLists::maxPerColumn() const {
    int64_t m = 0;
    for (std::size_t c = 0; c + 1 < offsets_.size(); ++c) m = std::max(m, offsets_[c + 1] - offsets_[c]);
    return m;
}

} // namespace voxfx
