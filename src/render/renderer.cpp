// voxfx — the renderer's driver: one frame is an ordered list of passes over one frame state, each
// timed and given its share of the progress (see render.hpp for the passes).
#include <algorithm>
#include <chrono>
#include <optional>

#include "core/progress_range.hpp"
#include "render/antialias.hpp"
#include "render/frame_state.hpp"
#include "render/glass_pass.hpp"
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

// The ambient light's occlusion field over the opaque triangles (see RenderOptions::ambientOcclusion).
void occlusionPass(FrameState& f, Progress* progress) {
    const RenderOptions& o = f.options;
    const bool ambientLight = o.skyLight > 0 || o.ambient.x > 0 || o.ambient.y > 0 || o.ambient.z > 0;
    if (o.ambientOcclusion == Occlusion::Off || !ambientLight) return;
    detail::Hasher key;
    key.value(f.meshesKey), key.value(f.materialsKey), key.value(o.creaseAngle);
    key.value(o.occlusionRadius), key.value(o.occlusionResolution);
    f.occlusion = f.cache.occlusion.find(key.get());
    if (f.occlusion) {
        f.cachedPass = true;
        return;
    }
    const auto none = std::make_shared<const AmbientOcclusion>(); // visibility 1 everywhere
    const SceneGeometry& g = f.geometry;
    const Mesh& mesh = g.mesh;
    // Opaque triangles occlude; per mesh, its bounds and whether it is flat (every vertex on the
    // plane of its largest triangle, to 1e-6 of its size): a flat mesh never occludes itself.
    std::vector<uint32_t> indices;
    struct PerMesh {
        Box3d box;
        Vec3d normal, point;
        double area2 = 0;
        bool flat = true;
    };
    std::vector<PerMesh> meshes(f.scene.meshes.size());
    std::vector<std::size_t> opaque;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t mat = g.triangleMaterial[t];
        if (mat >= f.scene.materials.size() || !f.scene.materials[mat].isOpaque()) continue;
        opaque.push_back(t);
        PerMesh& m = meshes[g.triangleMesh[t]];
        const Vec3d a = Vec3d(mesh.positions[mesh.indices[3 * t]]),
                    b = Vec3d(mesh.positions[mesh.indices[3 * t + 1]]),
                    c = Vec3d(mesh.positions[mesh.indices[3 * t + 2]]);
        m.box.extend(a), m.box.extend(b), m.box.extend(c);
        const Vec3d n = cross(b - a, c - a);
        if (dot(n, n) > m.area2) m.area2 = dot(n, n), m.normal = n, m.point = a;
    }
    if (opaque.empty()) {
        f.cache.occlusion.insert(key.get(), none); // nothing occludes
        return;
    }
    for (const std::size_t t : opaque) {
        PerMesh& m = meshes[g.triangleMesh[t]];
        if (!m.flat || m.area2 <= 0) continue;
        const double tol = 1e-6 * length(m.box.extent());
        const Vec3d n = m.normal / std::sqrt(m.area2);
        for (int k = 0; k < 3; ++k)
            if (std::fabs(dot(Vec3d(mesh.positions[mesh.indices[3 * t + k]]) - m.point, n)) > tol)
                m.flat = false;
    }
    indices.reserve(3 * opaque.size());
    for (const std::size_t t : opaque)
        for (int k = 0; k < 3; ++k) indices.push_back(mesh.indices[3 * t + k]);
    // The region: the non-flat opaque meshes (all of them when every one is flat); the radius a
    // tenth of their median diagonal unless given.
    std::vector<double> diagonals;
    Box3d region;
    for (int pass = 0; pass < 2 && region.empty(); ++pass)
        for (const PerMesh& m : meshes)
            if (!m.box.empty() && (pass == 1 || !m.flat)) {
                region.extend(m.box.lo), region.extend(m.box.hi);
                diagonals.push_back(length(m.box.extent()));
            }
    std::sort(diagonals.begin(), diagonals.end());
    AmbientOcclusionOptions ao;
    ao.radius = o.occlusionRadius > 0 ? o.occlusionRadius : 0.1 * diagonals[diagonals.size() / 2];
    if (!(ao.radius > 0)) {
        f.cache.occlusion.insert(key.get(), none);
        return;
    }
    const Vec3d extent = region.extent() + Vec3d{2, 2, 2} * ao.radius;
    const double longest = std::max({extent.x, extent.y, extent.z});
    ao.resolution = std::clamp<int64_t>(
        std::max<int64_t>(o.occlusionResolution, int64_t(std::ceil(4 * longest / ao.radius))), 8, 2048);
    ao.threads = o.threads;
    ao.progress = progress;
    MeshView view;
    view.positions = &mesh.positions[0].x;
    view.vertexCount = mesh.positions.size();
    view.indices = indices.data();
    view.triangleCount = opaque.size();
    f.occlusion = std::make_shared<const AmbientOcclusion>(view, region, ao);
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
