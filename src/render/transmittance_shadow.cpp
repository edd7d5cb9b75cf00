// voxfx — transmittance shadow maps (ED06 §3.1, "Fast Scene Voxelization and Applications").
//
// The partial occluders are voxelized from the light into slicemaps, one per channel (a group of
// equal crossing transmittance, e.g. leaves of one colour). At a point p the light has crossed
// n = popcount(column bits in front of p) filled cells, and is attenuated by t^n per channel.
// The lookup skips the cell holding p (its own surface; see shadow.hpp's bias note).
#include <cmath>

#include "render/light_grid_lookup.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {

TransmittanceShadowMap TransmittanceShadowMap::build(const LightView& view, std::span<const MeshView> groups,
                                                     std::span<const Vec3f> transmittances, VoxelizeMode mode,
                                                     Slicing slicing, Progress* progress, Device device) {
    if (groups.size() != transmittances.size())
        fail("transmittance shadow map: ", groups.size(), " groups but ", transmittances.size(),
             " transmittances");
    if (mode != VoxelizeMode::Surface && mode != VoxelizeMode::Conservative)
        fail("transmittance shadow map: voxelization mode must be surface or conservative, got ",
             toString(mode));
    TransmittanceShadowMap map;
    map.view_ = view;
    for (std::size_t k = 0; k < groups.size(); ++k) {
        VoxelizeOptions vo;
        vo.mode = mode;
        vo.slicing = slicing;
        vo.progress = progress;
        vo.device = device;
        map.channels_.push_back({voxelize(groups[k], view.frame, vo), transmittances[k]});
        // A column holds at most D filled cells.
        const Vec3f& t = transmittances[k];
        std::vector<Vec3f>& powers = map.powers_.emplace_back(size_t(view.frame.depth() + 1));
        for (std::size_t n = 0; n < powers.size(); ++n)
            for (int ch = 0; ch < 3; ++ch) powers[n][ch] = std::pow(t[ch], float(n));
    }
    return map;
}

int64_t TransmittanceShadowMap::columnCells(std::size_t k, int64_t column, double depth,
                                            int64_t skipCells) const {
    const VoxelGrid& g = channels_[k].grid;
    const int64_t end = detail::slicesInFront(g.frame, column, depth, skipCells);
    return countColumnRange(g.bits.column(column), g.frame.depth(), 0, end);
}

Vec3f TransmittanceShadowMap::columnTransmittance(int64_t column, double depth, int64_t skipCells) const {
    Vec3f out{1, 1, 1};
    for (std::size_t k = 0; k < channels_.size(); ++k) {
        const int64_t n = columnCells(k, column, depth, skipCells);
        if (n == 0) continue;
        out = out * powers_[k][size_t(n)];
    }
    return out;
}

int64_t TransmittanceShadowMap::cellsBefore(std::size_t k, const Vec3d& world, int64_t skipCells) const {
    if (k >= channels_.size() || !view_.covers(world)) return 0;
    const detail::ColumnAt c = detail::nearestColumn(view_, world);
    return columnCells(k, c.column, c.depth, skipCells);
}

Vec3f TransmittanceShadowMap::transmittance(const Vec3d& world, int64_t skipCells) const {
    if (channels_.empty() || !view_.covers(world)) return {1, 1, 1};
    const detail::ColumnAt c = detail::nearestColumn(view_, world);
    return columnTransmittance(c.column, c.depth, skipCells);
}

Vec3f TransmittanceShadowMap::transmittanceBilinear(const Vec3d& world, int64_t skipCells) const {
    if (channels_.empty() || !view_.covers(world)) return {1, 1, 1};
    return detail::bilinearColumns<Vec3f, float>(
        view_, world, Vec3f{1, 1, 1},
        [&](const detail::ColumnAt& c) { return columnTransmittance(c.column, c.depth, skipCells); });
}

} // namespace voxfx
