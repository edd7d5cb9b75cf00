// voxfx — walking a mixed polygon and volume scene along rays: empty-space bricks, the flattened
// leaves, and the per-object flags of the segment walker (voxfx/segment_walker.hpp).
#include "voxfx/segment_walker.hpp"

#include <algorithm>
#include <limits>

#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace {

// Per block of a lattice over the volume's voxels (`count[a]` blocks along axis a, x fastest; block b
// covers voxels b stride + from .. b stride + to along each axis, clamped to the volume): 1 where the
// transfer function is transparent over every value between the block's smallest and largest.
std::vector<uint8_t> transparentBlocks(const Volume& volume, const TransferFunction& transfer,
                                       const int64_t (&count)[3], int64_t stride, int64_t from, int64_t to) {
    const Vec3i d = volume.dims();
    const int64_t n[3] = {d.x, d.y, d.z};
    std::vector<uint8_t> out(std::size_t(count[0] * count[1] * count[2]), 0);
    parallelFor(0, count[2], 1, [&](int64_t k0, int64_t k1) {
        for (int64_t kb = k0; kb < k1; ++kb)
            for (int64_t jb = 0; jb < count[1]; ++jb)
                for (int64_t ib = 0; ib < count[0]; ++ib) {
                    float mn = std::numeric_limits<float>::infinity(), mx = -mn;
                    const int64_t b[3] = {ib, jb, kb};
                    int64_t first[3], last[3];
                    for (int a = 0; a < 3; ++a) {
                        first[a] = std::clamp<int64_t>(b[a] * stride + from, 0, n[a] - 1);
                        last[a] = std::clamp<int64_t>(b[a] * stride + to, 0, n[a] - 1);
                    }
                    for (int64_t k = first[2]; k <= last[2]; ++k)
                        for (int64_t j = first[1]; j <= last[1]; ++j)
                            for (int64_t i = first[0]; i <= last[0]; ++i) {
                                const float v = volume.at(i, j, k);
                                mn = std::min(mn, v);
                                mx = std::max(mx, v);
                            }
                    out[std::size_t(ib + count[0] * (jb + count[1] * kb))] =
                        transfer.maxOpacity(double(mn), double(mx)) <= 0;
                }
    });
    return out;
}

} // namespace

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
    // A sample in brick b (continuous voxel coordinate u in [b B, (b + 1) B]) interpolates voxels
    // floor(u - 0.5) and the next one: voxels b B - 1 .. (b + 1) B, clamped to the volume.
    empty_ = transparentBlocks(volume, transfer, bricks_, kBrick, -1, kBrick);
    // The sample lattice's cells: centres i and i + 1 (clamped) along each axis.
    for (int a = 0; a < 3; ++a) cells_[a] = std::max<int64_t>(n[a] - 1, 1);
    transparent_ = transparentBlocks(volume, transfer, cells_, 1, 0, 1);
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

double EmptySpace::emptyRun(const Vec3d& p, const Vec3d& dir, double maxLength) const {
    if (empty_.empty() || !(maxLength > 0)) return 0;
    double u[3], du[3];
    int64_t b[3];
    for (int a = 0; a < 3; ++a) {
        u[a] = place_.voxelCoordinate(p, a);
        du[a] = place_.voxelCoordinate(p + dir, a) - u[a]; // voxel coordinates are affine in p
        if (!(u[a] >= 0 && u[a] <= double(voxels_[a]))) return 0;
        b[a] = std::min(int64_t(u[a]) / kBrick, bricks_[a] - 1);
    }
    double s = 0;
    for (;;) {
        if (!empty_[std::size_t(b[0] + bricks_[0] * (b[1] + bricks_[1] * b[2]))]) return s;
        // Where the ray leaves brick b (the last brick along an axis ends at the box's side).
        double exit = std::numeric_limits<double>::infinity();
        int axis = -1;
        for (int a = 0; a < 3; ++a) {
            double t = exit;
            if (du[a] > 0) t = (double(std::min((b[a] + 1) * kBrick, voxels_[a])) - u[a]) / du[a];
            if (du[a] < 0) t = (double(b[a] * kBrick) - u[a]) / du[a];
            if (t < exit) exit = t, axis = a;
        }
        if (axis < 0) return maxLength; // dir is zero: p stays in its empty brick
        s = std::max(s, exit);
        if (s >= maxLength) return maxLength;
        b[axis] += du[axis] > 0 ? 1 : -1;
        if (b[axis] < 0 || b[axis] >= bricks_[axis]) return s; // leaves the box
    }
}

double EmptySpace::emptyFraction() const {
    if (empty_.empty()) return 0;
    return double(std::count(empty_.begin(), empty_.end(), uint8_t(1))) / double(empty_.size());
}

FlatLeaves flattenLeaves(const VolumeScene& scene, bool castersOnly) {
    const std::vector<uint8_t> used = scene.usedLeaves(castersOnly);
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
