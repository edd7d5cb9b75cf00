// voxfx — triangle meshes: a non-owning view for input, an owning Mesh for loaders, and checks.
// Thread-safety: Mesh is a value and MeshView a read-only view: concurrent reads are fine; the
// analysis functions are pure and run on the calling thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "voxfx/math.hpp"

namespace voxfx {

/// A non-owning view of an indexed triangle mesh, so callers never copy their data.
///
/// positions: vertexCount points of three floats each, `positionStride` bytes apart (12 for a
/// packed array; larger when positions are interleaved with other attributes).
/// indices: 3 * triangleCount vertex indices, counter-clockwise seen from outside for closed
/// meshes (orientation only matters to front/back-facing consumers; parity ignores it).
struct MeshView {
    const float* positions = nullptr;
    std::size_t vertexCount = 0;
    std::size_t positionStride = 3 * sizeof(float);
    const uint32_t* indices = nullptr;
    std::size_t triangleCount = 0;

    Vec3d vertex(std::size_t i) const {
        const float* p = reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(positions) +
                                                        i * positionStride);
        return {p[0], p[1], p[2]};
    }
    uint32_t index(std::size_t triangle, int corner) const { return indices[3 * triangle + corner]; }
};

/// An owning triangle mesh: what the loaders return.
struct Mesh {
    std::vector<Vec3f> positions;
    std::vector<uint32_t> indices; ///< 3 per triangle

    std::size_t triangleCount() const { return indices.size() / 3; }
    MeshView view() const {
        return {positions.empty() ? nullptr : &positions[0].x, positions.size(), sizeof(Vec3f),
                indices.empty() ? nullptr : indices.data(), indices.size() / 3};
    }
};

/// Bounds of the vertices referenced by triangles (unreferenced vertices and triangles with
/// out-of-range indices are ignored).
/// Empty box for a mesh without triangles.
Box3d computeBounds(const MeshView& mesh);

/// Validates a mesh at the library boundary: every index < vertexCount, every referenced vertex
/// finite. Throws voxfx::Error naming `source`, the triangle and the value otherwise.
void validateMesh(const MeshView& mesh, const std::string& source);

/// Removes triangles with a repeated vertex index or zero area (all three positions collinear,
/// tested exactly on the float coordinates). Returns the number removed.
std::size_t removeDegenerateTriangles(Mesh& mesh);

/// Edge topology of a mesh, after merging vertices with equal positions (-0 equals +0).
/// Triangles with out-of-range indices are skipped (validateMesh reports them).
struct MeshTopology {
    std::size_t edges = 0;            ///< distinct undirected edges
    std::size_t boundaryEdges = 0;    ///< used by exactly one triangle
    std::size_t nonManifoldEdges = 0; ///< used by three or more triangles
    std::size_t misorientedEdges = 0; ///< used twice in the same direction (inconsistent winding)
    /// Closed: every edge shared by exactly two triangles, traversed in opposite directions.
    bool closed() const {
        return edges > 0 && boundaryEdges == 0 && nonManifoldEdges == 0 && misorientedEdges == 0;
    }
};

/// Counts boundary, non-manifold and misoriented edges. O(V + T) with hashing.
MeshTopology analyzeTopology(const MeshView& mesh);

} // namespace voxfx
