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

#include "render/float_threshold.hpp"
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
    map.buildLowerPlanes();
    return map;
}

ShadowMap::DepthPlane ShadowMap::lowerPlane(int64_t x0, int64_t y0) const {
    const int64_t W = view_.frame.width(), H = view_.frame.height();
    const int64_t xa = std::max<int64_t>(x0 - kTileBorder, 0), xb = std::min(x0 + kTile + kTileBorder, W);
    const int64_t ya = std::max<int64_t>(y0 - kTileBorder, 0), yb = std::min(y0 + kTile + kTileBorder, H);
    constexpr float inf = std::numeric_limits<float>::infinity();
    const DepthPlane never{-inf, 0, 0, -inf, inf};
    float least = inf, most = -inf;
    // Least squares over the texels holding a caster (a plane for flat ground; anything else, such
    // as a trunk standing on it, only lowers the bound below what a lookup can use).
    double n = 0, sx = 0, sy = 0, sz = 0, sxx = 0, syy = 0, sxy = 0, sxz = 0, syz = 0;
    for (int64_t y = ya; y < yb; ++y)
        for (int64_t x = xa; x < xb; ++x) {
            const float d = depth_[size_t(y * W + x)];
            most = std::max(most, d);
            if (d == inf) continue;
            if (!std::isfinite(d)) return never;
            least = std::min(least, d);
            const double u = double(x - x0), v = double(y - y0), z = double(d);
            n += 1, sx += u, sy += v, sz += z, sxx += u * u, syy += v * v, sxy += u * v, sxz += u * z,
                syz += v * z;
        }
    if (n == 0) return {inf, 0, 0, inf, inf};
    // Centred sums; the slopes solve the 2 x 2 normal equations (0 where they are singular).
    const double cxx = sxx - sx * sx / n, cyy = syy - sy * sy / n, cxy = sxy - sx * sy / n;
    const double cxz = sxz - sx * sz / n, cyz = syz - sy * sz / n, det = cxx * cyy - cxy * cxy;
    const bool solvable = det > 1e-9 * (cxx * cyy + 1);
    DepthPlane p{0, solvable ? float((cxz * cyy - cyz * cxy) / det) : 0.0f,
                 solvable ? float((cyz * cxx - cxz * cxy) / det) : 0.0f, least, most};
    if (!std::isfinite(p.b) || !std::isfinite(p.c)) return {-inf, 0, 0, least, most};
    double a = std::numeric_limits<double>::infinity();
    for (int64_t y = ya; y < yb; ++y)
        for (int64_t x = xa; x < xb; ++x)
            a = std::min(a, double(depth_[size_t(y * W + x)]) - p.at(x - x0, y - y0));
    // Lowered a little below the least residual (the rounding of a and of the plane's sums), then
    // checked with the lookup's arithmetic.
    p.a = float(a - 1e-6 * (std::abs(a) + 1));
    for (int64_t y = ya; y < yb; ++y)
        for (int64_t x = xa; x < xb; ++x)
            if (!(p.at(x - x0, y - y0) <= double(depth_[size_t(y * W + x)])))
                return {-inf, 0, 0, least, most};
    return p;
}

void ShadowMap::buildLowerPlanes() {
    const int64_t W = view_.frame.width(), H = view_.frame.height();
    const int64_t tx = (W + kTile - 1) / kTile, ty = (H + kTile - 1) / kTile;
    lowerPlanes_.resize(size_t(tx * ty));
    parallelFor(0, tx * ty, 64, [&](int64_t t0, int64_t t1) {
        for (int64_t t = t0; t < t1; ++t)
            lowerPlanes_[size_t(t)] = lowerPlane((t % tx) * kTile, (t / tx) * kTile);
    });
}

float ShadowMap::visibility(const Vec3d& world, int pcfRadius, double bias) const {
    // bias / worldPerDepthUnit(), which is 1 for a perspective view (x / 1 is x: no division).
    return visibilityWithDepthBias(world, pcfRadius,
                                   view_.frame.isPerspective() ? bias : bias / view_.frame.cellSize().z);
}

float ShadowMap::visibilityWithDepthBias(const Vec3d& world, int pcfRadius, double depthBias) const {
    Vec3d g;
    if (depth_.empty() || !view_.locate(world, g)) return 1.0f;
    const double limit = g.z - depthBias;
    const int64_t W = view_.frame.width(), H = view_.frame.height();
    // Clamp: a point on the frame's border (or a rounding error) must not walk off the map.
    const int64_t cx = std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, W - 1);
    const int64_t cy = std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, H - 1);
    if (pcfRadius <= kTileBorder && !lowerPlanes_.empty()) {
        // Rounding is monotonic, so the plane's least value over the taps is at the corner of the
        // (clamped) tap square its slopes point away from.
        const int64_t bx = cx / kTile, by = cy / kTile;
        const DepthPlane& p = lowerPlanes_[size_t(by * ((W + kTile - 1) / kTile) + bx)];
        const int64_t x = std::clamp<int64_t>(p.b >= 0 ? cx - pcfRadius : cx + pcfRadius, 0, W - 1);
        const int64_t y = std::clamp<int64_t>(p.c >= 0 ? cy - pcfRadius : cy + pcfRadius, 0, H - 1);
        if (double(p.least) >= limit || p.at(x - bx * kTile, y - by * kTile) >= limit) return 1.0f;
        if (double(p.most) < limit) return 0.0f; // every tap in front of p
    }
    // The taps as rows: one clamp and one row address per row, and where the square's columns lie
    // inside the map (all but the map's border texels) a plain run of 2r + 1 texels. A depth d is lit exactly
    // where float d >= least, least the smallest float whose double is >= limit (rounded up from limit): the
    // same answer as double(d) >= limit, in float compares.
    const float least = detail::leastFloatAtLeast(limit);
    const int64_t r = pcfRadius, side = 2 * r + 1;
    const bool inside = cx >= r && cx + r < W;
    int lit = 0;
    for (int64_t dy = -r; dy <= r; ++dy) {
        const float* row = depth_.data() + std::clamp<int64_t>(cy + dy, 0, H - 1) * W;
        if (inside)
            for (const float* t = row + (cx - r); t != row + (cx + r + 1); ++t) lit += *t >= least;
        else
            for (int64_t dx = -r; dx <= r; ++dx) lit += row[std::clamp<int64_t>(cx + dx, 0, W - 1)] >= least;
    }
    return float(lit) / float(side * side);
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
    for (const LightView& v : out.views_) {
        out.maps_.push_back(ShadowMap::build(casters, v, progress));
        // What a lookup's bias comes to (visibility below): depthBias * columnWorldSize, divided
        // by the cell's depth; the same operands at every point of an orthographic view.
        out.depthBias_.push_back(v.frame.isPerspective()
                                     ? std::numeric_limits<double>::quiet_NaN()
                                     : options.depthBias * v.frame.cellSize().x / v.frame.cellSize().z);
    }
    return out;
}

MapShadow MapShadow::build(const Scene& scene, const Light& light, const ShadowMapOptions& options,
                           Progress* progress) {
    const detail::CasterSets casters = detail::collectCasters(scene);
    return build(light, casters.all.view(), options, progress);
}

float MapShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    Vec3d q;
    double texel = 0;
    const int i = detail::lookupView(views_, p, n, options_.normalOffset, q, &texel);
    if (i < 0) return 1.0f;
    const ShadowMap& map = maps_[size_t(i)];
    if (!views_[size_t(i)].frame.isPerspective())
        return map.visibilityWithDepthBias(q, options_.pcfRadius, depthBias_[size_t(i)]);
    return map.visibility(q, options_.pcfRadius, options_.depthBias * texel);
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
