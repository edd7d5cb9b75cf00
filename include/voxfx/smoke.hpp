// voxfx — procedural smoke: a deterministic density volume for demos.
#pragma once

#include <cstdint>

#include "voxfx/volume.hpp"

namespace voxfx {

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
