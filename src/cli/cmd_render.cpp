// voxfx render SCENE -o IMAGE — the library's renderer: the scene's own settings (renderOptionsFor),
// then the options given as flags (render_flags.hpp); prints a summary line, the shadow technique's
// counters and per-pass timings.
#include <iostream>

#include "cli_common.hpp"
#include "render_flags.hpp"

namespace voxfx::cli {
namespace {

struct RenderArgs {
    std::string input, output, environment;
    int camera = 0, threads = 0;
    bool quiet = false;
    RenderFlags flags;
};

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

void printSummary(const RenderArgs& a, const Scene& scene, const Camera& camera, const RenderOptions& o,
                  const RenderResult& r, double loadMs) {
    std::cout << a.input << ": " << withCommas(int64_t(scene.triangleCount())) << " triangles, "
              << scene.lights.size() << " light(s), camera '" << camera.name << "' -> " << o.width << " x "
              << o.height;
    if (o.supersample > 1) std::cout << " (" << o.supersample << "x" << o.supersample << " supersampled)";
    const std::string settings =
        std::visit([](const auto& s) { return optionsText(s, kebabCase); }, o.shadow);
    std::cout << ", shadows " << shadowName(o.shadow) << (settings.empty() ? "" : " (" + settings + ")")
              << "\n";
    if (const std::string counters = summary(r.shadowStats); !counters.empty())
        std::cout << "shadows: " << counters << "\n";
    std::cout << "load " << fmtMs(loadMs) << "; time:";
    std::cout << passTimesText(r.timings);
    std::cout << " total " << fmtMs(r.timings.totalMs) << " -> " << a.output << "\n";
    if (!std::holds_alternative<NoGlassOptions>(o.glass)) {
        const std::string glass =
            std::visit([](const auto& g) { return optionsText(g, kebabCase); }, o.glass);
        std::cout << "glass " << r.glass.method << " (" << glass << "): " << withCommas(r.glass.pixels)
                  << " pixels, prepare " << fmtMs(r.glass.prepareMs) << ", trace " << fmtMs(r.glass.traceMs)
                  << " (" << withCommas(r.glass.paths) << " paths, " << withCommas(r.glass.interpolated)
                  << " pixels interpolated)\n";
        if (r.glass.grid > 0)
            std::cout << "glass grid " << r.glass.grid << " (" << r.glass.gridReason << ")\n";
    }
}

int runRender(const RenderArgs& a) {
    checkImageExtension(a.output);
    const auto t0 = Clock::now();
    const Scene scene = loadScene(a.input);
    const double loadMs = msSince(t0);

    RenderOptions o = renderOptionsFor(scene, a.flags.shadows, a.flags.glass);
    a.flags.apply(o, !a.quiet);
    o.toneMap = toneMapForImage(o.toneMap, a.output); // auto: linear for .exr/.pfm, filmic for .png
    const OptionValue* device = a.flags.find("device");
    if (device && std::get<std::string>(*device) == "cuda" && !cudaStatus().available && !a.quiet)
        std::cerr << "voxfx: --device cuda: " << cudaStatus().reason
                  << "; the light grids are voxelized on the CPU\n";
    o.threads = a.threads;
    o.environment = loadSceneEnvironment(scene, o, a.environment);
    const Camera camera = sceneCamera(scene, a.camera, double(o.width) / double(o.height));

    ProgressLine progress("rendering", !a.quiet);
    o.progress = &progress;
    const RenderResult r = render(scene, camera, o);
    progress.done();
    writeImage(r.image, a.output);
    if (!a.quiet) printSummary(a, scene, camera, o, r, loadMs);
    return 0;
}

const char* kRenderHelp = R"(
A scene without lights is lit by the sky's sun (Preetham's daylight: --sun-elevation, --sun-azimuth,
--turbidity) or by an environment map's own sun (its brightest region, taken out of its ambient
light). The background, what glass reflects and the ambient light all come from that one
environment (--sky, --sky-light; below the horizon a ground of --ground-albedo). --exposure 0
makes the exposure automatic (the frame's log-average luminance to 0.18); the default is 1.
Settings a JSON scene file gives under "render" (the options above, by their camelCase names:
"gridResolution", "shadows", ...) are used unless a flag overrides them. An option of another
shadow kind or glass method than the chosen ones does nothing (a line on stderr says so).
Output by extension: .png (8-bit sRGB), .exr (OpenEXR, linear half-float RGB, HDR) or
.pfm (linear 32-bit float, HDR). The tone map follows the format unless --tone-map (or the scene
file's "toneMap") names one: .exr and .pfm hold the scene-linear radiance (times --exposure, no
curve), as pbrt, Mitsuba and Blender write them; .png gets the filmic curve.)";

const Command kRender{
    "render", "Render a scene (glTF, JSON wrapper, mesh) with shadows, glass and volumes", [](CLI::App& app) {
        auto a = std::make_shared<RenderArgs>();
        app.footer(RenderFlags::footer() + kRenderHelp);
        app.add_option("SCENE", a->input, "Scene: .gltf .glb .json, or a mesh file")->required();
        app.add_option("-o,--output", a->output,
                       "Image: .png (sRGB, filmic), .exr or .pfm (linear HDR radiance)")
            ->required();
        app.add_option("--camera", a->camera, "Index of the scene camera (default 0)");
        app.add_option("--environment", a->environment, "Environment map: .exr .hdr .pfm .png, or 'sky'");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (identical output)")
            ->check(CLI::NonNegativeNumber);
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        a->flags.add(app);
        return std::function<int()>([a] { return runRender(*a); });
    }};

} // namespace
} // namespace voxfx::cli
