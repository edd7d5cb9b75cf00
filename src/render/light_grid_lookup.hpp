// voxfx — the one lookup path of the light grids (transmittance slicemaps, ED06 §3.1, and the
// absorption columns, CHANG §3): which column a world point falls in, which slices lie in front
// of it, and the bilinear blend of the four columns around it. Each map supplies only what a
// column holds in front of a slice.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "voxfx/frame.hpp"
#include "voxfx/shadow.hpp"

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
    const Vec3d p = view.gridFromWorld(world);
    const int64_t x = std::clamp<int64_t>(int64_t(std::floor(p.x)), 0, view.frame.width() - 1);
    const int64_t y = std::clamp<int64_t>(int64_t(std::floor(p.y)), 0, view.frame.height() - 1);
    return {y * view.frame.width() + x, p.z};
}

/// Bilinear interpolation of value(ColumnAt) over the four columns whose centres (x + 0.5)
/// surround p, at p's depth; columns outside the frame hold no caster and give `empty`.
/// Weights are computed in double and applied as S (float for colours, double for scalars).
/// Precondition: view.covers(world).
template <class T, class S, class Value>
T bilinearColumns(const LightView& view, const Vec3d& world, const T& empty, const Value& value) {
    const Vec3d p = view.gridFromWorld(world);
    const int64_t W = view.frame.width(), H = view.frame.height();
    const double fx = p.x - 0.5, fy = p.y - 0.5;
    const int64_t x0 = int64_t(std::floor(fx)), y0 = int64_t(std::floor(fy));
    const double wx = fx - double(x0), wy = fy - double(y0);
    T out{};
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int64_t x = x0 + dx, y = y0 + dy;
            const S w = S((dx ? wx : 1 - wx) * (dy ? wy : 1 - wy));
            const bool inside = x >= 0 && y >= 0 && x < W && y < H;
            out += (inside ? value(ColumnAt{y * W + x, p.z}) : empty) * w;
        }
    return out;
}

} // namespace voxfx::detail
