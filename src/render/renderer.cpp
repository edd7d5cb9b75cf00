// voxfx — the renderer's driver: one frame is an ordered list of passes over one frame state, each
// timed and given its share of the progress (see render.hpp for the passes).
#include <algorithm>
#include <chrono>
#include <optional>

#include "core/progress_range.hpp"
#include "render/antialias.hpp"
#include "render/frame_state.hpp"
#include "render/glass_pass.hpp"
#include "render/screen_space_ao.hpp"
#include "render/shading.hpp"
#include "render/technique_list.hpp"
#include "render/translucency_pass.hpp"
#include "render/volume_pass.hpp"
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
    f.cache.geometryKey = h.get();
}

void gbufferPass(FrameState& f, Progress* progress) {
    renderGBuffer(f.geometry, cameraFrame(f.camera, f.width, f.height), f.gbuffer, progress);
    int64_t covered = 0;
    for (const uint32_t tri : f.gbuffer.triangle) covered += tri != GBuffer::kNone;
    f.result.coveredPixels = covered;
    detail::markRefinedCells(f);
}

// One shadow per light, each built by the chosen technique with its share of the progress (or
// reused from the cache when built from the same meshes, materials, light and options), then given
// the G-buffer where the technique counts over it; their counters summed.
void shadowPass(FrameState& f, Progress* progress) {
    const std::size_t n = f.lights.size();
    f.result.shadowStats = std::visit(
        []<class O>(const O&) -> ShadowStats { return typename detail::BuiltFor<LightShadow, O>::Stats{}; },
        f.options.shadow);
    // Deep shadows fit their clusters to the camera (DeepShadowOptions::camera).
    ShadowOptions options = f.options.shadow;
    if (auto* deep = std::get_if<DeepShadowOptions>(&options)) deep->camera = f.camera.position;
    // Room for two techniques' shadows of every light.
    f.cache.shadows.setCapacity(std::max<std::size_t>(8, 2 * n));
    bool allCached = n > 0;
    for (std::size_t i = 0; i < n; ++i) {
        detail::Hasher h;
        h.value(f.meshesKey), h.value(f.materialsKey);
        detail::hashLight(h, f.lights[i]);
        h.options(options);
        if (detail::viewDependent(options)) detail::hashCamera(h, f.camera);
        std::shared_ptr<LightShadow> shadow = f.cache.shadows.find(h.get());
        if (!shadow) {
            allCached = false;
            detail::ProgressRange sp(progress, double(i) / double(n), double(i + 1) / double(n));
            shadow = std::make_shared<LightShadow>(buildLightShadow(f.scene, f.lights[i], options, sp.get()));
            f.cache.shadows.insert(h.get(), shadow);
        }
        prepareLightShadow(*shadow, f.gbuffer, f.geometry);
        accumulate(f.result.shadowStats, shadowStats(*shadow));
        f.shadows.push_back(std::move(shadow));
    }
    f.cachedPass = allCached;
}

// Screen-space occlusion per cell of the G-buffer (adaptive x adaptive samples), from the sample the
// shading pass shades for it: its surface point and whether it occludes (opaque), then GTAO over
// the cells in the camera's frame at the cells' resolution, into f.screenOcclusion.
void screenOcclusion(FrameState& f, double radius) {
    const int a = f.adaptive;
    const int64_t cw = f.width / a, ch = f.height / a;
    detail::RenderCacheData::ScreenOcclusion& c = f.cache.screen;
    c.position.resize(size_t(cw * ch));
    c.normal.resize(size_t(cw * ch));
    c.covered.resize(size_t(cw * ch));
    c.occluder.resize(size_t(cw * ch));
    std::vector<uint8_t> opaque(f.scene.materials.size());
    for (std::size_t m = 0; m < opaque.size(); ++m) opaque[m] = f.scene.materials[m].isOpaque();
    parallelFor(0, ch, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                const auto i = size_t(cy * cw + cx);
                SurfacePoint s;
                const bool hit = detail::surfaceFromBasis(f.gbuffer, f.geometry, f.triangleBases,
                                                          cx * a + a / 2, cy * a + a / 2, s);
                c.covered[i] = hit;
                c.occluder[i] = hit && s.material < opaque.size() && opaque[s.material];
                if (!hit) continue;
                c.position[i] = Vec3f(s.position);
                c.normal[i] = Vec3f(s.normal);
            }
    });
    f.screenOcclusion.resize(size_t(cw * ch));
    detail::ScreenSpaceOcclusionOptions so;
    so.radius = radius;
    detail::screenSpaceOcclusion(cameraFrame(f.camera, cw, ch), cw, ch, c.position, c.normal, c.covered, so,
                                 c.occluder, f.screenOcclusion, c.scratch);
}

// The ambient light's occlusion (RenderOptions::ambientOcclusion): its setup (opaque triangles,
// region, radius) and, for the field method, the field, both kept in the cache; for the screen
// method, GTAO over the G-buffer's cells (one sample each: the one the shading pass shades).
void occlusionPass(FrameState& f, Progress* progress) {
    const RenderOptions& o = f.options;
    const bool ambientLight = o.skyLight > 0 || o.ambient.x > 0 || o.ambient.y > 0 || o.ambient.z > 0;
    if (o.ambientOcclusion == Occlusion::Off || !ambientLight) return;
    detail::Hasher key;
    key.value(f.meshesKey), key.value(f.materialsKey), key.value(o.creaseAngle);
    key.value(o.occlusionRadius), key.value(o.occlusionResolution);
    std::shared_ptr<const detail::FieldOcclusionSetup> setup = f.cache.occlusionSetup.find(key.get());
    const bool setupCached = setup != nullptr;
    if (!setup) {
        setup = std::make_shared<const detail::FieldOcclusionSetup>(detail::fieldOcclusionSetup(
            f.geometry, f.scene.materials, f.scene.meshes.size(), o.occlusionRadius, o.occlusionResolution));
        f.cache.occlusionSetup.insert(key.get(), setup);
    }
    if (!(setup->radius > 0)) { // nothing occludes
        f.cachedPass = setupCached;
        return;
    }
    if (o.ambientOcclusion == Occlusion::Screen) {
        screenOcclusion(f, setup->radius);
        return;
    }
    f.occlusion = f.cache.occlusion.find(key.get());
    if (f.occlusion) {
        f.cachedPass = true;
        return;
    }
    const SceneGeometry& g = f.geometry;
    AmbientOcclusionOptions ao;
    ao.radius = setup->radius;
    ao.resolution = setup->resolution;
    ao.threads = o.threads;
    ao.progress = progress;
    MeshView view;
    view.positions = &g.mesh.positions[0].x;
    view.vertexCount = g.mesh.positions.size();
    view.indices = setup->indices.data();
    view.triangleCount = setup->indices.size() / 3;
    f.occlusion = std::make_shared<const AmbientOcclusion>(view, setup->region, ao);
    f.cache.occlusion.insert(key.get(), f.occlusion);
}

void shadingPass(FrameState& f, Progress* progress) { detail::shadeGBuffer(f, progress); }

void translucencyPass(FrameState& f, Progress*) { detail::compositeTranslucency(f); }

void glassPass(FrameState& f, Progress*) {
    f.result.glass.method = glassName(f.options.glass);
    detail::shadeGlass(f);
}

void volumePass(FrameState& f, Progress*) { detail::compositeVolumes(f); }

// The output transform of one sample.
Vec3f toneMapped(const Vec3f& c, ToneMap t) {
    if (t == ToneMap::Clamp) return c;
    return {filmicToneMap(c.x), filmicToneMap(c.y), filmicToneMap(c.z)};
}

// The tone-mapped sum of the samples of cell (cx, cy) that the passes shaded: all a x a of a refined
// cell; the mean of its N-rooks samples (glass inside), or its one representative sample, a x a
// times, elsewhere (adaptive anti-aliasing left the others unshaded).
Vec3f cellSum(const FrameState& f, int64_t cx, int64_t cy, ToneMap t) {
    const int a = f.adaptive;
    const int64_t W = f.width, sx = cx * a, sy = cy * a;
    const uint8_t kind =
        f.refined.empty() ? detail::kEveryRefinedSample : f.refined[size_t(cy * (W / a) + cx)];
    Vec3f sum;
    if (kind == detail::kEveryRefinedSample) {
        for (int dy = 0; dy < a; ++dy)
            for (int dx = 0; dx < a; ++dx) sum += toneMapped(f.shaded[size_t((sy + dy) * W + sx + dx)], t);
        return sum;
    }
    if (kind == detail::kRookSamples) {
        Vec3f mean;
        for (int dy = 0; dy < a; ++dy)
            mean += f.shaded[size_t((sy + dy) * W + sx + detail::rookColumn(a, dy))];
        return toneMapped(mean * (1.0f / float(a)), t) * float(a * a);
    }
    return toneMapped(f.shaded[size_t((sy + a / 2) * W + sx + a / 2)], t) * float(a * a);
}

// Box filter of the k x k (times adaptive) samples of each pixel, each tone-mapped first (so an edge
// against a bright sky keeps its coverage), and flip: frame rows run up, image rows down. Then the
// post-process anti-aliasing on the pixels adaptive sampling did not refine (nor touch).
void resolvePass(FrameState& f, Progress*) {
    const RenderOptions& o = f.options;
    const int k = o.supersample * f.adaptive, a = f.adaptive;
    const int64_t W = f.width, cw = f.width / std::max(a, 1), w = o.width, h = o.height;
    RenderResult& r = f.result;
    detail::RenderCacheData::Resolve& scratch = f.cache.resolve;
    const bool post = o.antiAliasing == AntiAliasing::Post || o.antiAliasing == AntiAliasing::Full;
    // The box-filtered image: the result, or (post-process) its input, kept between frames.
    r.image = Image(w, h);
    Image& filtered = post ? scratch.filtered : r.image;
    if (post) {
        filtered.width = w, filtered.height = h;
        filtered.pixels.resize(size_t(w * h));
    }
    // Per output pixel (image rows): 1 where a cell of it was shaded at every sample.
    std::vector<uint8_t>& refined = scratch.refined;
    refined.resize(size_t(w * h));
    const float norm = 1.0f / float(k * k);
    const int cells = o.supersample; // cells of a x a samples per pixel side
    parallelFor(0, h, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < w; ++x) {
                Vec3f sum;
                uint8_t every = 0;
                for (int cy = 0; cy < cells; ++cy)
                    for (int cx = 0; cx < cells; ++cx) {
                        sum += cellSum(f, x * cells + cx, y * cells + cy, o.toneMap);
                        if (!f.refined.empty())
                            every |= f.refined[size_t((y * cells + cy) * cw + x * cells + cx)] ==
                                     detail::kEveryRefinedSample;
                    }
                const Vec3f c = sum * norm;
                filtered.at(x, h - 1 - y) = c;
                if (post) r.image.at(x, h - 1 - y) = c;
                refined[size_t((h - 1 - y) * w + x)] = every;
            }
    });
    for (const uint8_t v : refined) r.refinedPixels += v;
    if (post) {
        // Pixels next to a refined one keep their samples' coverage too.
        // The 3 x 3 dilation of `refined`, as a row pass then a column pass.
        std::vector<uint8_t>& skip = scratch.skip;
        std::vector<uint8_t>& rows = scratch.rows;
        skip.assign(refined.size(), 0);
        if (r.refinedPixels > 0) {
            rows.resize(refined.size());
            parallelFor(0, h, 32, [&](int64_t y0, int64_t y1) {
                for (int64_t y = y0; y < y1; ++y) {
                    const uint8_t* in = &refined[size_t(y * w)];
                    uint8_t* out = &rows[size_t(y * w)];
                    for (int64_t x = 0; x < w; ++x)
                        out[x] = in[x] | (x > 0 ? in[x - 1] : 0) | (x + 1 < w ? in[x + 1] : 0);
                }
            });
            parallelFor(0, h, 32, [&](int64_t y0, int64_t y1) {
                for (int64_t y = y0; y < y1; ++y) {
                    const uint8_t* above = &rows[size_t(std::max<int64_t>(0, y - 1) * w)];
                    const uint8_t* at = &rows[size_t(y * w)];
                    const uint8_t* below = &rows[size_t(std::min(h - 1, y + 1) * w)];
                    uint8_t* out = &skip[size_t(y * w)];
                    for (int64_t x = 0; x < w; ++x) out[x] = above[x] | at[x] | below[x];
                }
            });
        }
        detail::postAntiAlias(filtered, skip, r.image, scratch.luma);
    }
    if (f.glassSamples.empty()) return;
    r.glassMask.assign(size_t(w * h), 0);
    parallelFor(0, h, 32, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < w; ++x) {
                uint8_t any = 0;
                for (int dy = 0; dy < k; ++dy)
                    for (int dx = 0; dx < k; ++dx)
                        any |= f.glassSamples[size_t((y * k + dy) * W + x * k + dx)];
                r.glassMask[size_t((h - 1 - y) * w + x)] = any;
            }
    });
    for (const uint8_t v : r.glassMask) r.glass.pixels += v;
}

struct RenderPass {
    std::string_view name;
    double progressEnd; ///< the share of the whole render done when the pass ends
    void (*run)(FrameState&, Progress*);
};

// The frame, in order. A pass reads what the passes before it left in the frame state.
constexpr RenderPass kPasses[] = {
    {"flatten", 0.0, flattenPass}, {"G-buffer", 0.2, gbufferPass}, {"occlusion", 0.3, occlusionPass},
    {"shadows", 0.5, shadowPass},  {"shading", 1.0, shadingPass},  {"translucency", 1.0, translucencyPass},
    {"glass", 1.0, glassPass},     {"volumes", 1.0, volumePass},   {"resolve", 1.0, resolvePass}};

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

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options) {
    RenderCache cache; // this frame's alone
    return render(scene, camera, options, cache);
}

RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options,
                    RenderCache& cache) {
    checkRender(scene, options);
    const auto t0 = Clock::now();
    // The one environment: given, else the procedural sky or the flat background. A scene without
    // lights gets the default sun: the sky's, or a map's brightest region.
    static const Environment defaultSky = Environment::sky();
    std::optional<Environment> flat;
    const Environment* env = options.environment.get();
    if (!env)
        env = options.sky == SkyKind::Flat ? &flat.emplace(Image(1, 1, options.background)) : &defaultSky;
    std::span<const Light> lights = scene.lights;
    Light sun;
    if (scene.lights.empty() && options.defaultLights) {
        sun.name = "default sun";
        const Vec3d towards =
            length(env->sunDirection()) > 0 ? env->sunDirection() : SkyOptions{}.sunDirection;
        sun.direction = -normalize(towards);
        sun.color = {1.0f, 0.96f, 0.9f};
        sun.intensity = 3;
        lights = {&sun, 1};
    }
    // Adaptive anti-aliasing, except where the volume pass draws (it casts a ray per sample).
    const bool volumes = (scene.volumeScene && !scene.volumeScene->objects.empty()) ||
                         std::any_of(scene.meshes.begin(), scene.meshes.end(), [&](const SceneMesh& m) {
                             return m.material < scene.materials.size() && scene.materials[m.material].blend;
                         });
    const bool adaptiveOn =
        options.antiAliasing == AntiAliasing::Adaptive || options.antiAliasing == AntiAliasing::Full;
    const int adaptive = adaptiveOn && !volumes ? options.adaptiveSamples : 1;
    RenderResult result;
    const int k = options.supersample * adaptive;
    detail::RenderCacheData& c = cache.data();
    FrameState frame{scene,
                     lights,
                     camera,
                     options,
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
