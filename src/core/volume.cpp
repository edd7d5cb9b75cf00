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
