// voxfx — deferred shading: normalized Blinn–Phong (Blinn 1977; the (s + 8) / 8pi normalization of
// Akenine-Möller et al., Real-Time Rendering) per light, times the light's RGB shadow visibility.
//
// Surfaces are lit on both sides. The side facing away from a light receives what crosses the
// surface (Material::crossingTransmittance): back-lit leaves glow, opaque surfaces stay dark; a
// translucent solid (Material::isTranslucent) passes diffuseTransmission of it, times the shadow.
#include "render/shading.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

#include "render/antialias.hpp"

namespace voxfx::detail {

Vec3f lightIrradiance(const Light& light, const Vec3d& p, Vec3d& toLight) {
    const Vec3f e = light.color * light.intensity;
    if (light.type == LightType::Directional) {
        toLight = -normalize(light.direction);
        return e;
    }
    const Vec3d d = light.position - p;
    const double dist2 = std::max(dot(d, d), 1e-12);
    toLight = d / std::sqrt(dist2);
    double falloff = 1.0 / dist2;
    if (light.type == LightType::Spot) {
        // Smoothstep between the outer and inner cone in the angle's cosine: continuous with a
        // continuous slope at both cones (glTF's reference t^2 has a kink at the inner cone, which
        // the eye sees as a bright ring: a Mach band).
        const double cosAngle = dot(-toLight, normalize(light.direction));
        const double cosOuter = std::cos(light.outerConeAngle), cosInner = std::cos(light.innerConeAngle);
        double s =
            cosInner > cosOuter ? (cosAngle - cosOuter) / (cosInner - cosOuter) : (cosAngle >= cosOuter);
        s = std::clamp(s, 0.0, 1.0);
        falloff *= s * s * (3 - 2 * s);
    }
    return e * float(falloff);
}

Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Vec3d& eye) {
    return shadePoint(frame, s, frame.lit.materials[s.material], eye);
}

Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Material& m, const Vec3d& eye) {
    const Scene& scene = frame.lit;
    const RenderOptions& options = frame.options;
    const std::vector<LightShadow>& shadows = frame.shadows;
    // Ambient: the constant plus the environment's irradiance around the normal (Lambert: / pi).
    Vec3f ambient = options.ambient;
    if (options.skyLight > 0)
        ambient += frame.environment->irradiance(s.normal) * float(options.skyLight / M_PI);
    if (options.ambientOcclusion == Occlusion::Field)
        ambient = ambient * float(frame.occlusion.visibility(s.position, s.normal));
    // A translucent solid reflects 1 - t of its diffuse light and passes t (KHR_materials_diffuse_
    // transmission): the light from behind is the translucency pass's, the lights' below.
    const float t = m.isTranslucent() ? m.diffuseTransmission : 0.0f;
    Vec3f out = t > 0 ? ambient * m.baseColor * (1 - t) : ambient * m.baseColor;
    const Vec3d toEye = normalize(eye - s.position);
    for (std::size_t k = 0; k < scene.lights.size(); ++k) {
        Vec3d l;
        const Vec3f e = lightIrradiance(scene.lights[k], s.position, l);
        if (e.x <= 0 && e.y <= 0 && e.z <= 0) continue;
        // Which side of the surface the light is on decides lit front vs. transmitted back light.
        const bool front = dot(s.geometricNormal, l) > 0;
        Vec3f radiance;
        if (front) {
            const double ndl = std::max(0.0, dot(s.normal, l));
            if (ndl <= 0) continue;
            const Vec3d h = normalize(l + toEye);
            const double spec = m.specular * (m.shininess + 8) / (8 * M_PI) *
                                std::pow(std::max(0.0, dot(s.normal, h)), double(m.shininess));
            const Vec3f diffuse =
                t > 0 ? m.baseColor * float((1 - t) / M_PI) : m.baseColor * float(1.0 / M_PI);
            radiance = (diffuse + Vec3f{1, 1, 1} * float(spec)) * float(ndl);
        } else if (t > 0) {
            // Diffuse transmission through a translucent solid; the shadow (translucency: Beer-Lambert
            // over the matter the light crossed) says how much reaches this side.
            const double ndl = std::max(0.0, -dot(s.normal, l));
            if (ndl <= 0) continue;
            radiance = m.diffuseTransmissionColor * float(t * ndl / M_PI);
        } else {
            if (m.isOpaque()) continue;
            const double ndl = std::max(0.0, -dot(s.normal, l));
            if (ndl <= 0) continue;
            radiance = m.baseColor * m.crossingTransmittance() * float(ndl / M_PI);
        }
        // The shadow lookup's normal offset goes towards the light's side of the surface.
        const Vec3d n = front ? s.geometricNormal : -s.geometricNormal;
        const Vec3f vis = k < shadows.size() ? shadowVisibility(shadows[k], s.position, n) : Vec3f{1, 1, 1};
        out += radiance * e * vis;
    }
    return out * options.exposure;
}

namespace {

// Background pixels show the environment along their ray.
void shadeBackground(FrameState& frame) {
    const Environment* env = frame.environment;
    const GBuffer& gbuffer = frame.gbuffer;
    const Frame& cam = gbuffer.frame;
    const int64_t W = frame.width;
    parallelFor(0, frame.height, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x)
                if (gbuffer.triangle[size_t(y * W + x)] == GBuffer::kNone && shadedSample(frame, x, y))
                    frame.shaded[size_t(y * W + x)] =
                        env->lookup(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - cam.eye()) *
                        frame.options.exposure;
    });
}

} // namespace

void shadeGBuffer(FrameState& frame, Progress* progress) {
    const GBuffer& gbuffer = frame.gbuffer;
    const SceneGeometry& geometry = frame.geometry;
    const RenderOptions& options = frame.options;
    const int64_t W = gbuffer.frame.width(), H = gbuffer.frame.height();
    // Exposure scales the whole linear image, the background included.
    std::vector<Vec3f>& out = frame.shaded;
    out.assign(size_t(W * H), options.background * options.exposure);
    constexpr int64_t kRows = 8;
    const int64_t blocks = (H + kRows - 1) / kRows;
    ProgressSteps steps(progress, blocks);
    parallelFor(0, blocks, 1, [&](int64_t b0, int64_t b1) {
        for (int64_t b = b0; b < b1 && !steps.cancelled(); ++b) {
            for (int64_t y = b * kRows; y < std::min(H, (b + 1) * kRows); ++y)
                for (int64_t x = 0; x < W; ++x) {
                    SurfacePoint s;
                    if (shadedSample(frame, x, y) && surfaceAt(gbuffer, geometry, x, y, s))
                        out[size_t(y * W + x)] = shadePoint(frame, s, gbuffer.frame.eye());
                }
            steps.step();
        }
    });
    if (steps.cancelled()) fail("cancelled");
    shadeBackground(frame);
}

} // namespace voxfx::detail
