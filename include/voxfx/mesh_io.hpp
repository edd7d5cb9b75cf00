// voxfx — loading triangle meshes: OFF, OBJ, PLY, STL, glTF 2.0 (.gltf/.glb) and what Assimp reads;
// writing the surface meshes that marching cubes extracts (voxfx/surface_mesh.hpp).
// Thread-safety: loads of different (or the same) files may run concurrently and writes of
// different paths too; readers run on the calling thread.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "voxfx/mesh.hpp"
#include "voxfx/surface_mesh.hpp"

namespace voxfx {

struct MeshLoadReport {
    std::string format; ///< e.g. "off", "obj", "ply", "stl", "gltf"
    std::size_t fileBytes = 0;
    std::size_t inputTriangles = 0;    ///< after triangulating polygons, before dropping degenerates
    std::size_t degenerateRemoved = 0; ///< dropped by removeDegenerateTriangles
};

/// Loads every triangle of a mesh or scene file into one Mesh, with the scene's node transforms
/// applied (glTF, OBJ groups, ...). Polygons are triangulated (fan), points and lines ignored,
/// degenerate triangles removed and counted in `report`.
/// Throws voxfx::Error naming the file for: unreadable or missing file, unknown format,
/// malformed or truncated content (with the line or byte offset where known), NaN/Inf
/// coordinates, out-of-range indices, and a file without any triangle.
Mesh loadMesh(const std::string& path, MeshLoadReport* report = nullptr);

/// loadMesh, keeping the file's per-vertex colours: `vertexColors` receives one RGB colour per
/// vertex of the returned mesh (whose vertices are the file's, in order) from PLY red/green/blue
/// properties (integer types over their largest value: uchar / 255) and COFF vertex lines (3 or 4
/// components, integers on a 0..255 scale, decimals in 0..1; alpha dropped); it is left empty
/// when the file has none, and for the other formats (OBJ, STL, Assimp's). A malformed colour
/// (COFF: not 3 or 4 numbers) is an error naming the line, as for any other value.
Mesh loadMesh(const std::string& path, MeshLoadReport* report, std::vector<Vec3f>* vertexColors);

/// Writes the mesh by extension: .ply (binary little-endian, positions and normals, triangles
/// as uchar-counted int lists) or .obj (v, vn and f a//a lines). Atomic. Throws voxfx::Error.
void writeSurfaceMesh(const SurfaceMesh& mesh, const std::string& path);

} // namespace voxfx
