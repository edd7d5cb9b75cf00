// voxfx — signed distance fields: the exact Euclidean distance from voxel centres to a mesh's
// triangles, in a narrow band around the surface (as OpenVDB's level sets) or in the whole grid,
// negative inside, with the sign of the solid voxelization.
//
// Grid: an orthographic frame (fitFrame), voxel (i, j, k) (indices along world x, y, z) with its
// centre at lo + (i + 0.5, j + 0.5, k + 0.5) * cell, as every voxfx grid.
// Distance: |value| is the distance from the centre to the nearest triangle, exact in the sense of
// voxfx/distance.hpp (double precision, then rounded to float: within one float ulp of the value,
// plus a few double ulps of the coordinates). It is computed by the one closest-point query of
// voxfx/distance.hpp, so it equals closestPoints(mesh, centres)[..].distance rounded to float.
// Sign: negative where the voxel is inside, i.e. where voxelize(mesh, frame, {Solid, fill}) sets the
// voxel (with the frame re-sliced along z, the voxelizer's default): the sign bit of every value
// (-0.0 included, for a centre on the surface that the tie rule puts inside) is that voxel's bit,
// so the field and the occupancy never disagree. The fill is parity for closed meshes (exact) and
// gwn for open ones (generalized winding number >= 0.5) unless one is given.
// Band: with band width W = bandVoxels * (the largest cell edge), the voxels whose distance is below
// W are active and hold it; every other voxel is inactive and holds +W or -W (OpenVDB's background
// convention for level sets). Which voxels to compute comes from the surface, not from testing
// every voxel: the conservative voxelization dilated by ceil(W / cell - 1/2) cells per axis holds
// every centre closer than W to a triangle; blocks of 8^3 voxels with such cells gather the
// triangles within W of them from the hierarchy and evaluate those at their candidate voxels. So
// the time grows with the surface (the band's voxels), and blocks without band voxels cost a look
// at their solid bits only.
// Full (SdfOptions::full): every voxel is active and exact, at any distance: each 8^3 block finds
// the distance d at its centre, gathers the triangles that can be nearest to any of its voxels
// (within d + its half diagonal) and splits itself into smaller blocks while that set is large
// (far from concave surfaces many triangles are nearly equidistant). Cost grows with the volume.
//
// Bricks: the field is built brick by brick (SdfOptions::brickSize voxels a side, in parallel): a
// brick takes its solid bits and the conservative surface of the triangles within the band of it,
// voxelized in the brick grown by the dilation, so no surface grid of the whole mesh is made and
// bricks far from the surface cost a look at their solid bits (none when the brick is uniform).
// The solid bits come brick by brick from the tiled voxelizer (voxfx/tiled.hpp: parity, winding
// and gwn carried down each stack of bricks), the same bits as the dense voxelization's, so no
// grid of the whole volume is made: memory ~ a few bricks per thread plus the result (the band's
// leaves, 2 KiB per 8^3 block), growing with the surface (to a file, voxfx/sdf_io.hpp's
// writeSdf(mesh, ...) streams a .vdb brick by brick into its tree instead of keeping the
// result). The flood and vote fills need the whole grid (voxfx::wholeGridReason) and take them
// from one dense solid voxelization, N^3 / 8 bytes.
// Thread-safety: pure functions; blocks of a layer are spread over worker threads, one owner per
// block, so the result does not depend on the thread count. A SignedDistanceField is a value.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

struct SdfOptions {
    /// Half-width of the narrow band in voxels (>= 1; OpenVDB's default is 3): voxels closer than
    /// bandVoxels * (largest cell edge) to the surface are active. Ignored when `full`.
    double bandVoxels = 3.0;
    /// Every voxel active and exact (see the file comment); the background is then the length
    /// of the grid's diagonal, more than any distance in it.
    bool full = false;
    /// The inside test behind the sign (Fill::Parity, Gwn, Flood, Vote, Winding). Auto: parity for
    /// closed meshes (voxfx::analyzeTopology), gwn otherwise (not flood, as voxelize()'s Auto: the
    /// distance is exact, and the gwn inside closes holes without a voxel's tolerance).
    Fill fill = Fill::Auto;
    /// Edge of the bricks the grid is processed in, in voxels (a positive multiple of 8): each
    /// brick voxelizes the surface of its own triangles, and bricks run in parallel. Results are
    /// identical for every value; memory per brick in flight ~ (brickSize + 2 band)^3 / 8 bytes.
    int64_t brickSize = 128;
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
    /// Polled between bricks; may cancel (voxfx::Error "cancelled"). Not owned.
    Progress* progress = nullptr;
};

/// An 8 x 8 x 8 block of voxels starting at `origin` (world-axis voxel indices, multiples of 8).
/// Voxel origin + (i, j, k) is entry n = (i << 6) | (j << 3) | k (z fastest: OpenVDB's leaf
/// order): its value is values[n] and it is active when bit n % 64 of active[n / 64] is set.
/// Entries outside the grid are inactive and hold the background.
struct SdfLeaf {
    Vec3i origin;
    std::array<uint64_t, 8> active{};
    std::array<float, 512> values{};
};

/// A run of 8^3 blocks along x, wholly inside the grid, inside the solid and without a band voxel:
/// blocks (x0 .. x1 - 1, y, z) in block units; every voxel in them is inactive at -background.
struct SdfInsideRun {
    int32_t x0 = 0, x1 = 0, y = 0, z = 0;
};

struct SignedDistanceField {
    Frame frame;           ///< orthographic, sliced along z, uniform
    double background = 0; ///< band width W (world units); inactive voxels hold +W or -W
    double bandVoxels = 0; ///< W in voxels of the largest cell edge (0 when full)
    bool full = false;
    Fill fill = Fill::Parity;             ///< the inside test behind the sign
    std::vector<SdfLeaf> leaves;          ///< ordered by (z, y, x) of the origin
    std::vector<SdfInsideRun> insideRuns; ///< ordered by (z, y, x0)

    /// Voxels along world x, y, z.
    Vec3i dims() const;
    int64_t activeCount() const;
    /// The value of voxel (i, j, k) (in range, else voxfx::Error). O(log leaves).
    float value(int64_t i, int64_t j, int64_t k) const;
    /// Every voxel's value, x fastest, then y, then z. voxfx::Error when the grid does not fit
    /// in the memory available.
    std::vector<float> dense() const;
    /// The active voxels: indices (i, j, k) and values, in leaf order.
    void activeVoxels(std::vector<std::array<int32_t, 3>>& indices, std::vector<float>& values) const;
};

/// The signed distance field of `mesh` on the voxel centres of `frame` (orthographic, axis-aligned,
/// any slicing axis: the result is sliced along z). Validates the mesh (voxfx::Error on bad
/// indices or non-finite vertices; a mesh without triangles gives an all-outside field); throws
/// voxfx::Error for a perspective or oriented frame, bandVoxels < 1 or not finite, a brick size
/// that is not a positive multiple of 8, or too little memory (the dense solid of the flood and
/// vote fills, or the tiled voxelizer's triangle lists). Cost: two voxelizations (solid, brick by
/// brick, and conservative) plus, per band voxel, the distance to the few triangles its block
/// gathered; see the file comment.
SignedDistanceField signedDistanceField(const MeshView& mesh, const Frame& frame,
                                        const SdfOptions& options = {});

} // namespace voxfx
