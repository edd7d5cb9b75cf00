// voxfx — mixed polygon and volume scenes: the Boolean shape graph, its validation, flattening of
// the leaves for the rasterizer, and the per-object flags of the segment walker (volume_scene.hpp).
#include "voxfx/volume_scene.hpp"

#include <algorithm>
#include <cmath>

#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

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

EmptySpace::EmptySpace(const Volume& volume, const TransferFunction& transfer) : place_(volume.view()) {
    place_.values = nullptr;
    const Vec3i d = volume.dims();
    const int64_t n[3] = {d.x, d.y, d.z};
    for (int a = 0; a < 3; ++a) {
        voxels_[a] = n[a];
        bricks_[a] = (n[a] + kBrick - 1) / kBrick;
    }
    outsideEmpty_ = transfer.opacity(0.0) <= 0;
    if (volume.voxelCount() == 0) {
        bricks_[0] = bricks_[1] = bricks_[2] = 0;
        return;
    }
    const int64_t bx = bricks_[0], by = bricks_[1], bz = bricks_[2];
    // A sample in brick b (continuous voxel coordinate u in [b B, (b + 1) B]) interpolates voxels
    // floor(u - 0.5) and the next one: voxels b B - 1 .. (b + 1) B, clamped to the volume.
    empty_.assign(std::size_t(bx * by * bz), 0);
    parallelFor(0, bz, 1, [&](int64_t k0, int64_t k1) {
        for (int64_t kb = k0; kb < k1; ++kb)
            for (int64_t jb = 0; jb < by; ++jb)
                for (int64_t ib = 0; ib < bx; ++ib) {
                    float mn = std::numeric_limits<float>::infinity(), mx = -mn;
                    const int64_t b[3] = {ib, jb, kb};
                    int64_t first[3], last[3];
                    for (int a = 0; a < 3; ++a) {
                        first[a] = std::max<int64_t>(b[a] * kBrick - 1, 0);
                        last[a] = std::min((b[a] + 1) * kBrick, n[a] - 1);
                    }
                    for (int64_t k = first[2]; k <= last[2]; ++k)
                        for (int64_t j = first[1]; j <= last[1]; ++j)
                            for (int64_t i = first[0]; i <= last[0]; ++i) {
                                const float v = volume.at(i, j, k);
                                mn = std::min(mn, v);
                                mx = std::max(mx, v);
                            }
                    empty_[std::size_t(ib + bx * (jb + by * kb))] =
                        transfer.maxOpacity(double(mn), double(mx)) <= 0;
                }
    });
}

std::vector<EmptySpace> emptySpaceOf(const VolumeScene& scene) {
    std::vector<EmptySpace> out(scene.objects.size());
    for (std::size_t o = 0; o < scene.objects.size(); ++o) {
        const VolumeSceneObject& obj = scene.objects[o];
        if (obj.kind == ObjectKind::Volume && obj.volume >= 0 &&
            std::size_t(obj.volume) < scene.volumes.size() && scene.volumes[std::size_t(obj.volume)])
            out[o] = EmptySpace(*scene.volumes[std::size_t(obj.volume)], obj.transfer);
    }
    return out;
}

double EmptySpace::emptyFraction() const {
    if (empty_.empty()) return 0;
    return double(std::count(empty_.begin(), empty_.end(), uint8_t(1))) / double(empty_.size());
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

namespace {

std::vector<uint8_t> volumeSceneUsedLeaves(const VolumeScene& s, bool castersOnly) {
    std::vector<uint8_t> used(s.leaves.size(), 0);
    for (const VolumeSceneObject& o : s.objects)
        if (!castersOnly || o.castsShadow) markShapeLeaves(s, o.shape, used);
    return used;
}

} // namespace

Box3d VolumeScene::bounds(bool castersOnly) const {
    const std::vector<uint8_t> used = volumeSceneUsedLeaves(*this, castersOnly);
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

FlatLeaves flattenLeaves(const VolumeScene& scene, bool castersOnly) {
    const std::vector<uint8_t> used = volumeSceneUsedLeaves(scene, castersOnly);
    FlatLeaves f;
    for (std::size_t i = 0; i < scene.leaves.size(); ++i) {
        if (!used[i]) continue;
        const Mesh& m = scene.leaves[i];
        const auto base = uint32_t(f.mesh.positions.size());
        f.mesh.positions.insert(f.mesh.positions.end(), m.positions.begin(), m.positions.end());
        for (const uint32_t v : m.indices) f.mesh.indices.push_back(base + v);
        f.triangleLeaf.insert(f.triangleLeaf.end(), m.triangleCount(), uint32_t(i));
    }
    return f;
}

SegmentWalker::SegmentWalker(const VolumeScene& scene, const std::vector<uint32_t>& triangleLeaf,
                             bool castersOnly)
    : scene_(&scene), triangleLeaf_(&triangleLeaf), leafInside_(scene.leaves.size(), 0),
      objectInside_(scene.objects.size(), 0), previous_(scene.objects.size(), 0),
      active_(scene.objects.size(), 1) {
    if (castersOnly)
        for (std::size_t o = 0; o < active_.size(); ++o) active_[o] = scene.objects[o].castsShadow ? 1 : 0;
}

void SegmentWalker::updateObjects() {
    for (std::size_t o = 0; o < objectInside_.size(); ++o)
        if (active_[o]) objectInside_[o] = scene_->evalShape(scene_->objects[o].shape, leafInside_) ? 1 : 0;
}

} // namespace voxfx
