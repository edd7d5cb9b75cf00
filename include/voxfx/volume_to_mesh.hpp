// voxfx — marching cubes on scalar fields: a triangle mesh of the iso-surface of a level set, a
// signed distance field or any dense float array, by OpenVDB's tools::volumeToMesh (the library
// the field trusts for it, behind the voxfx_vdb module; in io/ because the module is io's).
// For a voxfx::VoxelGrid's occupancy or density, see voxfx/surface_mesh.hpp (extractSurface).
//
// EXPERIMENTAL until #35 closes.
//
// Conventions:
//   - Inside is where the field is below the iso value (signed distances: voxfx's convention,
//     negative inside), or above it with insideAbove (occupancy, densities, and signed distances
//     positive inside, as trimesh's). The mesh separates the two.
//   - Triangles are counter-clockwise seen from outside, so their normals (and the vertex
//     normals, area-weighted means of the triangles') point outwards: towards the outside values.
//     OpenVDB's quads are split along their 0-2 diagonal.
//   - Dense fields are samples at points: value (i, j, k) lies at origin + (i, j, k) * spacing.
//     Beyond the array the field counts as outside, so the surface is closed at the array's box
//     (a solid touching the border is capped there, between the last sample and the next).
//   - With adaptivity 0 (the default) the mesh is OpenVDB's uniform one: a closed, consistently
//     oriented surface for a closed level set (tested on spheres and meshes' fields: every edge
//     shared by two triangles in opposite directions). Adaptivity up to 1 merges polygons in flat
//     regions (fewer triangles; OpenVDB keeps the result watertight but may leave slivers).
//   - OpenVDB's mesher is dual: one vertex in each voxel the surface crosses (more in ambiguous
//     voxels, so the surface stays a manifold), at the mean of the points where the surface crosses
//     that voxel's edges (linear interpolation of the samples along each edge), and a quad around
//     each crossed edge joining the vertices of its four voxels. Vertices therefore lie near the
//     surface, not on it: within h^2 / (2 r) of a sphere of radius r for its exact distance field
//     sampled h apart (tested), within a fraction of a voxel for smooth fields in general.
//
// Thread-safety: pure functions; OpenVDB uses worker threads (within the caller's withThreads).
#pragma once

#include <cstdint>

#include "voxfx/level_set.hpp"
#include "voxfx/math.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/surface_mesh.hpp"

namespace voxfx {

struct VolumeToMeshOptions {
    /// The iso value (world units for distances). For a level set or a narrow-band SDF it must
    /// lie strictly within the band (|isovalue| < background), where the values are defined.
    double isovalue = 0;
    /// OpenVDB's adaptivity in [0, 1]: 0 keeps the uniform mesh, larger merges flat regions.
    double adaptivity = 0;
    /// Inside where values are above the iso value (occupancy, density, positive-inside SDFs)
    /// instead of below. Dense fields only (level sets are negative inside by definition).
    bool insideAbove = false;
};

/// A dense scalar field, not owned: value (i, j, k) at world position origin + (i, j, k) * spacing
/// is values[i + nx * (j + ny * k)] (x fastest: a Fortran-order [i, j, k] array), or with zFastest
/// values[(i * ny + j) * nz + k] (a C-order [i, j, k] array, as NumPy makes them).
struct ScalarFieldView {
    const float* values = nullptr;
    Vec3i dims{0, 0, 0};
    Vec3d origin{0, 0, 0};
    Vec3d spacing{1, 1, 1};
    bool zFastest = false;
};

/// The iso-surface of a dense field (see the file comment). Throws voxfx::Error for dims below 1
/// or beyond OpenVDB's 32-bit indices, a spacing that is not finite and positive, a non-finite
/// origin, iso value, adaptivity outside [0, 1], or a NaN or infinite value. A field without a
/// crossing gives an empty mesh. Cost: a few passes over the array (the voxels near the iso value
/// found by 3 x 3 x 3 minima and maxima of the inside flags, 5 bytes per voxel while it runs), a
/// sparse OpenVDB grid of those voxels' leaves, and OpenVDB's mesher over that band.
SurfaceMesh volumeToMesh(const ScalarFieldView& field, const VolumeToMeshOptions& options = {});

/// The iso-surface of a level set (in its own transform's world coordinates). Throws voxfx::Error
/// for an empty level set, an iso value outside its band, insideAbove, or adaptivity outside [0, 1].
SurfaceMesh volumeToMesh(const LevelSet& levelSet, const VolumeToMeshOptions& options = {});

/// The iso-surface of a signed distance field (voxfx/sdf.hpp): a narrow band through its level
/// set (LevelSet::fromField), a full field as a dense field of its voxel centres. insideAbove is
/// refused (the field is negative inside); the iso value must lie within a narrow band.
SurfaceMesh volumeToMesh(const SignedDistanceField& field, const VolumeToMeshOptions& options = {});

} // namespace voxfx
