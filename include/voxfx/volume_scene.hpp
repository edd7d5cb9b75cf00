// voxfx — mixed polygon and volume scenes (Bornik et al. §3): a graph whose leaves are closed meshes
// and whose inner nodes are volumetric Boolean operations (union, intersection, difference); objects
// are shapes of that graph that are opaque, translucent (a fraction α of the light stopped at every
// crossing of their boundary) or filled with a Volume seen through a transfer function. A plain
// volume is an object bounded by its box (addVolumeBox).
//
// How rays walk such a scene (fragment lists, the segment walker, empty-space skipping) is in
// voxfx/segment_walker.hpp.
//
// Volume extinction: the transfer function's opacity α(value) is the fraction stopped over
// `opacityLength` world units, so σ = -ln(1 - α) / opacityLength (α clamped below 1).
//
// Thread-safety: a VolumeScene is a value; concurrent reads are fine.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/scene.hpp"
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
    /// Translucent, for shadows: the RGB fraction of the light one crossing passes (volumeSceneOf:
    /// Material::shadowCrossingTransmittance, coloured leaves and glass); none: 1 - opacity.
    std::optional<Vec3f> transmittance;
    /// Translucent glass, for shadows: Beer–Lambert coefficient per world unit over the chord
    /// between a crossing that enters the object and the next that leaves it (volumeSceneOf:
    /// Material::shadowAttenuationCoefficient); zero for a sheet.
    Vec3f attenuation{0, 0, 0};
    /// Glass, for shadows: its index of refraction (0: not glass). `transmittance` holds the Fresnel
    /// of normal incidence, (1 - F0); deep shadow maps replace it by the crossing's own (1 - F) at
    /// the angle between the light's ray and the crossed triangle's normal.
    float ior = 0;

    /// What one crossing passes per channel: `transmittance`, or 1 - opacity in every channel.
    Vec3f shadowTransmittance() const {
        return transmittance ? *transmittance : Vec3f{1 - opacity, 1 - opacity, 1 - opacity};
    }
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
    /// Per leaf, 1 when some object's shape uses it (only objects that cast shadows when castersOnly).
    std::vector<uint8_t> usedLeaves(bool castersOnly) const;
    /// Throws voxfx::Error naming the object or node: indices out of range or not topologically
    /// ordered, invalid meshes, a Volume object without a volume or with a non-positive
    /// opacityLength, opacity outside [0, 1].
    void validate() const;
};

/// A triangle mesh box (12 triangles, outward facing) of `box`.
Mesh boxMesh(const Box3d& box);

/// Sets used[leaf] = 1 for every leaf under shape node `node` (used has one entry per leaf).
void markShapeLeaves(const VolumeScene& scene, int32_t node, std::vector<uint8_t>& used);

/// Which of a Scene's meshes volumeSceneOf turns into objects.
enum class SceneMeshes {
    All,     ///< every mesh: what the light sees (deep shadows)
    Blended, ///< the meshes of blended materials (Material::blend): what the camera's G-buffer leaves out
};

/// The renderer's scene as a volume scene: the chosen meshes, each a leaf and an object (opaque, or
/// translucent with opacity 1 - luminance(shadowCrossingTransmittance), that transmittance and the
/// material's shadowAttenuationCoefficient; `material` names the mesh's material), then the objects
/// of scene.volumeScene.
VolumeScene volumeSceneOf(const Scene& scene, SceneMeshes meshes = SceneMeshes::All);

} // namespace voxfx
