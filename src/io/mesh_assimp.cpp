// voxfx — the Assimp fallback: glTF 2.0 (.gltf/.glb) and every other format Assimp imports.
//
// Assimp flattens the node tree itself (aiProcess_PreTransformVertices multiplies each mesh by
// its node's world transform, instancing a mesh once per node that uses it) and fan-triangulates
// polygons. It is deliberately not asked to join vertices, so each mesh keeps its own vertex order;
// ValidateDataStructure runs first so that broken indices become an error instead of a crash.
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "io/mesh_formats.hpp"

namespace voxfx::detail {

Mesh loadWithAssimp(const std::string& path) {
    Assimp::Importer importer;
    const unsigned flags =
        aiProcess_ValidateDataStructure | aiProcess_Triangulate | aiProcess_PreTransformVertices;
    const aiScene* scene = importer.ReadFile(path, flags);
    if (!scene) fail(path, ": Assimp could not read the file: ", importer.GetErrorString());

    Mesh mesh;
    std::size_t vertices = 0, triangles = 0;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        vertices += scene->mMeshes[m]->mNumVertices;
        triangles += scene->mMeshes[m]->mNumFaces;
    }
    if (vertices > kMaxVertices) fail(path, ": ", vertices, " vertices, more than 32-bit indices allow");
    mesh.positions.reserve(vertices);
    mesh.indices.reserve(3 * triangles);
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh* part = scene->mMeshes[m];
        const auto base = uint32_t(mesh.positions.size());
        for (unsigned v = 0; v < part->mNumVertices; ++v) {
            const aiVector3D& p = part->mVertices[v];
            mesh.positions.push_back({p.x, p.y, p.z});
        }
        // After triangulation a face has 1, 2 or 3 corners: points and lines are not surfaces.
        for (unsigned f = 0; f < part->mNumFaces; ++f) {
            const aiFace& face = part->mFaces[f];
            if (face.mNumIndices != 3) continue;
            for (int c = 0; c < 3; ++c) {
                if (face.mIndices[c] >= part->mNumVertices)
                    fail(path, ": mesh ", m, " face ", f, ": vertex index ", face.mIndices[c],
                         " is out of range (the mesh has ", part->mNumVertices, " vertices)");
                mesh.indices.push_back(base + face.mIndices[c]);
            }
        }
    }
    return mesh;
}

bool assimpReadsExtension(const std::string& extension) {
    Assimp::Importer importer;
    return importer.IsExtensionSupported("." + extension);
}

std::string assimpExtensions() {
    Assimp::Importer importer;
    std::string list; // "*.3ds;*.obj;..."
    importer.GetExtensionList(list);
    std::string out;
    for (std::size_t i = 0; i < list.size(); ++i) {
        if (list[i] == '*') continue;
        out += list[i] == ';' ? ' ' : list[i];
    }
    return out;
}

} // namespace voxfx::detail
