// voxfx — Volume: a scalar field on a regular grid placed in the world (CT scans, smoke).
//
// Placement follows VoxelGrid's convention: voxel (i, j, k) covers
//     [lo + (i, j, k) * spacing, lo + (i + 1, j + 1, k + 1) * spacing]
// and its value is the sample at the voxel's centre, lo + (i + 0.5, j + 0.5, k + 0.5) * spacing.
// A volume may also be turned (setAxes: NRRD's oblique "space directions", a scene's "rotate"):
// the voxel axes i, j, k then run along orthonormal world directions axes[0..2], and the centre
// of voxel (i, j, k) is lo + axes[0] (i + 0.5) spacing.x + axes[1] (j + 0.5) spacing.y + ...
// Values are stored as float, x fastest: index = i + nx * (j + ny * k), the order of INR, NRRD
// and raw files; the scalar type the file stored is kept in sourceType().
//
// Files are read by loadVolume (voxfx/volume_io.hpp); makeSmoke (voxfx/smoke.hpp) makes one.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx {

/// Scalar type of the samples a volume file stored.
enum class ScalarType : uint8_t { UInt8, Int8, UInt16, Int16, UInt32, Int32, Float32, Float64 };
inline constexpr EnumName<ScalarType> kScalarTypeNames[] = {
    {"uint8", ScalarType::UInt8},     {"int8", ScalarType::Int8},      {"uint16", ScalarType::UInt16},
    {"int16", ScalarType::Int16},     {"uint32", ScalarType::UInt32},  {"int32", ScalarType::Int32},
    {"float32", ScalarType::Float32}, {"float64", ScalarType::Float64}};

const char* toString(ScalarType t);
/// Bytes per sample of the type.
int scalarBytes(ScalarType t);
/// Parses "uint8", "int16", "float32" (or "float"), "float64" (or "double")...; throws voxfx::Error
/// naming the accepted names.
ScalarType scalarTypeFromString(const std::string& name);

/// Largest voxel count a volume may have (2^40: 4 TiB of floats; guards products against overflow).
inline constexpr int64_t kMaxVolumeVoxels = int64_t(1) << 40;

/// A volume's samples and placement as plain values, for kernels that may run on the host or a
/// device: no ownership, no allocation, no exceptions. Volume::view() makes one; it stays valid
/// while the volume lives and is not resized.
struct VolumeView {
    const float* values = nullptr;
    int64_t nx = 0, ny = 0, nz = 0;
    Vec3d lo{0, 0, 0};
    Vec3d spacing{1, 1, 1};
    /// World directions of the voxel axes i, j, k (orthonormal; the world axes unless turned).
    Vec3d axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    /// 1 / spacing per axis (voxelCoordinate multiplies: a division per axis was a large part of a
    /// volume sample's cost).
    Vec3d invSpacing{1, 1, 1};

    VOXFX_HOSTDEV float at(int64_t i, int64_t j, int64_t k) const { return values[i + nx * (j + ny * k)]; }
    /// Continuous voxel coordinate of world point p along voxel axis a (0 at the volume's lo face,
    /// n at the far one). For the world axes the products with 0 and 1 are exact: (p - lo)[a],
    /// times invSpacing[a] (within an ulp of the quotient by spacing[a]).
    VOXFX_HOSTDEV double voxelCoordinate(const Vec3d& p, int a) const {
        const Vec3d d = p - lo;
        return (d.x * axes[a].x + d.y * axes[a].y + d.z * axes[a].z) * invSpacing[a];
    }

    /// The continuous voxel coordinates of world point p along the three voxel axes
    /// (voxelCoordinate of each): what sampleVoxel takes, so that a march that also asks other
    /// lattices of the same placement (empty bricks, light grids) computes them once.
    VOXFX_HOSTDEV Vec3d voxelCoordinates(const Vec3d& p) const {
        return {voxelCoordinate(p, 0), voxelCoordinate(p, 1), voxelCoordinate(p, 2)};
    }

    /// Trilinear interpolation of the voxel-centre samples at world point p: clamped to the nearest
    /// centres within half a voxel of the box's faces, `outside` beyond the box or for a NaN p.
    VOXFX_HOSTDEV float sample(const Vec3d& p, float outside = 0.0f) const {
        if (values == nullptr) return outside;
        return sampleVoxel(voxelCoordinates(p), outside);
    }

    /// sample() at the point of voxel coordinates u (voxelCoordinates(p)): the same value, bit for bit.
    VOXFX_HOSTDEV float sampleVoxel(const Vec3d& u, float outside = 0.0f) const {
        if (values == nullptr) return outside;
        const int64_t n[3] = {nx, ny, nz};
        int64_t i0[3], d[3]; // the lower centre and 1 where the upper one is the next (0: clamped)
        double t[3];
        for (int a = 0; a < 3; ++a) {
            // Continuous index of the sample lattice: voxel centres sit at integers. Written so
            // that a NaN coordinate fails both comparisons and lands outside.
            if (!(u[a] >= 0 && u[a] <= double(n[a]))) return outside;
            const double c = u[a] - 0.5;
            if (c <= 0) {
                i0[a] = 0, d[a] = 0;
                t[a] = 0;
            } else if (c >= double(n[a] - 1)) {
                i0[a] = n[a] - 1, d[a] = 0;
                t[a] = 0;
            } else {
                i0[a] = int64_t(c); // c > 0: truncation is floor
                d[a] = i0[a] + 1 < n[a] ? 1 : 0;
                t[a] = c - double(i0[a]);
            }
        }
        // The eight centres from one base index and the strides (at(): i + nx (j + ny k)).
        const float* b = values + (i0[0] + nx * (i0[1] + ny * i0[2]));
        const int64_t ox = d[0], oy = d[1] * nx, oz = d[2] * nx * ny;
        const auto lerp = [](double a, double c, double s) { return a + (c - a) * s; };
        const double x00 = lerp(double(b[0]), double(b[ox]), t[0]);
        const double x10 = lerp(double(b[oy]), double(b[oy + ox]), t[0]);
        const double x01 = lerp(double(b[oz]), double(b[oz + ox]), t[0]);
        const double x11 = lerp(double(b[oz + oy]), double(b[oz + oy + ox]), t[0]);
        return float(lerp(lerp(x00, x10, t[1]), lerp(x01, x11, t[1]), t[2]));
    }

    /// The gradient of sample() at world point p, per world unit, by central differences one voxel
    /// either side along each voxel axis (spacing[a] apart, so anisotropic spacing counts), turned
    /// into world axes. The field is taken as sample() sees it inside the box, clamped at the
    /// outermost voxel centres: there the difference is one-sided (to the centre itself), so a
    /// constant volume has a zero gradient up to its faces and an affine one its exact gradient
    /// everywhere in the box. Zero outside the box (where sample() is the constant `outside`), for
    /// a NaN p, and along an axis of one voxel.
    VOXFX_HOSTDEV Vec3d gradient(const Vec3d& p) const {
        if (values == nullptr) return {0, 0, 0};
        const int64_t n[3] = {nx, ny, nz};
        double c[3];
        for (int a = 0; a < 3; ++a) {
            const double u = voxelCoordinate(p, a);
            if (!(u >= 0 && u <= double(n[a]))) return {0, 0, 0};
            // Lattice coordinate (voxel centres at integers), clamped to the outermost centres.
            const double l = u - 0.5, hi = double(n[a] - 1);
            c[a] = l < 0 ? 0 : (l > hi ? hi : l);
        }
        Vec3d g{0, 0, 0};
        for (int a = 0; a < 3; ++a) {
            const double hi = double(n[a] - 1);
            const double cm = c[a] - 1 < 0 ? 0 : c[a] - 1, cp = c[a] + 1 > hi ? hi : c[a] + 1;
            if (!(cp > cm)) continue;
            double q[3] = {c[0], c[1], c[2]};
            q[a] = cp;
            const double fp = lattice(q);
            q[a] = cm;
            const double fm = lattice(q);
            const double d = (fp - fm) / ((cp - cm) * spacing[a]);
            g = g + axes[a] * d;
        }
        return g;
    }

    /// Trilinear interpolation at lattice coordinates c (voxel centres at integers), each within
    /// [0, n - 1].
    VOXFX_HOSTDEV double lattice(const double c[3]) const {
        const int64_t n[3] = {nx, ny, nz};
        int64_t i0[3], i1[3];
        double t[3];
        for (int a = 0; a < 3; ++a) {
            i0[a] = int64_t(c[a]); // c >= 0: truncation is floor
            if (i0[a] > n[a] - 1) i0[a] = n[a] - 1;
            i1[a] = i0[a] + 1 < n[a] ? i0[a] + 1 : n[a] - 1;
            t[a] = c[a] - double(i0[a]);
        }
        const auto v = [&](int dx, int dy, int dz) {
            return double(at(dx ? i1[0] : i0[0], dy ? i1[1] : i0[1], dz ? i1[2] : i0[2]));
        };
        const auto lerp = [](double a, double b, double s) { return a + (b - a) * s; };
        const double x00 = lerp(v(0, 0, 0), v(1, 0, 0), t[0]);
        const double x10 = lerp(v(0, 1, 0), v(1, 1, 0), t[0]);
        const double x01 = lerp(v(0, 0, 1), v(1, 0, 1), t[0]);
        const double x11 = lerp(v(0, 1, 1), v(1, 1, 1), t[0]);
        return lerp(lerp(x00, x10, t[1]), lerp(x01, x11, t[1]), t[2]);
    }
};

class Volume {
public:
    Volume() = default;
    /// A volume of nx x ny x nz voxels, all 0, whose voxel (0, 0, 0) starts at `lo`. Throws
    /// voxfx::Error for a dimension < 1, more than kMaxVolumeVoxels voxels, a spacing that is
    /// not positive and finite, or a non-finite `lo`.
    Volume(const Vec3i& dims, const Vec3d& lo, const Vec3d& spacing,
           ScalarType sourceType = ScalarType::Float32);

    const Vec3i& dims() const { return dims_; }
    int64_t voxelCount() const { return dims_.x * dims_.y * dims_.z; }
    /// World corner of voxel (0, 0, 0) and the size of one voxel.
    const Vec3d& lo() const { return lo_; }
    const Vec3d& spacing() const { return spacing_; }
    /// World directions of the voxel axes i, j, k (the world axes unless setAxes turned them).
    const Vec3d& axis(int a) const { return axes_[a]; }
    /// True when the voxel axes are the world axes.
    bool axisAligned() const;
    /// Turns the volume about `lo`: voxel axis a runs along world direction axes[a]. Throws
    /// voxfx::Error unless the three are unit length and pairwise orthogonal (within 1e-6).
    void setAxes(const Vec3d& i, const Vec3d& j, const Vec3d& k);
    /// World point of continuous voxel coordinates u (voxel (i, j, k) spans u in [i, i + 1] x ...).
    Vec3d worldFromVoxel(const Vec3d& u) const;
    /// The world bounding box of the voxels (the box they tile when the volume is not turned).
    Box3d box() const;
    /// The voxels' box as a closed, outward-facing triangle mesh (12 triangles), turned with the
    /// volume: the default shape of a volume object.
    Mesh boxMesh() const;
    /// World centre of voxel (i, j, k).
    Vec3d voxelCenter(int64_t i, int64_t j, int64_t k) const;

    ScalarType sourceType() const { return type_; }
    void setSourceType(ScalarType t) { type_ = t; }

    int64_t index(int64_t i, int64_t j, int64_t k) const { return i + dims_.x * (j + dims_.y * k); }
    float at(int64_t i, int64_t j, int64_t k) const { return values_[std::size_t(index(i, j, k))]; }
    float& at(int64_t i, int64_t j, int64_t k) { return values_[std::size_t(index(i, j, k))]; }
    const std::vector<float>& values() const { return values_; }
    std::vector<float>& values() { return values_; }

    /// Trilinear interpolation of the voxel-centre samples at world point p. Inside the box but
    /// within half a voxel of its faces the samples are clamped to the nearest centre (no fade at
    /// the border); outside the box (or for a non-finite p) it returns `outside`.
    float sample(const Vec3d& p, float outside = 0.0f) const { return view().sample(p, outside); }
    /// The gradient of sample() per world unit by central differences (see VolumeView::gradient).
    Vec3d gradient(const Vec3d& p) const { return view().gradient(p); }
    /// The plain view kernels sample (see VolumeView).
    VolumeView view() const {
        return {values_.empty() ? nullptr : values_.data(),
                dims_.x,
                dims_.y,
                dims_.z,
                lo_,
                spacing_,
                {axes_[0], axes_[1], axes_[2]},
                invSpacing_};
    }

    /// Smallest and largest value (0 and 0 for an empty volume).
    float minValue() const;
    float maxValue() const;

    /// The orthographic frame whose cells are this volume's voxels, sliced along `axis` (an
    /// oriented one for a turned volume):
    /// frame.cellCenter(x, y, s) is the centre of the voxel whose index along columnXAxis(axis) is
    /// x, along columnYAxis(axis) y and along the axis s.
    Frame frame(Axis axis = Axis::Z) const;

private:
    Vec3i dims_{0, 0, 0};
    Vec3d lo_{0, 0, 0};
    Vec3d spacing_{1, 1, 1};
    Vec3d invSpacing_{1, 1, 1}; ///< 1 / spacing_
    Vec3d axes_[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    ScalarType type_ = ScalarType::Float32;
    std::vector<float> values_;
};

} // namespace voxfx
