// voxfx — attribute voxelization (CHANG §2): per voxel, the channels a use asks for: how many
// times it was written, the sum of the normals written into it, the absorption accumulated from
// those writes, and the material (id, refraction index, RGB attenuation coefficient) of its first
// write.
//
// CHANG duplicates every triangle once per slice its depth range spans, clips each copy to the
// slab of its slice and rasterizes it into that slice. With centre sampling a piece clipped to
// slab s covers a column centre exactly when the triangle covers it at a depth inside the slab, so
// the writes are: per (triangle, covered column centre), the slices whose slab holds the
// triangle's depth there. With slabOverlap = 0 that is one slice (the same fragments as ED06
// surface voxelization). CHANG widens the slabs so that neighbouring voxels overlap: with
// slabOverlap = w each slab [s, s + 1) grows to [s - w, s + 1 + w) (in slices), and a centre is
// written into every slice whose widened slab holds its depth. Steep triangles, whose depth jumps
// by several slices from one column centre to the next, then miss fewer voxels, at the price of
// doubled ones (voxels the triangle does not pass through; CHANG's refraction skips them with its
// angle threshold). Coverage::Conservative writes every voxel whose closed box the triangle meets:
// no missed voxels at all, steep triangles included (slabOverlap widens its spans too).
//
// Channels (AttributeChannels) are chosen per use, so each pays only for what it reads: absorption
// shadows store count + absorption (6 bytes per voxel), the glass renderer normals + material id
// (16 bytes); everything is 38 bytes per voxel.
//
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

/// The per-voxel channels of an AttributeGrid (bytes per voxel in brackets). A channel is stored
/// when it is asked for and, for absorption and material id, when its per-triangle input is given.
struct AttributeChannels {
    bool count = true;        ///< [2] writes per voxel, saturating at 65535
    bool absorption = true;   ///< [4] sum of the triangles' absorption (needs triangleAbsorption)
    bool normals = true;      ///< [12] sum of the unit triangle normals
    bool material = true;     ///< [4] material id of the first write (needs triangleMaterial)
    bool ior = false;         ///< [4] refraction index of the first write's material (needs materials)
    bool attenuation = false; ///< [12] RGB attenuation coefficient of that material (needs materials)

    /// CHANG §3 absorption shadows: count and absorption only.
    static AttributeChannels shadows() { return {true, true, false, false, false, false}; }
    /// The voxel glass methods: normals and material id (occupancy from the id).
    static AttributeChannels glass() { return {false, false, true, true, false, false}; }
    /// Every channel.
    static AttributeChannels all() { return {true, true, true, true, true, true}; }
    /// Bytes per voxel of these channels.
    uint64_t bytesPerVoxel() const;
};

/// A material as the attribute channels see it.
struct AttributeMaterial {
    float ior = 1.5f;                    ///< refraction index
    Vec3f attenuation{0.0f, 0.0f, 0.0f}; ///< Beer–Lambert coefficient per world unit, RGB
};

struct AttributeOptions {
    /// Center: per triangle and covered column centre, the slice(s) of its depth (CHANG, default).
    /// Conservative: one write per triangle and touched voxel.
    Coverage coverage = Coverage::Center;
    /// CHANG's widened slabs: each slab grows by this many slices on both sides (>= 0, finite).
    double slabOverlap = 0;
    /// What to store (see AttributeChannels).
    AttributeChannels channels;
    /// One material id per triangle (the material, ior and attenuation channels read it), or empty.
    std::span<const uint32_t> triangleMaterial;
    /// Material table indexed by the ids of triangleMaterial: needed by the ior and attenuation
    /// channels, ignored otherwise.
    std::span<const AttributeMaterial> materials;
    /// One unit normal per vertex (smooth shading), or empty. With them the normals channel sums,
    /// per write, the normal interpolated at the point of the triangle nearest the voxel's centre
    /// (barycentric weights of its projection, negative ones clamped to 0) instead of the face
    /// normal: the normal a renderer shades the surface with, not its facets'.
    std::span<const Vec3f> vertexNormals;
    /// ED06 local slicing: each column's D slices cover only the depth range its geometry spans.
    Slicing slicing = Slicing::Uniform;
    int threads = 0;              ///< worker threads, 0 = all; results are identical for every value
    Progress* progress = nullptr; ///< polled between tiles; may cancel. Not owned.
};

/// The result of an attribute voxelization. Value type; each channel's array has voxelCount()
/// entries when the channel was stored (see channels()) and is empty otherwise.
struct AttributeGrid {
    Frame frame;
    std::vector<uint16_t> count;   ///< writes per voxel, saturating at 65535
    std::vector<float> absorption; ///< sum over the voxel's writes of the triangle's absorption
    std::vector<Vec3f> normalSum;  ///< sum over the voxel's writes of the unit triangle normal (CCW)
    /// Material of the voxel's first write (the lowest triangle index written into it: triangles are
    /// visited in index order), kNoMaterial where nothing was written.
    std::vector<uint32_t> material;
    std::vector<float> ior;         ///< refraction index of the first write's material, 0 where unwritten
    std::vector<Vec3f> attenuation; ///< attenuation coefficient of that material, 0 where unwritten
    static constexpr uint32_t kNoMaterial = 0xffffffffu;

    /// The channels this grid holds.
    AttributeChannels channels() const;
    /// Bytes held by the channels.
    uint64_t bytes() const;
    /// True when voxel i was written at least once. Needs the count, material or ior channel (false
    /// everywhere without them).
    bool written(int64_t i) const {
        if (!count.empty()) return count[size_t(i)] != 0;
        if (!material.empty()) return material[size_t(i)] != kNoMaterial;
        return !ior.empty() && ior[size_t(i)] != 0;
    }

    int64_t voxelCount() const { return frame.columnCount() * frame.depth(); }
    int64_t index(int64_t x, int64_t y, int64_t s) const {
        return (y * frame.width() + x) * frame.depth() + s;
    }
    /// Unit average normal of voxel i (zero when it was never written or the normals cancel).
    Vec3f normal(int64_t i) const;
    /// Cells written at least once (see written()), as a slicemap in the same frame. Throws
    /// voxfx::Error when the grid has none of the count, material and ior channels.
    BitGrid occupancy() const;
    /// Total number of writes (sum of count; 0 without the count channel).
    int64_t writeCount() const;
};

/// Bytes an attribute grid of this frame with these channels needs (to check before voxelizing).
uint64_t attributeGridBytes(const Frame& frame, const AttributeChannels& channels);

/// Voxelizes `mesh` into `frame`, storing per-voxel attributes. `triangleAbsorption` holds one
/// value per triangle (any unit; e.g. optical depth per write) added to the voxel on each write,
/// or is empty (no absorption channel). For local slicing the returned frame carries the per-column
/// ranges. Throws voxfx::Error for an invalid mesh, a span of the wrong size (absorption, materials,
/// vertex normals), a material id outside
/// the table, a negative or non-finite slabOverlap, or a grid larger than the available memory. Cost:
/// O(triangles + writes + voxels) time, attributeGridBytes memory.
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
/// errors of voxelizeAttributes (options.channels is ignored).
AttributeColumns voxelizeAttributeColumns(const MeshView& mesh, const Frame& frame,
                                          std::span<const float> triangleAbsorption,
                                          const AttributeOptions& options = {});

} // namespace voxfx
