// voxfx — template part of the rasterizer (included by raster.hpp; not a public entry point).
#pragma once

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <mutex>

#include "voxfx/raster.hpp"

namespace voxfx::detail {

/// The pieces of a perspective triangle (camera coordinates `in`) on one side of the eye: the part
/// with side * depth >= clip (side +1: in front of the eye; -1: behind it), fanned into
/// triangles and projected onto the image plane through the eye. An edge's clip point is
/// interpolated from its kept end towards the other, so the two triangles sharing the edge get
/// it bit for bit (no crack and no double count along the seam).
template <class Emit>
VOXFX_HOSTDEV void emitPerspectivePieces(const Projection& pr, const Vec3d* in, uint32_t index, double clip,
                                         double side, Emit& emit) {
    Vec3d poly[4];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
        const Vec3d& p = in[k];
        const Vec3d& q = in[(k + 1) % 3];
        const bool pin = side * p.z >= clip, qin = side * q.z >= clip;
        if (pin) poly[n++] = p;
        if (pin != qin) {
            const Vec3d& kept = pin ? p : q;
            const Vec3d& cut = pin ? q : p;
            const double s = (side * clip - kept.z) / (cut.z - kept.z);
            Vec3d x = kept + (cut - kept) * s;
            x.z = side * clip;
            poly[n++] = x;
        }
    }
    if (n < 3) return;
    double gx[4], gy[4], gw[4];
    for (int k = 0; k < n; ++k) {
        gx[k] = pr.imageX(poly[k].x, poly[k].z);
        gy[k] = pr.imageY(poly[k].y, poly[k].z);
        gw[k] = 1.0 / poly[k].z;
    }
    for (int k = 1; k + 1 < n; ++k) {
        RasterTriangle r{
            {gx[0], gx[k], gx[k + 1]}, {gy[0], gy[k], gy[k + 1]}, {gw[0], gw[k], gw[k + 1]}, index, false};
        // The camera basis (right, up, forward) is left-handed, so the facing test flips. Behind
        // the eye the projection reverses the image's orientation and the line's direction
        // alike: `front` still means the normal points against the column's direction.
        const double det = (r.x[1] - r.x[0]) * (r.y[2] - r.y[0]) - (r.x[2] - r.x[0]) * (r.y[1] - r.y[0]);
        r.front = det > 0;
        emit(r);
    }
}

template <class Emit>
VOXFX_HOSTDEV void setupTriangle(const Projection& pr, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                                 uint32_t index, double clipDepth, Emit&& emit) {
    if (!pr.perspective) {
        RasterTriangle r{{a.x, b.x, c.x}, {a.y, b.y, c.y}, {a.z, b.z, c.z}, index, false};
        const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        r.front = det < 0; // outward normal points against +depth, towards the viewer
        emit(r);
        return;
    }
    // Perspective: clip in camera space against depth >= |clipDepth| (geometry between the eye
    // and the near plane still counts: depth clamping), then project the pieces; a negative
    // clipDepth adds the pieces at depth <= clipDepth, behind the eye (see clipDepthOf).
    const Vec3d in[3] = {a, b, c};
    const double clip = clipDepth < 0 ? -clipDepth : clipDepth;
    emitPerspectivePieces(pr, in, index, clip, 1.0, emit);
    if (clipDepth < 0) emitPerspectivePieces(pr, in, index, clip, -1.0, emit);
}

template <class Emit> void RasterSetup::triangle(std::size_t t, Emit&& emit) const {
    setupTriangle(frame.projection, vertices[mesh->index(t, 0)], vertices[mesh->index(t, 1)],
                  vertices[mesh->index(t, 2)], uint32_t(t), clipDepth, emit);
}

/// The vertex transform of prepareVertices for one vertex: grid coordinates (orthographic; a vertex
/// on a side of the box lands on it exactly, Projection::gridFromVertex) or camera coordinates
/// (perspective).
VOXFX_HOSTDEV inline Vec3d projectVertex(const Projection& pr, const Vec3d& p) {
    return pr.perspective ? pr.cameraFromWorld(p) : pr.gridFromVertex(p);
}

/// One edge of a triangle, stored with its endpoints in canonical (lexicographic) order so that
/// the two triangles sharing it evaluate bit-identical edge functions.
struct CanonicalEdge {
    double ax, ay, dx, dy;
    int flip; // +1 when the triangle traverses the edge a -> b, -1 when b -> a
    int tie;  // sign of the edge function at a sample on the edge, perturbed by (+eps, +eps^2)

    VOXFX_HOSTDEV void set(double px, double py, double qx, double qy) {
        const bool swap = qx < px || (qx == px && qy < py);
        ax = swap ? qx : px;
        ay = swap ? qy : py;
        dx = (swap ? px : qx) - ax;
        dy = (swap ? py : qy) - ay;
        flip = swap ? -1 : 1;
        // E(s + (eps, eps^2)) = E(s) - dy * eps + dx * eps^2: the first non-zero term decides.
        tie = dy != 0 ? (dy < 0 ? 1 : -1) : (dx > 0 ? 1 : -1);
    }
    /// Sign (+1 / -1, never 0) of the oriented edge function at sample (sx, sy).
    VOXFX_HOSTDEV int side(double sx, double sy) const {
        const double e = dx * (sy - ay) - dy * (sx - ax);
        const int s = e > 0 ? 1 : (e < 0 ? -1 : tie);
        return s * flip;
    }
};

#if !defined(__CUDACC__) && defined(__GNUC__)
/// Four doubles / four 64-bit lane masks (GCC vector extensions) for rasterizeCenter's rows.
using V4d = double __attribute__((vector_size(32)));
using V4l = int64_t __attribute__((vector_size(32)));
#endif

template <class Sink>
VOXFX_HOSTDEV void rasterizeCenter(const RasterTriangle& t, const FrameView& frame, int64_t rowBegin,
                                   int64_t rowEnd, Sink& sink, int64_t colBegin, int64_t colEnd) {
    const bool perspective = frame.isPerspective();
    const int64_t width = std::min(frame.width, colEnd);
    // Columns whose centre lies in the bounding box. The box corners are vertex coordinates and
    // x - 0.5 is exact for grid-sized values, so the range is exact: no margin needed.
    const double bxlo = std::min({t.x[0], t.x[1], t.x[2]}), bxhi = std::max({t.x[0], t.x[1], t.x[2]});
    if (!(bxhi >= double(colBegin) + 0.5 && bxlo <= double(width) - 0.5)) return;
    const int64_t bx0 = std::max<int64_t>(colBegin, int64_t(std::ceil(bxlo - 0.5)));
    const int64_t bx1 = std::min<int64_t>(width - 1, int64_t(std::floor(bxhi - 0.5)));
    if (bx0 > bx1) return;

    CanonicalEdge edges[3];
    for (int k = 0; k < 3; ++k) edges[k].set(t.x[k], t.y[k], t.x[(k + 1) % 3], t.y[(k + 1) % 3]);
    // Orientation from the first edge's function at the opposite corner (same arithmetic as the
    // sample test); a triangle seen edge-on covers no centre.
    const double e0 = edges[0].dx * (t.y[2] - edges[0].ay) - edges[0].dy * (t.x[2] - edges[0].ax);
    if (e0 == 0) return;
    const int orient = (e0 > 0 ? 1 : -1) * edges[0].flip;
    // Depth plane w(x, y) = w0 + gx (x - x0) + gy (y - y0).
    const double ux = t.x[1] - t.x[0], uy = t.y[1] - t.y[0], vx = t.x[2] - t.x[0], vy = t.y[2] - t.y[0];
    const double det = ux * vy - vx * uy;
    if (det == 0) return;
    // The gradient (two divisions) is computed at the first covered sample: most triangles of a
    // dense mesh cover none.
    double gx = 0, gy = 0;
    bool havePlane = false;
    // Per edge: the factor that turns the canonical edge function into "positive = inside" (an
    // exact sign flip), and whether a sample exactly on the edge counts as inside (tie rule).
    double inward[3];
    bool tieInside[3];
    for (int k = 0; k < 3; ++k) {
        inward[k] = double(edges[k].flip * orient);
        tieInside[k] = edges[k].tie * edges[k].flip * orient > 0;
    }
    // Narrow triangles (the common case on real meshes) test every column of the box; wide ones
    // first narrow each row to the span between its edge crossings.
    const bool narrow = bx1 - bx0 < 8;

    for (int64_t y = rowBegin; y < rowEnd; ++y) {
        const double sy = double(y) + 0.5;
        int64_t xb = bx0, xe = bx1;
        if (!narrow) {
            double xmin = INFINITY, xmax = -INFINITY;
            for (int k = 0; k < 3; ++k) {
                const double y0 = t.y[k], y1 = t.y[(k + 1) % 3];
                if ((sy < y0 && sy < y1) || (sy > y0 && sy > y1)) continue;
                const double x0 = t.x[k], x1 = t.x[(k + 1) % 3];
                const double xc = y1 == y0 ? x0 : x0 + (sy - y0) * (x1 - x0) / (y1 - y0);
                const double xd = y1 == y0 ? x1 : xc;
                xmin = std::min({xmin, xc, xd});
                xmax = std::max({xmax, xc, xd});
            }
            if (!(xmin <= xmax)) continue;
            xb = std::max<int64_t>(xb, int64_t(std::floor(xmin - 0.5)));
            xe = std::min<int64_t>(xe, int64_t(std::ceil(xmax - 0.5)));
        }
        // The row term of each edge function, dx * (sy - ay): evaluated exactly as in
        // CanonicalEdge::side, so shared edges still agree bit for bit.
        const double rowTerm[3] = {edges[0].dx * (sy - edges[0].ay), edges[1].dx * (sy - edges[1].ay),
                                   edges[2].dx * (sy - edges[2].ay)};
        // The depth's row part, t.w[0] + gy (sy - y0), once per row: the sum below is evaluated
        // left to right, so the fragment's depth is the same double as summed in one expression.
        double rowW = 0;
        bool haveRowW = false;
        auto prepareRow = [&] {
            if (haveRowW) return;
            if (!havePlane) {
                const double uw = t.w[1] - t.w[0], vw = t.w[2] - t.w[0];
                gx = (uw * vy - vw * uy) / det;
                gy = (ux * vw - vx * uw) / det;
                havePlane = true;
            }
            rowW = t.w[0] + gy * (sy - t.y[0]);
            haveRowW = true;
        };
        auto emit = [&](int64_t x) {
            const double sx = double(x) + 0.5;
            prepareRow();
            const double w = rowW + gx * (sx - t.x[0]);
            sink.fragment(x, y, perspective ? 1.0 / w : w, t.index, t.front);
        };
        int64_t x = xb;
#if !defined(__CUDACC__) && defined(__GNUC__)
        // Four samples at a time (GCC vector extensions, one AVX2 register): each lane evaluates
        // the edge functions with the scalar loop's operations in the same order (no contraction:
        // -ffp-contract=off), so the covered samples are the same bit for bit; lanes past the
        // row's end are masked off and fragments go out in increasing x.
        for (; x <= xe; x += 4) {
            const V4d sx = V4d{0.5, 1.5, 2.5, 3.5} + double(x);
            V4l inside = V4l{0, 1, 2, 3} + x <= xe;
            for (int k = 0; k < 3; ++k) {
                const V4d e = (rowTerm[k] - edges[k].dy * (sx - edges[k].ax)) * inward[k];
                inside &= (e > 0) | ((e == 0) & (tieInside[k] ? V4l{-1, -1, -1, -1} : V4l{0, 0, 0, 0}));
            }
#ifdef __AVX__
            // The covered lanes as bits (the sign bit of each all-ones lane), lowest first.
            unsigned bits = unsigned(__builtin_ia32_movmskpd256(V4d(inside)));
            if (bits == 0) continue;
            if constexpr (QuadSink<Sink>) {
                // The four lanes' depths as below (a lane's are emit's operations), in one call.
                prepareRow();
                const V4d w = rowW + gx * (sx - t.x[0]);
                const V4d depth = perspective ? 1.0 / w : w;
                double lanes[4];
                for (int lane = 0; lane < 4; ++lane) lanes[lane] = depth[lane];
                sink.fragments(x, y, lanes, bits, t.index, t.front);
                continue;
            }
            if (bits & (bits - 1)) {
                // Two or more: their depths in one vector division, lane for lane emit's
                // operations (sx is exact either way: x + 0.5 + k for a grid-sized x).
                prepareRow();
                const V4d w = rowW + gx * (sx - t.x[0]);
                const V4d depth = perspective ? 1.0 / w : w;
                for (; bits != 0; bits &= bits - 1) {
                    const int lane = std::countr_zero(bits);
                    sink.fragment(x + lane, y, depth[lane], t.index, t.front);
                }
                continue;
            }
            emit(x + std::countr_zero(bits));
#else
            for (int lane = 0; lane < 4; ++lane)
                if (inside[lane]) emit(x + lane);
#endif
        }
#endif
        for (; x <= xe; ++x) {
            const double sx = double(x) + 0.5;
            bool inside = true;
            for (int k = 0; k < 3; ++k) {
                const double e = (rowTerm[k] - edges[k].dy * (sx - edges[k].ax)) * inward[k];
                inside &= (e > 0) | ((e == 0) & tieInside[k]);
            }
            if (inside) emit(x);
        }
    }
}

/// A convex polygon in grid space (x, y, w), as produced by clipping a triangle to column prisms.
struct ClipPolygon {
    static constexpr int kMax = 9;
    double x[kMax], y[kMax], w[kMax];
    int n = 0;
};

/// Sutherland–Hodgman against one closed half-plane: keeps coord(axis) >= c (keepAbove) or <= c.
/// Points on the line are kept, so polygons touching a boundary survive as points or segments.
VOXFX_HOSTDEV inline void clipAxis(const ClipPolygon& in, ClipPolygon& out, int axis, double c,
                                   bool keepAbove) {
    out.n = 0;
    const double* coord = axis == 0 ? in.x : in.y;
    for (int k = 0; k < in.n; ++k) {
        const int j = (k + 1) % in.n;
        const double pk = coord[k], pj = coord[j];
        const bool kin = keepAbove ? pk >= c : pk <= c;
        const bool jin = keepAbove ? pj >= c : pj <= c;
        if (kin) {
            out.x[out.n] = in.x[k];
            out.y[out.n] = in.y[k];
            out.w[out.n] = in.w[k];
            ++out.n;
        }
        if (kin != jin) {
            const double s = (c - pk) / (pj - pk);
            out.x[out.n] = axis == 0 ? c : in.x[k] + (in.x[j] - in.x[k]) * s;
            out.y[out.n] = axis == 1 ? c : in.y[k] + (in.y[j] - in.y[k]) * s;
            out.w[out.n] = in.w[k] + (in.w[j] - in.w[k]) * s;
            ++out.n;
        }
    }
}

/// Conservative coverage slack, in cells: clipping interpolates new vertices, and a triangle
/// that touches a cell boundary exactly (a face through cell corners) can land 1e-13 short of
/// it. Every boundary is moved out by this much, far above rounding and far below any distance
/// real geometry resolves, so touching cells are kept; only cells missed by less than 1e-9 of a
/// cell are added.
inline constexpr double kConservativeSlack = 1e-9;

/// Depth range [lo, hi] where the convex polygon's boundary meets the line X = c (empty:
/// lo > hi). Edges are interpolated at c; an edge lying on the line contributes both ends.
VOXFX_HOSTDEV inline void lineDepthRange(const ClipPolygon& p, double c, double& lo, double& hi) {
    lo = INFINITY;
    hi = -INFINITY;
    for (int k = 0; k < p.n; ++k) {
        const int j = k + 1 == p.n ? 0 : k + 1;
        const double ax = p.x[k], bx = p.x[j];
        if ((ax < c && bx < c) || (ax > c && bx > c)) continue;
        if (ax == bx) {
            lo = std::min({lo, p.w[k], p.w[j]});
            hi = std::max({hi, p.w[k], p.w[j]});
            continue;
        }
        const double w = p.w[k] + (p.w[j] - p.w[k]) * ((c - ax) / (bx - ax));
        lo = std::min(lo, w);
        hi = std::max(hi, w);
    }
}

VOXFX_HOSTDEV inline void coveredRows(const RasterTriangle& t, Coverage coverage, int64_t height,
                                      int64_t& first, int64_t& last) {
    const double lo = std::min({t.y[0], t.y[1], t.y[2]}), hi = std::max({t.y[0], t.y[1], t.y[2]});
    // Clamp in floating point first so that far-away triangles cannot overflow the conversion.
    const double h = double(height);
    if (coverage == Coverage::Center) {
        // Rows whose centre y + 0.5 lies in [lo, hi] (lo, hi are vertex coordinates; the
        // subtraction is exact for grid-sized values, so no margin is needed).
        first = int64_t(std::clamp(std::ceil(lo - 0.5), -1.0, h));
        last = int64_t(std::clamp(std::floor(hi - 0.5), -1.0, h));
    } else {
        // Rows whose closed extent [y, y + 1] meets [lo, hi].
        first = int64_t(std::clamp(std::ceil(lo - kConservativeSlack) - 1.0, -1.0, h));
        last = int64_t(std::clamp(std::floor(hi + kConservativeSlack), -1.0, h));
    }
    first = std::max<int64_t>(first, 0);
    last = std::min<int64_t>(last, height - 1);
}

template <class Sink>
VOXFX_HOSTDEV void rasterizeConservative(const RasterTriangle& t, const FrameView& frame, int64_t rowBegin,
                                         int64_t rowEnd, Sink& sink, int64_t colBegin, int64_t colEnd) {
    const bool perspective = frame.isPerspective();
    const int64_t width = std::min(frame.width, colEnd);
    // A triangle inside one column's prism, away from its sides by more than the slack (most
    // triangles of a dense mesh): clipping would keep it whole and no edge crosses the column's
    // sides, so the sweep below would give exactly its vertices' depth range in that one column.
    {
        const double xlo = std::min({t.x[0], t.x[1], t.x[2]}), xhi = std::max({t.x[0], t.x[1], t.x[2]});
        const double ylo = std::min({t.y[0], t.y[1], t.y[2]}), yhi = std::max({t.y[0], t.y[1], t.y[2]});
        const double cx = std::ceil(xlo - kConservativeSlack) - 1.0,
                     cy = std::ceil(ylo - kConservativeSlack) - 1.0;
        if (cx == std::floor(xhi + kConservativeSlack) && cy == std::floor(yhi + kConservativeSlack)) {
            if (cy >= double(rowBegin) && cy < double(rowEnd) && cx >= double(colBegin) &&
                cx < double(width)) {
                const double lo = std::min({t.w[0], t.w[1], t.w[2]}), hi = std::max({t.w[0], t.w[1], t.w[2]});
                if (perspective)
                    sink.span(int64_t(cx), int64_t(cy), 1.0 / hi, 1.0 / lo, t.index);
                else
                    sink.span(int64_t(cx), int64_t(cy), lo, hi, t.index);
            }
            return;
        }
    }
    ClipPolygon tri;
    for (int k = 0; k < 3; ++k) {
        tri.x[k] = t.x[k];
        tri.y[k] = t.y[k];
        tri.w[k] = t.w[k];
    }
    tri.n = 3;
    ClipPolygon tmp, row;
    for (int64_t y = rowBegin; y < rowEnd; ++y) {
        // The triangle's part in the row's strip (closed, widened by the slack).
        clipAxis(tri, tmp, 1, double(y) - kConservativeSlack, true);
        if (tmp.n == 0) continue;
        clipAxis(tmp, row, 1, double(y + 1) + kConservativeSlack, false);
        if (row.n == 0) continue;
        double xmin = row.x[0], xmax = row.x[0];
        for (int k = 1; k < row.n; ++k) {
            xmin = std::min(xmin, row.x[k]);
            xmax = std::max(xmax, row.x[k]);
        }
        const int64_t xb = std::max<int64_t>(colBegin, int64_t(std::ceil(xmin - kConservativeSlack)) - 1);
        const int64_t xe = std::min<int64_t>(width - 1, int64_t(std::floor(xmax + kConservativeSlack)));
        if (xb > xe) continue;
        // Sweep the columns: the polygon's depth range inside column x is attained where its
        // boundary crosses the lines X = x and X = x + 1, or at its vertices in between (vertices
        // within the slack of a line count on both sides).
        double leftLo, leftHi;
        lineDepthRange(row, double(xb), leftLo, leftHi);
        for (int64_t x = xb; x <= xe; ++x) {
            double rightLo, rightHi;
            lineDepthRange(row, double(x + 1), rightLo, rightHi);
            double lo = std::min(leftLo, rightLo), hi = std::max(leftHi, rightHi);
            const double cellLo = double(x) - kConservativeSlack, cellHi = double(x + 1) + kConservativeSlack;
            for (int k = 0; k < row.n; ++k)
                if (row.x[k] >= cellLo && row.x[k] <= cellHi) {
                    lo = std::min(lo, row.w[k]);
                    hi = std::max(hi, row.w[k]);
                }
            leftLo = rightLo;
            leftHi = rightHi;
            if (!(lo <= hi)) continue;
            // Perspective w is 1 / depth: the order of the bounds flips.
            if (perspective)
                sink.span(x, y, 1.0 / hi, 1.0 / lo, t.index);
            else
                sink.span(x, y, lo, hi, t.index);
        }
    }
}

} // namespace voxfx::detail

namespace voxfx {

namespace detail {

/// Rasterizes one piece over rows [y0, y1) (and columns [x0, x1)) of the frame with the options'
/// coverage rule (the caller has checked that the sink supports it).
template <class Sink>
VOXFX_HOSTDEV void rasterizePiece(const RasterTriangle& rt, Coverage coverage, const FrameView& frame,
                                  int64_t y0, int64_t y1, Sink& sink, int64_t x0 = 0,
                                  int64_t x1 = INT64_MAX) {
    int64_t first, last;
    coveredRows(rt, coverage, frame.height, first, last);
    first = std::max(first, y0);
    last = std::min(last, y1 - 1);
    if (first > last) return;
    if (coverage == Coverage::Center) {
        if constexpr (CenterSink<Sink>) rasterizeCenter(rt, frame, first, last + 1, sink, x0, x1);
    } else {
        if constexpr (ConservativeSink<Sink>) rasterizeConservative(rt, frame, first, last + 1, sink, x0, x1);
    }
}

/// Throws voxfx::Error when sink type S lacks the member `coverage` needs.
template <class S> void requireSinkSupports(Coverage coverage, const char* which) {
    if (!sinkSupports<S>(coverage))
        fail("rasterize: the consumer's ", which, " sink has no ",
             coverage == Coverage::Center ? "fragment() member, which Coverage::Center needs"
                                          : "span() member, which Coverage::Conservative needs");
}

/// Whether rasterize() takes the direct path for a consumer that offers it: only when triangles
/// are much smaller than a column (at least three per column), where setting each triangle up
/// once beats binning. Otherwise binning wins clearly: a tile's writes stay in its rows (cache)
/// and need no atomics (bench_voxelize, Binned/Direct rows: bunny00 solid 512^3 14 vs 25 ms,
/// bunny1m 73 vs 65 ms). Depends on the mesh and frame only, never on threads.
inline bool preferDirect(std::size_t triangles, int64_t width, int64_t height) {
    return int64_t(triangles) >= 3 * width * height;
}

} // namespace detail

template <TileConsumer Consumer>
void rasterize(const Frame& frame, const MeshView& mesh, const RasterOptions& options, Consumer& consumer) {
    detail::requireSinkSupports<decltype(consumer.tile(Tile{}))>(options.coverage, "tile");
    if constexpr (DirectConsumer<Consumer>)
        detail::requireSinkSupports<decltype(consumer.direct())>(options.coverage, "direct");
    const int64_t H = frame.height(), W = frame.width();
    const int64_t rowsPerTile =
        options.rowsPerTile > 0 ? options.rowsPerTile : std::max<int64_t>(1, (H + 63) / 64);
    const int64_t tileCount = (H + rowsPerTile - 1) / rowsPerTile;
    auto tileAt = [&](int64_t index) {
        return Tile{index, index * rowsPerTile, std::min(H, (index + 1) * rowsPerTile)};
    };
    detail::RasterSetup setup = detail::prepareVertices(frame, mesh, options.fullLine);
    const FrameView& view = setup.frame;

    if constexpr (DirectConsumer<Consumer>) {
        if (options.path == RasterPath::Direct ||
            (options.path == RasterPath::Auto && detail::preferDirect(mesh.triangleCount, W, H))) {
            // Direct path: triangles in fixed chunks on any thread, writing through the
            // consumer's atomic sink (commutative writes, so the bits do not depend on the order),
            // then the per-row finishing pass. No binning, each triangle set up once.
            constexpr int64_t kChunk = 4096;
            const int64_t T = int64_t(mesh.triangleCount), chunks = (T + kChunk - 1) / kChunk;
            ProgressSteps steps(options.progress, chunks + tileCount);
            parallelFor(0, chunks, 1, [&](int64_t cb, int64_t ce) {
                auto sink = consumer.direct();
                for (int64_t c = cb; c < ce && !steps.cancelled(); ++c) {
                    for (int64_t t = c * kChunk, e = std::min(T, t + kChunk); t < e; ++t)
                        setup.triangle(size_t(t), [&](const detail::RasterTriangle& rt) {
                            detail::rasterizePiece(rt, options.coverage, view, 0, H, sink);
                        });
                    steps.step();
                }
            });
            if (steps.cancelled()) fail("cancelled");
            parallelFor(0, tileCount, 1, [&](int64_t tb, int64_t te) {
                for (int64_t tile = tb; tile < te && !steps.cancelled(); ++tile) {
                    consumer.finishRows(tileAt(tile));
                    steps.step();
                }
            });
            if (steps.cancelled()) fail("cancelled");
            detail::recycle(setup, nullptr);
            return;
        }
    }

    detail::TileBins bins = detail::binTriangles(setup, options.coverage, rowsPerTile);
    ProgressSteps steps(options.progress, bins.tileCount);
    parallelFor(0, bins.tileCount, 1, [&](int64_t tb, int64_t te) {
        for (int64_t tile = tb; tile < te && !steps.cancelled(); ++tile) {
            const Tile rows = tileAt(tile);
            auto sink = consumer.tile(rows);
            for (int64_t i = bins.offsets[size_t(tile)]; i < bins.offsets[size_t(tile) + 1]; ++i)
                setup.triangle(bins.entries[size_t(i)], [&](const detail::RasterTriangle& rt) {
                    detail::rasterizePiece(rt, options.coverage, view, rows.y0, rows.y1, sink);
                });
            sink.finish();
            steps.step();
        }
    });
    if (steps.cancelled()) fail("cancelled");
    detail::recycle(setup, &bins);
}

template <Coverage C, TileConsumer Consumer>
void rasterize(const Frame& frame, const MeshView& mesh, const RasterOptions& options, Consumer& consumer) {
    using TileSink = decltype(consumer.tile(Tile{}));
    static_assert(sinkSupports<TileSink>(C),
                  "rasterize<C>: the consumer's tile sink lacks the member this coverage needs "
                  "(fragment(x, y, depth, triangle, front) for Coverage::Center, "
                  "span(x, y, depthMin, depthMax, triangle) for Coverage::Conservative)");
    if constexpr (DirectConsumer<Consumer>)
        static_assert(sinkSupports<decltype(consumer.direct())>(C),
                      "rasterize<C>: the consumer's direct sink lacks the member this coverage needs");
    RasterOptions o = options;
    o.coverage = C;
    rasterize(frame, mesh, o, consumer);
}

} // namespace voxfx
