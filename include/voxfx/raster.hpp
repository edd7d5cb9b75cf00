// voxfx — the one fragment rasterizer (DESIGN.md: "fragments over columns").
//
// Triangles are rasterized over the W x H columns of a Frame; each column receives fragments,
// which a *consumer* turns into bits, counts, lists or pixels. Two coverage rules:
//
//   Coverage::Center        a column gets a fragment when its centre (x + 0.5, y + 0.5) lies inside
//                           the projected triangle. Strict tie rule: the sample point is treated as
//                           perturbed by (+eps, +eps^2), and every edge function is evaluated on the
//                           edge's canonical (lexicographically ordered) endpoints, so a centre on a
//                           shared edge or vertex belongs to exactly one triangle of a closed mesh,
//                           bit-for-bit, and triangles parallel to the view cover no centre. This is
//                           what makes parity exact. Fragment depth: the triangle's depth at the
//                           centre.
//   Coverage::Conservative  a column gets a span when the triangle touches its closed footprint
//                           [x, x+1] x [y, y+1]; the span is the depth interval of the triangle
//                           clipped to the column's prism, so a cell [s, s+1] of the column overlaps
//                           the triangle iff it overlaps the span. Boundaries are widened by
//                           kConservativeSlack (1e-9 cell) so that touching contacts survive the
//                           rounding of clipping. Triangles parallel to the view direction are
//                           handled (they clip to segments).
//
// Work is split into tiles of whole rows; every triangle is binned to the tiles its rows touch
// (count, allocate, fill — in triangle order), and each tile is rasterized by one thread that owns
// its rows, so consumers write without atomics and results do not depend on the thread count.
//
// Consumer interface (duck-typed, see voxelize/*.cpp for examples):
//   TileConsumer consumer.tile(int64_t y0, int64_t y1);        // one per tile, rows [y0, y1)
//   void TileConsumer::fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool front);
//   void TileConsumer::span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t triangle);
//   void TileConsumer::finish();                               // after the tile's last triangle
// A consumer whose writes commute (bit OR, bit XOR) may also offer the direct path:
//   DirectSink consumer.direct();        // fragment/span as above, callable from any thread
//   void consumer.finishRows(y0, y1);    // after every triangle, per tile of rows, in parallel
// rasterize() then skips binning when triangles are much smaller than a column (a dense mesh):
// fixed chunks of triangles go to any thread and write with atomic word operations. The bits
// are the same on both paths and for any thread count.
// Depths are frame depths (orthographic: slice units; perspective: view distance); map them to
// slices with Frame::depthToSlice(column). `front` is true when the triangle's counter-clockwise
// side faces the frame's viewer (its outward normal points against the view direction).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

enum class Coverage : uint8_t { Center, Conservative };

/// The parallel scheme, for consumers that offer the direct path (see above); the bits are the
/// same either way. Auto picks direct for dense meshes. For tests and benchmarks.
enum class RasterPath : uint8_t { Auto, Binned, Direct };

struct RasterOptions {
    Coverage coverage = Coverage::Center;
    RasterPath path = RasterPath::Auto;
    /// Rows per tile; 0 picks about 64 tiles (at least one row each).
    int64_t rowsPerTile = 0;
    /// Polled between tiles; returning false cancels with voxfx::Error. Not owned.
    Progress* progress = nullptr;
};

namespace detail {

/// A triangle set up for rasterization in grid space: (gx, gy, w) per corner, where w is the
/// frame depth (orthographic) or 1 / view depth (perspective), both affine over the image plane.
struct RasterTriangle {
    double x[3], y[3], w[3];
    uint32_t index;
    bool front;
};

/// Calls emit(rasterTriangle) for the pieces of mesh triangle t in `frame`'s grid space (one for
/// orthographic frames; perspective frames clip at a plane just in front of the eye, giving 0–2).
/// `gridVertices` holds Frame-space vertex positions from prepareVertices.
struct RasterSetup {
    const Frame* frame;
    const MeshView* mesh;
    std::vector<Vec3d> vertices; // orthographic: grid coordinates; perspective: camera (right, up, forward)
    double clipDepth = 0;
    template <class Emit> void triangle(std::size_t t, Emit&& emit) const;
};
RasterSetup prepareVertices(const Frame& frame, const MeshView& mesh);

/// Row range [first, last] of the triangle's coverage, clamped to [0, H); empty when last < first.
void coveredRows(const RasterTriangle& tri, Coverage coverage, int64_t height, int64_t& first, int64_t& last);

/// Emits the centre-sampled fragments of `tri` in rows [rowBegin, rowEnd).
template <class Sink>
void rasterizeCenter(const RasterTriangle& tri, bool perspective, int64_t width, int64_t rowBegin,
                     int64_t rowEnd, Sink& sink);
/// Emits the conservative spans of `tri` in rows [rowBegin, rowEnd).
template <class Sink>
void rasterizeConservative(const RasterTriangle& tri, bool perspective, int64_t width, int64_t rowBegin,
                           int64_t rowEnd, Sink& sink);

/// Tiling and binning: triangles (in index order) per tile of `rowsPerTile` rows.
struct TileBins {
    int64_t rowsPerTile = 1;
    int64_t tileCount = 0;
    std::vector<int64_t> offsets;  // tileCount + 1
    std::vector<uint32_t> entries; // indices into `pieces`
    std::vector<RasterTriangle> pieces;
};
TileBins binTriangles(const RasterSetup& setup, Coverage coverage, int64_t rowsPerTile);

} // namespace detail

/// Rasterizes `mesh` over `frame`'s columns and hands fragments or spans to `consumer`, tile by
/// tile in parallel. See the file comment for the consumer interface. Mesh must be valid
/// (validateMesh); triangles outside the frame's columns are skipped.
template <class Consumer>
void rasterize(const Frame& frame, const MeshView& mesh, const RasterOptions& options, Consumer& consumer);

} // namespace voxfx

#include "voxfx/raster_impl.hpp"
