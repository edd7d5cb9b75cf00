// voxfx — what the volume-reader fuzz targets share.
#pragma once

#include <cmath>

#include "fuzz_target.hpp"
#include "io/volume_formats.hpp"

namespace voxfx::fuzz {

/// A path whose folder does not exist: data files a header names relative to it are never found
/// (absolute names still are, which is what a hostile header can do too).
inline const std::string kNowhere = "/nonexistent-voxfx-fuzz/input";

/// An accepted volume holds dims.x * dims.y * dims.z finite samples.
inline void checkVolume(const Volume& v) {
    const Vec3i d = v.dims();
    require(d.x >= 1 && d.y >= 1 && d.z >= 1, "dimensions are at least 1");
    require(v.values().size() == std::size_t(d.x * d.y * d.z), "one sample per voxel");
    for (const float s : v.values()) require(std::isfinite(s), "samples are finite");
}

} // namespace voxfx::fuzz
