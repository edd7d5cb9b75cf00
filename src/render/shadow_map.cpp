// voxfx — the standard shadow map (Williams 1978) with percentage-closer filtering (Reeves et al.
// 1987): the baseline every other shadow is compared with (ED06 table 1, CHANG §3).
//
// A consumer of the one rasterizer keeps the nearest centre-sampled caster depth per texel; a lookup
// compares the point's depth with the (2r+1)^2 texels around its own and returns the lit fraction.
#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/raster.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {

namespace {

struct NearestDepthConsumer {
    int64_t width;
    std::vector<float>& depth;
    struct Sink {
        int64_t width;
        std::vector<float>& depth;
        void fragment(int64_t x, int64_t y, double d, uint32_t, bool) {
            float& slot = depth[size_t(y * width + x)];
            slot = std::min(slot, float(d));
        }
        void finish() {}
    };
    Sink tile(const Tile&) const { return {width, depth}; }
};

} // namespace

ShadowMap ShadowMap::build(const MeshView& casters, const LightView& view, Progress* progress) {
    ShadowMap map;
    map.view_ = view;
    map.depth_.assign(size_t(view.frame.columnCount()), std::numeric_limits<float>::infinity());
    NearestDepthConsumer consumer{view.frame.width(), map.depth_};
    RasterOptions ro;
    ro.progress = progress;
    rasterize(view.frame, casters, ro, consumer);
    return map;
}

float ShadowMap::visibility(const Vec3d& world, int pcfRadius, double bias) const {
    if (depth_.empty() || !view_.covers(world)) return 1.0f;
    const Vec3d g = view_.gridFromWorld(world);
    const double limit = g.z - bias / view_.worldPerDepthUnit();
    const int64_t W = view_.frame.width(), H = view_.frame.height();
    // Clamp: a point on the frame's border (or a rounding error) must not walk off the map.
    const int64_t cx = std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, W - 1);
    const int64_t cy = std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, H - 1);
    int lit = 0, taps = 0;
    for (int64_t dy = -pcfRadius; dy <= pcfRadius; ++dy)
        for (int64_t dx = -pcfRadius; dx <= pcfRadius; ++dx) {
            const int64_t x = std::clamp<int64_t>(cx + dx, 0, W - 1),
                          y = std::clamp<int64_t>(cy + dy, 0, H - 1);
            lit += double(depth_[size_t(y * W + x)]) >= limit;
            ++taps;
        }
    return float(lit) / float(taps);
}

} // namespace voxfx
