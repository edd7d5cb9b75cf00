// voxfx — fragment lists: every centre-sampled fragment of the one rasterizer, kept per column and
// sorted by depth (Bornik et al. §3: "rasterize all boundary polygons, keep every fragment").
//
// A consumer of rasterize<Coverage::Center>: each tile's sink appends its fragments to the rows it
// owns; afterwards every row is sorted by (column, depth, triangle) and packed into one array with
// per-column offsets. The order is a total order on the fragments, so the lists do not depend on
// the thread count or the tiling. Depths are frame depths (orthographic: slice units; perspective:
// view distance), `front` is the rasterizer's facing (the triangle's outward side faces the viewer:
// a ray entering a closed mesh crosses a front fragment, one leaving it a back fragment).
//
// Thread-safety: build uses worker threads; a built FragmentLists is read-only and may be read from
// any number of threads.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

/// One fragment of a column: depth along the column, the mesh triangle and its facing.
struct ListFragment {
    double depth = 0;
    uint32_t triangle = 0;
    bool front = false;
};

class FragmentLists {
public:
    /// Rasterizes `mesh` (centre sampling, validateMesh'd) over `frame`'s columns and keeps all
    /// fragments per column, sorted by depth (ties: lower triangle first). Throws voxfx::Error when
    /// `progress` cancels.
    static FragmentLists build(const Frame& frame, const MeshView& mesh, Progress* progress = nullptr);
    /// The same into this object, reusing its memory: lists rebuilt every frame of the same size
    /// allocate (and page-fault) nothing new.
    void rebuild(const Frame& frame, const MeshView& mesh, Progress* progress = nullptr);

    int64_t width() const { return width_; }
    int64_t height() const { return height_; }
    /// The fragments of column (x, y), nearest first.
    std::span<const ListFragment> column(int64_t x, int64_t y) const {
        const std::size_t c = std::size_t(y * width_ + x);
        return {fragments_.data() + offsets_[c], std::size_t(offsets_[c + 1] - offsets_[c])};
    }
    int64_t fragmentCount() const { return int64_t(fragments_.size()); }
    /// Largest number of fragments in one column.
    int64_t maxPerColumn() const;

private:
    /// A fragment while its row is gathered (16 bytes: the rows are written and read twice, and
    /// the lists run to millions of fragments): depth, triangle, and column x * 2 + front.
    struct RowEntry {
        double depth;
        uint32_t triangle;
        uint32_t columnFront;
        int64_t x() const { return int64_t(columnFront >> 1); }
        ListFragment fragment() const { return {depth, triangle, (columnFront & 1u) != 0}; }
    };
    std::vector<std::vector<RowEntry>> rows_; ///< scratch of rebuild: each row's fragments, unsorted
    int64_t width_ = 0, height_ = 0;
    std::vector<int64_t> offsets_; ///< columnCount + 1
    std::vector<ListFragment> fragments_;
};

} // namespace voxfx
