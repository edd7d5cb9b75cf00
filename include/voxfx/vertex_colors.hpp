// voxfx — per-vertex colours voxelized: the average colour of the surface in each voxel, for
// coloured datasets (a consumer of the one rasterizer, with the writes of attribute voxelization,
// voxfx/attribute_grid.hpp, CHANG §2).
//
// EXPERIMENTAL until #35 closes.
//
// The writes are attribute voxelization's with slabOverlap 0: Coverage::Center, per triangle and
// covered column centre, the voxel of the triangle's depth there (ED06 surface voxels);
// Coverage::Conservative, every voxel whose closed box the triangle meets. Each write adds the
// triangle's colour at the point nearest the voxel's centre: the colours of its corners weighted
// by the barycentric coordinates of the centre's projection onto the triangle's plane, negative
// weights set to 0 and the rest renormalized to sum 1 (the point of the triangle nearest the
// centre when the projection falls outside it, near enough: exact inside the triangle and along
// the normals of its edges' interiors). A voxel's colour is the mean over its writes; voxels
// without a write hold 0 and count 0.
//
// Determinism: tiles own their rows and visit triangles in index order, so the float sums, and
// the colours, are the same for every thread count.
// Thread-safety: a pure function of its inputs; it uses worker threads (`threads`).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {

struct VertexColorOptions {
    Coverage coverage = Coverage::Center;
    int threads = 0;              ///< worker threads, 0 = all; results are identical for every value
    Progress* progress = nullptr; ///< polled between tiles; may cancel. Not owned.
};

/// The average colour per voxel of a frame. Voxel (x, y, s) (column x, y, slice s of the frame) is
/// entry (y * width + x) * depth + s, as in AttributeGrid.
struct ColorGrid {
    Frame frame;
    std::vector<uint32_t> count; ///< writes per voxel
    std::vector<Vec3f> color;    ///< mean colour of the writes, 0 where count is 0

    int64_t voxelCount() const { return frame.columnCount() * frame.depth(); }
    int64_t index(int64_t x, int64_t y, int64_t s) const {
        return (y * frame.width() + x) * frame.depth() + s;
    }
};

/// Voxelizes the mesh's per-vertex colours into `frame` (see the file comment). `vertexColors` holds
/// one colour per vertex (any finite values: RGB in [0, 1] by convention; the mean keeps their
/// range). Throws voxfx::Error for an invalid mesh, a colour count other than the vertex count, a
/// non-finite colour of a vertex that a triangle uses, a perspective frame, or a grid larger than
/// the available memory (16 bytes per voxel). Cost: O(triangles + writes + voxels).
ColorGrid voxelizeVertexColors(const MeshView& mesh, std::span<const Vec3f> vertexColors, const Frame& frame,
                               const VertexColorOptions& options = {});

} // namespace voxfx
