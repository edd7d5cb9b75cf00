// voxfx — the renderer's driver: one frame is an ordered list of passes over one frame state, each
// timed and given its share of the progress (see render.hpp for the passes).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>

#include "core/progress_range.hpp"
#include "render/antialias.hpp"
#include "render/frame_passes.hpp"
#include "render/frame_state.hpp"
#include "render/glass_pass.hpp"
#include "render/shading.hpp"
#include "render/technique_list.hpp"
#include "render/translucency_pass.hpp"
#include "render/volume_pass.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"

namespace voxfx {

const char* toString(Occlusion o) { return enumName(o, kOcclusionNames); }
Occlusion parseOcclusion(const std::string& name) {
    return parseEnum<Occlusion>(name, "ambient occlusion", kOcclusionNames);
}

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

using detail::FrameState;

// The scene as one mesh, unless the cache holds it for the same meshes, materials (blended meshes
// go last) and crease angle.
void flattenPass(FrameState& f, Progress*) {
    detail::Hasher h;
    h.value(f.meshesKey), h.value(f.materialsKey), h.value(f.options.creaseAngle);
    if (f.cache.geometryKey == h.get()) {
        f.cachedPass = true;
        return;
    }
    f.cache.geometryKey.reset();
    f.geometry = flattenScene(f.scene, f.options.creaseAngle);
    f.triangleBases = detail::triangleBases(f.geometry);
    // The compact records, with the occlusion's rule of what occludes.
    std::vector<uint8_t> opaque;
    detail::opaqueMaterials(f.scene, opaque);
    f.cache.triangleTags = detail::triangleTags(f.geometry, f.triangleBases, opaque);
    f.cache.geometryKey = h.get();
}

void gbufferPass(FrameState& f, Progress* progress) {
    // Adaptive anti-aliasing counts the covered samples as it marks the cells to refine.
    if ((f.result.coveredPixels =
             detail::renderGBufferAndMark(f, cameraFrame(f.camera, f.width, f.height), progress)) >= 0)
        return;
    const std::vector<uint32_t>& tri = f.gbuffer.triangle;
    f.result.coveredPixels = parallelReduce(
        0, int64_t(tri.size()), int64_t(1) << 16, int64_t(0),
        [&](int64_t i0, int64_t i1) {
            int64_t n = 0;
            for (int64_t i = i0; i < i1; ++i) n += tri[size_t(i)] != GBuffer::kNone;
            return n;
        },
        [](int64_t a, int64_t b) { return a + b; });
}

// `scene` with every glass material's attenuation coefficient times k (its attenuation distance
// over k; none for k = 0): what the glass methods make of the materials under absorption constant k.
Scene withAbsorptionConstant(const Scene& scene, double k) {
    if (!(k >= 0) || !std::isfinite(k))
        fail("glass: the absorption constant must be finite and >= 0, got ", k);
    Scene out = scene;
    for (Material& m : out.materials)
        if (m.isGlass())
            m.attenuationDistance =
                k > 0 ? float(double(m.attenuationDistance) / k) : std::numeric_limits<float>::infinity();
    return out;
}

// One shadow per light, each built by the chosen technique with its share of the progress (or
// reused from the cache when built from the same meshes, materials, light and options), then given
// the G-buffer where the technique counts over it; their counters summed.
void shadowPass(FrameState& f, Progress* progress) {
    const std::size_t n = f.lights.size();
    f.result.shadowStats = std::visit(
        []<class O>(const O&) -> ShadowStats { return typename detail::BuiltFor<LightShadow, O>::Stats{}; },
        f.options.shadow);
    const ShadowOptions& options = f.options.shadow;
    // What a technique may fit to the view (deep shadows' clusters: the camera).
    const BuildContext context{f.camera, f.width, f.height};
    // CHANG's absorption constant scales the glass's attenuation for the shadows as for the camera's
    // rays (the glass pass): the shadows are built from the scene with it applied to the materials.
    const double absorption = glassAbsorptionConstant(f.options.glass);
    const std::optional<Scene> absorbing =
        absorption != 1.0 ? std::optional<Scene>(withAbsorptionConstant(f.scene, absorption)) : std::nullopt;
    const Scene& casters = absorbing ? *absorbing : f.scene;
    // Room for two techniques' shadows of every light.
    f.cache.shadows.setCapacity(std::max<std::size_t>(8, 2 * n));
    bool allCached = n > 0;
    for (std::size_t i = 0; i < n; ++i) {
        detail::Hasher h;
        h.value(f.meshesKey), h.value(f.materialsKey);
        detail::hashLight(h, f.lights[i]);
        h.options(options);
        h.value(absorption);
        if (detail::viewDependent(options)) detail::hashCamera(h, f.camera);
        std::shared_ptr<LightShadow> shadow = f.cache.shadows.find(h.get());
        if (!shadow) {
            allCached = false;
            detail::ProgressRange sp(progress, double(i) / double(n), double(i + 1) / double(n));
            shadow = std::make_shared<LightShadow>(
                buildLightShadow(casters, f.lights[i], options, context, sp.get()));
            f.cache.shadows.insert(h.get(), shadow);
        }
        prepareLightShadow(*shadow, f.gbuffer, f.geometry);
        accumulate(f.result.shadowStats, shadowStats(*shadow));
        f.shadows.push_back(std::move(shadow));
        f.shadowKeys.push_back(h.get());
    }
    f.cachedPass = allCached;
}

void shadingPass(FrameState& f, Progress* progress) { detail::shadeGBuffer(f, progress); }

void translucencyPass(FrameState& f, Progress*) { detail::compositeTranslucency(f); }

void glassPass(FrameState& f, Progress*) {
    f.result.glass.method = glassName(f.options.glass);
    detail::shadeGlass(f);
}

void volumePass(FrameState& f, Progress*) { detail::compositeVolumes(f); }

struct RenderPass {
    std::string_view name;
    double progressEnd; ///< the share of the whole render done when the pass ends
    void (*run)(FrameState&, Progress*);
};

// The frame, in order. A pass reads what the passes before it left in the frame state.
constexpr RenderPass kPasses[] = {{"flatten", 0.0, flattenPass},
                                  {"G-buffer", 0.2, gbufferPass},
                                  {"occlusion", 0.3, detail::occlusionPass},
                                  {"shadows", 0.5, shadowPass},
                                  {"shading", 1.0, shadingPass},
                                  {"translucency", 1.0, translucencyPass},
                                  {"glass", 1.0, glassPass},
                                  {"ray casting", 1.0, volumePass},
                                  {"resolve", 1.0, detail::resolvePass}};

// The procedural sky of these options, baked once and kept (the last few) for the next frames.
std::shared_ptr<const Environment> cachedSky(const SkyOptions& o) {
    static std::mutex mutex;
    static std::vector<std::pair<std::array<double, 13>, std::shared_ptr<const Environment>>> kept;
    const std::array<double, 13> key{
        o.sunDirection.x, o.sunDirection.y, o.sunDirection.z,   o.turbidity,      o.groundAlbedo.x,
        o.groundAlbedo.y, o.groundAlbedo.z, o.sunAngularRadius, o.groundSkyLight, double(o.groundSun),
        o.groundLight.x,  o.groundLight.y,  o.groundLight.z};
    std::lock_guard lock(mutex);
    for (const auto& [k, env] : kept)
        if (k == key) return env;
    auto env = std::make_shared<const Environment>(Environment::sky(o));
    if (kept.size() >= 4) kept.erase(kept.begin());
    kept.emplace_back(key, env);
    return env;
}

void checkRender(const Scene& scene, const RenderOptions& options) {
    if (options.width <= 0 || options.height <= 0 || options.width > 65536 || options.height > 65536)
        fail("image size must be between 1 and 65536 pixels per side, got ", options.width, " x ",
             options.height);
    if (options.supersample < 1 || options.supersample > 8)
        fail("supersampling must be between 1 and 8, got ", options.supersample);
    if (options.adaptiveSamples < 2 || options.adaptiveSamples > 8)
        fail("adaptive samples must be between 2 and 8, got ", options.adaptiveSamples);
    scene.validate();
    if (scene.triangleCount() == 0 && !(scene.volumeScene && !scene.volumeScene->objects.empty()))
        fail("the scene has no triangles to render");
}

} // namespace

SkyOptions skyOptions(const RenderOptions& o) {
    SkyOptions s;
    s.sunDirection = sunDirectionFromAngles(o.sunElevation, o.sunAzimuth);
    s.turbidity = o.turbidity;
    s.groundAlbedo = o.groundAlbedo;
    s.groundSkyLight = o.skyLight;
    return s;
}

namespace {

// The sky of a frame: its ground below the horizon lit as the scene's own ground is, far from
// everything: by skyLight's share of the sky, the constant ambient and the scene's directional
// lights (spot and point lights do not reach the horizon), or the sky's sun when that is the
// scene's default light.
SkyOptions frameSky(const Scene& scene, const RenderOptions& o) {
    SkyOptions s = skyOptions(o);
    s.groundSun = scene.lights.empty() && o.defaultLights;
    s.groundLight = o.ambient * float(M_PI);
    for (const Light& l : scene.lights)
        if (l.type == LightType::Directional)
            s.groundLight += l.color * float(double(l.intensity) * std::max(0.0, -normalize(l.direction).y));
    return s;
}

} // namespace

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options) {
    RenderCache cache; // this frame's alone
    return render(scene, camera, options, cache);
}

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options,
                    RenderCache& cache) {
    checkRender(scene, options);
    const auto t0 = Clock::now();
    // The one environment: given, else the procedural sky or the flat background. A scene without
    // lights gets the default sun: the environment's (the sky's, or a map's sun region), else (the
    // flat background) a white sun of irradiance 3 along SkyOptions' direction.
    std::shared_ptr<const Environment> keep;
    std::optional<Environment> flat;
    const Environment* env = options.environment.get();
    if (!env && options.sky == SkyKind::Flat) env = &flat.emplace(Image(1, 1, options.background));
    if (!env) env = (keep = cachedSky(frameSky(scene, options))).get();
    std::span<const Light> lights = scene.lights;
    Light sun;
    if (scene.lights.empty() && options.defaultLights) {
        sun.name = "default sun";
        const bool own = length(env->sunDirection()) > 0;
        sun.direction = -normalize(own ? env->sunDirection() : SkyOptions{}.sunDirection);
        sun.color = own ? env->sunIrradiance() : Vec3f{1.0f, 0.96f, 0.9f};
        sun.intensity = own ? 1 : 3;
        if (own || options.environment == nullptr) lights = {&sun, 1};
    }
    // Automatic exposure: the passes render at exposure 1 and the resolve pass scales.
    const bool autoExposure = !(options.exposure > 0);
    std::optional<RenderOptions> unitExposure;
    if (autoExposure) unitExposure.emplace(options).exposure = 1;
    const bool adaptiveOn =
        options.antiAliasing == AntiAliasing::Adaptive || options.antiAliasing == AntiAliasing::Full;
    const int adaptive = adaptiveOn ? options.adaptiveSamples : 1;
    RenderResult result;
    const int k = options.supersample * adaptive;
    detail::RenderCacheData& c = cache.data();
    FrameState frame{scene,
                     lights,
                     camera,
                     autoExposure ? *unitExposure : options,
                     env,
                     options.width * k,
                     options.height * k,
                     adaptive,
                     c,
                     detail::meshesKey(scene),
                     detail::materialsKey(scene.materials),
                     c.refined,
                     c.geometry,
                     c.triangleBases,
                     c.gbuffer,
                     {},
                     {},
                     c.screenOcclusion,
                     {},
                     c.shaded,
                     c.glassSamples,
                     result};
    frame.autoExposure = autoExposure;
    frame.refined.clear();
    frame.glassSamples.clear();
    frame.screenOcclusion.clear();
    withThreads(options.threads, [&] {
        double done = 0;
        for (const RenderPass& pass : kPasses) {
            detail::ProgressRange progress(options.progress, done, pass.progressEnd);
            const auto tp = Clock::now();
            frame.cachedPass = false;
            pass.run(frame, progress.get());
            result.timings.passes.push_back({pass.name, msSince(tp), frame.cachedPass});
            done = pass.progressEnd;
        }
    });
    result.timings.totalMs = msSince(t0);
    return result;
}

} // namespace voxfx
