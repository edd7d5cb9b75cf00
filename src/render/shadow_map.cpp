// voxfx — the standard shadow map (Williams 1978) with percentage-closer filtering (Reeves et al.
// 1987): the baseline every other shadow is compared with (ED06 table 1, CHANG §3). See
// voxfx/shadow_map.hpp.
//
// A consumer of the one rasterizer keeps the nearest centre-sampled caster depth per texel; a lookup
// compares the point's depth with the (2r+1)^2 texels around its own and returns the lit fraction.
#include "voxfx/shadow_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "render/light_grid_lookup.hpp"
#include "render/shadow_casters.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/text.hpp"

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

std::span<const OptionField<ShadowMapOptions>> ShadowMapOptions::fields() {
    using O = ShadowMapOptions;
    static const std::vector<OptionField<O>> table = {
        numberOption<O, &O::resolution>("mapResolution",
                                        "shadow map texels along the longer side of a light view", 1, 32768,
                                        "shadowMapResolution"),
        numberOption<O, &O::pcfRadius>("pcf", "PCF radius r: (2r+1)^2 taps", 0, 8),
        numberOption<O, &O::normalOffset>(
            "normalOffset", "lookup offset along the surface normal, in texel footprints", 0, 1000),
        numberOption<O, &O::depthBias>("depthBias", "shadow map depth bias, in texel footprints", 0, 1000)};
    return table;
}

MapShadowStats& MapShadowStats::operator+=(const MapShadowStats& o) {
    maps += o.maps;
    texels += o.texels;
    return *this;
}

std::string MapShadowStats::summary() const {
    return countText(maps) + (maps == 1 ? " shadow map, " : " shadow maps, ") + countText(texels) + " texels";
}

MapShadow MapShadow::build(const Light& light, const MeshView& casters, const ShadowMapOptions& options,
                           Progress* progress) {
    if (options.resolution <= 0 || options.pcfRadius < 0)
        fail("shadow map: the resolution must be positive and the PCF radius >= 0, got ", options.resolution,
             " and ", options.pcfRadius);
    MapShadow out;
    out.options_ = options;
    if (casters.triangleCount == 0) return out;
    out.views_ = makeLightViews(light, computeBounds(casters), options.resolution, 1);
    for (const LightView& v : out.views_) out.maps_.push_back(ShadowMap::build(casters, v, progress));
    return out;
}

MapShadow MapShadow::build(const Scene& scene, const Light& light, const ShadowMapOptions& options,
                           Progress* progress) {
    const detail::CasterSets casters = detail::collectCasters(scene);
    return build(light, casters.all.view(), options, progress);
}

float MapShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    Vec3d q;
    const int i = detail::lookupView(views_, p, n, options_.normalOffset, q);
    if (i < 0) return 1.0f;
    const double texel = views_[size_t(i)].columnWorldSize(p);
    return maps_[size_t(i)].visibility(q, options_.pcfRadius, options_.depthBias * texel);
}

MapShadow::Stats MapShadow::stats() const {
    Stats s;
    for (const LightView& v : views_) {
        ++s.maps;
        s.texels += v.frame.columnCount();
    }
    return s;
}

} // namespace voxfx
