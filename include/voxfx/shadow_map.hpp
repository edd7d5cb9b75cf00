// voxfx — the standard shadow map (Williams 1978) with percentage-closer filtering (Reeves et al.
// 1987): the baseline every other shadow is compared with (ED06 table 1, CHANG §3). Shadow
// technique "map" (voxfx/shadow.hpp): every caster in one depth map per light view, binary
// visibility, PCF; leaves are opaque to it.
//
// A consumer of the one rasterizer keeps the nearest centre-sampled caster depth per texel; a
// lookup compares the point's depth with the (2r+1)^2 texels around its own and returns the lit
// fraction. Self-shadowing bias: the lookup point moves along the normal (turned towards the light)
// by `normalOffset` column footprints, and casters count only `depthBias` texel footprints in front
// of it.
//
// Thread-safety: a built map is read-only (lookups from any number of threads); build rasterizes
// with worker threads.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/light_view.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_options.hpp"

namespace voxfx {

/// One depth map in one light view.
class ShadowMap {
public:
    ShadowMap() = default;
    /// `casters` in world space. Cost: one rasterization at the view's resolution.
    static ShadowMap build(const MeshView& casters, const LightView& view, Progress* progress = nullptr);
    /// Fraction in [0, 1] of the (2r+1)^2 texels around p's texel whose nearest caster is not in
    /// front of p by more than `bias` (world units). 1 outside the view.
    float visibility(const Vec3d& world, int pcfRadius, double bias) const;
    /// visibility with the bias in the frame's depth units (bias / worldPerDepthUnit()), for a
    /// caller that has it at hand (MapShadow: one division per orthographic view, not per lookup).
    float visibilityWithDepthBias(const Vec3d& world, int pcfRadius, double depthBias) const;
    /// Nearest caster depth of texel (x, y) in frame depth units; +inf where there is none.
    float depthAt(int64_t x, int64_t y) const { return depth_[size_t(y * view_.frame.width() + x)]; }
    const LightView& view() const { return view_; }

private:
    LightView view_;
    std::vector<float> depth_;
    // Two lower bounds of the depths of each kTile x kTile block of texels and of the kTileBorder
    // texels around it: the least depth, and a plane, depth(x, y) >= a + b (x - x0) + c (y - y0)
    // with (x0, y0) the block's first texel, checked texel by texel with the lookup's own
    // arithmetic. A lookup whose taps all lie there and whose point is not behind either bound at
    // the lowest tap is lit by every tap (open ground beside the casters, most of a forest floor,
    // leaves above a trunk's block), answered without reading the taps; the answer is the same.
    // Also the greatest depth there (+inf where a texel holds no caster): a point behind it is
    // dark at every tap (the ground under a trunk or branch whose block it fills).
    static constexpr int64_t kTile = 16, kTileBorder = 1;
    struct DepthPlane {
        float a, b, c;
        float least, most;
        double at(int64_t dx, int64_t dy) const {
            return double(a) + double(b) * double(dx) + double(c) * double(dy);
        }
    };
    std::vector<DepthPlane> lowerPlanes_; // row-major blocks
    void buildLowerPlanes();
    DepthPlane lowerPlane(int64_t x0, int64_t y0) const;
};

/// The maps of one light (one per light view: six cube faces for a point light), with the lookup.
class MapShadow {
public:
    using Options = ShadowMapOptions;
    using Stats = MapShadowStats;
    MapShadow() = default; ///< no casters: visibility 1
    /// The maps of `casters` (world space) fitted to them. Throws voxfx::Error for a resolution
    /// < 1 or a PCF radius < 0.
    static MapShadow build(const Light& light, const MeshView& casters, const ShadowMapOptions& options,
                           Progress* progress = nullptr);
    /// Every mesh of `scene` that casts shadows (SceneMesh::castsShadow).
    static MapShadow build(const Scene& scene, const Light& light, const ShadowMapOptions& options,
                           Progress* progress = nullptr);
    /// Fraction of the light reaching p (see the file comment); `n` the unit geometric normal
    /// turned towards the light (zero: no offset). 1 outside every view.
    float visibility(const Vec3d& p, const Vec3d& n) const;
    Stats stats() const;
    const std::vector<ShadowMap>& maps() const { return maps_; }
    const std::vector<LightView>& views() const { return views_; }

private:
    ShadowMapOptions options_;
    std::vector<LightView> views_;
    std::vector<ShadowMap> maps_;
    // Per view: the depth bias in frame depth units, depthBias * texel / worldPerDepthUnit(), where
    // it is the same at every point (orthographic views: the texel footprint is constant); NaN for
    // perspective views, whose lookups take it at the point.
    std::vector<double> depthBias_;
};

} // namespace voxfx
