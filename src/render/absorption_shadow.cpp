// voxfx — per-voxel absorption shadows (CHANG §3, "Real-time Realistic Voxel-based Rendering").
//
// An attribute voxelization from the light stores, per voxel, the absorption of every write
// (material optical depth per crossing; dense foliage writes a voxel several times and so absorbs
// more). The occlusion at p is the sum of the absorption of the occupied voxels between the light
// and p (CHANG §3 step 4); the light is attenuated by exp(-sum). Columns are reduced to exclusive
// prefix sums once, so a lookup is one read.
#include <algorithm>
#include <cmath>

#include "voxfx/shadow.hpp"

namespace voxfx {

AbsorptionShadowMap AbsorptionShadowMap::build(const LightView& view, const MeshView& casters,
                                               std::span<const float> triangleAbsorption, Coverage coverage,
                                               Slicing slicing, Progress* progress) {
    AbsorptionShadowMap map;
    map.view_ = view;
    const Mesh local = toFrameSpace(casters, view);
    AttributeOptions ao;
    ao.coverage = coverage;
    ao.normals = false;
    ao.slicing = slicing;
    ao.progress = progress;
    // The sparse form of the attribute voxelization: light grids through foliage are mostly empty.
    AttributeColumns grid = voxelizeAttributeColumns(local.view(), view.frame, triangleAbsorption, ao);
    map.frame_ = grid.frame;
    for (const uint16_t n : grid.count) map.writes_ += n;
    map.offsets_ = std::move(grid.offsets);
    map.slice_ = std::move(grid.slice);
    // Inclusive prefix sums along each column, in place; double accumulation.
    map.prefix_ = std::move(grid.absorption);
    parallelFor(0, map.frame_.columnCount(), 4096, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            double sum = 0;
            for (int64_t i = map.offsets_[size_t(c)]; i < map.offsets_[size_t(c) + 1]; ++i) {
                sum += double(map.prefix_[size_t(i)]);
                map.prefix_[size_t(i)] = float(sum);
            }
        }
    });
    return map;
}

float AbsorptionShadowMap::columnDepth(int64_t x, int64_t y, double depth, int64_t skipCells) const {
    const int64_t D = frame_.depth();
    const int64_t c = y * frame_.width() + x;
    const double t = frame_.depthToSlice(c)(depth);
    if (!(t >= 0)) return 0.0f;
    const int64_t s = t >= double(D) ? D : int64_t(t);
    const int64_t end = std::clamp<int64_t>(s - skipCells + 1, 0, D); // slices [0, end) count
    // Written voxels of the column with slice < end (few per column: a linear scan).
    const int64_t b = offsets_[size_t(c)], e = offsets_[size_t(c) + 1];
    int64_t i = b;
    while (i < e && int64_t(slice_[size_t(i)]) < end) ++i;
    return i == b ? 0.0f : prefix_[size_t(i - 1)];
}

float AbsorptionShadowMap::opticalDepth(const Vec3d& world, int64_t skipCells) const {
    if (offsets_.empty() || !view_.covers(world)) return 0.0f;
    const Vec3d p = view_.gridFromWorld(world);
    // Clamp: covers() admits the closed border of the columns.
    const int64_t x = std::clamp<int64_t>(int64_t(std::floor(p.x)), 0, frame_.width() - 1);
    const int64_t y = std::clamp<int64_t>(int64_t(std::floor(p.y)), 0, frame_.height() - 1);
    return columnDepth(x, y, p.z, skipCells);
}

float AbsorptionShadowMap::transmittance(const Vec3d& world, int64_t skipCells) const {
    return std::exp(-opticalDepth(world, skipCells));
}

float AbsorptionShadowMap::transmittanceBilinear(const Vec3d& world, int64_t skipCells) const {
    if (offsets_.empty() || !view_.covers(world)) return 1.0f;
    const Vec3d p = view_.gridFromWorld(world);
    const double fx = p.x - 0.5, fy = p.y - 0.5;
    const int64_t x0 = int64_t(std::floor(fx)), y0 = int64_t(std::floor(fy));
    const double wx = fx - double(x0), wy = fy - double(y0);
    double out = 0;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int64_t x = x0 + dx, y = y0 + dy;
            const double w = (dx ? wx : 1 - wx) * (dy ? wy : 1 - wy);
            const bool inside = x >= 0 && y >= 0 && x < frame_.width() && y < frame_.height();
            out += w * (inside ? std::exp(-double(columnDepth(x, y, p.z, skipCells))) : 1.0);
        }
    return float(out);
}

} // namespace voxfx
