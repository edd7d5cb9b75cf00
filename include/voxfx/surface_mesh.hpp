// voxfx — a triangle mesh of a grid's surface by marching cubes, so any grid can be looked at in
// a mesh viewer (experimental: the API may change until the issue closes).
//
// The scalar field is sampled at cell centres: the density map's occupancy (count / 8^L, smooth,
// default) or the raw occupancy of the bit grid (0/1 per cell, blocky). Samples outside the grid
// are 0, so every surface is closed. Cubes join the centres of 2 x 2 x 2 neighbouring cells;
// a corner is inside when its value is > iso. Each cube's polygons come from face segments:
// on every cube face the crossings are joined so the inside lies on a fixed side, and on faces
// with two diagonal inside corners the asymptotic decider (Nielson & Hamann 1991: bilinear saddle
// value vs iso) picks the pairing. Both cubes sharing a face see the same four values and make
// the same choice, so the result is watertight: every edge is shared by exactly two triangles,
// traversed in opposite directions, and triangles face outwards (counter-clockwise seen from
// the empty side). Each loop is fanned from a vertex whose diagonals never join two vertices of
// one cube face (such an edge could be picked by the neighbour as well); a loop without such a
// vertex (it passes an ambiguous face twice) is fanned around an extra vertex at its centroid.
// Vertices sit on cube edges by linear interpolation, kept at least 1% of an edge away from its
// ends so no two vertices coincide; normals are the negated, interpolated central-difference
// gradient of the field.
// Thread-safety: calls may run concurrently on shared const inputs (no global state);
// extraction uses worker threads (`threads`), writing runs on the calling thread.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "voxfx/density.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx {

/// An indexed triangle mesh with per-vertex unit normals, in world coordinates.
struct SurfaceMesh {
    std::vector<Vec3f> positions;
    std::vector<Vec3f> normals;    ///< one per position (outward)
    std::vector<uint32_t> indices; ///< 3 per triangle, counter-clockwise seen from outside

    std::size_t triangleCount() const { return indices.size() / 3; }
    MeshView view() const {
        return {positions.empty() ? nullptr : &positions[0].x, positions.size(), sizeof(Vec3f),
                indices.empty() ? nullptr : indices.data(), indices.size() / 3};
    }
};

enum class SurfaceSource : uint8_t { Density, Occupancy };
inline constexpr EnumName<SurfaceSource> kSurfaceSourceNames[] = {{"density", SurfaceSource::Density},
                                                                  {"occupancy", SurfaceSource::Occupancy}};
const char* toString(SurfaceSource s);
/// "density" or "occupancy"; throws voxfx::Error otherwise.
SurfaceSource parseSurfaceSource(const std::string& name);

struct SurfaceOptions {
    SurfaceSource source = SurfaceSource::Density;
    /// Density level (kernel 2^level, 1..5) for SurfaceSource::Density.
    int level = 1;
    /// Iso value in (0, 1): the surface separates values > iso from values <= iso.
    float iso = 0.5f;
    /// Worker threads for the density and field passes, 0 = all; the mesh is the same for any value.
    int threads = 0;
};

/// Marching cubes over the grid's field (see the file comment). The grid must be orthographic
/// and uniformly sliced (voxfx::Error otherwise); iso must lie in (0, 1). An empty grid gives an
/// empty mesh. Cost: one pass over (n + 1)^3 cubes of the field's n^3 samples (the density map
/// has 8^L times fewer samples than the grid) plus O(triangles); memory: two sample layers plus
/// the output. Vertex count ~ surface cells.
SurfaceMesh extractSurface(const VoxelGrid& grid, const SurfaceOptions& options = {});

/// Marching cubes over an already computed density map of a grid in `fineFrame`.
SurfaceMesh extractSurface(const DensityGrid& density, const Frame& fineFrame, float iso = 0.5f);

} // namespace voxfx
