// voxfx — the casters of a scene split by how they shadow (internal; the map, transmittance,
// absorption and exact shadows read them).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <vector>

#include "voxfx/mesh.hpp"
#include "voxfx/scene.hpp"

namespace voxfx::detail {

struct CasterSets {
    Mesh all, opaque;                       ///< every caster; the opaque ones
    std::vector<uint32_t> allMaterialIndex; ///< per triangle of `all`
    /// The partial occluders by what they do to light: shadowCrossingTransmittance (RGB), then
    /// shadowAttenuationCoefficient (RGB; zero but for glass). One channel each.
    std::map<std::array<float, 6>, Mesh> partial;
};

/// The meshes with SceneMesh::castsShadow, in scene order.
CasterSets collectCasters(const Scene& scene);

} // namespace voxfx::detail
