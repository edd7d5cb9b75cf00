// voxfx — deferred shading: normalized Blinn–Phong (Blinn 1977; the (s + 8) / 8pi normalization of
// Akenine-Möller et al., Real-Time Rendering) per light, times the light's RGB shadow visibility.
//
// Surfaces are lit on both sides. The side facing away from a light receives what crosses the
// surface (Material::crossingTransmittance): back-lit leaves glow, opaque surfaces stay dark; a
// translucent solid (Material::isTranslucent) passes diffuseTransmission of it, times the shadow.
#include "render/shading.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>

#include "render/antialias.hpp"
#include "render/screen_space_ao.hpp"
#include "render/vec_simd.hpp"

namespace voxfx::detail {

LightCone::LightCone(const Light& light) {
    if (light.type != LightType::Spot) return;
    axis = normalize(light.direction);
    cosOuter = std::cos(light.outerConeAngle);
    cosInner = std::cos(light.innerConeAngle);
}

Vec3f lightIrradiance(const Light& light, const LightCone& cone, const Vec3d& p, Vec3d& toLight) {
    const Vec3f e = light.color * light.intensity;
    if (!light.positioned()) {
        toLight = light.towards(p);
        return e;
    }
    const Vec3d d = light.towards(p);
    const double dist2 = std::max(dot(d, d), 1e-12);
    toLight = directionToLight(light, p);
    double falloff = 1.0 / dist2;
    if (light.type == LightType::Spot) {
        // Smoothstep between the outer and inner cone in the angle's cosine: continuous with a
        // continuous slope at both cones (glTF's reference t^2 has a kink at the inner cone, which
        // the eye sees as a bright ring: a Mach band).
        const double cosAngle = dot(-toLight, cone.axis);
        const double cosOuter = cone.cosOuter, cosInner = cone.cosInner;
        double s =
            cosInner > cosOuter ? (cosAngle - cosOuter) / (cosInner - cosOuter) : (cosAngle >= cosOuter);
        s = std::clamp(s, 0.0, 1.0);
        falloff *= s * s * (3 - 2 * s);
    }
    return e * float(falloff);
}

SurfaceShader::SurfaceShader(const FrameState& frame)
    : environment_(frame.environment), field_(frame.occlusion.get()), exposure_(frame.options.exposure),
      ambient_(frame.options.ambient) {
    const RenderOptions& o = frame.options;
    // Irradiance from the environment's order-2 harmonics (Environment::irradiance, in float): the
    // clamped cosine's coefficients per band pi, 2 pi / 3, pi / 4, times skyLight / pi (Lambert).
    sky_ = o.skyLight > 0;
    constexpr double band[9] = {M_PI,     2 * M_PI / 3, 2 * M_PI / 3, 2 * M_PI / 3, M_PI / 4,
                                M_PI / 4, M_PI / 4,     M_PI / 4,     M_PI / 4};
    for (int b = 0; b < 9; ++b) {
        sh_[size_t(b)] = environment_->sphericalHarmonics()[size_t(b)] * float(band[b] * o.skyLight / M_PI);
        shLanes_[b][0] = sh_[size_t(b)].x, shLanes_[b][1] = sh_[size_t(b)].y,
        shLanes_[b][2] = sh_[size_t(b)].z;
        shLanes_[b][3] = 0;
    }
    materials_.reserve(frame.scene.materials.size());
    for (const Material& m : frame.scene.materials) materials_.push_back(prepare(m));
    for (std::size_t k = 0; k < frame.lights.size(); ++k) {
        const Light& l = frame.lights[k];
        LightTerm t;
        t.light = &l;
        t.shadow = k < frame.shadows.size() ? frame.shadows[k].get() : nullptr;
        t.directional = !l.positioned();
        t.irradiance = l.color * l.intensity;
        t.cone = LightCone(l);
        if (t.directional) t.toLight = l.towards(Vec3d{0, 0, 0}); // the same from everywhere
        if (t.irradiance.x <= 0 && t.irradiance.y <= 0 && t.irradiance.z <= 0) continue;
        lights_.push_back(t);
    }
}

Vec3f SurfaceShader::skyIrradiance(const Vec3d& normal) const {
    // The shading normal is unit already (surfaceAt, surfaceFromBasis); others are normalized.
    Vec3f n(normal);
    const float len2 = dot(n, n);
    if (std::abs(len2 - 1) > 1e-5f) n = n / std::sqrt(len2);
    const float x = n.x, y = n.y, z = n.z;
    const float basis[9] = {0.282095f,
                            0.488603f * y,
                            0.488603f * z,
                            0.488603f * x,
                            1.092548f * x * y,
                            1.092548f * y * z,
                            0.315392f * (3 * z * z - 1),
                            1.092548f * x * z,
                            0.546274f * (x * x - y * y)};
#ifdef VOXFX_VEC_SIMD_SSE
    // The scalar sum below in lanes, term by term in the same order: the same floats.
    __m128 e = _mm_setzero_ps();
    for (int b = 0; b < 9; ++b)
        e = _mm_add_ps(e, _mm_mul_ps(_mm_load_ps(shLanes_[b]), _mm_set1_ps(basis[b])));
    // std::max(0.0f, v) is 0 < v ? v : 0, as maxps(v, 0).
    alignas(16) float r[4];
    _mm_store_ps(r, _mm_max_ps(e, _mm_setzero_ps()));
    return {r[0], r[1], r[2]};
#else
    Vec3f e;
    for (int b = 0; b < 9; ++b) e += sh_[size_t(b)] * basis[b];
    return {std::max(0.0f, e.x), std::max(0.0f, e.y), std::max(0.0f, e.z)};
#endif
}

ShadeMaterial SurfaceShader::prepare(const Material& m) {
    // A translucent solid reflects 1 - t of its diffuse light and passes t (KHR_materials_diffuse_
    // transmission): the light from behind is the translucency pass's, the lights' below.
    ShadeMaterial out;
    const float t = m.isTranslucent() ? m.diffuseTransmission : 0.0f;
    out.ambientAlbedo = t > 0 ? m.baseColor * (1 - t) : m.baseColor;
    out.diffuse = out.ambientAlbedo * float(1.0 / M_PI);
    if (t > 0) // diffuse transmission through a translucent solid, times its shadow
        out.behind = m.diffuseTransmissionColor * float(t / M_PI);
    else if (!m.isOpaque()) // what crosses a sheet (back-lit leaves glow)
        out.behind = m.baseColor * m.crossingTransmittance() * float(1.0 / M_PI);
    out.specular = m.specular > 0 ? m.specular * (m.shininess + 8) / float(8 * M_PI) : 0.0f;
    out.shininess = m.shininess;
    if (m.shininess >= 1 && m.shininess <= 4096 && m.shininess == std::floor(m.shininess))
        out.integerShininess = int(m.shininess);
    return out;
}

float specularPower(float ndh, const ShadeMaterial& m) {
    if (m.integerShininess == 0) return std::pow(ndh, m.shininess);
    // At most 2 log2(s) products, each rounded to 53 bits: a relative error below about s 2^-53.
    double r = 1, b = double(ndh);
    for (int e = m.integerShininess;; b *= b) {
        if (e & 1) r *= b;
        if ((e >>= 1) == 0) break;
    }
    return float(r);
}

Vec3f SurfaceShader::shade(const SurfacePoint& s, const Vec3d& eye, float occlusion) const {
    return shadeWith(s, materials_[s.material], eye, occlusion);
}

Vec3f SurfaceShader::shade(const SurfacePoint& s, const Material& m, const Vec3d& eye,
                           float occlusion) const {
    return shadeWith(s, prepare(m), eye, occlusion);
}

Vec3f SurfaceShader::shadeWith(const SurfacePoint& s, const ShadeMaterial& m, const Vec3d& eye,
                               float occlusion) const {
    // Ambient: the constant plus the environment's irradiance around the normal (Lambert: / pi),
    // times its occlusion (the field's, or the screen-space one the caller gives).
    Vec3f ambient = ambient_;
    if (sky_) ambient += skyIrradiance(s.normal);
    if (field_) occlusion *= float(field_->visibility(s.position, s.normal));
    Vec3f out = ambient * m.ambientAlbedo * occlusion;
    if (lights_.empty()) return out * exposure_;
    const Vec3d toEye = normalized(eye - s.position);
    const bool lightsBehind = m.behind.x > 0 || m.behind.y > 0 || m.behind.z > 0;
    for (const LightTerm& lt : lights_) {
        Vec3d l = lt.toLight;
        const Vec3f e = lt.directional ? lt.irradiance : lightIrradiance(*lt.light, lt.cone, s.position, l);
        if (e.x <= 0 && e.y <= 0 && e.z <= 0) continue;
        // Which side of the surface the light is on decides lit front vs. transmitted back light.
        const bool front = dot(s.geometricNormal, l) > 0;
        Vec3f radiance;
        if (front) {
            const double ndl = dot(s.normal, l);
            if (ndl <= 0) continue;
            float spec = 0;
            if (m.specular > 0) {
                const Vec3d h = normalized(l + toEye);
                const float ndh = float(std::max(0.0, dot(s.normal, h)));
                // x^s <= e^(s (x - 1)) (as ln x <= x - 1): below 1e-4 where s (1 - x) > 9.21, a lobe
                // too faint to show, so most samples skip the pow.
                if (m.shininess * (1 - ndh) < 9.21f) spec = m.specular * specularPower(ndh, m);
            }
            radiance = (m.diffuse + Vec3f{spec, spec, spec}) * float(ndl);
        } else {
            if (!lightsBehind) continue; // an opaque surface's back stays dark
            const double ndl = -dot(s.normal, l);
            if (ndl <= 0) continue;
            radiance = m.behind * float(ndl);
        }
        // The shadow lookup's normal offset goes towards the light's side of the surface.
        if (lt.shadow)
            radiance = radiance * shadowVisibility(*lt.shadow, s.position,
                                                   front ? s.geometricNormal : -s.geometricNormal);
        out += radiance * e;
    }
    return out * exposure_;
}

std::vector<TriangleBasis> triangleBases(const SceneGeometry& geometry) {
    const Mesh& mesh = geometry.mesh;
    std::vector<TriangleBasis> out(mesh.triangleCount());
    parallelFor(0, int64_t(out.size()), 4096, [&](int64_t t0, int64_t t1) {
        for (int64_t t = t0; t < t1; ++t) {
            const uint32_t* corner = &mesh.indices[3 * size_t(t)];
            const Vec3d a(mesh.positions[corner[0]]), b(mesh.positions[corner[1]]),
                c(mesh.positions[corner[2]]);
            const Vec3d e1 = b - a, e2 = c - a, n = cross(e1, e2);
            const double area2 = dot(n, n);
            TriangleBasis& basis = out[size_t(t)];
            basis.a = Vec3f(a);
            for (int k = 0; k < 3; ++k) basis.cornerNormal[k] = geometry.normals[corner[k]];
            if (area2 > 0) {
                // p - a = wb e1 + wc e2 in the plane: wb = (p - a).(e2 x n) / |n|^2 and
                // wc = (p - a).(n x e1) / |n|^2 (triple products of (p - a) x e2 = wb n).
                basis.toB = Vec3f(cross(e2, n) / area2);
                basis.toC = Vec3f(cross(n, e1) / area2);
                basis.normal = Vec3f(n / std::sqrt(area2));
            }
        }
    });
    return out;
}

void opaqueMaterials(const Scene& scene, std::vector<uint8_t>& out) {
    out.resize(scene.materials.size());
    for (std::size_t m = 0; m < out.size(); ++m) out[m] = scene.materials[m].isOpaque();
}

std::vector<TriangleTag> triangleTags(const SceneGeometry& geometry, std::span<const TriangleBasis> bases,
                                      std::span<const uint8_t> opaqueMaterial) {
    std::vector<TriangleTag> out(bases.size());
    parallelFor(0, int64_t(out.size()), 4096, [&](int64_t t0, int64_t t1) {
        for (auto t = std::size_t(t0); t < std::size_t(t1); ++t) {
            const uint32_t m = geometry.triangleMaterial[t];
            const bool opaque = m < opaqueMaterial.size() && opaqueMaterial[m];
            const TriangleBasis& b = bases[t];
            bool flat = true;
            for (const Vec3f& c : b.cornerNormal) flat = flat && std::fabs(dot(c, b.normal)) > kTagFlatCos;
            out[t] = {b.normal, (geometry.triangleMesh[t] & kTagMesh) | (opaque ? kTagOccludes : 0u) |
                                    (flat ? kTagFlat : 0u)};
        }
    });
    return out;
}

Vec3f interpolatedNormal(const TriangleBasis& basis, const Vec3f& rel) {
    // Barycentrics, clamped against rounding (a degenerate triangle: a third each).
    float wb = 1.0f / 3, wc = 1.0f / 3;
    const Vec3f& ng = basis.normal;
    if (ng.x != 0 || ng.y != 0 || ng.z != 0) {
        wb = std::max(0.0f, dot(rel, basis.toB));
        wc = std::max(0.0f, dot(rel, basis.toC));
    }
    const float wa = std::max(0.0f, 1 - wb - wc);
    const Vec3f n = basis.cornerNormal[0] * wa + basis.cornerNormal[1] * wb + basis.cornerNormal[2] * wc;
    const float len = length(n);
    return len > 0 ? dividedBy(n, len) : ng;
}

bool surfaceFromBasis(const GBuffer& gbuffer, const SceneGeometry& geometry,
                      std::span<const TriangleBasis> bases, int64_t x, int64_t y, SurfacePoint& out) {
    const auto i = size_t(y * gbuffer.frame.width() + x);
    const uint32_t t = gbuffer.triangle[i];
    if (t == GBuffer::kNone) return false;
    const TriangleBasis& basis = bases[t];
    // The pixel ray meets the triangle's plane where the interpolated depth says.
    const Vec3d p = gbuffer.frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, double(gbuffer.depth[i])});
    Vec3f ng = basis.normal;
    Vec3f n = interpolatedNormal(basis, Vec3f(p - Vec3d(basis.a)));
    // Both sides are visible: turn the normals towards the viewer.
    if (dot(Vec3d(ng), gbuffer.frame.eye() - p) < 0) ng = -ng;
    if (dot(n, ng) < 0) n = -n;
    out.position = p;
    out.normal = Vec3d(n);
    out.geometricNormal = Vec3d(ng);
    out.material = geometry.triangleMaterial[t];
    return true;
}

Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Vec3d& eye) {
    return frame.shader->shade(s, eye);
}

Vec3f shadePoint(const FrameState& frame, const SurfacePoint& s, const Material& m, const Vec3d& eye) {
    return frame.shader->shade(s, m, eye);
}

Vec3f shadeSample(const FrameState& frame, std::size_t i, float occlusion, const SurfacePoint* known) {
    const GBuffer& gbuffer = frame.gbuffer;
    const Frame& cam = gbuffer.frame;
    if (known) return frame.shader->shade(*known, cam.eye(), occlusion);
    const int64_t x = int64_t(i % size_t(frame.width)), y = int64_t(i / size_t(frame.width));
    SurfacePoint s;
    if (gbuffer.triangle[i] != GBuffer::kNone &&
        surfaceFromBasis(gbuffer, frame.geometry, frame.triangleBases, x, y, s))
        return frame.shader->shade(s, cam.eye(), occlusion);
    return frame.environment->lookup(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - cam.eye()) *
           frame.options.exposure;
}

namespace {

// Round 0 at cell (cx, cy): its representative sample `i`, with the screen-space occlusion's upsample
// to the cell where the occlusion pass left it (`cells`), whose value the cell keeps for round 1 and
// the passes after.
void shadeRepresentative(FrameState& frame, const CellOcclusion* cells, int64_t cx, int64_t cy,
                         std::size_t i) {
    const auto cell = size_t(cy * (frame.width / frame.adaptive) + cx);
    SurfacePoint s;
    const bool covered =
        frame.gbuffer.triangle[i] != GBuffer::kNone &&
        surfaceFromBasis(frame.gbuffer, frame.geometry, frame.triangleBases, int64_t(i % size_t(frame.width)),
                         int64_t(i / size_t(frame.width)), s);
    float occlusion = 1;
    if (cells) {
        if (covered) occlusion = cells->at(cx, cy, Vec3f(s.position), Vec3f(s.geometricNormal));
        frame.screenOcclusion[cell] = occlusion;
    } else if (!frame.screenOcclusion.empty()) {
        occlusion = frame.screenOcclusion[cell];
    }
    frame.shaded[i] = covered && glassReplacesShading(frame, s.material)
                          ? Vec3f{0, 0, 0}
                          : shadeSample(frame, i, occlusion, covered ? &s : nullptr);
}

constexpr int64_t kBasesAhead = 4; // samples ahead whose triangle's basis is fetched

// Fetches triangle t's basis ahead of its use (a random read: its miss overlaps the work before).
void prefetchBasis(const FrameState& frame, uint32_t t) {
    if (t == GBuffer::kNone) return;
    const char* basis = reinterpret_cast<const char*>(&frame.triangleBases[t]);
    __builtin_prefetch(basis);
    __builtin_prefetch(basis + sizeof(TriangleBasis) - 1);
}

// Round 1's work in a block of cell rows: the edge samples that take a shading of their own, and the
// copies (to, from) of every edge sample in the order they were listed ((i, i): its own shading).
struct EdgeWork {
    struct Shade {
        std::size_t sample;
        uint32_t triangle;
        float occlusion;
    };
    std::vector<Shade> shades;
    std::vector<std::pair<std::size_t, std::size_t>> copies;
};

// The representatives of the eight cells around a 2 x 2 cell whose representative is r, in
// neighbourShowing's order, where all of them lie inside the image: the first showing triangle tri,
// else kNoSample.
std::size_t neighbourShowing2x2(const GBuffer& g, std::size_t r, int64_t W, uint32_t tri) {
    const std::size_t row = size_t(2 * W);
    const std::size_t around[8] = {r - 2,       r + 2,       r - row,     r + row,
                                   r - row - 2, r - row + 2, r + row - 2, r + row + 2};
    for (const std::size_t k : around)
        if (g.triangle[k] == tri) return k;
    return kNoSample;
}

// Lists refined cell (cx, cy)'s samples other than its representative into `work`: samples of a cell
// showing one triangle (or the background) share its shading, as multisampling does, the first one's;
// else a neighbouring cell's representative showing the triangle lends its shading; else the sample
// takes one of its own, with the cell's occlusion.
void listEdgeCell(const FrameState& frame, int64_t cx, int64_t cy, float occlusion, EdgeWork& work) {
    const GBuffer& gbuffer = frame.gbuffer;
    const int a = frame.adaptive;
    const int64_t W = frame.width, cw = W / a, ch = frame.height / a;
    std::array<std::size_t, 64> samples;
    int n;
    if (a == 2 && frame.refined[size_t(cy * cw + cx)] == kEveryRefinedSample) {
        // cellSamples' order, without its bounds.
        const std::size_t base = size_t(2 * cy * W + 2 * cx);
        samples[0] = base + size_t(W) + 1, samples[1] = base + 1, samples[2] = base + size_t(W),
        samples[3] = base;
        n = 4;
    } else {
        n = cellSamples(frame, cx, cy, samples);
    }
    const bool inside = a == 2 && cx > 0 && cy > 0 && cx + 1 < cw && cy + 1 < ch;
    for (int k = 1; k < n; ++k) {
        const std::size_t i = samples[size_t(k)];
        const uint32_t tri = gbuffer.triangle[i];
        int same = 0;
        while (same < k && gbuffer.triangle[samples[size_t(same)]] != tri) ++same;
        if (same < k) {
            work.copies.push_back({i, samples[size_t(same)]});
            continue;
        }
        const std::size_t proxy =
            inside ? neighbourShowing2x2(gbuffer, samples[0], W, tri) : neighbourShowing(frame, cx, cy, tri);
        if (proxy != kNoSample) {
            work.copies.push_back({i, proxy});
            continue;
        }
        work.copies.push_back({i, i});
        work.shades.push_back({i, tri, occlusion});
    }
}

// Round 1's listed work: the samples that take a shading of their own, their triangles' bases fetched
// a few ahead (edge samples' triangles are mostly shown by no representative: cold in the cache);
// then the copies in the order they were listed (a copy's source is a representative, a sample
// shaded here or one copied earlier in its cell). The same values as shading them in turn.
void shadeEdgeWork(FrameState& frame, EdgeWork& work) {
    std::vector<Vec3f>& out = frame.shaded;
    for (std::size_t k = 0; k < work.shades.size(); ++k) {
        if (k + kBasesAhead < work.shades.size()) prefetchBasis(frame, work.shades[k + kBasesAhead].triangle);
        out[work.shades[k].sample] = shadeSample(frame, work.shades[k].sample, work.shades[k].occlusion);
    }
    for (const auto& [to, from] : work.copies)
        if (to != from) out[to] = out[from];
    work.shades.clear();
    work.copies.clear();
}

} // namespace

bool glassReplacesShading(const FrameState& frame, uint32_t m) {
    const Material& material = frame.scene.materials[m];
    return !std::holds_alternative<NoGlassOptions>(frame.options.glass) && material.isGlass() &&
           material.transmission >= 1;
}

// In two rounds where adaptive anti-aliasing is on: every cell's representative sample, then the
// other samples of edge cells, each shaded only where neither an earlier sample of its cell nor a
// neighbouring cell's representative shows its triangle (neighbourShowing).
void shadeGBuffer(FrameState& frame, Progress* progress) {
    frame.shader = std::make_shared<const SurfaceShader>(frame);
    const GBuffer& gbuffer = frame.gbuffer;
    const int a = frame.adaptive;
    const int64_t W = frame.width, H = frame.height, cw = W / a, ch = H / a;
    // Every sample the passes read is written below (the others, left out by adaptive
    // anti-aliasing, are never read): no need to clear.
    std::vector<Vec3f>& out = frame.shaded;
    out.resize(size_t(W * H));
    // Screen-space occlusion: the occlusion pass left its upsample to round 0 here, which has each
    // cell's surface point; round 1 and the passes after read the cells' values.
    const std::vector<float>& screenOcclusion = frame.screenOcclusion;
    const CellOcclusion* cellOcclusion = frame.cellOcclusion.get();
    constexpr int64_t kRows = 4; // cell rows per step
    const int64_t blocks = (ch + kRows - 1) / kRows;
    const int rounds = a > 1 ? 2 : 1;
    ProgressSteps steps(progress, rounds * blocks);
    // Round 0: the first sample of each cell (its representative); round 1: the others.
    const auto shadeRound = [&](int round) {
        parallelFor(0, blocks, 1, [&](int64_t b0, int64_t b1) {
            EdgeWork work;
            for (int64_t b = b0; b < b1 && !steps.cancelled(); ++b) {
                for (int64_t cy = b * kRows; cy < std::min(ch, (b + 1) * kRows); ++cy)
                    for (int64_t cx = 0; cx < cw; ++cx) {
                        if (round == 0) {
                            const std::size_t rep =
                                a > 1 ? representativeSample(frame, cx, cy) : size_t(cy * W + cx);
                            if (cx + kBasesAhead < cw)
                                prefetchBasis(frame, gbuffer.triangle[rep + size_t(kBasesAhead * a)]);
                            shadeRepresentative(frame, cellOcclusion, cx, cy, rep);
                            continue;
                        }
                        // A cell shaded once has its representative only, done in round 0 (eight
                        // such cells at a time skipped: most are).
                        const uint8_t* refined = &frame.refined[size_t(cy * cw)];
                        if (cx + 8 <= cw) {
                            uint64_t eight;
                            std::memcpy(&eight, refined + cx, 8);
                            if (eight == 0) {
                                cx += 7;
                                continue;
                            }
                        }
                        if (refined[cx] == 0) continue;
                        listEdgeCell(frame, cx, cy,
                                     screenOcclusion.empty() ? 1.0f : screenOcclusion[size_t(cy * cw + cx)],
                                     work);
                    }
                if (round == 1) shadeEdgeWork(frame, work);
                steps.step();
            }
        });
    };
    shadeRound(0);
    if (a > 1 && !steps.cancelled()) shadeRound(1);
    if (steps.cancelled()) fail("cancelled");
}

} // namespace voxfx::detail
