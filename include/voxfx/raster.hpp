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
// Consumer contract (C++20 concepts below, checked at compile time):
//   TileConsumer    sink = consumer.tile(const Tile&)    one sink per tile (index, rows [y0, y1))
//                   sink.finish()                         after the tile's last triangle
//   CenterSink      sink.fragment(x, y, depth, triangle, front)          for Coverage::Center
//   ConservativeSink sink.span(x, y, depthMin, depthMax, triangle)       for Coverage::Conservative
//   QuadSink (optional, with CenterSink) sink.fragments(x, y, depth, bits, triangle, front): the
//                   covered samples among (x + k, y), k < 4 (bit k of `bits`, at least one), their
//                   depths depth[k], in one call: the fragments fragment() would get one by one
//                   (the same depths), for a sink that merges four neighbours in vector registers
//                   (the G-buffer's depth test). The rasterizer may call either for any sample.
// A sink needs at least one of fragment/span. rasterize<Coverage::X>(...) checks the one it needs
// at compile time (static_assert); plain rasterize(...) with a run-time coverage throws
// voxfx::Error when the sink lacks the member for it (never silently emits nothing).
// A consumer whose writes commute (bit OR, bit XOR) may also offer the direct path:
//   DirectConsumer  sink = consumer.direct()    fragment/span as above, callable from any thread
//                   consumer.finishRows(tile)   after every triangle, per tile of rows, in parallel
// rasterize() then skips binning when triangles are much smaller than a column (a dense mesh):
// fixed chunks of triangles go to any thread and write with atomic word operations. The bits
// are the same on both paths and for any thread count.
// Depths are frame depths (orthographic: slice units; perspective: view distance); map them to
// slices with FrameView::depthToSlice(column). `front` is true when the triangle's
// counter-clockwise side faces the frame's viewer (its outward normal points against the view
// direction).
//
// Kernels: the per-triangle functions (edge functions, rasterizeCenter, rasterizeConservative,
// clipping) take plain values and a FrameView, allocate nothing, throw nothing and are marked
// VOXFX_HOSTDEV, so a CUDA back end can include this header and reuse them.
//
// Thread-safety: rasterize() may run concurrently with other rasterize() calls on different
// consumers (the frame and mesh are only read). Within one call, tile sinks run on several
// threads at once, each owning the rows of its tile; direct sinks run on any thread and must
// write atomically; finishRows runs in parallel over disjoint tiles. The consumer itself is
// shared by all of them: tile(), direct() and finishRows() must be safe to call concurrently.
#pragma once

#include <concepts>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/page_memory.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/types.hpp"

namespace voxfx {

const char* toString(Coverage c);
/// Parses center | conservative; throws voxfx::Error listing them otherwise.
Coverage parseCoverage(const std::string& name);

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
    /// Perspective frames: fragments along each column's whole line through the eye, not only in
    /// front of it, as orthographic frames have (what parity and winding need: GI08 §5's count is
    /// exact for an eye inside the solid too). Geometry behind the eye gives fragments of negative
    /// depth, in front of every slice; geometry at the eye is seen down to the clearance of
    /// clipDepthOf. Consumers that keep depths (near/far ranges, G-buffers) leave it off.
    bool fullLine = false;
};

/// The rows a tile covers: tile `index` of the frame's tiling holds rows [y0, y1).
struct Tile {
    int64_t index = 0;
    int64_t y0 = 0, y1 = 0;
};

template <class S>
concept CenterSink = requires(S& s, int64_t x, int64_t y, double depth, uint32_t triangle, bool front) {
    s.fragment(x, y, depth, triangle, front);
};
template <class S>
concept QuadSink = requires(S& s, int64_t x, int64_t y, const double* depth, unsigned bits, uint32_t triangle,
                            bool front) {
    s.fragments(x, y, depth, bits, triangle, front);
};
template <class S>
concept ConservativeSink = requires(S& s, int64_t x, int64_t y, double depth, uint32_t triangle) {
    s.span(x, y, depth, depth, triangle);
};
template <class S>
concept RasterSink = CenterSink<S> || ConservativeSink<S>;

template <class C>
concept TileConsumer = requires(C& c, const Tile& t) {
    requires RasterSink<decltype(c.tile(t))>;
    c.tile(t).finish();
};
template <class C>
concept DirectConsumer = requires(C& c, const Tile& t) {
    requires RasterSink<decltype(c.direct())>;
    c.finishRows(t);
};

/// Whether the sink type S has the member that `coverage` needs.
template <class S> constexpr bool sinkSupports(Coverage coverage) {
    return coverage == Coverage::Center ? CenterSink<S> : ConservativeSink<S>;
}

namespace detail {

/// A triangle set up for rasterization in grid space: (gx, gy, w) per corner, where w is the
/// frame depth (orthographic) or 1 / view depth (perspective), both affine over the image plane.
struct RasterTriangle {
    double x[3], y[3], w[3];
    uint32_t index;
    bool front;
};

/// Calls emit(rasterTriangle) for the pieces of mesh triangle t in the frame's grid space (one for
/// orthographic frames; perspective frames clip at a plane just in front of the eye, giving 0–2,
/// and with a full line at one just behind it too, 0-4).
/// `vertices` holds the vertices projected by the frame's Projection (prepareVertices).
struct RasterSetup {
    FrameView frame;
    const MeshView* mesh;
    PageVector<Vec3d> vertices; // orthographic: grid coordinates; perspective: camera (right, up, forward)
    double clipDepth = 0;
    template <class Emit> void triangle(std::size_t t, Emit&& emit) const;
};
/// The set-up of rasterize(): vertices projected, clipDepthOf(frame, mesh, fullLine).
RasterSetup prepareVertices(const Frame& frame, const MeshView& mesh, bool fullLine = false);

/// The camera depth at which a perspective frame's set-up clips triangles, just in front of the
/// eye (geometry between it and the near plane still counts: depth clamping); 0 for orthographic
/// frames. One definition for the CPU's set-up and the CUDA back end's.
inline double clipDepthOf(const Frame& frame) {
    return frame.isPerspective() ? frame.nearDepth() * 1e-3 : 0.0;
}

/// The same for `mesh`, and with `fullLine` (RasterOptions::fullLine) the negative of a clearance
/// c: pieces at depth >= c and <= -c are rasterized. c is 1e-3 near unless the mesh comes closer
/// to the eye: then half the distance from the eye to the nearest triangle's bounding box over
/// sqrt(1 + tanX^2 + tanY^2), so that no point of the mesh on any column's line lies within c of
/// the eye plane; at least 1e-9 near (a mesh through the eye itself is not resolved). Cost:
/// O(triangles), parallel, deterministic.
double clipDepthOf(const Frame& frame, const MeshView& mesh, bool fullLine);

/// Calls emit(rasterTriangle) for the pieces of the triangle with projected corners a, b, c
/// (projectVertex): what RasterSetup::triangle does, as a kernel that a GPU back end shares.
/// Perspective: the part at camera depth >= |clipDepth| (0-2 pieces) and, when clipDepth < 0,
/// the part at depth <= clipDepth (0-2 more: fragments of negative depth).
template <class Emit>
VOXFX_HOSTDEV void setupTriangle(const Projection& projection, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                                 uint32_t index, double clipDepth, Emit&& emit);
/// The vertex transform of prepareVertices for one vertex.
VOXFX_HOSTDEV inline Vec3d projectVertex(const Projection& projection, const Vec3d& p);

/// Row range [first, last] of the triangle's coverage, clamped to [0, H); empty when last < first.
VOXFX_HOSTDEV inline void coveredRows(const RasterTriangle& tri, Coverage coverage, int64_t height,
                                      int64_t& first, int64_t& last);

/// Emits the centre-sampled fragments of `tri` in rows [rowBegin, rowEnd) and columns
/// [colBegin, colEnd) of `frame` (the columns clamped to the frame: the default is all of them).
/// A window emits exactly the fragments of the whole frame that fall in it, bit for bit.
template <class Sink>
VOXFX_HOSTDEV void rasterizeCenter(const RasterTriangle& tri, const FrameView& frame, int64_t rowBegin,
                                   int64_t rowEnd, Sink& sink, int64_t colBegin = 0,
                                   int64_t colEnd = INT64_MAX);
/// Emits the conservative spans of `tri` in rows [rowBegin, rowEnd) and columns [colBegin, colEnd)
/// of `frame`, as rasterizeCenter.
template <class Sink>
VOXFX_HOSTDEV void rasterizeConservative(const RasterTriangle& tri, const FrameView& frame, int64_t rowBegin,
                                         int64_t rowEnd, Sink& sink, int64_t colBegin = 0,
                                         int64_t colEnd = INT64_MAX);

/// Tiling and binning: triangles (in index order) per tile of `rowsPerTile` rows and
/// `colsPerTile` columns (0: the whole width, one tile per band of rows). Tile (row r, column c)
/// has index r * tileColumns + c. A triangle goes to every tile whose rows and columns, grown by
/// `grow` on each side, its coverage may reach.
struct TileBins {
    int64_t rowsPerTile = 1, colsPerTile = 1;
    int64_t tileColumns = 1;
    int64_t tileCount = 0;
    PageVector<int64_t> offsets;  // tileCount + 1
    PageVector<uint32_t> entries; // triangle indices
};
/// `counted`, when given, receives the number of entries after they are counted and before they
/// are allocated (it may throw, for a memory check).
TileBins binTriangles(const RasterSetup& setup, Coverage coverage, int64_t rowsPerTile,
                      int64_t colsPerTile = 0, int64_t grow = 0,
                      const std::function<void(int64_t entries)>& counted = {});

/// Gives the set-up's and the bins' memory back for the next call's (no page faults there);
/// they are left empty. `bins` may be null.
void recycle(RasterSetup& setup, TileBins* bins);

} // namespace detail

/// Rasterizes `mesh` over `frame`'s columns and hands fragments or spans to `consumer`, tile by
/// tile in parallel. See the file comment for the consumer contract. Mesh must be valid
/// (validateMesh); triangles outside the frame's columns are skipped. Throws voxfx::Error when the
/// consumer's sinks lack the member options.coverage needs, or when progress cancels.
template <TileConsumer Consumer>
void rasterize(const Frame& frame, const MeshView& mesh, const RasterOptions& options, Consumer& consumer);

/// The same with the coverage fixed at compile time: a consumer without the member it needs
/// does not compile. options.coverage is ignored.
template <Coverage C, TileConsumer Consumer>
void rasterize(const Frame& frame, const MeshView& mesh, const RasterOptions& options, Consumer& consumer);

} // namespace voxfx

#include "voxfx/raster_impl.hpp"
