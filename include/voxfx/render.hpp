// voxfx — the rasterizing renderer: G-buffer, light loop with shadows, glass, volumes, Blinn–Phong
// shading.
//
// A frame runs an ordered list of passes over one frame state (render/renderer.cpp), each timed
// (RenderTimings::passes, in this order):
//   flatten   every SceneMesh into one indexed mesh with per-triangle material and vertex normals
//             (split at creases, RenderOptions::creaseAngle); meshes of blended materials last
//             (voxfx/gbuffer.hpp).
//   G-buffer  the camera is a perspective Frame whose columns are pixels; a consumer of the one
//             rasterizer keeps the nearest centre-sampled fragment per pixel (ties to the lower
//             triangle index, so the result does not depend on the thread count).
//   occlusion the ambient light's occlusion (RenderOptions::ambientOcclusion): screen (the default),
//             GTAO over the G-buffer's cells; field, the distance field of the opaque triangles
//             (voxfx/ambient_occlusion.hpp, built once per scene with a RenderCache); nothing when off.
//   shadows   one LightShadow per light, built by the chosen technique (voxfx/shadow.hpp) and, for
//             techniques that count over the camera's G-buffer, prepared with it.
//   shading   deferred, tile rows in parallel: ambient (times its occlusion) + per light Blinn–Phong times
//   the light's RGB
//             visibility. Surfaces are lit on both sides; the side facing away from a light receives
//             the light that crosses the surface (crossingTransmittance: back-lit leaves glow). With
//             an environment, background pixels show it along their ray.
//   translucency  the samples showing a translucent solid (Material::isTranslucent: diffuse
//             transmission without specular transmission; glTF KHR_materials_diffuse_transmission
//             with KHR_materials_volume's attenuation) add the light from behind them (GI08 §7):
//             what the G-buffer without the translucent meshes shows there (shaded, or the
//             environment) times diffuseTransmission times exp(-sigma_c L) per channel, sigma =
//             attenuationCoefficient (-ln(attenuationColor) / attenuationDistance) and L the solid
//             matter from the sample's surface depth to the depth of what lies behind, counted
//             along its output pixel's centre ray in a solid voxelization of the translucent meshes
//             in the camera's frame at the output resolution (ViewMatter,
//             voxfx/translucency_shadow.hpp; within one slice of translucencySlices per entry into
//             the solid of the exact chord). Thin parts show the light behind, thick parts are
//             dark; what lies behind is blurred over a cone of translucencyBlur * L /
//             attenuationDistance radians (at most 1: the solid scatters; 32 taps of the scene
//             behind, the environment read blurred), so thick jade is milky, not clear; the
//             lights' light through the solid is the shading pass's (diffuse transmission
//             times the shadow: with `translucency` shadows, Beer-Lambert over the
//             matter the light crossed). Nothing when no sample shows a translucent solid.
//   glass     the pixels showing glass (Material::isGlass) get the light through it by the chosen
//             method (voxfx/glass.hpp).
//   ray casting  scenes with volume objects, Boolean shapes (scene.volumeScene) or meshes of
//             blended materials: ray casting over fragment lists from the camera, composited over the shaded
//             image: volumes sampled (lit by Phong about their gradient normals unless
//             RenderOptions::volumeShading is none), and the visible surfaces of opaque and translucent
//             objects (where a Boolean's inside flag changes) and of blended meshes shaded like meshes and
//             α-blended in depth order.
//   resolve   box filter of the samples of each pixel, flipped to image rows (y down), then the
//             output transform (RenderOptions::toneMap) and the post-process anti-aliasing.
// Anti-aliasing (RenderOptions::antiAliasing, default full): the G-buffer holds s x s samples per
// pixel (s = adaptiveSamples, times supersample); the shading pass shades every pixel's central
// sample, then the other samples only in the pixels on an edge (more than one mesh or material,
// background and geometry, a depth or normal discontinuity), where a sample showing the triangle a
// neighbouring pixel's central sample shows takes its shading; elsewhere the one sample is copied.
// The glass pass traces the glass samples shaded, then s samples (N-rooks) in pixels showing glass
// inside whose light differs from a neighbour's. Pixels shaded once then get FXAA-style
// post-process anti-aliasing (Lottes 2009: an edge along the luma gradient, searched to its ends, blended by
// the sub-pixel distance). The volume pass (volumes, Boolean shapes, blended meshes) composites over
// the samples shaded, then shades every sample of the pixels where its rays cross different faces or
// its light differs from a neighbour's. Lighting: one environment
// (RenderOptions::environment, else the procedural sky, or the flat `background` with sky = flat) is what the
// background shows, what glass reflects and refracts, and the ambient light: albedo / pi times the
// environment's irradiance around the normal (order-2 spherical harmonics, Ramamoorthi & Hanrahan 2001) times
// skyLight, plus the constant `ambient`. Output: RenderOptions::toneMap filmic (the ACES fit of
// Narkowicz 2015: display-referred, in [0, 1)), linear (the image as it is: writePng clamps at 1;
// .pfm/.exr keep HDR) or auto (the default: linear for HDR files, filmic for display formats,
// toneMapForImage; render() itself, knowing no file, takes auto as filmic). Deterministic for any
// thread count.
//
// Options by name. Every setting a front end reaches has a name (voxfx/options.hpp): the fields of
// RenderOptions itself (renderOptionFields), of each shadow technique and of each glass method.
// setRenderOption sets one wherever the render uses it, renderOptionsFor applies a scene file's
// settings, and renderOptionCatalog lists every name for front ends (the CLI's flags, Python's
// keywords): the defaults are stated once, as the structs' member initializers.
//
// Thread-safety: render calls may run concurrently on one const Scene; each uses worker threads
// (RenderOptions::threads) itself.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/glass_options.hpp"
#include "voxfx/image.hpp"
#include "voxfx/options.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_options.hpp"
#include "voxfx/types.hpp"

// What a program that renders compiles: the options (of the render, of each shadow technique and
// glass method: voxfx/shadow_options.hpp, voxfx/glass_options.hpp), the scene, the image and the
// results; not the techniques themselves (voxfx/shadow.hpp, voxfx/glass.hpp and their rooms, which
// the renderer's implementation includes). BENCHMARKS.md measures what including this costs.
namespace voxfx {

class Progress; // voxfx/parallel.hpp

/// Anti-aliasing of render(): off (one sample per pixel), post (FXAA-style post-process only),
/// adaptive (edge and glass pixels supersampled only), full (both; the default).
enum class AntiAliasing : uint8_t { Off, Post, Adaptive, Full };
inline constexpr EnumName<AntiAliasing> kAntiAliasingNames[] = {{"off", AntiAliasing::Off},
                                                                {"post", AntiAliasing::Post},
                                                                {"adaptive", AntiAliasing::Adaptive},
                                                                {"full", AntiAliasing::Full}};
const char* toString(AntiAliasing a);
/// Parses off | post | adaptive | full; throws voxfx::Error listing them otherwise.
AntiAliasing parseAntiAliasing(const std::string& name);

/// The output transform of render(): filmic (ACES fit, display-referred), linear (the scene-linear
/// radiance as is, times the exposure; "clamp" is its old name: writePng clips at 1) or auto (the
/// default: what toneMapForImage picks for the file written, filmic where render() is not told).
enum class ToneMap : uint8_t { Filmic, Clamp, Auto };
inline constexpr EnumName<ToneMap> kToneMapNames[] = {{"filmic", ToneMap::Filmic},
                                                      {"linear", ToneMap::Clamp},
                                                      {"auto", ToneMap::Auto},
                                                      {"clamp", ToneMap::Clamp, true}};
const char* toString(ToneMap t);
ToneMap parseToneMap(const std::string& name);
/// The output transform an image written to `path` gets: `requested` when it is filmic or linear;
/// for auto, linear for the HDR formats (.exr, .pfm, .hdr: scene-linear radiance, as pbrt, Mitsuba
/// and Blender write them) and filmic for display formats (.png, .ppm, ...) and an empty path.
/// The one place the default depends on the format: front ends that write files call it.
ToneMap toneMapForImage(ToneMap requested, std::string_view path);
/// The filmic curve (Narkowicz 2015's fit of ACES, input scaled by 0.6): f(0) = 0, increasing,
/// f(x) < 1 for every x below about 12, f(x) -> 1.033 (clamped to 1). Per channel.
float filmicToneMap(float x);

/// Which environment render() uses when RenderOptions::environment is null: the procedural sky
/// (Environment::sky) or a flat one of radiance RenderOptions::background.
enum class SkyKind : uint8_t { Procedural, Flat };
inline constexpr EnumName<SkyKind> kSkyKindNames[] = {{"procedural", SkyKind::Procedural},
                                                      {"flat", SkyKind::Flat}};
const char* toString(SkyKind k);
SkyKind parseSkyKind(const std::string& name);

/// How render() lights volume samples (DSM §3.2: Phong): none (ambient plus each light's irradiance
/// times its shadow, whatever the direction) or phong (Blinn–Phong about the gradient normal,
/// weighted by the gradient's magnitude; see RenderOptions::volumeShading).
enum class VolumeShading : uint8_t { None, Phong };
inline constexpr EnumName<VolumeShading> kVolumeShadingNames[] = {{"none", VolumeShading::None},
                                                                  {"phong", VolumeShading::Phong}};
const char* toString(VolumeShading v);
VolumeShading parseVolumeShading(const std::string& name);

/// Ambient occlusion of the ambient light (RenderOptions::ambientOcclusion): off; screen
/// (ground-truth ambient occlusion on the G-buffer, Jimenez et al. 2016: the horizons the visible
/// surfaces make within the radius, at half resolution with a bilateral upsample; fast, blind to
/// what the camera does not see); or field (cone tracing the opaque geometry's distance field,
/// voxfx/ambient_occlusion.hpp: sees hidden and off-screen occluders, built once per scene, slower
/// per pixel).
enum class Occlusion : uint8_t { Off, Field, Screen };
inline constexpr EnumName<Occlusion> kOcclusionNames[] = {
    {"off", Occlusion::Off}, {"field", Occlusion::Field}, {"screen", Occlusion::Screen}};
const char* toString(Occlusion o);
Occlusion parseOcclusion(const std::string& name);

struct RenderOptions {
    int64_t width = 1280, height = 720;        ///< output pixels, 1..65536
    int supersample = 1;                       ///< k: render k*width x k*height, box-filter down (1..8)
    ShadowOptions shadow = ShadowMapOptions{}; ///< the shadow technique and its options
    Vec3f ambient{0, 0, 0}; ///< constant ambient radiance (times albedo), added to the sky's
    /// The environment's irradiance (over pi, times albedo) as ambient light is scaled by this (0: none).
    double skyLight = 1;
    SkyKind sky = SkyKind::Procedural;     ///< the environment when none is given
    Vec3f background{0.60f, 0.72f, 0.90f}; ///< the flat environment's radiance (sky = flat)
    /// The procedural sky (Environment::sky, SkyOptions): the sun's place (degrees above the horizon,
    /// and from -z towards +x), the turbidity and the ground's albedo below the horizon. The default
    /// sun of a scene without lights is the sky's.
    double sunElevation = kDefaultSunElevation;
    double sunAzimuth = kDefaultSunAzimuth;
    double turbidity = kDefaultTurbidity;
    Vec3f groundAlbedo = SkyOptions{}.groundAlbedo;
    AntiAliasing antiAliasing = AntiAliasing::Full;
    /// Adaptive anti-aliasing: edge and glass pixels get s x s samples (2..8).
    int adaptiveSamples = 2;
    ToneMap toneMap = ToneMap::Auto; ///< the output transform (auto: toneMapForImage)
    /// Multiplies the linear result (background included); 0: automatic, key / the frame's
    /// log-average luminance (Reinhard et al. 2002, key 0.18: RenderResult::exposure).
    float exposure = 1;
    GlassOptions glass; ///< the glass method and its options (default none: shaded as surfaces)
    /// Glass, adaptive image-space refinement: the light through every other pixel (cell) along x
    /// and y is traced first; a pixel between them is traced too only where their paths part: other
    /// glass objects crossed or crossed otherwise (GlassPath::crossed, total internal reflection),
    /// another object, or triangles that do not share an edge, where the light leaving the glass or
    /// its reflection lands, exit directions more than 3 degrees apart, a pixel the G-buffer refined
    /// (an edge) among them, or their shown light (luma, 0..1, after the output transform) departing
    /// from a straight line through their lattice neighbours' by more than this; elsewhere the light
    /// through the glass is interpolated from them (two or four). 0: every pixel traced.
    double glassRefinement = 1.0 / 32;
    /// Glass, adaptive anti-aliasing (antiAliasing adaptive or full): a glass pixel shaded once gets
    /// its N-rooks samples where its shown light (luma, 0..1) departs from the straight line through
    /// its neighbours' by more than this (a bend or a step inside the glass). The default, 1/16, is
    /// the cut with the least error per path saved (BENCHMARKS.md, frames-glass8: against 1/32, the
    /// smallest step the post-process blends, 4 % fewer glass paths on the glass demo for 1.7 % more
    /// mean shown-luma error against a 16-sample reference, still below the post-process alone's
    /// there and on the glass ball test); larger values trade more accuracy for speed (frames-glass7:
    /// 1/4 takes about a tenth off the cached frame and leaves the reference 11 % further away; 1
    /// takes none).
    double glassSampleContrast = 1.0 / 16;
    /// Radiance around the scene: shown as the background, seen through and in glass, and the ambient
    /// light. Null: the procedural sky (Environment::sky), or the flat `background` (sky = flat).
    std::shared_ptr<const Environment> environment;
    /// A scene without lights is lit by a sun (the sky's, or a map's brightest region, else SkyOptions'
    /// default direction) besides the environment's ambient light, as glTF viewers do.
    bool defaultLights = true;
    int threads = 0;              ///< 0 = all; output is identical for every value
    Progress* progress = nullptr; ///< polled between tiles of every pass; may cancel
    /// Volume ray casting (scene.volumeScene): sample step in voxel spacings, each volume at its own
    /// smallest spacing (where volumes overlap, the finest of them).
    double volumeStep = 1.0;
    /// Volume ray casting: volume bricks the transfer function leaves transparent are not sampled
    /// (EmptySpace, voxfx/segment_walker.hpp); the image is the same either way, only faster.
    bool skipEmptySpace = true;
    /// Volume ray casting, adaptive image-space refinement (Levoy 1990) on a lattice of three
    /// levels: the rays of every fourth pixel (cell) along x and y are cast first, then those of
    /// every second pixel and then the rest are each interpolated from the pixels 2 (then 1) apart
    /// that the level before gave (two along x or y, or four diagonal), or cast where its ray crosses
    /// other faces of the volume scene than theirs (a volume's box, a Boolean's or a blended mesh's
    /// edge), the G-buffer's depth there is more than 2 % from theirs (a mesh in front of or inside a
    /// volume), their rays reach opacity one half at depths more than 2 % apart or not all of them do
    /// (the silhouette of the volume's matter), or their volumes' light composited over its own
    /// background departs from a straight line in shown luma (0..1, after the output transform) by
    /// more than this (half the lattice's largest second difference there). 0: every pixel cast.
    double volumeRefinement = 1.0 / 64;
    /// Volume ray casting: how samples are lit. phong: the normal is -gradient / |gradient| (central
    /// differences of the volume, VolumeView::gradient: it points from high values to low, out of a
    /// dense core), each light adds diffuse max(0, n.l) / pi times the sample's colour plus the
    /// normalized Blinn–Phong specular of a default Material (white), and the result is blended with
    /// the unshaded light by s = min(1, |gradient| * h / (0.05 * range)) (h the smallest spacing,
    /// range the volume's max - min: full shading where the value changes by 5 % of its range per
    /// voxel, none where the volume is homogeneous). none: every sample unshaded.
    VolumeShading volumeShading = VolumeShading::Phong;
    /// Meshes without normals of their own: faces meeting at more than this angle (degrees, 0..180)
    /// have a crease between them, smaller angles are smoothed over (flattenScene, gbuffer.hpp).
    double creaseAngle = kDefaultCreaseAngle;
    /// The ambient light (sky irradiance and `ambient`) is multiplied by how much of the hemisphere
    /// a point sees past the opaque geometry within `occlusionRadius`: dark creases, contact shadows
    /// under objects. Direct light is not affected. Screen (the default) finds it from the G-buffer
    /// (one evaluation per pixel, half resolution, bilateral upsample: see Occlusion); field from
    /// the distance field (voxfx/ambient_occlusion.hpp), which also sees what the camera does not.
    Occlusion ambientOcclusion = Occlusion::Screen;
    /// World units; 0: a tenth of the median diagonal of the opaque meshes that are not flat (a
    /// floor is flat), so an object darkens the ground around it about a tenth of its size away.
    double occlusionRadius = 0;
    /// Field occlusion: cells along the longest side of the field (the opaque non-flat meshes'
    /// bounds grown by the radius), at least 4 per radius, at most 2^24 cells in all.
    int64_t occlusionResolution = 128;
    /// The translucency pass: slices of the camera-space solid grid over the translucent meshes'
    /// depth range (1..65536); the matter along a ray is within one slice per entry of the chord.
    int64_t translucencySlices = 256;
    /// The translucency pass: a translucent solid scatters, so what lies behind it is blurred over a
    /// cone of blur * L / attenuationDistance radians (at most 1), L the matter the ray crosses
    /// (render pass "translucency" above). 0: seen sharply, as through clear glass.
    double translucencyBlur = 1.0;

    /// The named fields of RenderOptions itself: width, height, supersample, antiAliasing,
    /// adaptiveSamples, toneMap, exposure, ambient, skyLight, sky, background, sunElevation,
    /// sunAzimuth, turbidity, groundAlbedo, volumeStep,
    /// emptySpaceSkipping, volumeRefinement, glassRefinement, volumeShading, defaultLights, creaseAngle,
    /// ambientOcclusion, occlusionRadius, occlusionResolution, translucencySlices, translucencyBlur.
    static std::span<const OptionField<RenderOptions>> fields();
};

/// The procedural sky RenderOptions describe (sunElevation, sunAzimuth, turbidity, groundAlbedo, and
/// skyLight's share of the sky on its ground; SkyOptions' defaults otherwise). render() uses it
/// without an environment map, its ground lit as it lights the scene's (SkyOptions::groundLight).
SkyOptions skyOptions(const RenderOptions& options);

/// Sets the option `name` (lowerCamelCase, or its kebab- or snake-case spelling) wherever the
/// render uses it. "shadows" and "glass" (names) choose a technique with its default options; any
/// other name sets that field of RenderOptions, of the chosen shadow technique and of the chosen
/// glass method, each that has one of that name. Returns false when none of them has it (it belongs
/// to a technique not chosen). Throws voxfx::Error ("WHERE: NAME: ...") for a name no part of the
/// render knows, a value of the wrong type or out of range, or an unknown technique.
bool setRenderOption(RenderOptions& options, std::string_view name, const OptionValue& value,
                     std::string_view where = {});

/// Checks a setting as a scene file gives it: "shadows" or "glass" names a technique, any other name
/// a field of RenderOptions, of some shadow technique or of some glass method, with a value that
/// field takes. Throws voxfx::Error ("WHERE: NAME: ...") otherwise.
void checkRenderSetting(std::string_view name, const OptionValue& value, std::string_view where = {});

/// The options `scene` renders with unless a front end says otherwise: RenderOptions' defaults; the
/// shadow technique `shadows` if not empty, else the scene file's "shadows", else map; the glass
/// method `glass` if not empty, else the scene file's "glass", else defaultGlass(scene); then the
/// scene file's other settings (SceneSettings::render) where they apply (a setting of a technique not
/// chosen is ignored). The environment is left to the caller (loadSceneEnvironment
/// in voxfx/environment_io.hpp reads the scene's map). Throws voxfx::Error as setRenderOption does.
RenderOptions renderOptionsFor(const Scene& scene, std::string_view shadows = {},
                               std::string_view glass = {});

/// One name a render takes, for front ends that list them (the CLI's flags, Python's keywords).
struct RenderOptionInfo {
    std::string name;  ///< lowerCamelCase
    std::string alias; ///< an older name meaning the same (lowerCamelCase), or empty
    OptionType type = OptionType::Real;
    std::string help;
    double lo = 0, hi = 0; ///< Integer, Real, Triple: the range (of the first user)
    std::string choices;   ///< Name: the names allowed
    /// Who uses it, each with its default: "render (1280)", "shadows map (2048)", "glass multi (128)".
    std::vector<std::string> users;
};
/// Every name setRenderOption takes besides "shadows" and "glass", in the order: RenderOptions',
/// then each shadow technique's, then each glass method's (a name several use is listed once, with
/// every user). The types of one name agree (a test checks it).
std::vector<RenderOptionInfo> renderOptionCatalog();

/// Wall-clock time of one pass.
struct PassTime {
    std::string_view name;
    double ms = 0;
    /// The pass reused what an earlier frame built (RenderCache) instead of building it: the
    /// flattened scene, the lights' shadows, the occlusion field, the glass structures or the volume
    /// pass's setup.
    bool cached = false;
};

struct RenderTimings {
    std::vector<PassTime> passes; ///< every pass, in the order they ran (see the file comment)
    double totalMs = 0;
    /// The time of the pass called `name` ("flatten", "G-buffer", "occlusion", "shadows", "shading",
    /// "translucency", "glass", "ray casting", "resolve"); 0 for one that did not run.
    double ms(std::string_view name) const;
};

/// What the glass pass did.
struct GlassReport {
    std::string_view method = "none";
    int64_t pixels = 0;   ///< output pixels showing glass
    double prepareMs = 0; ///< Embree build (exact) or the grids (voxel methods, frosted)
    double traceMs = 0;   ///< tracing the glass pixels
    int64_t paths = 0;    ///< samples traced through the glass (the method's traceGlass calls)
    /// Cells (output pixels) whose light through the glass was interpolated from the traced cells
    /// around them instead of traced (RenderOptions::glassRefinement).
    int64_t interpolated = 0;
    /// Voxel methods: the grid's voxels along the glass's longest side, and why (given, or auto from
    /// the glass objects' size on screen: chooseGlassGrid); 0 and empty for the other methods.
    int64_t grid = 0;
    std::string gridReason;
};

struct RenderResult {
    Image image;
    RenderTimings timings;
    int64_t coveredPixels = 0; ///< samples (of the supersampled G-buffer) showing geometry
    /// Output pixels shaded at every sample by adaptive anti-aliasing (the rest shaded once).
    int64_t refinedPixels = 0;
    /// The shadow technique's counters, summed over the lights (summary() prints them).
    ShadowStats shadowStats;
    /// Per output pixel (row-major, row 0 on top): 1 where any of its samples shows glass, else 0.
    /// Empty when the glass method is none.
    std::vector<uint8_t> glassMask;
    GlassReport glass;
    int64_t volumeSamples = 0; ///< volume samples the ray-casting pass took
    /// Cells (output pixels) whose volume light the ray-casting pass interpolated from the casts
    /// around them instead of casting (RenderOptions::volumeRefinement).
    int64_t volumeInterpolated = 0;
    /// The exposure the image was made with: RenderOptions::exposure, or the automatic one.
    float exposure = 1;
};

namespace detail {
struct RenderCacheData;
}

/// What the frames of a static scene share, kept between render() calls: the flattened scene, each
/// light's shadow (light grids, shadow maps, deep shadow maps, BVHs), the ambient-occlusion field,
/// the glass method's structures, the volume pass's setup (its volume scene, surfaces, empty space,
/// pre-integrated transfer functions), and the frame buffers and fragment lists (so a frame of the
/// same size allocates nothing large). Pass one cache to every frame of a scene: an orbiting
/// camera, a viewer, the renders of several shadow kinds. Each part is keyed by what it was built
/// from (the meshes, materials and lights by content, the options, the camera where a technique is
/// fitted to it: frosted glass, clustered deep shadows), so a change to the scene or the options
/// rebuilds just what it touches and a stale part is never used; RenderTimings marks the passes
/// that reused one (PassTime::cached). Not thread-safe: one render at a time per cache. Movable,
/// not copyable.
class RenderCache {
public:
    RenderCache();
    ~RenderCache();
    RenderCache(RenderCache&&) noexcept;
    RenderCache& operator=(RenderCache&&) noexcept;
    RenderCache(const RenderCache&) = delete;
    RenderCache& operator=(const RenderCache&) = delete;
    /// Drops everything kept (the memory too).
    void clear();
    detail::RenderCacheData& data() { return *data_; } ///< internal (render/render_cache.hpp)

private:
    std::unique_ptr<detail::RenderCacheData> data_;
};

/// Renders the scene as seen by `camera`. Throws voxfx::Error for invalid options (size, supersample)
/// or a scene without triangles; Scene::validate is called first.
RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options);
/// The same, reusing what `cache` holds from earlier frames and keeping what this frame built
/// (see RenderCache). The image is identical to render() without a cache.
RenderResult render(const Scene& scene, const Camera& camera, const RenderOptions& options,
                    RenderCache& cache);

} // namespace voxfx
