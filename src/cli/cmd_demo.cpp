// voxfx demo — renders the procedural demo scenes (tree, bunny under leaves, CGAL meshes under a
// pergola) with one or more shadow kinds, and optionally saves the scenes as glTF.
#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "voxfx/demo.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"

namespace voxfx::cli {
namespace {

struct DemoArgs {
    std::string scenes = "all", shadows = "transmittance", outDir = "docs/images", meshes = "data/meshes",
                writeScenes;
    int64_t width = 640, height = 360, grid = 256, gridDepth = 256;
    int supersample = 2, threads = 0;
    std::string slicing = "uniform";
    bool quiet = false, bilinear = false;
};

// What --shadows all renders: every shadow kind that renders each demo scene. Volumes refuse open
// casters (the tree's leaves), so they are rendered only when named.
const std::vector<std::string> kAllDemoShadows{"none", "map", "transmittance", "absorption", "exact", "deep"};

std::string demoNameList(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

std::vector<std::string> splitList(const std::string& s, const std::vector<std::string>& all) {
    if (s == "all") return all;
    std::vector<std::string> out;
    std::size_t at = 0;
    while (at <= s.size()) {
        const std::size_t comma = s.find(',', at);
        out.push_back(s.substr(at, comma == std::string::npos ? std::string::npos : comma - at));
        if (comma == std::string::npos) break;
        at = comma + 1;
    }
    return out;
}

int runDemo(const DemoArgs& a) {
    const std::vector<std::string> names = splitList(a.scenes, demoSceneNames());
    std::vector<ShadowKind> kinds;
    for (const std::string& k : splitList(a.shadows, kAllDemoShadows)) kinds.push_back(parseShadowKind(k));
    std::filesystem::create_directories(a.outDir);
    if (!a.writeScenes.empty()) std::filesystem::create_directories(a.writeScenes);
    for (const std::string& name : names) {
        const auto t0 = Clock::now();
        const Scene scene = makeDemoScene(name, a.meshes);
        const double buildMs = msSince(t0);
        if (!a.quiet)
            std::cout << name << ": " << withCommas(int64_t(scene.triangleCount())) << " triangles, "
                      << scene.meshes.size() << " meshes, " << scene.lights.size() << " light(s), built in "
                      << fmtMs(buildMs) << "\n";
        if (!a.writeScenes.empty()) {
            const std::string path = (std::filesystem::path(a.writeScenes) / (name + ".glb")).string();
            writeGltf(scene, path);
            if (!a.quiet) std::cout << "  scene -> " << path << "\n";
        }
        for (const ShadowKind kind : kinds) {
            RenderOptions o;
            o.width = a.width;
            o.height = a.height;
            o.supersample = a.supersample;
            o.shadow.kind = kind;
            o.shadow.gridResolution = a.grid;
            o.shadow.gridDepth = a.gridDepth;
            o.shadow.slicing = parseSlicing(a.slicing);
            o.threads = a.threads;
            o.shadow.bilinear = a.bilinear;
            o.glass.kind = defaultGlassKind(scene); // the glass demo renders its glass as glass
            ProgressLine progress("rendering " + name + " (" + toString(kind) + ")", !a.quiet);
            o.progress = &progress;
            const RenderResult r = render(scene, scene.cameras.at(0), o);
            progress.done();
            const std::string out =
                (std::filesystem::path(a.outDir) / (name + "-" + toString(kind) + ".png")).string();
            writePng(r.image, out);
            if (!a.quiet) {
                const RenderTimings& t = r.timings;
                std::cout << "  " << toString(kind) << ": G-buffer " << fmtMs(t.gbufferMs) << ", shadow map "
                          << fmtMs(t.shadowMapMs) << ", voxelization from light " << fmtMs(t.lightVoxelizeMs)
                          << ", shading " << fmtMs(t.shadingMs) << ", total " << fmtMs(t.totalMs) << " -> "
                          << out << "\n";
            }
        }
    }
    return 0;
}

const Command kDemo{
    "demo", "Render the demo scenes (procedural tree, bunny under leaves, CGAL meshes)", [](CLI::App& app) {
        auto a = std::make_shared<DemoArgs>();
        app.add_option("--scenes", a->scenes, "all, or a comma list of: " + demoNameList(demoSceneNames()))
            ->default_val("all");
        app.add_option("--shadows", a->shadows,
                       "all (" + demoNameList(kAllDemoShadows) + "), or a comma list of those and volumes")
            ->default_val("transmittance");
        app.add_option("-o,--out-dir", a->outDir, "Folder for <scene>-<shadows>.png")
            ->default_val("docs/images");
        app.add_option("--meshes", a->meshes, "Folder holding bunny00.off, elephant.off, ...")
            ->default_val("data/meshes");
        app.add_option("--write-scenes", a->writeScenes, "Also save each scene as <name>.glb here");
        app.add_option("--width", a->width, "Image width")
            ->default_val(640)
            ->check(CLI::Range(int64_t(1), int64_t(16384)));
        app.add_option("--height", a->height, "Image height")
            ->default_val(360)
            ->check(CLI::Range(int64_t(1), int64_t(16384)));
        app.add_option("--supersample", a->supersample, "k x k samples per pixel")
            ->default_val(2)
            ->check(CLI::Range(1, 8));
        app.add_option("--grid", a->grid, "Light grid columns")
            ->default_val(256)
            ->check(CLI::Range(int64_t(1), int64_t(16384)));
        app.add_option("--grid-depth", a->gridDepth, "Light grid slices")
            ->default_val(256)
            ->check(CLI::Range(int64_t(1), int64_t(16384)));
        app.add_option("--slicing", a->slicing, "uniform | local")->default_val("uniform");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all")->default_val(0);
        app.add_flag("--bilinear", a->bilinear, "Interpolate light-grid lookups between 4 columns (softer)");
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        return std::function<int()>([a] { return runDemo(*a); });
    }};

} // namespace
} // namespace voxfx::cli
