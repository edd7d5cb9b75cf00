// voxfx — Volume: a scalar field on a regular grid placed in the world (CT scans, smoke).
//
// Placement follows VoxelGrid's convention: voxel (i, j, k) covers
//     [lo + (i, j, k) * spacing, lo + (i + 1, j + 1, k + 1) * spacing]
// and its value is the sample at the voxel's centre, lo + (i + 0.5, j + 0.5, k + 0.5) * spacing.
// Values are stored as float, x fastest: index = i + nx * (j + ny * k), the order of INR, NRRD
// and raw files; the scalar type the file stored is kept in sourceType().
//
// Readers (loadVolume) pick the format by extension, then by magic bytes:
//   .inr, .inr.gz   INRIMAGE-4 (CGAL's images); TX/TY/TZ is the centre of voxel (0, 0, 0), as in
//                   CGAL's ImageIO, and 0 when absent, so meshes CGAL makes from the image line up
//   .nrrd, .nhdr    NRRD scalar volumes (raw or gzip encoding, either endian, attached or one
//                   detached data file); "space origin" is the centre of voxel (0, 0, 0); without
//                   it the box starts at 0, as voxfx's NRRD grid reader does
//   .json           raw samples described by a JSON header:
//                   {"file": "ct.raw", "dims": [nx, ny, nz], "type": "uint16",
//                    "endian": "little", "spacing": [sx, sy, sz], "origin": [x, y, z],
//                    "offset": 0}
//                   "origin" is the centre of voxel (0, 0, 0) (box from 0 without it), "file"
//                   is relative to the JSON file, "offset" skips a header of that many bytes
// Every header is checked against the bytes the file holds before anything is allocated, and a
// NaN or infinite sample is an error: voxfx::Error names the file and what is wrong.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/math.hpp"

namespace voxfx {

/// Scalar type of the samples a volume file stored.
enum class ScalarType : uint8_t { UInt8, Int8, UInt16, Int16, UInt32, Int32, Float32, Float64 };

const char* toString(ScalarType t);
/// Bytes per sample of the type.
int scalarBytes(ScalarType t);
/// Parses "uint8", "int16", "float32" (or "float"), "float64" (or "double")...; throws voxfx::Error
/// naming the accepted names.
ScalarType scalarTypeFromString(const std::string& name);

/// Largest voxel count a volume may have (2^40: 4 TiB of floats; guards products against overflow).
inline constexpr int64_t kMaxVolumeVoxels = int64_t(1) << 40;

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
    /// The world box the voxels tile.
    Box3d box() const;
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
    float sample(const Vec3d& p, float outside = 0.0f) const;

    /// Smallest and largest value (0 and 0 for an empty volume).
    float minValue() const;
    float maxValue() const;

    /// The orthographic frame whose cells are this volume's voxels, sliced along `axis`:
    /// frame.cellCenter(x, y, s) is the centre of the voxel whose index along columnXAxis(axis) is
    /// x, along columnYAxis(axis) y and along the axis s.
    Frame frame(Axis axis = Axis::Z) const;

private:
    Vec3i dims_{0, 0, 0};
    Vec3d lo_{0, 0, 0};
    Vec3d spacing_{1, 1, 1};
    ScalarType type_ = ScalarType::Float32;
    std::vector<float> values_;
};

/// File format of a volume.
enum class VolumeFormat : uint8_t { Inr, Nrrd, RawJson };
const char* toString(VolumeFormat f);

/// What loadVolume found besides the volume.
struct VolumeLoadReport {
    VolumeFormat format = VolumeFormat::Inr;
    bool gzip = false;      ///< the samples were gzip-compressed
    uint64_t fileBytes = 0; ///< size of the file named (the header for a detached NRRD or JSON)
};

/// Reads a scalar volume (see the file comment for the formats). Throws voxfx::Error naming the
/// file and the problem. OpenVDB float grids are not read here yet.
Volume loadVolume(const std::string& path, VolumeLoadReport* report = nullptr);

/// Parameters of the procedural smoke (makeSmoke).
struct SmokeParams {
    Vec3i dims{64, 64, 64};
    /// World box the volume fills; the plume rises along +z from the bottom centre.
    Box3d box{{-1, -1, -1}, {1, 1, 1}};
    uint32_t seed = 1;
    int octaves = 5;
    /// Frequency of the first noise octave, in periods across the box.
    double frequency = 3.0;
};

/// A deterministic smoke density in [0, 1]: fractal (fBm) value noise inside a soft plume that
/// widens as it rises and fades at its edges and top. Same parameters, same values, whatever the
/// thread count. Throws voxfx::Error for bad dimensions, box or octaves (not in [1, 16]).
Volume makeSmoke(const SmokeParams& params);

} // namespace voxfx
