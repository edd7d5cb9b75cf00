// voxfx demo — renders the procedural demo scenes (tree, bunny under leaves, CGAL meshes under a
// pergola, glass; a forest when named) with one or more shadow kinds, and optionally saves the scenes as
// glTF. The scenes are built through the public API (demo/demo_scenes.hpp); the render options are render's.
#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "demo/demo_scenes.hpp"
#include "render_flags.hpp"

namespace voxfx::cli {
namespace {

using namespace voxfx::demo;

// What the demo renders with unless a flag says otherwise, its --help prints these same values: an
// image smaller than render's default, anti-aliased as render's; transmittance shadows.
const RenderDefaults& demoDefaults() {
    static const RenderDefaults d{"transmittance", {{"width", int64_t(640)}, {"height", int64_t(360)}}};
    return d;
}

// Where the images go without -o: a folder of the current directory, never the source tree's
// docs/images (README's images are rendered there with -o docs/images on purpose).
constexpr const char* kDemoOutDir = "voxfx-demo";

struct DemoArgs {
    std::string scenes = "all", outDir = kDemoOutDir, meshes = "data/meshes", writeScenes;
    int threads = 0;
    bool quiet = false;
    RenderFlags flags{demoDefaults()}; ///< --shadows: a comma list or all
};

std::vector<std::string> allShadowNames() {
    std::vector<std::string> out;
    for (const std::string_view n : shadowNames()) out.emplace_back(n);
    return out;
}

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

// Renders `scene` with one shadow kind into OUT/<name>-<kind>.png; a kind that refuses the scene
// (shadow volumes refuse open casters) is reported and skipped.
void renderDemo(const DemoArgs& a, const Scene& scene, const std::string& name, const std::string& kind,
                RenderCache& cache) {
    // --glass as given, else the scene's default (the glass demo renders its glass as glass).
    RenderOptions o = renderOptionsFor(scene, kind, a.flags.glass);
    a.flags.apply(o, true); // a flag the kind does not use says so (absorption has no --voxel-mode)
    o.threads = a.threads;
    ProgressLine progress("rendering " + name + " (" + kind + ")", !a.quiet);
    o.progress = &progress;
    RenderResult r;
    try {
        r = render(scene, scene.cameras.at(0), o, cache);
    } catch (const Error& e) {
        progress.done();
        if (!a.quiet) std::cout << "  " << kind << ": refused: " << e.what() << "\n";
        return;
    }
    progress.done();
    const std::string out = (std::filesystem::path(a.outDir) / (name + "-" + kind + ".png")).string();
    writePng(r.image, out);
    if (!a.quiet) {
        std::cout << "  " << kind << ":";
        std::cout << passTimesText(r.timings);
        std::cout << " total " << fmtMs(r.timings.totalMs) << " -> " << out << "\n";
    }
}

int runDemo(const DemoArgs& a) {
    const std::vector<std::string> names = splitList(a.scenes, demoSceneNames());
    const std::vector<std::string> kinds = splitList(a.flags.shadowsOrDefault(), allShadowNames());
    for (const std::string& k : kinds) shadowOptionsNamed(k); // unknown names fail before any work
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
        // One cache per scene: its kinds share the flattened scene and the glass structures.
        RenderCache cache;
        for (const std::string& kind : kinds) renderDemo(a, scene, name, kind, cache);
    }
    return 0;
}

const Command kDemo{
    "demo", "Render the demo scenes (procedural tree, bunny under leaves, CGAL meshes, glass)",
    [](CLI::App& app) {
        auto a = std::make_shared<DemoArgs>();
        app.footer("\nThe render options apply where the shadow kind has them; the demo renders " +
                   formatOption(*a->flags.defaultOf("width")) + " x " +
                   formatOption(*a->flags.defaultOf("height")) +
                   " (anti-aliased as render),\nunless --width, --height say otherwise. --shadows takes "
                   "all (" +
                   demoNameList(allShadowNames()) +
                   ") or a comma list;\na kind that refuses a scene (volumes: open casters) is reported and "
                   "skipped.\n" +
                   RenderFlags::footer());
        app.add_option("--scenes", a->scenes,
                       "all = " + demoNameList(demoSceneNames()) + "; or a comma list of those and " +
                           demoNameList(largeDemoSceneNames()) +
                           " (128,000 leaf triangles: made only when named)")
            ->capture_default_str();
        app.add_option("-o,--out-dir", a->outDir,
                       "Folder for <scene>-<shadows>.png (made if missing; README's images: -o docs/images)")
            ->capture_default_str();
        app.add_option("--meshes", a->meshes, "Folder holding bunny00.off, elephant.off, ...")
            ->capture_default_str();
        app.add_option("--write-scenes", a->writeScenes, "Also save each scene as <name>.glb here");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all")->capture_default_str();
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        a->flags.add(app);
        return std::function<int()>([a] { return runDemo(*a); });
    }};

} // namespace
} // namespace voxfx::cli
