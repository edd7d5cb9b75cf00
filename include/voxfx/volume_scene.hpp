// voxfx — mixed polygon and volume scenes (Bornik et al. §3): a graph whose leaves are closed meshes
// and whose inner nodes are volumetric Boolean operations (union, intersection, difference); objects
// are shapes of that graph that are opaque, translucent (a fraction α of the light stopped at every
// crossing of their boundary) or filled with a Volume seen through a transfer function. A plain
// volume is an object bounded by its box (addVolumeBox).
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
// Volume extinction: the transfer function's opacity α(value) is the fraction stopped over
// `opacityLength` world units, so σ = -ln(1 - α) / opacityLength (α clamped below 1).
//
// Thread-safety: a VolumeScene is a value; concurrent reads are fine. SegmentWalker is per thread.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/transfer_function.hpp"
#include "voxfx/volume.hpp"

namespace voxfx {

enum class ShapeOp : uint8_t { Leaf, Union, Intersection, Difference };
inline constexpr EnumName<ShapeOp> kShapeOpNames[] = {{"leaf", ShapeOp::Leaf},
                                                      {"union", ShapeOp::Union},
                                                      {"intersection", ShapeOp::Intersection},
                                                      {"difference", ShapeOp::Difference}};
const char* toString(ShapeOp op);

/// A node of the shape graph: a leaf (index into VolumeScene::leaves) or a Boolean of two nodes
/// (indices into VolumeScene::nodes, smaller than the node's own index).
struct ShapeNode {
    ShapeOp op = ShapeOp::Leaf;
    int32_t leaf = -1;
    int32_t a = -1, b = -1;
};

enum class ObjectKind : uint8_t { Opaque, Translucent, Volume };
inline constexpr EnumName<ObjectKind> kObjectKindNames[] = {
    {"opaque", ObjectKind::Opaque}, {"translucent", ObjectKind::Translucent}, {"volume", ObjectKind::Volume}};
const char* toString(ObjectKind k);

struct VolumeSceneObject {
    std::string name;
    int32_t shape = -1; ///< root node of its shape
    ObjectKind kind = ObjectKind::Opaque;
    float opacity = 1; ///< translucent: fraction of the light a crossing stops, in [0, 1]
    Vec3f color{0.8f, 0.8f, 0.8f};
    int32_t volume = -1;       ///< Volume kind: index into VolumeScene::volumes
    TransferFunction transfer; ///< Volume kind: value -> colour and opacity
    double opacityLength = 1;  ///< Volume kind: world length the transfer function's opacity is for
    bool castsShadow = true;
    /// An object made of a scene mesh (volumeSceneOf): the index of its Material in Scene::materials,
    /// which shades it; -1 otherwise (shaded with `color`).
    int32_t material = -1;
};

struct VolumeScene {
    std::vector<Mesh> leaves;
    std::vector<ShapeNode> nodes;
    std::vector<VolumeSceneObject> objects;
    std::vector<std::shared_ptr<const Volume>> volumes;

    /// Adds a leaf mesh and a node for it; returns the node index.
    int32_t addLeaf(Mesh mesh);
    /// Adds a Boolean node of nodes a and b; returns its index.
    int32_t addNode(ShapeOp op, int32_t a, int32_t b);
    /// Adds an object; returns its index.
    int32_t addObject(VolumeSceneObject object);
    /// Adds a volume bounded by its box (a box mesh leaf) as a Volume object; returns its index.
    int32_t addVolumeBox(std::shared_ptr<const Volume> volume, TransferFunction transfer,
                         double opacityLength, const std::string& name = "volume");
    /// Whether the shape of node `node` contains a point whose leaves' inside flags are `leafInside`.
    bool evalShape(int32_t node, std::span<const uint8_t> leafInside) const;
    /// Bounds of the leaves under objects that cast shadows (castersOnly) or of every object.
    Box3d bounds(bool castersOnly = false) const;
    /// Throws voxfx::Error naming the object or node: indices out of range or not topologically
    /// ordered, invalid meshes, a Volume object without a volume or with a non-positive
    /// opacityLength, opacity outside [0, 1].
    void validate() const;
};

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
    /// Fraction of the bricks that are empty (0 for a volume without voxels).
    double emptyFraction() const;

private:
    VolumeView place_; // the volume's placement (no values)
    int64_t voxels_[3] = {0, 0, 0}, bricks_[3] = {0, 0, 0};
    bool outsideEmpty_ = false;
    std::vector<uint8_t> empty_;
};

/// The EmptySpace of every Volume object of the scene (a default one, skipping nothing, for the
/// other objects), index by index.
std::vector<EmptySpace> emptySpaceOf(const VolumeScene& scene);

/// A triangle mesh box (12 triangles, outward facing) of `box`.
Mesh boxMesh(const Box3d& box);

/// All leaves of a scene in one mesh, with the leaf of every triangle. Only leaves under objects
/// that cast shadows when castersOnly.
struct FlatLeaves {
    Mesh mesh;
    std::vector<uint32_t> triangleLeaf;
};
FlatLeaves flattenLeaves(const VolumeScene& scene, bool castersOnly);
/// Sets used[leaf] = 1 for every leaf under shape node `node` (used has one entry per leaf).
void markShapeLeaves(const VolumeScene& scene, int32_t node, std::vector<uint8_t>& used);

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
