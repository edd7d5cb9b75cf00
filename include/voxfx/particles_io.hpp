// voxfx — writing particle sets (voxfx/particles.hpp): PLY or CSV.
// Thread-safety: writes of different paths may run concurrently; runs on the calling thread.
#pragma once

#include <string>

#include "voxfx/particles.hpp"

namespace voxfx {

/// Writes positions (and velocities) by extension: .ply (binary little-endian vertices with
/// x y z vx vy vz floats) or .csv (header "x,y,z,vx,vy,vz"). Atomic. Throws voxfx::Error.
void writeParticles(const Particles& particles, const std::string& path);

} // namespace voxfx
