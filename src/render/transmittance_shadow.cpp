// voxfx — transmittance shadow maps (ED06 §3.1, "Fast Scene Voxelization and Applications").
//
// The partial occluders are voxelized from the light into slicemaps, one per channel (a group of
// equal crossing transmittance, e.g. leaves of one colour). At a point p the light has crossed
// n = popcount(column bits in front of p) filled cells, and is attenuated by t^n per channel.
// The lookup skips the cell holding p (its own surface; see shadow.hpp's bias note).
#include <algorithm>
#include <bit>
#include <cmath>

#include "voxfx/shadow.hpp"

namespace voxfx {

TransmittanceShadowMap TransmittanceShadowMap::build(const LightView& view, std::span<const MeshView> groups,
                                                     std::span<const Vec3f> transmittances, VoxelizeMode mode,
                                                     Slicing slicing, Progress* progress) {
    if (groups.size() != transmittances.size())
        fail("transmittance shadow map: ", groups.size(), " groups but ", transmittances.size(),
             " transmittances");
    if (mode != VoxelizeMode::Surface && mode != VoxelizeMode::Conservative)
        fail("transmittance shadow map: voxelization mode must be surface or conservative, got ",
             toString(mode));
    TransmittanceShadowMap map;
    map.view_ = view;
    for (std::size_t k = 0; k < groups.size(); ++k) {
        const Mesh local = toFrameSpace(groups[k], view);
        VoxelizeOptions vo;
        vo.mode = mode;
        vo.slicing = slicing;
        vo.progress = progress;
        map.channels_.push_back({voxelize(local.view(), view.frame, vo), transmittances[k]});
        // A column holds at most D filled cells.
        const Vec3f& t = transmittances[k];
        std::vector<Vec3f>& powers = map.powers_.emplace_back(size_t(view.frame.depth() + 1));
        for (std::size_t n = 0; n < powers.size(); ++n)
            for (int ch = 0; ch < 3; ++ch) powers[n][ch] = std::pow(t[ch], float(n));
    }
    return map;
}

int64_t TransmittanceShadowMap::columnCells(std::size_t k, int64_t x, int64_t y, double depth,
                                            int64_t skipCells) const {
    const VoxelGrid& g = channels_[k].grid;
    const int64_t W = g.frame.width(), D = g.frame.depth();
    const int64_t c = y * W + x;
    const double t = g.frame.depthToSlice(c)(depth);
    if (!(t >= 0)) return 0; // in front of the grid (or NaN)
    const int64_t s = t >= double(D) ? D : int64_t(t);
    // Count slices [0, end): everything in front of the skipped cells; whole words, then a mask.
    const int64_t end = std::clamp<int64_t>(s - skipCells + 1, 0, D);
    const uint64_t* col = g.bits.column(c);
    int64_t n = 0;
    for (int64_t w = 0; w < (end >> 6); ++w) n += std::popcount(col[w]);
    if (end & 63) n += std::popcount(col[end >> 6] & ((uint64_t(1) << (end & 63)) - 1));
    return n;
}

Vec3f TransmittanceShadowMap::columnTransmittance(int64_t x, int64_t y, double depth,
                                                  int64_t skipCells) const {
    Vec3f out{1, 1, 1};
    for (std::size_t k = 0; k < channels_.size(); ++k) {
        const int64_t n = columnCells(k, x, y, depth, skipCells);
        if (n == 0) continue;
        out = out * powers_[k][size_t(n)];
    }
    return out;
}

int64_t TransmittanceShadowMap::cellsBefore(std::size_t k, const Vec3d& world, int64_t skipCells) const {
    if (k >= channels_.size() || !view_.covers(world)) return 0;
    const Vec3d p = view_.gridFromWorld(world);
    // Clamp: covers() admits the closed border of the columns.
    const int64_t x = std::clamp<int64_t>(int64_t(std::floor(p.x)), 0, view_.frame.width() - 1);
    const int64_t y = std::clamp<int64_t>(int64_t(std::floor(p.y)), 0, view_.frame.height() - 1);
    return columnCells(k, x, y, p.z, skipCells);
}

Vec3f TransmittanceShadowMap::transmittance(const Vec3d& world, int64_t skipCells) const {
    if (channels_.empty() || !view_.covers(world)) return {1, 1, 1};
    const Vec3d p = view_.gridFromWorld(world);
    const int64_t x = std::clamp<int64_t>(int64_t(std::floor(p.x)), 0, view_.frame.width() - 1);
    const int64_t y = std::clamp<int64_t>(int64_t(std::floor(p.y)), 0, view_.frame.height() - 1);
    return columnTransmittance(x, y, p.z, skipCells);
}

Vec3f TransmittanceShadowMap::transmittanceBilinear(const Vec3d& world, int64_t skipCells) const {
    if (channels_.empty() || !view_.covers(world)) return {1, 1, 1};
    const Vec3d p = view_.gridFromWorld(world);
    // Column centres sit at x + 0.5: interpolate between the four around p.
    const double fx = p.x - 0.5, fy = p.y - 0.5;
    const int64_t x0 = int64_t(std::floor(fx)), y0 = int64_t(std::floor(fy));
    const double wx = fx - double(x0), wy = fy - double(y0);
    Vec3f out;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int64_t x = x0 + dx, y = y0 + dy;
            const float w = float((dx ? wx : 1 - wx) * (dy ? wy : 1 - wy));
            // Columns outside the frame hold no caster (the frame covers them all).
            const bool inside = x >= 0 && y >= 0 && x < view_.frame.width() && y < view_.frame.height();
            out += (inside ? columnTransmittance(x, y, p.z, skipCells) : Vec3f{1, 1, 1}) * w;
        }
    return out;
}

} // namespace voxfx
