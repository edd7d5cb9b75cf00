// voxfx — the generalized winding number, fast (internal header): the one evaluator behind
// contains()'s winding method and Fill::Gwn.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

/// Barill et al. 2018, first order: a bounding-volume hierarchy over the triangles; a cluster
/// whose bounding sphere (radius r, around its area-weighted centroid) is farther than beta * r
/// from the point contributes its dipole (vector area at the centroid), nearer ones are summed
/// exactly (Van Oosterom-Strackee). beta = 0 sums every triangle. Immutable after build(): at()
/// may be called from many threads.
struct WindingNode {
    Vec3d centre;
    Vec3d area; ///< sum of (b - a) x (c - a) / 2
    double radius = 0;
    uint32_t begin = 0, end = 0;
    int32_t left = -1, right = -1;
};

struct WindingTree {
    std::vector<WindingNode> nodes;
    std::vector<std::array<Vec3d, 3>> triangles; ///< in leaf order
    double beta = 2.0;

    void build(const MeshView& mesh, double betaValue);
    /// The winding number at p (sum of solid angles / 4 pi); 0 for an empty tree.
    double at(const Vec3d& p) const;

private:
    int32_t split(const std::vector<std::array<Vec3d, 3>>& tris, const std::vector<Vec3d>& centroid,
                  std::vector<uint32_t>& order, uint32_t begin, uint32_t end);
};

/// Fill::Gwn: the cells whose centre has a winding number |w| >= 0.5 (`tree` built from `mesh`;
/// `surface` its conservative surface in `frame`). Not every centre is evaluated: blocks of cells
/// (16, 8, 4, 2 cells wide) are decided from their eight corner cells. Across the surface the
/// winding number w jumps by exactly the sign of the crossing, so C = w - N, with N the signed
/// count of the column's crossings in front of the centre (the parity fill's fragments), is
/// continuous there and harmonic off the "curtains" behind the boundary edges (or, counting from
/// the far end, in front of them); zero on a closed mesh. A block that no curtain reaches, kept a
/// cell or two from every boundary edge, whose corners' C lie within 0.4 of one integer k, takes
/// N + k != 0 for every cell. Blocks a curtain crosses go column by column (no curtain is crossed
/// along a column) with the same test on runs of cells; blocks with no surface cell in or next to
/// them take their corners' answer when those agree (the winding number is smooth away from the
/// surface). Other blocks are split, down to single cells evaluated alone. Cost ~ (cells near the
/// boundary edges or where w is near 0.5 + blocks) x one evaluation. Needs an orthographic frame
/// with uniform slicing and the mesh behind the near plane for the counts; otherwise only the
/// last two rules apply. Deterministic for every thread count. `progress` (may be null) is polled
/// after each tile of 16 x 16 columns; false cancels with voxfx::Error.
BitGrid gwnFillInside(const Frame& frame, const MeshView& mesh, const WindingTree& tree,
                      const BitGrid& surface, Progress* progress = nullptr);

} // namespace voxfx::detail
