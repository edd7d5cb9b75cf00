#include "voxfx/volume.hpp"

#include <algorithm>
#include <cmath>

namespace voxfx {

const char* toString(ScalarType t) {
    switch (t) {
    case ScalarType::UInt8:
        return "uint8";
    case ScalarType::Int8:
        return "int8";
    case ScalarType::UInt16:
        return "uint16";
    case ScalarType::Int16:
        return "int16";
    case ScalarType::UInt32:
        return "uint32";
    case ScalarType::Int32:
        return "int32";
    case ScalarType::Float32:
        return "float32";
    case ScalarType::Float64:
        return "float64";
    }
    return "unknown";
}

int scalarBytes(ScalarType t) {
    switch (t) {
    case ScalarType::UInt8:
    case ScalarType::Int8:
        return 1;
    case ScalarType::UInt16:
    case ScalarType::Int16:
        return 2;
    case ScalarType::UInt32:
    case ScalarType::Int32:
    case ScalarType::Float32:
        return 4;
    case ScalarType::Float64:
        return 8;
    }
    return 0;
}

ScalarType scalarTypeFromString(const std::string& name) {
    static const struct {
        const char* name;
        ScalarType type;
    } kNames[] = {{"uint8", ScalarType::UInt8},     {"int8", ScalarType::Int8},
                  {"uint16", ScalarType::UInt16},   {"int16", ScalarType::Int16},
                  {"uint32", ScalarType::UInt32},   {"int32", ScalarType::Int32},
                  {"float32", ScalarType::Float32}, {"float", ScalarType::Float32},
                  {"float64", ScalarType::Float64}, {"double", ScalarType::Float64}};
    for (const auto& n : kNames)
        if (name == n.name) return n.type;
    fail("unknown scalar type '", name,
         "' (known: uint8, int8, uint16, int16, uint32, int32, float32 or float, float64 or double)");
}

Volume::Volume(const Vec3i& dims, const Vec3d& lo, const Vec3d& spacing, ScalarType sourceType)
    : dims_(dims), lo_(lo), spacing_(spacing), type_(sourceType) {
    if (dims.x < 1 || dims.y < 1 || dims.z < 1)
        fail("volume dimensions must be at least 1, got ", dims.x, " x ", dims.y, " x ", dims.z);
    if (dims.x > kMaxVolumeVoxels || dims.y > kMaxVolumeVoxels / dims.x ||
        dims.z > kMaxVolumeVoxels / (dims.x * dims.y))
        fail("volume of ", dims.x, " x ", dims.y, " x ", dims.z,
             " voxels is larger than the limit of 2^40 voxels");
    if (!isFinite(spacing) || !(spacing.x > 0 && spacing.y > 0 && spacing.z > 0))
        fail("volume spacing must be positive and finite, got (", spacing.x, ", ", spacing.y, ", ", spacing.z,
             ")");
    if (!isFinite(lo)) fail("volume origin must be finite, got (", lo.x, ", ", lo.y, ", ", lo.z, ")");
    values_.assign(std::size_t(voxelCount()), 0.0f);
}

Box3d Volume::box() const {
    return {lo_, lo_ + Vec3d(double(dims_.x), double(dims_.y), double(dims_.z)) * spacing_};
}

Vec3d Volume::voxelCenter(int64_t i, int64_t j, int64_t k) const {
    return lo_ + Vec3d(double(i) + 0.5, double(j) + 0.5, double(k) + 0.5) * spacing_;
}

float Volume::sample(const Vec3d& p, float outside) const {
    if (values_.empty()) return outside;
    const Box3d b = box();
    // Written so that a NaN coordinate fails every comparison and lands outside.
    if (!(p.x >= b.lo.x && p.x <= b.hi.x && p.y >= b.lo.y && p.y <= b.hi.y && p.z >= b.lo.z && p.z <= b.hi.z))
        return outside;
    int64_t i0[3], i1[3];
    double t[3];
    for (int a = 0; a < 3; ++a) {
        // Continuous index of the sample lattice: voxel centres sit at integers.
        const double u = (p[a] - lo_[a]) / spacing_[a] - 0.5;
        const int64_t n = dims_[a];
        if (u <= 0) {
            i0[a] = i1[a] = 0;
            t[a] = 0;
        } else if (u >= double(n - 1)) {
            i0[a] = i1[a] = n - 1;
            t[a] = 0;
        } else {
            i0[a] = int64_t(std::floor(u));
            i1[a] = std::min(i0[a] + 1, n - 1);
            t[a] = u - double(i0[a]);
        }
    }
    const auto v = [&](int dx, int dy, int dz) {
        return double(at(dx ? i1[0] : i0[0], dy ? i1[1] : i0[1], dz ? i1[2] : i0[2]));
    };
    const auto lerp = [](double a, double c, double s) { return a + (c - a) * s; };
    const double x00 = lerp(v(0, 0, 0), v(1, 0, 0), t[0]);
    const double x10 = lerp(v(0, 1, 0), v(1, 1, 0), t[0]);
    const double x01 = lerp(v(0, 0, 1), v(1, 0, 1), t[0]);
    const double x11 = lerp(v(0, 1, 1), v(1, 1, 1), t[0]);
    return float(lerp(lerp(x00, x10, t[1]), lerp(x01, x11, t[1]), t[2]));
}

float Volume::minValue() const {
    return values_.empty() ? 0.0f : *std::min_element(values_.begin(), values_.end());
}

float Volume::maxValue() const {
    return values_.empty() ? 0.0f : *std::max_element(values_.begin(), values_.end());
}

Frame Volume::frame(Axis axis) const {
    if (values_.empty()) fail("cannot make a frame for an empty volume");
    return Frame::orthographic(box(), axis, dims_[columnXAxis(axis)], dims_[columnYAxis(axis)],
                               dims_[sliceAxis(axis)]);
}

} // namespace voxfx
