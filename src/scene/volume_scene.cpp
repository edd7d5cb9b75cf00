// voxfx — mixed polygon and volume scenes: the Boolean shape graph, its validation, and the
// renderer's scene as a volume scene (volume_scene.hpp).
#include "voxfx/volume_scene.hpp"

#include <algorithm>
#include <cmath>

#include "voxfx/error.hpp"

namespace voxfx {

const char* toString(ShapeOp op) { return enumName(op, kShapeOpNames); }

const char* toString(ObjectKind k) { return enumName(k, kObjectKindNames); }

int32_t VolumeScene::addLeaf(Mesh mesh) {
    leaves.push_back(std::move(mesh));
    ShapeNode n;
    n.op = ShapeOp::Leaf;
    n.leaf = int32_t(leaves.size() - 1);
    nodes.push_back(n);
    return int32_t(nodes.size() - 1);
}

int32_t VolumeScene::addNode(ShapeOp op, int32_t a, int32_t b) {
    if (op == ShapeOp::Leaf) fail("volume scene: addNode needs a Boolean operation (use addLeaf)");
    ShapeNode n;
    n.op = op;
    n.a = a;
    n.b = b;
    nodes.push_back(n);
    return int32_t(nodes.size() - 1);
}

int32_t VolumeScene::addObject(VolumeSceneObject object) {
    objects.push_back(std::move(object));
    return int32_t(objects.size() - 1);
}

Mesh boxMesh(const Box3d& box) {
    Mesh m;
    for (int k = 0; k < 8; ++k)
        m.positions.push_back(Vec3f(Vec3d{(k & 1) ? box.hi.x : box.lo.x, (k & 2) ? box.hi.y : box.lo.y,
                                          (k & 4) ? box.hi.z : box.lo.z}));
    static const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads)
        for (const uint32_t t : {q[0], q[1], q[2], q[0], q[2], q[3]}) m.indices.push_back(t);
    return m;
}

int32_t VolumeScene::addVolumeBox(std::shared_ptr<const Volume> volume, TransferFunction transfer,
                                  double opacityLength, const std::string& name) {
    if (!volume) fail("volume scene: addVolumeBox without a volume");
    VolumeSceneObject o;
    o.name = name;
    o.shape = addLeaf(volume->boxMesh());
    o.kind = ObjectKind::Volume;
    volumes.push_back(std::move(volume));
    o.volume = int32_t(volumes.size() - 1);
    o.transfer = std::move(transfer);
    o.opacityLength = opacityLength;
    return addObject(std::move(o));
}

bool VolumeScene::evalShape(int32_t node, std::span<const uint8_t> leafInside) const {
    const ShapeNode& n = nodes[std::size_t(node)];
    switch (n.op) {
    case ShapeOp::Leaf:
        return leafInside[std::size_t(n.leaf)] != 0;
    case ShapeOp::Union:
        return evalShape(n.a, leafInside) || evalShape(n.b, leafInside);
    case ShapeOp::Intersection:
        return evalShape(n.a, leafInside) && evalShape(n.b, leafInside);
    case ShapeOp::Difference:
        return evalShape(n.a, leafInside) && !evalShape(n.b, leafInside);
    }
    return false;
}

std::vector<uint8_t> VolumeScene::usedLeaves(bool castersOnly) const {
    std::vector<uint8_t> used(leaves.size(), 0);
    for (const VolumeSceneObject& o : objects)
        if (!castersOnly || o.castsShadow) markShapeLeaves(*this, o.shape, used);
    return used;
}

Box3d VolumeScene::bounds(bool castersOnly) const {
    const std::vector<uint8_t> used = usedLeaves(castersOnly);
    Box3d b;
    for (std::size_t i = 0; i < leaves.size(); ++i)
        if (used[i]) b.extend(computeBounds(leaves[i].view()));
    return b;
}

void VolumeScene::validate() const {
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const ShapeNode& n = nodes[i];
        if (n.op == ShapeOp::Leaf) {
            if (n.leaf < 0 || std::size_t(n.leaf) >= leaves.size())
                fail("volume scene: node ", i, " names leaf ", n.leaf, " of ", leaves.size());
        } else if (n.a < 0 || n.b < 0 || std::size_t(n.a) >= i || std::size_t(n.b) >= i) {
            fail("volume scene: ", toString(n.op), " node ", i, " must combine earlier nodes, got ", n.a,
                 " and ", n.b);
        }
    }
    for (std::size_t i = 0; i < leaves.size(); ++i)
        validateMesh(leaves[i].view(), "volume scene leaf " + std::to_string(i));
    for (const VolumeSceneObject& o : objects) {
        if (o.shape < 0 || std::size_t(o.shape) >= nodes.size())
            fail("volume scene: object '", o.name, "' has shape ", o.shape, " of ", nodes.size(), " nodes");
        if (!(o.opacity >= 0 && o.opacity <= 1))
            fail("volume scene: object '", o.name, "' has opacity ", o.opacity, " outside [0, 1]");
        for (int c = 0; c < 3; ++c) {
            if (o.transmittance && !((*o.transmittance)[c] >= 0 && (*o.transmittance)[c] <= 1))
                fail("volume scene: object '", o.name, "' has a transmittance outside [0, 1]");
            if (!(o.attenuation[c] >= 0 && std::isfinite(o.attenuation[c])))
                fail("volume scene: object '", o.name, "' has a negative or non-finite attenuation");
        }
        if (o.kind == ObjectKind::Volume) {
            if (o.volume < 0 || std::size_t(o.volume) >= volumes.size() || !volumes[std::size_t(o.volume)])
                fail("volume scene: volume object '", o.name, "' has no volume (index ", o.volume, ")");
            if (!(o.opacityLength > 0) || !std::isfinite(o.opacityLength))
                fail("volume scene: volume object '", o.name, "' needs a positive opacityLength, got ",
                     o.opacityLength);
        }
    }
}

void markShapeLeaves(const VolumeScene& s, int32_t node, std::vector<uint8_t>& used) {
    const ShapeNode& n = s.nodes[std::size_t(node)];
    if (n.op == ShapeOp::Leaf) {
        used[std::size_t(n.leaf)] = 1;
        return;
    }
    markShapeLeaves(s, n.a, used);
    markShapeLeaves(s, n.b, used);
}

VolumeScene volumeSceneOf(const Scene& scene, SceneMeshes meshes) {
    VolumeScene v;
    for (const SceneMesh& m : scene.meshes) {
        const Material& mat = scene.materials[m.material];
        if (meshes == SceneMeshes::Blended && !mat.blend) continue;
        VolumeSceneObject o;
        o.name = m.name;
        o.material = int32_t(m.material);
        o.shape = v.addLeaf(m.mesh);
        o.castsShadow = m.castsShadow;
        o.color = mat.baseColor;
        if (mat.isOpaque()) {
            o.kind = ObjectKind::Opaque;
        } else {
            const Vec3f t = mat.shadowCrossingTransmittance();
            o.kind = ObjectKind::Translucent;
            o.opacity = std::clamp(1.0f - (0.2126f * t.x + 0.7152f * t.y + 0.0722f * t.z), 0.0f, 1.0f);
            o.transmittance = t;
            o.attenuation = mat.shadowAttenuationCoefficient();
            if (mat.isGlass()) o.ior = std::max(1.0f, mat.ior);
        }
        v.addObject(std::move(o));
    }
    if (scene.volumeScene) {
        const VolumeScene& s = *scene.volumeScene;
        const auto leafBase = int32_t(v.leaves.size()), nodeBase = int32_t(v.nodes.size()),
                   volumeBase = int32_t(v.volumes.size());
        v.leaves.insert(v.leaves.end(), s.leaves.begin(), s.leaves.end());
        for (ShapeNode n : s.nodes) {
            if (n.op == ShapeOp::Leaf) {
                n.leaf += leafBase;
            } else {
                n.a += nodeBase;
                n.b += nodeBase;
            }
            v.nodes.push_back(n);
        }
        v.volumes.insert(v.volumes.end(), s.volumes.begin(), s.volumes.end());
        for (VolumeSceneObject o : s.objects) {
            o.shape += nodeBase;
            if (o.volume >= 0) o.volume += volumeBase;
            v.objects.push_back(std::move(o));
        }
    }
    return v;
}

} // namespace voxfx
