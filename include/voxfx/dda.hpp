// voxfx — the one 3D DDA: the incremental voxel traversal of J. Amanatides and A. Woo, "A Fast
// Voxel Traversal Algorithm for Ray Tracing", Eurographics 1987, §3, over the cells of a
// W x H x D grid in grid coordinates (cell (x, y, s) is [x, x+1) x [y, y+1) x [s, s+1)).
// Segment queries (grid_query) and particle paths (particles) both walk with it.
//
// The segment is p(t) = origin + t * dir. Unlike the paper's tDelta increments, the parameter of
// the next crossing along an axis is recomputed from the origin at every step, so it is exact to
// one rounding and does not drift over long walks.
//
// Plain data, no allocation, no exceptions: every function is VOXFX_HOSTDEV so a GPU kernel
// walks the same way. Thread-safety: a Dda is a value; distinct Dda objects may be used
// concurrently, one object by one thread at a time. Nothing here uses threads.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "voxfx/error.hpp"
#include "voxfx/math.hpp"

namespace voxfx {

/// The part of a segment's parameter range that lies in the grid box [0, W] x [0, H] x [0, D]
/// (slab method). Empty when t0 >= t1; an axis with a zero direction component keeps the whole
/// range when origin lies in [0, n) along it (cells are half-open) and empties it otherwise.
struct DdaClip {
    double t0 = 0, t1 = 0;
    int entryAxis = -1; ///< the axis whose slab raised t0 above the given start (-1: none did)
    VOXFX_HOSTDEV bool empty() const { return !(t0 < t1); }
};

/// Clips [tStart, tEnd] of origin + t * dir to the grid box of `dims` (W, H, D).
VOXFX_HOSTDEV inline DdaClip clipToGrid(const Vec3d& origin, const Vec3d& dir, const int64_t dims[3],
                                        double tStart = 0.0, double tEnd = 1.0) {
    DdaClip c;
    c.t0 = tStart;
    c.t1 = tEnd;
    for (int i = 0; i < 3; ++i) {
        const double n = double(dims[i]);
        if (dir[i] == 0) {
            if (!(origin[i] >= 0 && origin[i] < n)) {
                c.t1 = c.t0; // parallel to the slab and outside it
                return c;
            }
            continue;
        }
        double ta = (0.0 - origin[i]) / dir[i], tb = (n - origin[i]) / dir[i];
        if (ta > tb) {
            const double s = ta;
            ta = tb;
            tb = s;
        }
        if (ta > c.t0) {
            c.t0 = ta;
            c.entryAxis = i;
        }
        if (tb < c.t1) c.t1 = tb;
    }
    return c;
}

/// How Dda::start picks the first cell when the start point lies on a cell boundary.
enum class DdaStart : uint8_t {
    AlongSegment, ///< the cell the segment occupies just after the start (rounds towards travel)
    Containing,   ///< the half-open cell that contains the start point (floor on every axis)
};

/// The walk's state: the current cell and, per axis, the parameter of the next boundary.
struct Dda {
    Vec3d origin, dir;
    int64_t dims[3] = {0, 0, 0};
    int64_t cell[3] = {0, 0, 0};
    int64_t step[3] = {0, 0, 0}; ///< +1, -1 or 0 (the axis is never crossed)
    double tMax[3] = {0, 0, 0};  ///< parameter of the next boundary crossing per axis (inf: none)

    /// The walk from the point at parameter t (normally a clip's t0). The first cell is clamped
    /// into the grid, since t * dir may round across its faces.
    VOXFX_HOSTDEV static Dda start(const Vec3d& origin, const Vec3d& dir, const int64_t dims[3], double t,
                                   DdaStart rule = DdaStart::AlongSegment) {
        Dda w;
        w.origin = origin;
        w.dir = dir;
        for (int i = 0; i < 3; ++i) {
            w.dims[i] = dims[i];
            w.step[i] = dir[i] > 0 ? 1 : (dir[i] < 0 ? -1 : 0);
            const double p = origin[i] + t * dir[i];
            int64_t k = rule == DdaStart::AlongSegment && dir[i] < 0 ? int64_t(std::ceil(p)) - 1
                                                                     : int64_t(std::floor(p));
            k = k < 0 ? 0 : (k > dims[i] - 1 ? dims[i] - 1 : k);
            w.cell[i] = k;
            w.tMax[i] = w.boundary(i);
        }
        return w;
    }

    /// The axis crossed next: the one with the smallest tMax; on a tie (the segment passes
    /// through an edge or corner) the later axis, and the others follow at the same t.
    VOXFX_HOSTDEV int nextAxis() const {
        return tMax[0] < tMax[1] ? (tMax[0] < tMax[2] ? 0 : 2) : (tMax[1] < tMax[2] ? 1 : 2);
    }
    /// The index of the neighbour across the next boundary along `axis` (may lie outside).
    VOXFX_HOSTDEV int64_t neighbour(int axis) const { return cell[axis] + step[axis]; }
    /// Whether index k lies in [0, n) along `axis`.
    VOXFX_HOSTDEV bool inside(int axis, int64_t k) const { return k >= 0 && k < dims[axis]; }
    /// Crosses the next boundary along `axis`. Returns false (and leaves the state as it was)
    /// when that leaves the grid.
    VOXFX_HOSTDEV bool advance(int axis) {
        const int64_t k = neighbour(axis);
        if (!inside(axis, k)) return false;
        cell[axis] = k;
        tMax[axis] = boundary(axis);
        return true;
    }

private:
    // Parameter where the segment leaves the current cell along axis i, from the origin.
    VOXFX_HOSTDEV double boundary(int i) const {
        if (step[i] == 0) return std::numeric_limits<double>::infinity();
        return (double(step[i] > 0 ? cell[i] + 1 : cell[i]) - origin[i]) / dir[i];
    }
};

} // namespace voxfx
