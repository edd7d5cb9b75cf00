// voxfx render SCENE -o IMAGE — rasterizing renderer with shadow maps, ED06 transmittance shadows or
// CHANG absorption shadows; prints a progress line and per-pass timings.
#include <iostream>

#include "cli_common.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"

namespace voxfx::cli {
namespace {

struct RenderArgs {
    std::string input, output, shadows, slicing, voxelMode, glass, environment;
    int64_t glassGrid = 0;
    int64_t width = 0, height = 0, grid = 0, gridDepth = 0, mapResolution = 0;
    int supersample = 0, pcf = 1, camera = 0, threads = 0;
    double exposure = 1, epsilon = 0.05;
    std::string dsmStorage = "chunked";
    std::string device = "cpu";
    int64_t dsmResolution = 512;
    int clusters = 0;
    bool quiet = false, bilinear = false, noVolumeCulling = false, noEmptySpaceSkipping = false;
};

void printTimings(const RenderResult& r, const std::string& output) {
    const RenderTimings& t = r.timings;
    std::cout << "time: G-buffer " << fmtMs(t.gbufferMs) << ", shadow map " << fmtMs(t.shadowMapMs)
              << ", voxelization from light " << fmtMs(t.lightVoxelizeMs) << ", shading "
              << fmtMs(t.shadingMs) << (r.volumeSamples ? ", volumes " + fmtMs(t.volumeMs) : std::string())
              << ", resolve " << fmtMs(t.resolveMs) << " (flatten " << fmtMs(t.flattenMs) << "), total "
              << fmtMs(t.totalMs) << " -> " << output << "\n";
}

/// Writes .png (sRGB), .pfm or .exr (linear HDR); anything else is refused before rendering.
void checkImageExtension(const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext == ".png" || ext == ".pfm" || ext == ".exr") return;
    fail(path, ": unknown image extension (allowed: .png, .pfm, .exr)");
}

void writeImage(const Image& image, const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext == ".pfm")
        writePfm(image, path);
    else if (ext == ".exr")
        writeExr(image, path);
    else
        writePng(image, path);
}

int runRender(const RenderArgs& a) {
    checkImageExtension(a.output);
    const auto t0 = Clock::now();
    const Scene scene = loadScene(a.input);
    const double loadMs = msSince(t0);
    const SceneSettings& s = scene.settings;

    RenderOptions o;
    o.width = a.width ? a.width : (s.width ? s.width : 1280);
    o.height = a.height ? a.height : (s.height ? s.height : 720);
    o.supersample = a.supersample ? a.supersample : (s.supersample ? s.supersample : 1);
    o.shadow.kind =
        parseShadowKind(!a.shadows.empty() ? a.shadows : (!s.shadows.empty() ? s.shadows : "map"));
    o.shadow.gridResolution = a.grid ? a.grid : (s.gridResolution ? s.gridResolution : 256);
    o.shadow.gridDepth = a.gridDepth ? a.gridDepth : (s.gridDepth ? s.gridDepth : 256);
    o.shadow.mapResolution =
        a.mapResolution ? a.mapResolution : (s.shadowMapResolution ? s.shadowMapResolution : 2048);
    o.shadow.slicing =
        parseSlicing(!a.slicing.empty() ? a.slicing : (!s.slicing.empty() ? s.slicing : "uniform"));
    o.shadow.voxelMode = parseVoxelizeMode(
        !a.voxelMode.empty() ? a.voxelMode : (!s.voxelMode.empty() ? s.voxelMode : "surface"));
    if (o.shadow.voxelMode != VoxelizeMode::Surface && o.shadow.voxelMode != VoxelizeMode::Conservative)
        fail("--voxel-mode must be surface or conservative for shadows");
    o.shadow.device = parseDevice(a.device);
    if (o.shadow.device == Device::Cuda && !cudaStatus().available && !a.quiet)
        std::cerr << "voxfx: --device cuda: " << cudaStatus().reason
                  << "; the light grids are voxelized on the CPU\n";
    o.shadow.pcfRadius = a.pcf;
    o.shadow.bilinear = a.bilinear;
    o.shadow.volumeCulling = o.shadow.volumeClamping = !a.noVolumeCulling;
    o.shadow.dsmEpsilon = a.epsilon;
    o.shadow.dsmStorage = parseDsmStorage(a.dsmStorage);
    o.shadow.dsmResolution = a.dsmResolution;
    o.shadow.dsmClusters = a.clusters;
    o.skipEmptySpace = o.shadow.dsmSkipEmptySpace = !a.noEmptySpaceSkipping;
    if (s.ambient.x >= 0) o.ambient = s.ambient;
    if (s.background.x >= 0) o.background = s.background;
    o.exposure = float(a.exposure);
    o.threads = a.threads;
    o.glass.kind = a.glass.empty() ? defaultGlassKind(scene) : parseGlassKind(a.glass);
    if (a.glassGrid) o.glass.gridResolution = a.glassGrid;
    // The environment: --environment, the scene's map, or the procedural sky where glass or a scene
    // without lights needs one (the background then shows it too).
    const std::string envPath = !a.environment.empty() ? a.environment : s.environmentMap;
    Environment environment;
    if (!envPath.empty() || o.glass.kind != GlassKind::None || scene.lights.empty()) {
        environment = loadEnvironment(envPath.empty() ? "sky" : envPath);
        o.environment = &environment;
    }

    Camera camera;
    if (scene.cameras.empty()) {
        if (a.camera != 0) fail(a.input, ": the scene has no cameras (--camera ", a.camera, ")");
        camera = defaultCamera(scene, double(o.width) / double(o.height));
    } else {
        if (a.camera < 0 || std::size_t(a.camera) >= scene.cameras.size())
            fail("--camera ", a.camera, ": the scene has ", scene.cameras.size(), " cameras (0 .. ",
                 scene.cameras.size() - 1, ")");
        camera = scene.cameras[std::size_t(a.camera)];
    }

    ProgressLine progress("rendering", !a.quiet);
    o.progress = &progress;
    const RenderResult r = render(scene, camera, o);
    progress.done();
    writeImage(r.image, a.output);
    if (!a.quiet) {
        std::cout << a.input << ": " << withCommas(int64_t(scene.triangleCount())) << " triangles, "
                  << scene.lights.size() << " light(s), camera '" << camera.name << "' -> " << o.width
                  << " x " << o.height;
        if (o.supersample > 1) std::cout << " (" << o.supersample << "x" << o.supersample << " supersampled)";
        std::cout << ", shadows " << toString(o.shadow.kind);
        if (o.shadow.kind == ShadowKind::Transmittance || o.shadow.kind == ShadowKind::Absorption)
            std::cout << " (grid " << o.shadow.gridResolution << " x " << o.shadow.gridDepth << ", "
                      << toString(o.shadow.slicing) << " slicing)";
        else if (o.shadow.kind == ShadowKind::Deep)
            std::cout << " (" << o.shadow.dsmResolution << " texels, epsilon " << o.shadow.dsmEpsilon << ", "
                      << toString(o.shadow.dsmStorage) << " storage"
                      << (o.shadow.dsmClusters > 1
                              ? ", at most " + std::to_string(o.shadow.dsmClusters) + " clusters"
                              : "")
                      << ")";
        else if (o.shadow.kind == ShadowKind::Map)
            std::cout << " (" << o.shadow.mapResolution << " texels, PCF " << 2 * o.shadow.pcfRadius + 1
                      << "x" << 2 * o.shadow.pcfRadius + 1 << ")";
        else if (o.shadow.kind == ShadowKind::Volumes)
            std::cout << " (" << withCommas(r.shadowVolumeFragments)
                      << " volume fragments, culling and clamping " << (o.shadow.volumeCulling ? "on" : "off")
                      << ", " << fmtMs(r.timings.shadowVolumeMs) << ")";
        if (o.shadow.kind == ShadowKind::Deep && r.deepShadowStats.texels > 0) {
            const DsmStats& d = r.deepShadowStats;
            const double fixedMiB =
                double(d.texels) * double(d.maxNodes * int64_t(sizeof(DsmNode)) + 2) / 1048576.0;
            std::cout << "\ndeep shadow maps: " << withCommas(d.texels) << " texels, nodes per texel mean "
                      << d.meanNodes() << " max " << d.maxNodes << ", " << double(d.bytes) / 1048576.0
                      << " MiB " << toString(o.shadow.dsmStorage)
                      << " (fixed layout sized by the worst texel: " << fixedMiB << " MiB)";
        }
        std::cout << "\nload " << fmtMs(loadMs) << "; ";
        printTimings(r, a.output);
        if (o.glass.kind != GlassKind::None) {
            int64_t glassPixels = 0;
            for (const uint8_t m : r.glassMask) glassPixels += m;
            std::cout << "glass " << toString(o.glass.kind);
            if (o.glass.kind != GlassKind::Exact) std::cout << " (grid " << o.glass.gridResolution << ")";
            std::cout << ": " << withCommas(glassPixels) << " pixels, prepare "
                      << fmtMs(r.timings.glassPrepareMs) << ", trace " << fmtMs(r.timings.glassMs) << "\n";
        }
    }
    return 0;
}

const char* kRenderHelp = R"(
Shadow kinds:
  none           no shadows
  map            standard shadow map with PCF (binary: leaves are opaque)
  transmittance  ED06: partial occluders (leaves, glass) voxelized from the light; light
                 is attenuated per filled cell, one channel per leaf colour group; opaque
                 objects keep a standard shadow map
  absorption     CHANG: attribute voxelization from the light, absorption = write count x
                 material constant, summed along the light path
  volumes        exact hard shadows: shadow volumes of the closed casters counted per
                 pixel (open casters are refused), culled and clamped against what the
                 camera sees (ED06 3.2; --no-volume-culling turns that off)
  exact          ray traced on the triangles (Embree): the product of the transmittances
                 of every surface crossed towards the light (the reference)

Glass (materials with transmission > 0 and opacity 1):
  none           shaded like any surface
  exact          ray tracing on the triangles (Embree): Snell, Fresnel, total internal
                 reflection, Beer-Lambert over true lengths; the reference
  multi          CHANG: march through an attribute grid, refract at boundary voxels
  two-surface    Wyman 2005: refract at the front surface and at the first back surface
  frosted        ED06: thickness from front/back-face slicemaps drives a refraction
                 offset, attenuation and a blurred environment lookup
A scene without lights is lit by a default sun and the sky (or --environment).
  deep           deep shadow maps (Bornik et al.): per texel an epsilon-compressed
                 visibility function over all fragments from the light; translucent
                 surfaces are steps, volume objects attenuate continuously

Settings a JSON scene file gives under "render" are used unless a flag overrides them.
Output by extension: .png (8-bit sRGB), .exr (OpenEXR, linear half-float RGB, HDR) or
.pfm (linear 32-bit float, HDR).)";

const Command kRender{
    "render", "Render a scene (glTF, JSON wrapper, mesh) with shadows through foliage", [](CLI::App& app) {
        app.footer(kRenderHelp);
        auto a = std::make_shared<RenderArgs>();
        app.add_option("SCENE", a->input, "Scene: .gltf .glb .json, or a mesh file")->required();
        app.add_option("-o,--output", a->output, "Image: .png (sRGB), .exr or .pfm (linear HDR)")->required();
        app.add_option("--width", a->width, "Image width (default 1280)")
            ->check(CLI::Range(int64_t(1), int64_t(65536)));
        app.add_option("--height", a->height, "Image height (default 720)")
            ->check(CLI::Range(int64_t(1), int64_t(65536)));
        app.add_option("--shadows", a->shadows,
                       "none | map | transmittance | absorption | volumes | exact | deep (default map)");
        app.add_option("--supersample", a->supersample, "Render k x k samples per pixel (1..8)")
            ->check(CLI::Range(1, 8));
        app.add_option("--grid", a->grid, "Light grid columns, longer side (default 256)")
            ->check(CLI::Range(int64_t(1), int64_t(16384)));
        app.add_option("--grid-depth", a->gridDepth, "Light grid slices (default 256)")
            ->check(CLI::Range(int64_t(1), int64_t(16384)));
        app.add_option(
               "--device", a->device,
               "Where the transmittance shadows' light grids are voxelized: cpu, cuda or auto (the same "
               "grids; see voxfx devices)")
            ->default_val("cpu");
        app.add_option("--map-resolution", a->mapResolution, "Shadow map texels (default 2048)")
            ->check(CLI::Range(int64_t(1), int64_t(32768)));
        app.add_option("--slicing", a->slicing, "uniform | local (ED06 per-column range)");
        app.add_option("--voxel-mode", a->voxelMode, "surface (ED06) | conservative");
        app.add_option("--pcf", a->pcf, "PCF radius r: (2r+1)^2 taps (default 1)")->check(CLI::Range(0, 8));
        app.add_option("--camera", a->camera, "Index of the scene camera (default 0)");
        app.add_option("--exposure", a->exposure, "Multiplies the linear image (default 1)")
            ->check(CLI::PositiveNumber);
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (identical output)")
            ->check(CLI::NonNegativeNumber);
        app.add_option("--glass", a->glass,
                       "none | exact | multi | two-surface | frosted (default: exact if the scene has glass, "
                       "else none)");
        app.add_option("--glass-grid", a->glassGrid, "Glass voxels along the longest side (default 128)")
            ->check(CLI::Range(int64_t(2), int64_t(4096)));
        app.add_option("--environment", a->environment, "Environment map: .exr .hdr .pfm .png, or 'sky'");
        app.add_option("--epsilon", a->epsilon, "Deep shadows: compression tolerance (default 0.05)")
            ->check(CLI::Range(0.0, 1.0));
        app.add_option("--dsm-storage", a->dsmStorage, "Deep shadows: fixed | chunked (default chunked)");
        app.add_option("--dsm-resolution", a->dsmResolution,
                       "Deep shadows: texels per view side (default 512)")
            ->check(CLI::Range(int64_t(1), int64_t(16384)));
        app.add_option("--clusters", a->clusters,
                       "Deep shadows: at most M clustered maps per light (0 = off)")
            ->check(CLI::Range(0, 64));
        app.add_flag("--bilinear", a->bilinear, "Interpolate light-grid lookups between 4 columns (softer)");
        app.add_flag("--no-volume-culling", a->noVolumeCulling,
                     "Shadow volumes: no culling or clamping (the same image, more fragments)");
        app.add_flag("--no-empty-space-skipping", a->noEmptySpaceSkipping,
                     "Volumes: sample the bricks the transfer function leaves transparent too (the same "
                     "image, slower; for timing)");
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        return std::function<int()>([a] { return runRender(*a); });
    }};

} // namespace
} // namespace voxfx::cli
