// voxfx — shadow volumes: closed casters with edge adjacency, per-light volume construction
// (near cap, silhouette quads, far cap on a plane), ED06 §3.2 culling and clamping against light
// slicemaps, and the per-pixel counting consumer of the one rasterizer. See shadow_volume.hpp.
//
// One file per concern (shadow_volume_internal.hpp lists them); this one holds the mask's lookups,
// the steps of computeShadowVolumes in their order, and the technique (VolumeShadow).
#include "voxfx/shadow_volume.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/shadow_volume_internal.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {

float ShadowVolumeMask::visibility(const Vec3d& p) const {
    if (shadowed.empty()) return 1.0f;
    if (!(camera.viewDepth(p) > 0)) return 1.0f;
    const Vec3d g = camera.gridFromWorld(p);
    const double fx = std::floor(g.x), fy = std::floor(g.y);
    if (!(fx >= 0 && fy >= 0 && fx < double(camera.width()) && fy < double(camera.height()))) return 1.0f;
    return shadowed[size_t(int64_t(fy) * camera.width() + int64_t(fx))] ? 0.0f : 1.0f;
}

bool ShadowVolumeMask::atSurface(const Vec3d& p) const {
    if (shadowed.empty() || depth.size() != shadowed.size()) return false;
    if (!(camera.viewDepth(p) > 0)) return false;
    const Vec3d g = camera.gridFromWorld(p);
    const double fx = std::floor(g.x), fy = std::floor(g.y);
    if (!(fx >= 0 && fy >= 0 && fx < double(camera.width()) && fy < double(camera.height()))) return false;
    const double d = depth[size_t(int64_t(fy) * camera.width() + int64_t(fx))];
    return std::abs(g.z - d) <= 1e-5 * std::max(std::abs(d), 1e-3);
}

ShadowVolumeMask computeShadowVolumes(const ShadowCasterSet& casters, const Light& light,
                                      const GBuffer& gbuffer, const std::vector<uint8_t>& receivers,
                                      const Box3d& sceneBounds, const ShadowVolumeOptions& options) {
    ShadowVolumeMask out;
    out.camera = gbuffer.frame;
    out.depth = gbuffer.depth;
    const Frame& cam = gbuffer.frame;
    out.shadowed.assign(size_t(cam.width() * cam.height()), 0);
    out.stats.casters = int64_t(casters.casters.size());
    if (casters.casters.empty()) return out;
    if (receivers.size() != size_t(cam.width() * cam.height()))
        fail("shadow volumes: one receiver flag per G-buffer pixel needed");
    if (options.mapResolution <= 0 || options.receiverSlices <= 0)
        fail("shadow volumes: culling resolutions must be positive");
    const std::size_t N = casters.casters.size();
    out.culled.assign(N, 0);
    using namespace detail::shadowvolume;

    const auto t0 = SvClock::now();
    std::vector<SvCasterLight> setup;
    setup.reserve(N);
    for (const ShadowCaster& c : casters.casters) setup.push_back(svSetup(c, light, sceneBounds, cam));
    SvDecision d{std::vector<uint8_t>(N, 1), std::vector<double>(N), std::vector<std::vector<SvRun>>(N),
                 std::vector<std::vector<uint8_t>>(N)};
    for (std::size_t i = 0; i < N; ++i) d.far[i] = setup[i].far;
    const bool byReceivers = options.cullReceivers || options.clamp || options.clampRuns;
    const bool byOccluders = options.cullOccluded || options.cullShadowedParts;
    if (byReceivers || byOccluders) {
        std::vector<Vec3d> points;
        const std::vector<LightView> views =
            svReceiverViews(casters, light, gbuffer, receivers, options, points);
        if (byReceivers) {
            std::vector<BitGrid> slicemaps;
            out.stats.receiversCovered = svReceiverSlicemaps(views, points, slicemaps);
            if (out.stats.receiversCovered)
                svCullByReceivers(casters, setup, views, slicemaps, options, d, out);
        }
        if (byOccluders) svCullOccluded(casters, setup, views, options, d, out);
    }
    out.stats.cullMs = svMsSince(t0);
    svCount(casters, setup, d, gbuffer, out);
    return out;
}

VolumeShadow VolumeShadow::build(const Scene& scene, const Light& light, const ShadowVolumeOptions& options,
                                 Progress*) {
    VolumeShadow out;
    out.options_ = options;
    out.casters_ = std::make_shared<const ShadowCasterSet>(ShadowCasterSet::build(scene));
    out.light_ = light;
    out.sceneBounds_ = scene.bounds(false);
    out.materials_ = scene.materials;
    // The exact answer off the G-buffer's surfaces: the same casters, each opaque, traced.
    Mesh all;
    for (const ShadowCaster& c : out.casters_->casters) {
        const auto base = uint32_t(all.positions.size());
        all.positions.insert(all.positions.end(), c.positions.begin(), c.positions.end());
        for (const uint32_t i : c.indices) all.indices.push_back(base + i);
    }
    if (!all.indices.empty()) out.tracer_ = std::make_shared<const TriangleTracer>(all.view());
    return out;
}

void VolumeShadow::prepare(const GBuffer& gbuffer, const SceneGeometry& geometry) {
    if (!casters_) return;
    mask_ = computeShadowVolumes(*casters_, light_, gbuffer,
                                 shadowVolumeReceivers(gbuffer, geometry, materials_, light_), sceneBounds_,
                                 options_);
}

float VolumeShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    if (mask_.shadowed.empty() || mask_.atSurface(p) || !tracer_) return mask_.visibility(p); // 1 unprepared
    // Off the G-buffer's surfaces (blended surfaces, volume samples, refracted points): whether
    // the segment towards the light crosses a caster, from p moved 10 epsilons along n.
    Vec3d l = light_.towards(p);
    double distance = std::numeric_limits<double>::infinity();
    if (light_.positioned()) {
        distance = length(l);
        l = l / std::max(distance, 1e-300);
    }
    const Vec3d o = p + n * (tracer_->epsilon() * 10);
    return tracer_->intersect(o, l, 0.0, distance).hit ? 0.0f : 1.0f;
}

} // namespace voxfx
