// voxfx — the deferred shading pass (internal): Blinn–Phong per light times the light's shadow.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "render/frame_state.hpp"
#include "render/vec_simd.hpp"

namespace voxfx::detail {

/// What lightIrradiance reads of a light beyond its position, computed once per light: a spot's unit
/// axis and the cosines of its cones (two cos per lookup were 3 % of the DSM demo's frame).
struct LightCone {
    Vec3d axis{0, 0, -1};
    double cosOuter = 0, cosInner = 1;
    LightCone() = default;
    explicit LightCone(const Light& light);
};

/// The unit direction from p towards the light (for a directional light, against its direction).
inline Vec3d directionToLight(const Light& light, const Vec3d& p) {
    const Vec3d d = light.towards(p);
    return light.positioned() ? dividedBy(d, std::sqrt(std::max(dot(d, d), 1e-12))) : d;
}

/// Irradiance the light delivers at p without shadow (spot cone and 1/d^2 falloff included), and the
/// unit direction from p towards the light; `cone` is LightCone(light).
Vec3f lightIrradiance(const Light& light, const LightCone& cone, const Vec3d& p, Vec3d& toLight);
/// The same, the cone computed here.
inline Vec3f lightIrradiance(const Light& light, const Vec3d& p, Vec3d& toLight) {
    return lightIrradiance(light, LightCone(light), p, toLight);
}

/// What shading reads of a material, computed once (SurfaceShader::prepare).
struct ShadeMaterial {
    Vec3f ambientAlbedo;      ///< baseColor, times 1 - t for a translucent solid
    Vec3f diffuse;            ///< the front's Lambert BRDF: ambientAlbedo / pi
    Vec3f behind;             ///< radiance per unit irradiance and cosine from a light on the far side
    float specular = 0;       ///< normalized Blinn–Phong factor: specular (s + 8) / 8 pi (0: none)
    float shininess = 32;     ///< s
    int integerShininess = 0; ///< s where it is an integer in [1, 4096] (powers by squaring), else 0
};

/// ndh^m.shininess for 0 <= ndh <= 1 (the specular lobe): std::pow, or for an integer exponent
/// (m.integerShininess) powers by squaring in double, rounded once to float: the correctly rounded
/// power but where the exact one lies within about s 2^-53 (relative) of a float rounding boundary,
/// so it differs from pow (within 0.82 ulp, glibc) by at most an ulp, where pow is not correctly
/// rounded; and it costs a few multiplications instead of a pow (4 % of the CGAL scene's frame).
float specularPower(float ndh, const ShadeMaterial& m);

/// Per triangle of the flattened scene, its TriangleBasis (render/render_cache.hpp).
std::vector<TriangleBasis> triangleBases(const SceneGeometry& geometry);

/// Per material of `scene`, 1 where it occludes (Material::isOpaque): the occlusion's rule, which
/// triangleTags and the screen-space occlusion read.
void opaqueMaterials(const Scene& scene, std::vector<uint8_t>& out);

/// Per triangle of the flattened scene, its TriangleTag (render/screen_space_ao.hpp) from its basis,
/// and whether it occludes from opaqueMaterial (per material index; past it: not).
std::vector<TriangleTag> triangleTags(const SceneGeometry& geometry, std::span<const TriangleBasis> bases,
                                      std::span<const uint8_t> opaqueMaterial);

/// The unit shading normal of the triangle of `basis` at the point basis.a + rel of its plane: its
/// vertex normals (basis.cornerNormal) weighted by the point's barycentrics (clamped at 0), the face
/// normal where they cancel; not yet turned towards the viewer (surfaceFromBasis does that).
Vec3f interpolatedNormal(const TriangleBasis& basis, const Vec3f& rel);

/// The surface seen through G-buffer sample (x, y), as surfaceAt (voxfx/gbuffer.hpp) gives it, from
/// the precomputed bases. False for the background.
bool surfaceFromBasis(const GBuffer& gbuffer, const SceneGeometry& geometry,
                      std::span<const TriangleBasis> bases, int64_t x, int64_t y, SurfacePoint& out);

/// What every surface sample of a frame is shaded with: the lights (irradiance, direction of the
/// directional ones, shadow), the environment's irradiance harmonics, the ambient constant and
/// occlusion field, the exposure, the scene's materials. Built by the shading pass once per frame
/// (FrameState::shader).
class SurfaceShader {
public:
    explicit SurfaceShader(const FrameState& frame);
    /// Linear radiance (times the exposure) of surface point s seen from `eye`, of the scene's
    /// material s.material: ambient (times `occlusion`, and the occlusion field's visibility where
    /// the frame has one) plus every light's normalized Blinn–Phong times its shadow's visibility.
    Vec3f shade(const SurfacePoint& s, const Vec3d& eye, float occlusion = 1) const;
    /// The same with material m instead (the volume pass's objects).
    Vec3f shade(const SurfacePoint& s, const Material& m, const Vec3d& eye, float occlusion = 1) const;
    static ShadeMaterial prepare(const Material& m);

private:
    Vec3f shadeWith(const SurfacePoint& s, const ShadeMaterial& m, const Vec3d& eye, float occlusion) const;
    Vec3f skyIrradiance(const Vec3d& normal) const;
    struct LightTerm {
        const Light* light = nullptr;
        const LightShadow* shadow = nullptr;
        Vec3f irradiance; ///< colour times intensity
        Vec3d toLight;    ///< directional: the unit direction towards it
        LightCone cone;
        bool directional = false;
    };
    const Environment* environment_;
    const AmbientOcclusion* field_;
    float exposure_;
    Vec3f ambient_;
    bool sky_ = false;
    std::array<Vec3f, 9> sh_;         ///< irradiance coefficients, times skyLight / pi
    alignas(16) float shLanes_[9][4]; ///< the same, as four lanes (the fourth 0) for SIMD sums
    std::vector<LightTerm> lights_;
    std::vector<ShadeMaterial> materials_; ///< the scene's, prepared
};

/// Linear radiance of one surface point of the frame's scene seen from `eye` (ambient + every light,
/// each times its shadow's visibility): frame.shader's, which the shading pass builds.
Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Vec3d& eye);
/// The same with material `m` instead of lit.materials[s.material] (the volume pass's objects).
Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Material& m, const Vec3d& eye);

/// The shading pass: every pixel of the G-buffer into frame.shaded (background where nothing was
/// hit, or the environment along the pixel's ray when one was given), rows in parallel; `progress`
/// is polled between row blocks. A cell's representative that shows glass the glass pass replaces
/// (glassReplacesShading) is left black: the glass pass shades it where no path goes through.
void shadeGBuffer(FrameState& frame, Progress* progress);

/// Whether the glass pass replaces the surface shading of material `m` entirely: a glass method is
/// chosen and `m` is glass of transmission 1 (its shading would be mixed in times 0).
bool glassReplacesShading(const FrameState& frame, uint32_t m);

/// Sample i of the G-buffer: its surface point shaded with the ambient light's `occlusion`, or the
/// environment along its ray where it shows the background (the shading pass's, and the glass
/// pass's for a representative glassReplacesShading left black and no path went through).
/// `known`: its surface point, where the caller has it.
Vec3f shadeSample(const FrameState& frame, std::size_t i, float occlusion,
                  const SurfacePoint* known = nullptr);

} // namespace voxfx::detail
