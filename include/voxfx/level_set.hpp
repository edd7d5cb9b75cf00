// voxfx — operations on narrow-band level sets (signed distance fields as OpenVDB keeps them): CSG
// and offsets, with OpenVDB's own tools (#23: "use OpenVDB's own tools for what it already does
// on sparse trees") rather than ours.
//
// EXPERIMENTAL until #23 closes.
//
// A LevelSet is an OpenVDB FloatGrid of class level set held by the voxfx_vdb module (loaded on
// first use, as for .vdb files; every operation may throw voxfx::Error when it is missing): signed
// distances in world units, negative inside, active voxels within the band, inactive ones holding
// +background outside and -background inside (background = the band's half-width in world units),
// and the grid's own transform from index (i, j, k) to world. voxfx's signed distance fields
// (voxfx/sdf.hpp) become one with LevelSet::fromField (the grid writeSdf writes to .vdb, with the
// same transform: index (i, j, k) is voxel (i, j, k), its centre at lo + (i + 0.5) * cell), and a
// mesh becomes one on another level set's lattice with levelSetOfMesh.
//
// What is exact:
//   - CSG (levelSetCsg): OpenVDB's csgUnion, csgIntersection and csgDifference take, voxel by
//     voxel, min(a, b), max(a, b) and max(a, -b) of the two fields' values (each input's value
//     where it is inactive being its +-background). The sign is therefore exactly the combined
//     solid's wherever the inputs' signs are exact; the value is the exact distance to the result
//     where the nearest point of the result's surface lies on one input's part of it (everywhere
//     outside a union, everywhere inside an intersection), and otherwise a bound (|value| <= the
//     true distance: near the creases where the two surfaces meet). When the two transforms
//     differ, b is first resampled onto a's by OpenVDB's resampleToMatch, which rebuilds a level
//     set (meshes the zero crossing, then measures distances to that mesh): approximate, within
//     about a voxel of the surface's position and slightly rounding sharp edges.
//   - A mesh on a level set's lattice (levelSetOfMesh): the mesh's signed distance field
//     (voxfx/sdf.hpp: exact distances, the sign of its solid voxelization) evaluated at the
//     lattice's own voxel centres, with the lattice's band and background, in a grid whose transform
//     is a copy of the lattice's. So the CSG of a level set and a mesh (levelSetCsg with the
//     mesh's level set, or evaluateLevelSetCsg with mesh leaves) needs no resampling: it is exact
//     as above, voxel by voxel min / max of the level set's values and the mesh's exact distances.
//     The centres are computed as lo + (i + 0.5) * cell in a frame that tiles the lattice's voxels,
//     so they lie within a few double ulps of indexOrigin() + (i, j, k) * voxelSize().
//   - Offset of a mesh's field (offsetSignedDistanceField): the field is computed with the band
//     widened by |distance| and `distance` subtracted from every value, so the band keeps its width
//     around the new surface. The zero level is exactly the offset surface (the points at
//     `distance` from the solid, or at -distance inside it), the sign that of the offset solid,
//     and |value| is the exact distance to it on the side away from the original surface
//     (outside when growing, inside when shrinking); on the other side it is a bound (|value| <=
//     the true distance, equal wherever the offset surface is smooth: it differs near the creases
//     an offset makes in concave parts), as for any level set offset by subtraction. Float
//     rounding: the field's value (within a float ulp of the exact distance) minus `distance`,
//     rounded once more.
//   - Offset of a level set (offsetLevelSet): OpenVDB's LevelSetFilter::offset, in steps of at most
//     half a voxel each followed by the tracker's renormalization: approximate (the tracker's
//     finite differences), works on any level set read from a file.
//
// Thread-safety: a LevelSet is a value (copies are deep). Const members may be called concurrently;
// operations use OpenVDB's worker threads (inside the caller's withThreads limit).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "voxfx/csg.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/sdf.hpp"

namespace voxfx {

class LevelSet {
public:
    /// An empty level set without a grid (every query throws voxfx::Error).
    LevelSet();
    ~LevelSet();
    LevelSet(const LevelSet& o);
    LevelSet& operator=(const LevelSet& o);
    LevelSet(LevelSet&& o) noexcept;
    LevelSet& operator=(LevelSet&& o) noexcept;

    /// The level set writeSdf(field, "x.vdb") writes, named `name`. voxfx::Error for a full field
    /// (SdfOptions::full: not a narrow band) or an empty one.
    static LevelSet fromField(const SignedDistanceField& field, const std::string& name = "sdf");

    bool valid() const { return grid_ != nullptr; }
    /// The band's half-width in world units: inactive voxels hold +background or -background.
    float background() const;
    /// World size of a voxel along the index axes.
    Vec3d voxelSize() const;
    /// The band's half-width in voxels (background / the voxel's x size).
    double bandVoxels() const;
    /// Whether the transform is a scale and a translation (index (i, j, k) at
    /// indexOrigin() + (i, j, k) * voxelSize(), per axis); voxfx's fields always are.
    bool axisAligned() const;
    /// World position of index (0, 0, 0) (for voxfx's fields: the centre of voxel (0, 0, 0)).
    Vec3d indexOrigin() const;
    int64_t activeCount() const;
    /// The active voxels' index box, inclusive (lo > hi when there is none).
    void activeBounds(Vec3i& lo, Vec3i& hi) const;
    /// The value at index (i, j, k) (any index; +-background away from the band).
    float value(int64_t i, int64_t j, int64_t k) const;
    /// value() at many indices: out[n] is the value at indices[n] (out.size() == indices.size(),
    /// else voxfx::Error). In parallel, with OpenVDB's cached accessors: much cheaper per index
    /// than value(), cheapest when neighbouring entries are nearby voxels.
    void values(std::span<const std::array<int32_t, 3>> indices, std::span<float> out) const;
    /// The active voxels: indices and values, in the tree's order.
    void activeVoxels(std::vector<std::array<int32_t, 3>>& indices, std::vector<float>& values) const;
    /// The grid's name.
    std::string name() const;

    /// For io/: the module's handle, and a level set owning one.
    const void* handle() const { return grid_; }
    void* handle() { return grid_; }
    static LevelSet adopt(void* grid);

private:
    void* grid_ = nullptr;
};

/// The first bool, float or double grid of a .vdb file, which must be a FloatGrid of class level
/// set with a positive background; voxfx::Error naming the path and what the grid is otherwise
/// (a BoolGrid, a fog volume, ...), or when the file cannot be read.
LevelSet readLevelSet(const std::string& path);
/// Whether `path` is a .vdb file whose first bool, float or double grid is a float level set
/// (reads the file; voxfx::Error when it cannot). *what, when given, says what the grid is when
/// it is not.
bool isLevelSetFile(const std::string& path, std::string* what = nullptr);
/// Writes the level set as a .vdb file (atomically), under its own name, class and transform.
void writeLevelSet(const LevelSet& levelSet, const std::string& path);

/// a op b (see the file comment): Union, Intersection, Difference with OpenVDB's csgUnion,
/// csgIntersection, csgDifference; Xor as union minus intersection. The result has a's transform
/// and background; *resampled (when given) is set when b had to be resampled onto a's transform.
LevelSet levelSetCsg(const LevelSet& a, const LevelSet& b, CsgOp op, bool* resampled = nullptr);
/// The level set of `mesh` on the lattice of `lattice`: its signed distance field
/// (signedDistanceField) at the lattice's voxel centres, index (i, j, k) at lattice.indexOrigin() +
/// (i, j, k) * voxelSize(), in the voxels within the mesh's bounds plus the band (the rest is +-the
/// background: outside the mesh it is +, which is right since the band does not reach there). The
/// band and background are the lattice's (options.bandVoxels is ignored): active exactly where the
/// distance is below lattice.background(). The transform is a copy of the lattice's, so
/// levelSetCsg(lattice, result) and the reverse combine without resampling (see the file comment
/// for what is exact); the name is the lattice's. options.fill, threads, brickSize and progress are
/// signedDistanceField's (Fill::Auto: parity for closed meshes, the generalized winding number for
/// open ones). `meshOrigin` is the world position of the mesh's coordinate origin (world = meshOrigin
/// + position: for a mesh kept relative to a point near it). Throws voxfx::Error for an empty
/// lattice, one that is not axis-aligned (LevelSet::axisAligned) or whose voxels are not cubes, a
/// full SDF (options.full), a mesh signedDistanceField refuses, or one that lies beyond OpenVDB's
/// 32-bit indices on the lattice. A mesh without triangles gives a level set without active voxels.
/// Cost: signedDistanceField's over the mesh's bounds on the lattice's cells.
LevelSet levelSetOfMesh(const MeshView& mesh, const LevelSet& lattice, const SdfOptions& options = {},
                        const Vec3d& meshOrigin = {0, 0, 0});

/// A CSG expression (voxfx/csg.hpp) over level sets, folded left as voxfx::evaluateCsg; the
/// first leaf's transform is the result's. *resampledLeaves (when given) receives the number of
/// operands resampled onto it. Mesh operands: `leaf` returns levelSetOfMesh on the lattice of
/// a level-set leaf, and nothing is resampled.
LevelSet evaluateLevelSetCsg(const CsgNode& node, const std::function<LevelSet(const std::string&)>& leaf,
                             int* resampledLeaves = nullptr);

/// OpenVDB's LevelSetFilter::offset: the surface moves `distance` world units outwards (inwards
/// when negative); approximate (see the file comment). voxfx::Error for a non-finite distance or
/// a grid whose voxels are not cubes.
LevelSet offsetLevelSet(const LevelSet& levelSet, double distance);

/// The signed distance field of the solid of `mesh` offset by `distance` world units (grown when
/// positive, shrunk when negative): signedDistanceField(mesh, frame, options) with the band
/// widened by |distance|, minus `distance`, with the band of options.bandVoxels around the new
/// surface (see the file comment for what is exact). With options.full every value is offset and
/// the background grows by |distance|. The frame must leave room for a grown surface's band.
/// Throws as signedDistanceField, and voxfx::Error for a non-finite distance.
SignedDistanceField offsetSignedDistanceField(const MeshView& mesh, const Frame& frame, double distance,
                                              const SdfOptions& options = {});

} // namespace voxfx
