// voxfx — walking a mixed polygon and volume scene (voxfx/volume_scene.hpp) along rays over
// fragment lists (Bornik et al. §3): the leaves flattened for the rasterizer, the segment walker
// that turns a column's fragments into surface crossings and volume segments, and empty-space
// skipping inside volume objects. The deep shadow maps (dsm/deep_shadow) and the renderer's camera
// ray casting (render/volume_pass) both walk with it.
//
// Segment classification along a ray (a column of fragment lists, FragmentLists): between two
// consecutive fragment depths the ray is inside or outside each leaf; the inside flag of a leaf
// toggles at each of its fragments (parity; front fragments enter, back fragments leave a closed
// mesh). An object's inside flag is its shape evaluated on the leaves' flags. Where an opaque or
// translucent object's flag changes the ray crosses its boundary (a surface); segments inside a
// volume object are sampled. All fragments at one depth are applied before flags are compared, so
// the shared faces of a Boolean expression's leaves are crossings of the result only where the
// result changes.
//
// Thread-safety: EmptySpace and FlatLeaves are values (concurrent reads are fine); a SegmentWalker
// is per thread.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "voxfx/fragment_list.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {

/// Empty-space skipping inside a volume object (an addition to Bornik et al., who skip only the
/// space outside the volumes' bounding geometry): the voxels in bricks of kBrick³; a brick is
/// empty when the transfer function's opacity is 0 for every value a trilinear sample taken in it
/// can have (the range of its voxels and of one more layer around it). Marching passes skip the
/// samples there, which would add nothing, so images and shadow maps are the same with it.
class EmptySpace {
public:
    static constexpr int64_t kBrick = 4;
    EmptySpace() = default;
    EmptySpace(const Volume& volume, const TransferFunction& transfer);
    /// True when the sample at world point p certainly has opacity 0: p lies in an empty brick, or
    /// outside the volume's box where samples read 0 and the opacity of 0 is 0.
    bool empty(const Vec3d& p) const {
        if (empty_.empty()) return outsideEmpty_; // no voxels: every sample reads 0
        int64_t b[3];
        for (int a = 0; a < 3; ++a) {
            // The continuous voxel coordinate as VolumeView::sample computes it.
            const double u = place_.voxelCoordinate(p, a);
            if (!(u >= 0 && u <= double(voxels_[a]))) return outsideEmpty_;
            b[a] = std::min(int64_t(u) / kBrick, bricks_[a] - 1);
        }
        return empty_[std::size_t(b[0] + bricks_[0] * (b[1] + bricks_[1] * b[2]))] != 0;
    }
    /// True when every value a linear ramp between the samples at p and q can take has opacity 0,
    /// so a pre-integrated interval (PreintegratedTransfer) from p to q is transparent: both lie
    /// outside the volume's box (samples read 0, whose opacity is 0), or both in empty bricks that
    /// touch (the same brick or neighbours, diagonals included: their value ranges share the voxels
    /// between them, so every value between the two samples lies in one of the two ranges). Points
    /// farther apart than a brick are never both "empty" here unless outside.
    bool emptyBetween(const Vec3d& p, const Vec3d& q) const {
        if (empty_.empty()) return outsideEmpty_;
        return emptyBetweenVoxel(place_.voxelCoordinates(p), place_.voxelCoordinates(q));
    }
    /// emptyBetween(p, q) given the volume's voxel coordinates of p and q (VolumeView::
    /// voxelCoordinates of the volume it was made for): the same answer.
    bool emptyBetweenVoxel(const Vec3d& up, const Vec3d& uq) const {
        if (empty_.empty()) return outsideEmpty_;
        int64_t a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
        const bool inP = brickOfVoxel(up, a), inQ = brickOfVoxel(uq, b);
        if (!inP && !inQ) return outsideEmpty_;
        if (inP != inQ) return false;
        for (int k = 0; k < 3; ++k)
            if (a[k] - b[k] > 1 || b[k] - a[k] > 1) return false;
        return empty_[std::size_t(a[0] + bricks_[0] * (a[1] + bricks_[1] * a[2]))] != 0 &&
               empty_[std::size_t(b[0] + bricks_[0] * (b[1] + bricks_[1] * b[2]))] != 0;
    }
    /// Finer than the bricks, for a march that samples the volume anyway: true when both points lie
    /// in the volume's box (voxel coordinates up and uq, VolumeView::voxelCoordinates) in cells of
    /// the sample lattice (the 2 x 2 x 2 voxel centres a trilinear sample there interpolates) that
    /// share a centre and whose centres' values all have opacity 0 over their range: every value of
    /// a linear ramp between the two samples then lies in one of the two ranges, which overlap, so
    /// the pre-integrated interval between them is exactly transparent (the march need not sample
    /// its ends). False wherever that is not known.
    bool transparentBetweenVoxel(const Vec3d& up, const Vec3d& uq) const {
        if (transparent_.empty()) return false;
        int64_t a[3], b[3];
        if (!cellOfVoxel(up, a) || !cellOfVoxel(uq, b)) return false;
        for (int k = 0; k < 3; ++k)
            if (a[k] - b[k] > 1 || b[k] - a[k] > 1) return false;
        return transparent_[std::size_t(a[0] + cells_[0] * (a[1] + cells_[1] * a[2]))] != 0 &&
               transparent_[std::size_t(b[0] + cells_[0] * (b[1] + cells_[1] * b[2]))] != 0;
    }
    /// How far the ray p + dir s (s >= 0, in the units of `dir`) runs through empty bricks from p:
    /// the s at which it enters the first brick that is not empty or leaves the volume's box (a
    /// 3D DDA over the bricks), at most maxLength; 0 where p itself lies outside the box or in a
    /// brick that is not empty. Every point of the ray before it lies in an empty brick, so a march
    /// may step over that run without sampling it.
    double emptyRun(const Vec3d& p, const Vec3d& dir, double maxLength) const;
    /// Fraction of the bricks that are empty (0 for a volume without voxels).
    double emptyFraction() const;

private:
    bool brickOfVoxel(const Vec3d& uv, int64_t b[3]) const {
        for (int a = 0; a < 3; ++a) {
            const double u = uv[a];
            if (!(u >= 0 && u <= double(voxels_[a]))) return false;
            b[a] = std::min(int64_t(u) / kBrick, bricks_[a] - 1);
        }
        return true;
    }
    // The sample lattice's cell at voxel coordinates uv (the lower of the centres a trilinear sample
    // interpolates along each axis, clamped as VolumeView::sampleVoxel clamps); false outside the box.
    bool cellOfVoxel(const Vec3d& uv, int64_t c[3]) const {
        for (int a = 0; a < 3; ++a) {
            const double u = uv[a];
            if (!(u >= 0 && u <= double(voxels_[a]))) return false;
            const double l = u - 0.5;
            c[a] = l <= 0 ? 0 : std::min(int64_t(l), cells_[a] - 1);
        }
        return true;
    }
    VolumeView place_; // the volume's placement (no values)
    int64_t voxels_[3] = {0, 0, 0}, bricks_[3] = {0, 0, 0};
    bool outsideEmpty_ = false;
    std::vector<uint8_t> empty_;
    int64_t cells_[3] = {0, 0, 0};     ///< sample lattice cells per axis: voxels - 1, at least 1
    std::vector<uint8_t> transparent_; ///< per lattice cell, x fastest: its centres' opacity is 0
};

/// Deterministic noise in [0, 1) for pixel or texel (x, y) and a salt naming the pass: the phase
/// by which volume ray casting and the deep shadow map's walk offset their first sample (a
/// jittered start turns the rings that equal steps from each segment's start draw into fine
/// noise). A hash, so images are the same for every thread count.
inline double sampleJitter(int64_t x, int64_t y, uint64_t salt) {
    uint64_t h = uint64_t(x) * 0x9E3779B97F4A7C15ull + uint64_t(y) * 0xC2B2AE3D27D4EB4Full +
                 salt * 0x165667B19E3779F9ull;
    h ^= h >> 30;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 27;
    h *= 0x94D049BB133111EBull;
    h ^= h >> 31;
    return double(h >> 11) * 0x1.0p-53;
}

/// The EmptySpace of every Volume object of the scene (a default one, skipping nothing, for the
/// other objects), index by index.
std::vector<EmptySpace> emptySpaceOf(const VolumeScene& scene);

/// All leaves of a scene in one mesh, with the leaf of every triangle. Only leaves under objects
/// that cast shadows when castersOnly.
struct FlatLeaves {
    Mesh mesh;
    std::vector<uint32_t> triangleLeaf;
};
FlatLeaves flattenLeaves(const VolumeScene& scene, bool castersOnly);
/// Walks a column's fragments (of a FlatLeaves mesh) front to back and reports, in depth order:
///   surface(depth, object, entering)   an opaque or translucent object's boundary is crossed
///   segment(z0, z1, inside)            the open depth interval to the next fragment depth, with the
///                                      inside flag of every object (only called when some Volume
///                                      object is inside, unless allSegments)
/// Stops early when a callback returns false.
class SegmentWalker {
public:
    /// castersOnly: objects that cast no shadow are ignored (neither surfaces nor volumes).
    SegmentWalker(const VolumeScene& scene, const std::vector<uint32_t>& triangleLeaf,
                  bool castersOnly = false);
    template <class Surface, class Segment>
    void walk(std::span<const ListFragment> fragments, Surface&& surface, Segment&& segment,
              bool allSegments = false);
    /// Inside flag per object after the last walk's fragments up to the current segment.
    std::span<const uint8_t> objectInside() const { return objectInside_; }

private:
    void updateObjects();
    const VolumeScene* scene_;
    const std::vector<uint32_t>* triangleLeaf_;
    std::vector<uint8_t> leafInside_, objectInside_, previous_, active_;
};

template <class Surface, class Segment>
void SegmentWalker::walk(std::span<const ListFragment> fragments, Surface&& surface, Segment&& segment,
                         bool allSegments) {
    std::fill(leafInside_.begin(), leafInside_.end(), uint8_t(0));
    std::fill(objectInside_.begin(), objectInside_.end(), uint8_t(0));
    std::size_t i = 0;
    while (i < fragments.size()) {
        const double z = fragments[i].depth;
        for (; i < fragments.size() && fragments[i].depth == z; ++i)
            leafInside_[(*triangleLeaf_)[fragments[i].triangle]] ^= 1;
        previous_ = objectInside_;
        updateObjects();
        bool anyVolume = false;
        for (std::size_t o = 0; o < objectInside_.size(); ++o) {
            if (!active_[o]) continue;
            const VolumeSceneObject& obj = scene_->objects[o];
            if (obj.kind != ObjectKind::Volume) {
                if (objectInside_[o] != previous_[o] && !surface(z, o, objectInside_[o] != 0)) return;
            } else if (objectInside_[o]) {
                anyVolume = true;
            }
        }
        if (i < fragments.size() && (anyVolume || allSegments))
            if (!segment(z, fragments[i].depth, std::span<const uint8_t>(objectInside_))) return;
    }
}

} // namespace voxfx
