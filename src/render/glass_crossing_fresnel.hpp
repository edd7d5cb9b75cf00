// voxfx — the Fresnel loss of every glass crossing along the columns of a light view (internal; the
// transmittance and absorption shadows read it).
//
// A light grid counts filled cells, so it gives every crossing of one glass the same factor, the
// 1 - F0 of normal incidence (Material::shadowCrossingTransmittance). Glass crossed at an angle
// passes less: e = -ln(1 - F(cos)) + ln(1 - F0) >= 0 more optical depth. Taken per triangle (its flat
// normal), e steps from triangle to triangle, and where the light grazes a curved glass (the rim of
// a ball's shadow) the steps are large and the rim darkens in beads. Here e is taken where the ray
// through each column's centre crosses the glass, with the stored normal interpolated there
// (flattenScene's: the scene's normals, else smoothed within the crease angle), so a smooth glass's
// shadow darkens smoothly towards its rim, as a smooth glass does.
//
// The crossings are found by rasterizing the glass triangles into the view's columns with exact
// integer edge functions and a top-left rule: a closed sheet is crossed once per column centre, never
// twice at a shared edge. Each column keeps its crossings in depth order with the fraction passed
// by all of them up to each (deterministic: sorted, whatever the thread count).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "voxfx/light_grid.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/scene.hpp"

namespace voxfx::detail {

/// The glass that casts shadows in a scene, as the shadows see it: triangles (world space), one unit
/// normal per vertex (flattenScene's), the index of refraction per triangle.
struct ShadowGlass {
    Mesh mesh;
    std::vector<Vec3f> normals;
    std::vector<float> ior;
    bool empty() const { return mesh.indices.empty(); }
};

/// The scene's shadow-casting glass (Material::isGlass, not opaque, SceneMesh::castsShadow).
ShadowGlass collectShadowGlass(const Scene& scene);

class GlassCrossingFresnel {
public:
    GlassCrossingFresnel() = default;
    /// The crossings of `glass` along every column of `view`, slices under view.frame's slicing;
    /// each passes exp(-e) (`beyondNormalIncidence`: the transmittance grid passes 1 - F0 per
    /// crossing already) or its whole 1 - F(cos) (the absorption grid writes no Fresnel).
    static GlassCrossingFresnel build(const ShadowGlass& glass, const LightView& view,
                                      bool beyondNormalIncidence);
    bool empty() const { return passes_.empty(); }
    /// The fraction of light the crossings of `column` in slices [0, end) pass (beyond 1 - F0 each
    /// where built so). 1 for a column without glass.
    double pass(int64_t column, int64_t end) const;

private:
    int64_t width_ = 0;                         // the view's columns per row
    int64_t x0_ = 0, y0_ = 0, x1_ = 0, y1_ = 0; // the columns holding crossings: [x0, x1) x [y0, y1)
    std::vector<uint32_t> offsets_;             // (x1 - x0) (y1 - y0) + 1
    std::vector<uint32_t> slices_;              // per crossing, in depth order within a column
    std::vector<float> passes_;                 // per crossing: exp(-e) of it and those before it
};

/// One per light view (none without shadow-casting glass).
using GlassFresnelViews = std::vector<std::shared_ptr<const GlassCrossingFresnel>>;
GlassFresnelViews buildGlassFresnelViews(const Scene& scene, const std::vector<LightView>& views,
                                         bool beyondNormalIncidence);
/// glassFresnelPass where the scene has shadow-casting glass (fresnel not empty).
double glassFresnelPassThrough(const GlassFresnelViews& fresnel, const std::vector<LightView>& views, int i,
                               const Vec3d& q, const Vec3d& n, const LightGridOptions& grid);
/// The fraction the glass crossings in front of lookup point q pass, through view i's columns as the
/// light grid's lookup reads them (bilinear and sharpened, or q's column; grid.skipCells). Without
/// shadow-casting glass 1, here without a call (every light-grid lookup asks).
inline double glassFresnelPass(const GlassFresnelViews& fresnel, const std::vector<LightView>& views, int i,
                               const Vec3d& q, const Vec3d& n, const LightGridOptions& grid) {
    return fresnel.empty() ? 1.0 : glassFresnelPassThrough(fresnel, views, i, q, n, grid);
}

} // namespace voxfx::detail
