#include "voxfx/volume.hpp"

#include <algorithm>
#include <cmath>

namespace voxfx {

const char* toString(ScalarType t) { return enumName(t, kScalarTypeNames); }

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
    invSpacing_ = {1 / spacing.x, 1 / spacing.y, 1 / spacing.z};
    values_.assign(std::size_t(voxelCount()), 0.0f);
}

bool Volume::axisAligned() const {
    return axes_[0] == Vec3d{1, 0, 0} && axes_[1] == Vec3d{0, 1, 0} && axes_[2] == Vec3d{0, 0, 1};
}

void Volume::setAxes(const Vec3d& i, const Vec3d& j, const Vec3d& k) {
    const Vec3d a[3] = {i, j, k};
    for (int x = 0; x < 3; ++x) {
        if (!isFinite(a[x]) || !(std::abs(length(a[x]) - 1) <= 1e-6))
            fail("volume axis ", x, " must be a unit vector, got (", a[x].x, ", ", a[x].y, ", ", a[x].z, ")");
        for (int y = 0; y < x; ++y)
            if (!(std::abs(dot(a[x], a[y])) <= 1e-6))
                fail("volume axes ", y, " and ", x,
                     " must be orthogonal (skewed volumes are not supported), ", "their dot product is ",
                     dot(a[x], a[y]));
    }
    for (int x = 0; x < 3; ++x) axes_[x] = a[x];
}

Vec3d Volume::worldFromVoxel(const Vec3d& u) const {
    if (axisAligned()) return lo_ + u * spacing_; // exactly the box's corners
    return lo_ + axes_[0] * (u.x * spacing_.x) + axes_[1] * (u.y * spacing_.y) +
           axes_[2] * (u.z * spacing_.z);
}

Box3d Volume::box() const {
    const Vec3d n(double(dims_.x), double(dims_.y), double(dims_.z));
    Box3d b;
    for (int c = 0; c < 8; ++c)
        b.extend(worldFromVoxel({(c & 1) ? n.x : 0.0, (c & 2) ? n.y : 0.0, (c & 4) ? n.z : 0.0}));
    return b;
}

Mesh Volume::boxMesh() const {
    const Vec3d n(double(dims_.x), double(dims_.y), double(dims_.z));
    Mesh m;
    for (int c = 0; c < 8; ++c)
        m.positions.push_back(
            Vec3f(worldFromVoxel({(c & 1) ? n.x : 0.0, (c & 2) ? n.y : 0.0, (c & 4) ? n.z : 0.0})));
    // Outward for right-handed axes; a mirroring set of axes turns the faces inside out.
    const bool mirrored = dot(cross(axes_[0], axes_[1]), axes_[2]) < 0;
    static const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        const uint32_t t[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
        for (int v = 0; v < 6; v += 3) {
            m.indices.push_back(t[v]);
            m.indices.push_back(mirrored ? t[v + 2] : t[v + 1]);
            m.indices.push_back(mirrored ? t[v + 1] : t[v + 2]);
        }
    }
    return m;
}

Vec3d Volume::voxelCenter(int64_t i, int64_t j, int64_t k) const {
    return worldFromVoxel({double(i) + 0.5, double(j) + 0.5, double(k) + 0.5});
}

float Volume::minValue() const {
    return values_.empty() ? 0.0f : *std::min_element(values_.begin(), values_.end());
}

float Volume::maxValue() const {
    return values_.empty() ? 0.0f : *std::max_element(values_.begin(), values_.end());
}

Frame Volume::frame(Axis axis) const {
    if (values_.empty()) fail("cannot make a frame for an empty volume");
    const int64_t w = dims_[columnXAxis(axis)], h = dims_[columnYAxis(axis)], d = dims_[sliceAxis(axis)];
    if (axisAligned()) return Frame::orthographic(box(), axis, w, h, d);
    // Turned: an oriented frame whose local axes are the voxel axes (right-handed order).
    const int ax = columnXAxis(axis), ay = columnYAxis(axis), az = sliceAxis(axis);
    Vec3d right = axes_[ax], up = axes_[ay], forward = axes_[az];
    if (dot(cross(right, up), forward) < 0)
        fail("cannot make a frame for a mirrored volume (its voxel axes are left-handed)");
    Box3d local;
    for (int c = 0; c < 8; ++c) {
        const Vec3d p = worldFromVoxel({(c & 1) ? double(dims_.x) : 0.0, (c & 2) ? double(dims_.y) : 0.0,
                                        (c & 4) ? double(dims_.z) : 0.0});
        local.extend({dot(p, right), dot(p, up), dot(p, forward)});
    }
    return Frame::orthographic(local, right, up, forward, w, h, d);
}

} // namespace voxfx
