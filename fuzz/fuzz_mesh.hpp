// voxfx — what the mesh-reader fuzz targets share: parse, then check the mesh a reader returns.
#pragma once

#include "fuzz_target.hpp"
#include "io/mesh_formats.hpp"

namespace voxfx::fuzz {

/// Runs a mesh parser over the bytes; an accepted file must give whole triangles whose indices
/// all name a vertex of the mesh, and non-finite vertices that exist.
template <class Parse> void fuzzMeshParser(std::span<const uint8_t> data, const char* path, Parse parse) {
    expectCleanError([&] {
        const detail::ParsedMesh parsed = parse(asText(data), std::string(path));
        const Mesh& m = parsed.mesh;
        require(m.indices.size() % 3 == 0, "indices form whole triangles");
        for (const uint32_t i : m.indices) require(i < m.positions.size(), "every index names a vertex");
        for (const auto& entry : parsed.nonFiniteVertices)
            require(entry.first < m.positions.size(), "non-finite vertices exist");
    });
}

} // namespace voxfx::fuzz
