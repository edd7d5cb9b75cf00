// voxfx — the translucency pass: GI08 §7 for the camera (see translucency_pass.hpp). The translucent
// meshes are voxelized as a solid in the camera's own frame (viewMatterBehind), the solid cells
// between each visible translucent surface and the opaque surface behind it counted into a length,
// and the light from behind attenuated by Beer-Lambert over it: thin parts show what lies behind,
// thick parts are dark. A translucent solid scatters: what lies behind is averaged over a cone
// whose angle grows with the length crossed (RenderOptions::translucencyBlur), so thick jade
// shows a blur of the scene behind it, not a sharp image as clear glass does.
#include "render/translucency_pass.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "render/antialias.hpp"
#include "render/shading.hpp"
#include "voxfx/translucency_shadow.hpp"

namespace voxfx::detail {

namespace {

// The samples the passes shade that show a translucent surface: their depth, the rest infinity;
// empty where there is none.
std::vector<float> translucentDepths(const FrameState& f, const std::vector<uint8_t>& translucent) {
    const SceneGeometry& g = f.geometry;
    const GBuffer& gb = f.gbuffer;
    std::vector<float> front(gb.depth.size(), std::numeric_limits<float>::infinity());
    bool anySample = false;
    for (int64_t y = 0; y < f.height; ++y)
        for (int64_t x = 0; x < f.width; ++x) {
            const auto i = size_t(y * f.width + x);
            const uint32_t t = gb.triangle[i];
            if (t == GBuffer::kNone || !translucent[g.triangleMaterial[t]] || !shadedSample(f, x, y))
                continue;
            front[i] = gb.depth[i];
            anySample = true;
        }
    if (!anySample) front.clear();
    return front;
}

// What lies behind: the scene without the translucent meshes (their triangles collapsed to a
// point, so the triangle numbers and surfaceAt stay valid); the translucent triangles' vertex
// indices appended to `solid`.
SceneGeometry withoutTranslucent(const SceneGeometry& g, const std::vector<uint8_t>& translucent,
                                 std::vector<uint32_t>& solid) {
    SceneGeometry behind = g;
    for (std::size_t t = 0; t < g.drawnTriangles; ++t) {
        if (!translucent[g.triangleMaterial[t]]) continue;
        for (int k = 0; k < 3; ++k) solid.push_back(g.mesh.indices[3 * t + k]);
        behind.mesh.indices[3 * t + 1] = behind.mesh.indices[3 * t + 2] = behind.mesh.indices[3 * t];
    }
    return behind;
}

// The taps of a blurred sample: kTaps points of a Vogel spiral over the disc of its radius (the
// same pattern for every sample, so the blur is smooth and deterministic); a tap lands on the
// sample whose cell holds it, clamped to the W x H image.
struct BlurTaps {
    static constexpr int kTaps = 32;
    std::array<std::array<double, 2>, kTaps> taps;
    int64_t W, H;
    BlurTaps(int64_t width, int64_t height) : W(width), H(height) {
        for (int t = 0; t < kTaps; ++t) {
            const double rho = std::sqrt((double(t) + 0.5) / kTaps), phi = 2.399963229728653 * double(t);
            taps[size_t(t)] = {rho * std::cos(phi), rho * std::sin(phi)};
        }
    }
    // The sample tap t of the sample (x, y) with blur radius r lands on; its position in (tx, ty).
    size_t at(int64_t x, int64_t y, double r, int t, double& tx, double& ty) const {
        tx = std::clamp(double(x) + 0.5 + r * taps[size_t(t)][0], 0.5, double(W) - 0.5);
        ty = std::clamp(double(y) + 0.5 + r * taps[size_t(t)][1], 0.5, double(H) - 0.5);
        return size_t(int64_t(ty) * W + int64_t(tx));
    }
};
constexpr int kBlurTaps = BlurTaps::kTaps;

} // namespace

void compositeTranslucency(FrameState& f) {
    const std::vector<Material>& materials = f.scene.materials;
    std::vector<uint8_t> translucent(materials.size(), 0);
    bool anyMaterial = false;
    for (std::size_t i = 0; i < materials.size(); ++i)
        anyMaterial |= (translucent[i] = materials[i].isTranslucent()) != 0;
    if (!anyMaterial) return;
    const SceneGeometry& g = f.geometry;
    const GBuffer& gb = f.gbuffer;
    const int64_t W = f.width, H = f.height;
    const float none = std::numeric_limits<float>::infinity();
    const std::vector<float> front = translucentDepths(f, translucent);
    if (front.empty()) return;
    std::vector<uint32_t> solid;
    const SceneGeometry behind = withoutTranslucent(g, translucent, solid);
    const GBuffer back = renderGBuffer(behind, gb.frame);
    MeshView solids;
    solids.positions = &g.mesh.positions[0].x;
    solids.vertexCount = g.mesh.positions.size();
    solids.indices = solid.data();
    solids.triangleCount = solid.size() / 3;
    // One column per output pixel: the samples of a pixel share its centre ray's cells (each from
    // its own depths), so supersampling does not multiply the grid.
    const int64_t k = W / f.options.width;
    const ViewMatter matter = ViewMatter::build(cameraFrame(f.camera, f.options.width, f.options.height),
                                                solids, Fill::Auto, f.options.translucencySlices);
    const Vec3d eye = gb.frame.eye();
    const Environment& env = *f.environment;
    const float exposure = f.options.exposure;
    auto background = [&](double x, double y, double blurCone) {
        return env.lookup(gb.frame.worldFromGrid({x, y, 1.0}) - eye, blurCone) * exposure;
    };
    // Per sample showing a translucent solid: the matter its ray crosses and the blur cone over
    // what lies behind (half-angle `cone`, `radius` samples across the image where it meets what
    // lies behind: the cone's apex at the visible surface, so the blur also grows with the gap
    // between the solid and what lies behind it; an infinite gap, the environment, gives
    // focal * tan(cone)).
    const double blur = f.options.translucencyBlur;
    const double focal = double(H) / (2 * gb.frame.tanHalfFovY());
    const size_t n = front.size();
    std::vector<double> crossed(n, 0);
    std::vector<float> cone(n, 0), radius(n, 0);
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto i = size_t(y * W + x);
                if (!std::isfinite(front[i])) continue;
                const Material& m = materials[g.triangleMaterial[gb.triangle[i]]];
                const double L = matter.between(x / k, y / k, double(front[i]), double(back.depth[i]));
                crossed[i] = L;
                const double a = translucencyCone(m, L, blur);
                if (!(a > 0)) continue;
                const double zb = back.triangle[i] == GBuffer::kNone ? none : double(back.depth[i]);
                const double gap = std::isfinite(zb) ? std::max(0.0, zb - double(front[i])) / zb : 1.0;
                cone[i] = float(a);
                radius[i] = float(focal * std::tan(a) * gap);
            }
    });
    const BlurTaps taps(W, H);
    const auto tapAt = [&](int64_t x, int64_t y, double r, int t, double& tx, double& ty) {
        return taps.at(x, y, r, t, tx, ty);
    };
    // The samples of the scene behind that some tap (or an unblurred sample itself) reads: shaded
    // once each. state: 1 needed, 2 a surface (behindLight), 3 none (the environment).
    std::vector<uint8_t> state(n, 0);
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const auto i = size_t(y * W + x);
            if (!std::isfinite(front[i])) continue;
            state[i] = 1;
            if (radius[i] < 0.5f) continue;
            double tx, ty;
            for (int t = 0; t < kBlurTaps; ++t) state[tapAt(x, y, radius[i], t, tx, ty)] = 1;
        }
    std::vector<Vec3f> behindLight(n);
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto i = size_t(y * W + x);
                if (!state[i]) continue;
                SurfacePoint s;
                const bool surface = surfaceAt(back, behind, x, y, s);
                if (surface) behindLight[i] = shadePoint(f, s, eye);
                state[i] = surface ? 2 : 3;
            }
    });
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto i = size_t(y * W + x);
                if (!std::isfinite(front[i])) continue;
                const Material& m = materials[g.triangleMaterial[gb.triangle[i]]];
                Vec3f light =
                    state[i] == 2 ? behindLight[i] : background(double(x) + 0.5, double(y) + 0.5, 0);
                if (radius[i] >= 0.5f) {
                    // The mean of the taps, leaving out surfaces in front of this one (an opaque
                    // object between the eye and the solid is not behind it).
                    Vec3f sum{0, 0, 0};
                    int count = 0;
                    for (int t = 0; t < kBlurTaps; ++t) {
                        double tx, ty;
                        const size_t j = tapAt(x, y, radius[i], t, tx, ty);
                        if (state[j] == 2) {
                            if (back.depth[j] < front[i]) continue;
                            sum += behindLight[j];
                        } else {
                            sum += background(tx, ty, cone[i]);
                        }
                        ++count;
                    }
                    if (count > 0) light = sum * (1.0f / float(count));
                }
                f.shaded[i] +=
                    light * beerLambert(attenuationCoefficient(m), crossed[i]) * m.diffuseTransmission;
            }
    });
}

double translucencyCone(const Material& m, double length, double blur) {
    if (!(blur > 0) || !(length > 0) || !(m.attenuationDistance > 0) || !std::isfinite(m.attenuationDistance))
        return 0;
    return std::min(kTranslucencyMaxCone, blur * length / double(m.attenuationDistance));
}

} // namespace voxfx::detail
