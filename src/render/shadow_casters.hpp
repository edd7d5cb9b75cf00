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
    Mesh all, opaque;                             ///< every caster; the opaque ones
    std::vector<uint32_t> allMaterialIndex;       ///< per triangle of `all`
    std::map<std::array<float, 3>, Mesh> partial; ///< by shadowCrossingTransmittance: one channel each
};

/// The meshes with SceneMesh::castsShadow, in scene order.
CasterSets collectCasters(const Scene& scene);

} // namespace voxfx::detail
