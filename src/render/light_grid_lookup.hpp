// voxfx — the one lookup path of the light grids (transmittance slicemaps, ED06 §3.1, and the
// absorption columns, CHANG §3) and of the shadow maps (internal): which view and column a world
// point falls in, which slices lie in front of it, and the bilinear blend of the four columns
// around it. Each map supplies only what a column holds in front of a slice. Also the named
// options the light-grid shadows share (voxfx/light_grid.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/light_grid.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/options.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx::detail {

/// A light-grid column and a depth along it (the frame's depth units).
struct ColumnAt {
    int64_t column;
    double depth;
};

/// Slices [0, end) of `column` that count as in front of `depth`, leaving out the `skipCells`
/// cells that end at the cell holding it (shadow.hpp's bias note). 0 in front of the grid (or
/// for NaN), the whole column behind it.
inline int64_t slicesInFront(const Frame& f, int64_t column, double depth, int64_t skipCells) {
    const int64_t D = f.depth();
    const double t = f.depthToSlice(column)(depth);
    if (!(t >= 0)) return 0;
    const int64_t s = t >= double(D) ? D : int64_t(t);
    return std::clamp<int64_t>(s - skipCells + 1, 0, D);
}

/// The column holding world point p. Precondition: view.covers(world); the index is clamped since
/// covers() admits the closed border of the columns.
inline ColumnAt nearestColumn(const LightView& view, const Vec3d& world) {
    const Vec3d p = view.frame.projection().gridFromWorld(world);
    const int64_t x = std::clamp<int64_t>(int64_t(std::floor(p.x)), 0, view.frame.width() - 1);
    const int64_t y = std::clamp<int64_t>(int64_t(std::floor(p.y)), 0, view.frame.height() - 1);
    return {y * view.frame.width() + x, p.z};
}

/// World length along the light's ray through p per frame depth unit (orthographic: a slice;
/// perspective: depth is the distance along the view axis, so |p - eye| / depth). Precondition:
/// view.covers(world).
inline double worldLengthPerDepth(const LightView& view, const Vec3d& world) {
    if (!view.frame.isPerspective()) return view.worldPerDepthUnit();
    const double depth = view.frame.viewDepth(world);
    return depth > 0 ? length(world - view.frame.eye()) / depth : 1.0;
}

/// Where the plane through a point q with normal n crosses the centre line of a column near
/// q, as a depth of the view's frame (receiver-plane depth): the receiver's own surface continued
/// into a neighbouring column. Within two column footprints of q's depth (a plane nearly along the
/// light's rays would send the lookup far along the column). worldFromGrid is affine in (x, y) at
/// a fixed depth, in orthographic and perspective frames alike, so the frame's steps at q, taken
/// once, give the crossing of every column around q.
class ReceiverPlane {
public:
    /// The plane through the point at grid coordinates qGrid with world normal n.
    VOXFX_ALWAYS_INLINE ReceiverPlane(const LightView& view, const Vec3d& qGrid, const Vec3d& n)
        : n_(n), qGrid_(qGrid), perspective_(view.frame.isPerspective()) {
        const Frame& f = view.frame;
        const Vec3d a = f.worldFromGrid(qGrid), ax = f.worldFromGrid(qGrid + Vec3d{1, 0, 0}) - a,
                    ay = f.worldFromGrid(qGrid + Vec3d{0, 1, 0}) - a;
        along_ = f.worldFromGrid(qGrid + Vec3d{0, 0, 1}) - a; // one depth unit
        if (perspective_) {
            alongX_ = f.worldFromGrid(qGrid + Vec3d{1, 0, 1}) - (a + ax) - along_;
            alongY_ = f.worldFromGrid(qGrid + Vec3d{0, 1, 1}) - (a + ay) - along_;
        }
        nx_ = dot(n, ax);
        ny_ = dot(n, ay);
        footprintSquared_ = dot(ax, ax);
        if (!perspective_) { // one depth step for every column: its slope taken once
            slope_ = dot(n_, along_);
            alongSquared_ = dot(along_, along_);
        }
    }
    /// The depth where the plane crosses the centre line through grid point (x, y).
#pragma GCC diagnostic push // LazyReceiverPlane's union: GCC cannot see that made_ means constructed
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    VOXFX_ALWAYS_INLINE double depthAt(double x, double y) const {
        const double u = x - qGrid_.x, v = y - qGrid_.y;
        double slope = slope_, alongSquared = alongSquared_;
        if (perspective_) {
            const Vec3d along = along_ + alongX_ * u + alongY_ * v;
            slope = dot(n_, along);
            alongSquared = dot(along, along);
        }
        if (!(std::abs(slope) > 0)) return qGrid_.z;
        const double step = -(nx_ * u + ny_ * v) / slope;
        // The reach, 2 |ax| / |along|, is a square root each and a division; a step inside it by a
        // margin far above their rounding (step^2 |along|^2 < 4 |ax|^2 (1 - 1e-9)) is what the clamp
        // returns, so only a step near or beyond it needs them (the same answer, bit for bit; NaN
        // and infinite steps fail the test and take the clamp as before).
        if (step * step * alongSquared < 4 * footprintSquared_ * (1 - 1e-9)) return qGrid_.z + step;
        const double reach = 2 * std::sqrt(footprintSquared_) / std::sqrt(alongSquared);
        return qGrid_.z + std::clamp(step, -reach, reach);
    }
#pragma GCC diagnostic pop

private:
    Vec3d n_, qGrid_, along_, alongX_, alongY_;
    double nx_ = 0, ny_ = 0, footprintSquared_ = 0, slope_ = 0, alongSquared_ = 0;
    bool perspective_;
};

/// A ReceiverPlane made by the first column that asks for a depth, its storage untouched until then
/// (a std::optional's was cleared on every lookup: a 176-byte `rep stos` per lookup).
class LazyReceiverPlane {
public:
    LazyReceiverPlane(const LightView& view, const Vec3d& qGrid, const Vec3d& n)
        : view_(view), qGrid_(qGrid), n_(n) {}
    VOXFX_ALWAYS_INLINE double depthAt(double x, double y) {
        if (!made_) {
            ::new (static_cast<void*>(&plane_)) ReceiverPlane(view_, qGrid_, n_); // (construct_at: a call)
            made_ = true;
        }
        return plane_.depthAt(x, y);
    }

private:
    const LightView& view_;
    const Vec3d& qGrid_;
    const Vec3d& n_;
    bool made_ = false;
    union {
        ReceiverPlane plane_;
    };
};

/// A blend v of values between lo and hi (one channel) stretched about their middle by slope k:
/// lo + (hi - lo) clamp(1/2 + k ((v - lo) / (hi - lo) - 1/2), 0, 1); v itself for k = 1 or equal
/// values.
inline double sharpenBlend(double v, double lo, double hi, double k) {
    if (k == 1 || !(hi - lo > 1e-7)) return v;
    return lo + (hi - lo) * std::clamp(0.5 + k * ((v - lo) / (hi - lo) - 0.5), 0.0, 1.0);
}
inline Vec3f sharpenBlend(const Vec3f& v, const Vec3f& lo, const Vec3f& hi, double k) {
    Vec3f out;
    for (int c = 0; c < 3; ++c) out[c] = float(sharpenBlend(double(v[c]), double(lo[c]), double(hi[c]), k));
    return out;
}
inline double blendMin(double a, double b) { return std::min(a, b); }
inline double blendMax(double a, double b) { return std::max(a, b); }
inline Vec3f blendMin(const Vec3f& a, const Vec3f& b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3f blendMax(const Vec3f& a, const Vec3f& b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

/// Bilinear interpolation of value(column, depth) over the four columns whose centres (x + 0.5)
/// surround p; beyond the frame's border the border column stands in (what lies there is the
/// neighbouring cube face of a point light, or no caster at all). Each column is read at
/// the depth where the receiver's tangent plane (through p, normal n) crosses it, so a receiver
/// tilted against the light is not shadowed by its own cells in the neighbouring columns (a
/// percentage-closer filter's receiver-plane depth); with a zero n, at p's depth. `depth` is a
/// callable returning that depth, computed only when called: a map whose column is empty answers
/// without it (most lookups in sparse foliage). Weights are computed in double and applied as S
/// (float for colours, double for scalars). The blend is sharpened by `sharpness` between the four
/// values' lowest and highest (sharpenBlend; LightGridOptions::sharpness). `p` is the point's grid
/// coordinates (LightView::locate: true).
template <class T, class S, class Value>
T bilinearColumnsAt(const LightView& view, const Vec3d& p, const Vec3d& n, const Value& value,
                    double sharpness = 1) {
    const int64_t W = view.frame.width(), H = view.frame.height();
    const double fx = p.x - 0.5, fy = p.y - 0.5;
    const int64_t x0 = int64_t(std::floor(fx)), y0 = int64_t(std::floor(fy));
    const double wx = fx - double(x0), wy = fy - double(y0);
    const bool plane = n.x != 0 || n.y != 0 || n.z != 0;
    LazyReceiverPlane receiver(view, p, n);
    T out{}, lo{}, hi{};
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int64_t x = std::clamp<int64_t>(x0 + dx, 0, W - 1),
                          y = std::clamp<int64_t>(y0 + dy, 0, H - 1);
            const S w = S((dx ? wx : 1 - wx) * (dy ? wy : 1 - wy));
            const auto depth = [&] {
                if (!plane) return p.z;
                return receiver.depthAt(double(x) + 0.5, double(y) + 0.5);
            };
            const T v = value(y * W + x, depth);
            out += v * w;
            lo = dx || dy ? blendMin(lo, v) : v;
            hi = dx || dy ? blendMax(hi, v) : v;
        }
    return sharpness == 1 ? out : sharpenBlend(out, lo, hi, sharpness);
}

/// Whether orientedBilinearColumns applies: an oriented orthographic view (the sun's) whose grids
/// (`slices`, the frame the slices are counted in) slice uniformly, and no sharpening.
inline bool orientedBilinearApplies(const LightView& view, const Frame& slices, double sharpness) {
    return sharpness == 1 && view.frame.isOriented() && slices.slicing() == Slicing::Uniform;
}

/// bilinearColumnsAt<Vec3f, float> for a map whose columns are read as light(column, end), `end` the
/// slices in front of the column's depth (slicesInFront with `skipCells`), and an empty column (bit
/// clear in `occupied`, one bit per column) is light, where orientedBilinearApplies: the four
/// columns' occupancy first (none: no plane at all), then the receiver plane's step per column from
/// the view's constant cell steps (right, up and forward times the cell size, the differences of
/// worldFromGrid that ReceiverPlane takes at the point with their rounding there), its slope divided
/// once. The same columns and weights; the depths may differ from ReceiverPlane's in the last bits
/// (a column's count only where a depth lies within about 1e-13 of a slice boundary; tested against
/// the plane's crossings solved in world space). `p`: the point's grid coordinates.
template <class Light>
Vec3f orientedBilinearColumns(const LightView& view, const Frame& slices, const Vec3d& p, const Vec3d& n,
                              int64_t skipCells, const uint64_t* occupied, const Light& light) {
    const Frame& f = view.frame;
    const int64_t W = f.width(), H = f.height();
    const double fx = p.x - 0.5, fy = p.y - 0.5;
    const int64_t x0 = int64_t(std::floor(fx)), y0 = int64_t(std::floor(fy));
    const double wx = fx - double(x0), wy = fy - double(y0);
    const int64_t xs[2] = {std::clamp<int64_t>(x0, 0, W - 1), std::clamp<int64_t>(x0 + 1, 0, W - 1)};
    const int64_t ys[2] = {std::clamp<int64_t>(y0, 0, H - 1), std::clamp<int64_t>(y0 + 1, 0, H - 1)};
    int64_t column[4];
    unsigned any = 0;
    for (int k = 0; k < 4; ++k) { // k = 2 dy + dx, the order of bilinearColumnsAt
        column[k] = ys[k >> 1] * W + xs[k & 1];
        any |= unsigned((occupied[size_t(column[k] >> 6)] >> (column[k] & 63)) & 1u) << k;
    }
    Vec3f v[4] = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
    if (any) {
        const Vec3d cell = f.cellSize();
        const Vec3d ax = f.right() * cell.x, ay = f.up() * cell.y, along = f.forward() * cell.z;
        const double slope = dot(n, along);
        const bool plane = (n.x != 0 || n.y != 0 || n.z != 0) && std::abs(slope) > 0;
        const double kx = plane ? -dot(n, ax) / slope : 0, ky = plane ? -dot(n, ay) / slope : 0;
        const double footprintSquared = dot(ax, ax), alongSquared = dot(along, along);
        const DepthToSlice toSlice = slices.depthToSlice(0);
        const int64_t D = slices.depth();
        for (int k = 0; k < 4; ++k) {
            if (!((any >> k) & 1u)) continue;
            double depth = p.z;
            if (plane) {
                const double step =
                    kx * (double(xs[k & 1]) + 0.5 - p.x) + ky * (double(ys[k >> 1]) + 0.5 - p.y);
                if (step * step * alongSquared < 4 * footprintSquared * (1 - 1e-9)) {
                    depth = p.z + step;
                } else {
                    const double reach = 2 * std::sqrt(footprintSquared) / std::sqrt(alongSquared);
                    depth = p.z + std::clamp(step, -reach, reach);
                }
            }
            const double t = toSlice(depth); // slicesInFront, uniform slices
            int64_t end = 0;
            if (t >= 0) end = std::clamp<int64_t>((t >= double(D) ? D : int64_t(t)) - skipCells + 1, 0, D);
            v[k] = light(column[k], end);
        }
    }
    Vec3f out{};
    for (int k = 0; k < 4; ++k) out += v[k] * float(((k & 1) ? wx : 1 - wx) * ((k >> 1) ? wy : 1 - wy));
    return out;
}

/// bilinearColumnsAt at world point `world`. Precondition: view.covers(world).
template <class T, class S, class Value>
T bilinearColumnsLazy(const LightView& view, const Vec3d& world, const Vec3d& n, const Value& value,
                      double sharpness = 1) {
    return bilinearColumnsAt<T, S>(view, view.frame.gridFromWorld(world), n, value, sharpness);
}

/// bilinearColumnsLazy for a value(ColumnAt) that always reads the depth.
template <class T, class S, class Value>
T bilinearColumns(const LightView& view, const Vec3d& world, const Vec3d& n, const Value& value,
                  double sharpness = 1) {
    return bilinearColumnsLazy<T, S>(
        view, world, n,
        [&](int64_t column, const auto& depth) {
            return value(ColumnAt{column, depth()});
        },
        sharpness);
}

/// The view among `views` to look p up in, and the lookup point q = p + n * offset (offset in column
/// footprints of the view at p); -1 (q untouched) when no view covers p. For point lights the
/// offset can carry q across a cube-face seam, out of the frustum of p's face (which would then
/// report "outside the view": full light); q picks its own face.
/// `texel`, where given: views[returned].columnWorldSize(p), which the offset needed too (a division
/// per lookup saved where q stays on p's face).
VOXFX_ALWAYS_INLINE inline int lookupView(const std::vector<LightView>& views, const Vec3d& p, const Vec3d& n,
                                          double offset, Vec3d& q, double* texel = nullptr) {
    int i = viewIndexFor(views, p);
    if (i < 0) return i;
    const double size = views[size_t(i)].columnWorldSize(p);
    q = p + n * (offset * size);
    const int first = i;
    if (views.size() > 1) {
        const int j = viewIndexFor(views, q);
        if (j >= 0) i = j;
    }
    if (texel) *texel = i == first ? size : views[size_t(i)].columnWorldSize(p);
    return i;
}

/// Throws voxfx::Error unless the grid's resolutions are positive and skipCells >= 0.
inline void checkLightGrid(const LightGridOptions& g, const char* technique) {
    if (g.resolution <= 0 || g.depth <= 0 || g.skipCells < 0)
        fail(technique, " shadows: light grid resolutions must be positive and skipped cells >= 0, got ",
             g.resolution, " x ", g.depth, ", ", g.skipCells);
}

/// The named options of a technique O's member `grid` (a LightGridOptions).
template <class O> void appendLightGridFields(std::vector<OptionField<O>>& out) {
    out.push_back(numberOption<O, &O::grid, &LightGridOptions::resolution>(
        "gridResolution", "light grid columns along the longer side of each light view", 1, 16384, "grid"));
    out.push_back(
        numberOption<O, &O::grid, &LightGridOptions::depth>("gridDepth", "light grid slices", 1, 16384));
    out.push_back(nameOption<O, parseSlicing, optionName<Slicing>, &O::grid, &LightGridOptions::slicing>(
        "slicing", "light grid slices: uniform, or local (ED06: each column's own range)",
        "uniform | local"));
    out.push_back(numberOption<O, &O::grid, &LightGridOptions::skipCells>(
        "skipCells", "cells ending at a point's own cell that its lookup leaves out", 0, 16384));
    out.push_back(flagOption<O, &O::grid, &LightGridOptions::bilinear>(
        "bilinear", "interpolate light-grid lookups between the four columns around a point, each at the "
                    "receiver's plane (off: the point's own column, ED06's stair-stepped edges)"));
    out.push_back(numberOption<O, &O::grid, &LightGridOptions::sharpness>(
        "sharpness",
        "bilinear light-grid lookups: slope of the blend between the four columns' lowest and "
        "highest value (1: plain bilinear; larger: narrower edges)",
        1, 1e6));
}

} // namespace voxfx::detail
