// voxfx — attribute voxelization (CHANG §2): per voxel, how many times it was written, the sum of
// the normals written into it, and the material absorption accumulated from those writes.
//
// CHANG duplicates every triangle once per slice its depth range spans, clips each copy to the
// slab of its slice and rasterizes it into that slice. With centre sampling this writes each
// (triangle, column) pair exactly once, into the slice holding the triangle's depth at the column
// centre: the same fragments as ED06 surface voxelization, so Coverage::Center is the faithful
// mode here. Coverage::Conservative instead writes every voxel the triangle touches (CHANG's
// widened slabs taken to the limit: no missed voxels, more doubled ones).
//
// Layout: flat arrays of W * H * D entries in the slicemap's order: column c = y * W + x
// (row-major), the D voxels of a column consecutive, voxel (x, y, s) at index c * D + s.
// Each tile of rows has one owner, so the sums are deterministic for any thread count (the
// triangles of a tile are visited in index order).
//
// EXPERIMENTAL until the renderer issue closes.
// Thread-safety: calls may run concurrently (no global state) as long as no call writes what
// another reads; voxelizeAttribute* spread one call over worker threads (`threads`) themselves.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {

struct AttributeOptions {
    /// Center: one write per triangle and covered column centre (CHANG, default).
    /// Conservative: one write per triangle and touched voxel.
    Coverage coverage = Coverage::Center;
    /// Also accumulate normals (12 bytes per voxel; the glass renderer needs them, shadows do not).
    bool normals = true;
    /// Material channel: one material index per triangle (a glass renderer reads the index of
    /// refraction and attenuation of the voxel's material from it), or empty (no channel, no memory).
    std::span<const uint32_t> triangleMaterial;
    /// ED06 local slicing: each column's D slices cover only the depth range its geometry spans.
    Slicing slicing = Slicing::Uniform;
    int threads = 0;              ///< worker threads, 0 = all; results are identical for every value
    Progress* progress = nullptr; ///< polled between tiles; may cancel. Not owned.
};

/// The result of an attribute voxelization. Value type; all arrays have voxelCount() entries except
/// normalSum, which is empty when normals were not requested.
struct AttributeGrid {
    Frame frame;
    std::vector<uint16_t> count;   ///< writes per voxel, saturating at 65535
    std::vector<float> absorption; ///< sum over the voxel's writes of the triangle's absorption
    std::vector<Vec3f> normalSum;  ///< sum over the voxel's writes of the unit triangle normal (CCW)
    /// Material of the voxel's first write (the lowest triangle index written into it: triangles are
    /// visited in index order), kNoMaterial where nothing was written; empty when
    /// AttributeOptions::triangleMaterial was.
    std::vector<uint32_t> material;
    static constexpr uint32_t kNoMaterial = 0xffffffffu;

    int64_t voxelCount() const { return frame.columnCount() * frame.depth(); }
    int64_t index(int64_t x, int64_t y, int64_t s) const {
        return (y * frame.width() + x) * frame.depth() + s;
    }
    /// Unit average normal of voxel i (zero when it was never written or the normals cancel).
    Vec3f normal(int64_t i) const;
    /// Cells written at least once, as a slicemap in the same frame.
    BitGrid occupancy() const;
    /// Total number of writes (sum of count).
    int64_t writeCount() const;
};

/// Bytes an attribute grid of this frame needs (to check before voxelizing).
uint64_t attributeGridBytes(const Frame& frame, bool normals, bool materials = false);

/// Voxelizes `mesh` into `frame`, storing per-voxel attributes. `triangleAbsorption` holds one
/// value per triangle (any unit; e.g. optical depth per write) added to the voxel on each write,
/// or is empty (absorption stays zero). For local slicing the returned frame carries the per-column
/// ranges. Throws voxfx::Error for an invalid mesh, a span of the wrong size, or a grid larger than
/// the available memory. Cost: O(triangles + writes + voxels) time, attributeGridBytes memory.
AttributeGrid voxelizeAttributes(const MeshView& mesh, const Frame& frame,
                                 std::span<const float> triangleAbsorption,
                                 const AttributeOptions& options = {});

/// The same writes in sparse form: per column, only the voxels written at least once, in slice order
/// (compressed sparse rows). For light grids that are mostly empty (shadows through foliage) this
/// costs O(writes) instead of O(voxels). Sums are bit-identical to voxelizeAttributes (same order).
struct AttributeColumns {
    Frame frame;
    std::vector<int64_t> offsets;  ///< columnCount() + 1; column c's entries are [offsets[c], offsets[c+1])
    std::vector<uint32_t> slice;   ///< per entry, ascending within a column
    std::vector<uint16_t> count;   ///< per entry: writes, saturating at 65535
    std::vector<float> absorption; ///< per entry: summed absorption of the writes

    int64_t entryCount() const { return int64_t(slice.size()); }
};

/// Sparse attribute voxelization (counts and absorption; no normals, no materials), with the options and
/// errors of voxelizeAttributes (options.normals is ignored).
AttributeColumns voxelizeAttributeColumns(const MeshView& mesh, const Frame& frame,
                                          std::span<const float> triangleAbsorption,
                                          const AttributeOptions& options = {});

} // namespace voxfx
