// voxfx — the Assimp fallback of loadMesh: glTF 2.0 (.gltf/.glb) and every other format Assimp
// imports, through the voxfx_assimp module. The module converts the scene (node transforms
// applied, mirrored nodes re-wound, polygons fan-triangulated); this concatenates its parts.
#include "io/mesh_formats.hpp"
#include "io/module_api.hpp"

namespace voxfx::detail {

Mesh loadWithAssimp(const std::string& path) {
    AssimpScene scene;
    std::string error;
    if (!assimpModule().load(path.c_str(), &scene, &error)) fail(path, ": ", error);

    std::size_t vertices = 0, indices = 0;
    for (const AssimpPart& part : scene.parts) {
        vertices += part.positions.size() / 3;
        indices += part.indices.size();
    }
    if (vertices > kMaxVertices) fail(path, ": ", vertices, " vertices, more than 32-bit indices allow");
    Mesh mesh;
    mesh.positions.reserve(vertices);
    mesh.indices.reserve(indices);
    for (const AssimpPart& part : scene.parts) {
        const auto base = uint32_t(mesh.positions.size());
        for (std::size_t v = 0; v + 2 < part.positions.size(); v += 3)
            mesh.positions.push_back({part.positions[v], part.positions[v + 1], part.positions[v + 2]});
        for (const uint32_t i : part.indices) mesh.indices.push_back(base + i);
    }
    return mesh;
}

bool assimpReadsExtension(const std::string& extension) {
    return assimpModule().readsExtension(extension.c_str());
}

std::string assimpExtensions() {
    std::string out;
    assimpModule().extensions(&out);
    return out;
}

} // namespace voxfx::detail
