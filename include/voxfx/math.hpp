// voxfx — small vector math: 3-vectors, boxes, 4x4 matrices. Plain structs, no SIMD.
// Thread-safety: plain values and pure functions; use from any thread.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "voxfx/error.hpp"

namespace voxfx {

template <class T> struct Vec3 {
    T x = 0, y = 0, z = 0;

    constexpr Vec3() = default;
    VOXFX_HOSTDEV constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    template <class U>
    VOXFX_HOSTDEV constexpr explicit Vec3(const Vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}

    VOXFX_HOSTDEV constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    VOXFX_HOSTDEV constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }

    VOXFX_HOSTDEV constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    VOXFX_HOSTDEV constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    VOXFX_HOSTDEV constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    VOXFX_HOSTDEV constexpr Vec3 operator*(T s) const { return {x * s, y * s, z * s}; }
    VOXFX_HOSTDEV constexpr Vec3 operator/(T s) const { return {x / s, y / s, z / s}; }
    VOXFX_HOSTDEV constexpr Vec3 operator*(const Vec3& o) const { return {x * o.x, y * o.y, z * o.z}; }
    VOXFX_HOSTDEV constexpr Vec3& operator+=(const Vec3& o) {
        x += o.x;
        y += o.y;
        z += o.z;
        return *this;
    }
    VOXFX_HOSTDEV constexpr Vec3& operator-=(const Vec3& o) {
        x -= o.x;
        y -= o.y;
        z -= o.z;
        return *this;
    }
    VOXFX_HOSTDEV constexpr Vec3& operator*=(T s) {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    constexpr bool operator==(const Vec3& o) const = default;
};

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;
using Vec3i = Vec3<int64_t>;

template <class T> VOXFX_HOSTDEV constexpr Vec3<T> operator*(T s, const Vec3<T>& v) { return v * s; }
template <class T> VOXFX_HOSTDEV constexpr T dot(const Vec3<T>& a, const Vec3<T>& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T> VOXFX_HOSTDEV constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T> VOXFX_HOSTDEV inline T length(const Vec3<T>& v) { return std::sqrt(dot(v, v)); }
template <class T> VOXFX_HOSTDEV inline Vec3<T> normalize(const Vec3<T>& v) {
    T l = length(v);
    return l > T(0) ? v / l : Vec3<T>{};
}
template <class T> VOXFX_HOSTDEV constexpr Vec3<T> min(const Vec3<T>& a, const Vec3<T>& b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
template <class T> VOXFX_HOSTDEV constexpr Vec3<T> max(const Vec3<T>& a, const Vec3<T>& b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
template <class T> inline bool isFinite(const Vec3<T>& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Axis-aligned box [lo, hi]. Empty when any lo > hi (the default).
struct Box3d {
    Vec3d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity()};
    Vec3d hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
             -std::numeric_limits<double>::infinity()};

    constexpr bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    constexpr Vec3d extent() const { return hi - lo; }
    constexpr Vec3d center() const { return (lo + hi) * 0.5; }
    constexpr void extend(const Vec3d& p) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
    constexpr void extend(const Box3d& b) {
        lo = min(lo, b.lo);
        hi = max(hi, b.hi);
    }
    constexpr bool operator==(const Box3d&) const = default;
};

/// Row-major 4x4 matrix acting on column vectors: p' = M * p.
struct Mat4d {
    double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};

    static constexpr Mat4d identity() { return {}; }
    constexpr Mat4d operator*(const Mat4d& o) const {
        Mat4d r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                double s = 0;
                for (int k = 0; k < 4; ++k) s += m[i][k] * o.m[k][j];
                r.m[i][j] = s;
            }
        return r;
    }
    /// Transforms a point (w = 1), without the perspective divide.
    constexpr Vec3d point(const Vec3d& p) const {
        return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
                m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
                m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
    }
    constexpr Vec3d vector(const Vec3d& v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
};

} // namespace voxfx
