// voxfx — ED06 §3.3 frosted glass. Glass method "frosted" (voxfx/glass.hpp).
//
// The glass's front faces and back faces (seen from the eye) are voxelized into two slicemaps in a
// camera-aligned perspective frame (gridResolution columns across, as many slices) with ED06's
// local slicing: each column's slices span only the glass's depth range in that column (its
// nearest and farthest fragment, front or back), one range shared by both slicemaps (ED06's
// "coherence" of the two maps). Each column is walked front to back once, at construction, into
// inside intervals: a front-only cell enters, a back-only cell leaves (a front face met inside or a
// back face met outside is ignored); a cell holding both (ambiguous) is resolved by the next
// non-empty cell: a front-only cell means the ray is outside after it, a back-only cell that it is
// inside, another ambiguous cell that it is inside (ED06 fig. 9: two ambiguous cells in a row
// count as inside); none, outside. Faces sit at their cell's middle, except the column's first
// and last fragments, which local slicing puts exactly on its ends; an ambiguous cell crossed from
// outside to outside is a sliver of a third of a cell. The thickness at a pixel is the length of
// the intervals its surface starts (those ending behind it), interpolated bilinearly over the four
// nearest columns (columns with no glass there left out), so it varies smoothly across a column.
// The thickness L scales the refraction's perturbation of the environment lookup (ED06: the
// refraction offset grows with the volume crossed), attenuates by exp(-sigma L) and sets the blur
// cone (a lookup into the environment's pre-filtered pyramid).
//
// Thread-safety: read-only after construction; trace may run from any number of threads.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/glass_options.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"

namespace voxfx {

struct GlassInput;

namespace detail {
/// ED06 fig. 9 on one column of the front and back slicemaps (wordsPerColumn words each, D
/// slices): appends its inside intervals, pairs of (start, end) slice coordinates in depth order, to
/// `out` (see the file comment for the rules).
void frostedColumnIntervals(const uint64_t* front, const uint64_t* back, int64_t wordsPerColumn, int64_t D,
                            std::vector<double>& out);
} // namespace detail

class FrostedGlass {
public:
    using Options = FrostedGlassOptions;
    /// `camera`: the view's perspective frame (the G-buffer's). Throws voxfx::Error for an
    /// orthographic camera, mismatched sizes, a resolution outside 2..4096 or glass behind the eye.
    FrostedGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium, std::vector<GlassMedium> media,
                 const Frame& camera, const FrostedGlassOptions& options);
    static FrostedGlass build(const GlassInput& input, const FrostedGlassOptions& options);
    /// View-depth length of the inside intervals of column (x, y) that end behind `fromDepth` (whole
    /// intervals: one that holds fromDepth counts from its start). 0 outside the grid.
    double columnThickness(int64_t x, int64_t y, double fromDepth) const;
    /// World length the eye ray through surface point p crosses inside the glass from p on: the
    /// columns' thickness interpolated bilinearly at p (see the file comment), converted from view
    /// depth to length along the ray. `normal` (any side; zero: none) predicts the surface's depth
    /// in the neighbouring columns, so a slanted surface's own intervals count there.
    double thickness(const Vec3d& p, const Vec3d& normal = {}) const;
    GlassPath trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir) const;
    GlassPath trace(const GlassHit& h) const { return trace(h.entry, h.normal, h.medium, h.dir); }
    const BitGrid& front() const { return front_; }
    const BitGrid& back() const { return back_; }
    const Frame& frame() const { return frame_; }

private:
    Frame frame_;
    BitGrid front_, back_;
    std::vector<GlassMedium> media_;
    /// Inside intervals of column c in depth order: (start, end) view depths spans_[2k], spans_[2k + 1]
    /// for k from spanStart_[c] up to spanStart_[c + 1].
    std::vector<double> spans_;
    std::vector<uint32_t> spanStart_;
    double diagonal_ = 1;
    double blur_ = FrostedGlassOptions{}.blur;
    double refraction_ = FrostedGlassOptions{}.refraction;
};

} // namespace voxfx
