// voxfx — the renderer's driver: flatten, G-buffer, shadows per light, shading, supersampling
// resolve, each pass timed (see render.hpp for the passes).
#include <algorithm>
#include <chrono>
#include <optional>

#include "render/glass_pass.hpp"
#include "render/shading.hpp"
#include "render/volume_pass.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow_volume.hpp"

namespace voxfx {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Maps a pass's progress [0, 1] into [lo, hi] of the whole render.
class PassProgress : public Progress {
public:
    PassProgress(Progress* parent, double lo, double hi) : parent_(parent), lo_(lo), hi_(hi) {}
    bool update(double f) override { return parent_ ? parent_->update(lo_ + (hi_ - lo_) * f) : true; }
    Progress* get() { return parent_ ? this : nullptr; }

private:
    Progress* parent_;
    double lo_, hi_;
};

} // namespace

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options) {
    if (options.width <= 0 || options.height <= 0 || options.width > 65536 || options.height > 65536)
        fail("image size must be between 1 and 65536 pixels per side, got ", options.width, " x ",
             options.height);
    if (options.supersample < 1 || options.supersample > 8)
        fail("supersampling must be between 1 and 8, got ", options.supersample);
    scene.validate();
    if (scene.triangleCount() == 0 && !(scene.volumeScene && !scene.volumeScene->objects.empty()))
        fail("the scene has no triangles to render");
    const auto t0 = Clock::now();
    // The environment (given, or the procedural sky when glass or default lights need one) and, for a
    // scene without lights, the default sun and sky ambient.
    std::optional<Environment> sky;
    const bool addSun = scene.lights.empty() && options.defaultLights;
    const Environment* env = options.environment;
    if (!env && (addSun || options.glass.kind != GlassKind::None)) env = &sky.emplace(Environment::sky());
    std::optional<Scene> sunlit;
    RenderOptions litOptions = options;
    if (addSun) {
        Light sun;
        sun.name = "default sun";
        const Vec3d towards =
            length(env->sunDirection()) > 0 ? env->sunDirection() : SkyOptions{}.sunDirection;
        sun.direction = -normalize(towards);
        sun.color = {1.0f, 0.96f, 0.9f};
        sun.intensity = 3;
        sunlit.emplace(scene).lights.push_back(sun);
        litOptions.ambient = env->average();
    }
    const Scene& lit = sunlit ? *sunlit : scene;
    RenderResult result;
    RenderTimings& t = result.timings;
    const int k = options.supersample;
    const int64_t W = options.width * k, H = options.height * k;
    withThreads(options.threads, [&] {
        auto tp = Clock::now();
        const SceneGeometry geometry = flattenScene(scene);
        t.flattenMs = msSince(tp);

        tp = Clock::now();
        PassProgress gp(options.progress, 0.0, 0.2);
        const GBuffer gbuffer = renderGBuffer(geometry, cameraFrame(camera, W, H), gp.get());
        t.gbufferMs = msSince(tp);
        for (const uint32_t tri : gbuffer.triangle) result.coveredPixels += tri != GBuffer::kNone;

        std::vector<LightShadow> shadows;
        // Shadow volumes: closed casters with edge adjacency, built once for every light.
        const bool volumes = options.shadow.kind == ShadowKind::Volumes;
        const ShadowCasterSet casters = volumes ? ShadowCasterSet::build(lit) : ShadowCasterSet{};
        for (std::size_t i = 0; i < lit.lights.size(); ++i) {
            PassProgress sp(options.progress, 0.2 + 0.3 * double(i) / double(lit.lights.size()),
                            0.2 + 0.3 * double(i + 1) / double(lit.lights.size()));
            ShadowBuildTimings st;
            if (volumes)
                shadows.push_back(
                    buildVolumeShadow(casters, lit, lit.lights[i], gbuffer, geometry, options.shadow, &st));
            else
                shadows.push_back(LightShadow::build(lit, lit.lights[i], options.shadow, &st, sp.get()));
            t.shadowMapMs += st.mapMs;
            t.lightVoxelizeMs += st.voxelizeMs;
            t.shadowVolumeMs += st.volumeMs;
            result.shadowVolumeFragments += st.volumeFragments;
            if (const DeepShadow* d = shadows.back().deepShadow()) {
                const DsmStats ds = d->stats();
                DsmStats& sum = result.deepShadowStats;
                sum.texels += ds.texels;
                sum.nodes += ds.nodes;
                sum.maxNodes = std::max(sum.maxNodes, ds.maxNodes);
                sum.bytes += ds.bytes;
                sum.overflowTexels += ds.overflowTexels;
                sum.maxEpsilon = std::max(sum.maxEpsilon, ds.maxEpsilon);
            }
        }

        tp = Clock::now();
        PassProgress shp(options.progress, 0.5, 1.0);
        std::vector<Vec3f> shaded =
            detail::shadeGBuffer(gbuffer, geometry, lit, shadows, litOptions, shp.get());
        if (options.environment) { // the background shows the environment along each pixel's ray
            const Frame& cam = gbuffer.frame;
            parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
                for (int64_t y = y0; y < y1; ++y)
                    for (int64_t x = 0; x < W; ++x)
                        if (gbuffer.triangle[size_t(y * W + x)] == GBuffer::kNone)
                            shaded[size_t(y * W + x)] =
                                options.environment->lookup(
                                    cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - cam.eye()) *
                                options.exposure;
            });
        }
        t.shadingMs = msSince(tp);
        std::vector<uint8_t> glassSamples;
        if (options.glass.kind != GlassKind::None)
            detail::shadeGlass(gbuffer, geometry, lit, shadows, litOptions, *env, shaded, glassSamples, t);
        tp = Clock::now();
        result.volumeSamples = detail::compositeVolumes(gbuffer, lit, shadows, litOptions, shaded, nullptr);
        t.volumeMs = msSince(tp);

        // Box filter k x k and flip: frame rows run up, image rows down.
        tp = Clock::now();
        result.image = Image(options.width, options.height);
        const float norm = 1.0f / float(k * k);
        parallelFor(0, options.height, 16, [&](int64_t y0, int64_t y1) {
            for (int64_t y = y0; y < y1; ++y)
                for (int64_t x = 0; x < options.width; ++x) {
                    Vec3f sum;
                    for (int dy = 0; dy < k; ++dy)
                        for (int dx = 0; dx < k; ++dx) sum += shaded[size_t((y * k + dy) * W + x * k + dx)];
                    result.image.at(x, options.height - 1 - y) = sum * norm;
                }
        });
        if (!glassSamples.empty()) {
            result.glassMask.assign(size_t(options.width * options.height), 0);
            for (int64_t y = 0; y < options.height; ++y)
                for (int64_t x = 0; x < options.width; ++x) {
                    uint8_t any = 0;
                    for (int dy = 0; dy < k; ++dy)
                        for (int dx = 0; dx < k; ++dx)
                            any |= glassSamples[size_t((y * k + dy) * W + x * k + dx)];
                    result.glassMask[size_t((options.height - 1 - y) * options.width + x)] = any;
                }
        }
        t.resolveMs = msSince(tp);
    });
    t.totalMs = msSince(t0);
    return result;
}

} // namespace voxfx
