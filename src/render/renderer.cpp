// voxfx — the renderer's driver: flatten, G-buffer, shadows per light, shading, supersampling
// resolve, each pass timed (see render.hpp for the passes).
#include <algorithm>
#include <chrono>

#include "render/shading.hpp"
#include "render/volume_pass.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/render.hpp"

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
    if (scene.triangleCount() == 0) fail("the scene has no triangles to render");
    const auto t0 = Clock::now();
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
        for (std::size_t i = 0; i < scene.lights.size(); ++i) {
            PassProgress sp(options.progress, 0.2 + 0.3 * double(i) / double(scene.lights.size()),
                            0.2 + 0.3 * double(i + 1) / double(scene.lights.size()));
            ShadowBuildTimings st;
            shadows.push_back(LightShadow::build(scene, scene.lights[i], options.shadow, &st, sp.get()));
            t.shadowMapMs += st.mapMs;
            t.lightVoxelizeMs += st.voxelizeMs;
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
            detail::shadeGBuffer(gbuffer, geometry, scene, shadows, options, shp.get());
        t.shadingMs = msSince(tp);
        tp = Clock::now();
        result.volumeSamples = detail::compositeVolumes(gbuffer, scene, shadows, options, shaded, nullptr);
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
        t.resolveMs = msSince(tp);
    });
    t.totalMs = msSince(t0);
    return result;
}

} // namespace voxfx
