// voxfx glass-error SCENE — the voxel glass methods against the exact tracer: per method and grid
// resolution, the mean absolute error and PSNR over the glass pixels and the time per frame, as a
// Markdown table (what BENCHMARKS.md shows).
#include <iostream>
#include <sstream>

#include "cli_common.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"

namespace voxfx::cli {
namespace {

struct GlassErrorArgs {
    std::string input, environment, images;
    std::vector<std::string> methods{"two-surface", "multi"};
    std::vector<int64_t> resolutions{64, 128, 256};
    std::vector<int64_t> crop; ///< x0, y0, x1, y1 (pixels, y down): only glass pixels inside count
    int64_t width = RenderOptions{}.width, height = RenderOptions{}.height;
    int camera = 0, threads = 0;
    std::string shadows = "none";
};

int runGlassError(const GlassErrorArgs& a) {
    const Scene scene = loadScene(a.input);
    RenderOptions o = renderOptionsFor(scene, a.shadows, ExactGlassOptions::kName);
    o.width = a.width;
    o.height = a.height;
    o.threads = a.threads;
    o.environment = loadSceneEnvironment(scene, o, a.environment);
    const Camera camera = sceneCamera(scene, a.camera, double(o.width) / double(o.height));
    auto save = [&](const Image& image, const std::string& name) {
        if (!a.images.empty()) writePng(image, a.images + "/" + name + ".png");
    };
    const RenderResult ref = render(scene, camera, o);
    save(ref.image, "exact");
    std::vector<uint8_t> mask = ref.glassMask;
    if (!a.crop.empty()) {
        if (a.crop.size() != 4) fail("--crop takes x0,y0,x1,y1");
        for (int64_t y = 0; y < o.height; ++y)
            for (int64_t x = 0; x < o.width; ++x)
                if (x < a.crop[0] || y < a.crop[1] || x >= a.crop[2] || y >= a.crop[3])
                    mask[size_t(y * o.width + x)] = 0;
    }
    int64_t glassPixels = 0;
    for (const uint8_t m : mask) glassPixels += m;
    if (glassPixels == 0) fail(a.input, ": no glass pixels (no material with transmission > 0 in view)");
    std::cout << a.input << ": " << withCommas(int64_t(scene.triangleCount())) << " triangles, " << o.width
              << " x " << o.height << ", " << withCommas(glassPixels) << " glass pixels\n\n"
              << "| method | grid | MAE | PSNR (dB) | glass prepare | glass trace | frame |\n"
              << "|---|---|---|---|---|---|---|\n"
              << "| exact (Embree) | - | 0 | inf | " << fmtMs(ref.glass.prepareMs) << " | "
              << fmtMs(ref.glass.traceMs) << " | " << fmtMs(ref.timings.totalMs) << " |\n";
    for (const std::string& method : a.methods) {
        setRenderOption(o, "glass", method, "--methods");
        for (const int64_t res : a.resolutions) {
            if (!setRenderOption(o, "glassGrid", res))
                fail(
                    "--methods: compare methods on a glass grid (multi, two-surface, frosted) with the exact "
                    "tracer, not ",
                    method);
            const RenderResult r = render(scene, camera, o);
            save(r.image, method + "-" + std::to_string(res));
            const ImageError e = imageError(r.image, ref.image, mask);
            std::cout << "| " << method << " | " << res << "³ | " << fmt(e.mae, 4) << " | " << fmt(e.psnr, 2)
                      << " | " << fmtMs(r.glass.prepareMs) << " | " << fmtMs(r.glass.traceMs) << " | "
                      << fmtMs(r.timings.totalMs) << " |\n";
        }
    }
    return 0;
}

const Command kGlassError{
    "glass-error", "Compare the voxel glass methods with the exact tracer (MAE, PSNR, time)",
    [](CLI::App& app) {
        auto a = std::make_shared<GlassErrorArgs>();
        app.add_option("SCENE", a->input, "Scene with glass (materials with transmission > 0)")->required();
        app.add_option("--methods", a->methods, "Voxel methods (default two-surface multi)")->delimiter(',');
        app.add_option("--resolutions", a->resolutions, "Glass grid resolutions (default 64,128,256)")
            ->delimiter(',')
            ->check(CLI::Range(int64_t(2), int64_t(4096)));
        app.add_option("--width", a->width, "Image width (default 1280)")
            ->check(CLI::Range(int64_t(1), int64_t(65536)));
        app.add_option("--height", a->height, "Image height (default 720)")
            ->check(CLI::Range(int64_t(1), int64_t(65536)));
        app.add_option("--environment", a->environment,
                       "Environment map, or 'sky' (default: the scene's, or sky)");
        app.add_option("--shadows", a->shadows, "Shadow kind of the opaque surfaces (default none)");
        app.add_option("--crop", a->crop, "x0,y0,x1,y1: count only the glass pixels in this box (y down)")
            ->delimiter(',');
        app.add_option("--images", a->images, "Folder to write each method's image into (PNG)");
        app.add_option("--camera", a->camera, "Index of the scene camera (default 0)");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (identical output)")
            ->check(CLI::NonNegativeNumber);
        return std::function<int()>([a] { return runGlassError(*a); });
    }};

} // namespace
} // namespace voxfx::cli
