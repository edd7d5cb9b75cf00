// voxfx view SCENE — a live window on a scene (or a demo scene): the camera orbits, pans and zooms
// with the mouse, keys switch the shadow kind, glass method, anti-aliasing and ambient occlusion,
// and a key saves the frame with a scene file that `voxfx render` reproduces it from. The window,
// its render thread and its state live in viewer/; this file reads the command line.
#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "demo/demo_scenes.hpp"
#include "render_flags.hpp"
#include "viewer/viewer.hpp"

namespace voxfx::cli {
namespace {

struct ViewArgs {
    std::string input, demo, meshes = "data/meshes", environment;
    int camera = 0, threads = 0, previewScale = 4;
    bool noOverlay = false;
    RenderFlags flags;
};

bool sceneSays(const Scene& scene, const std::string& name) {
    for (const auto& [key, value] : scene.settings.render)
        if (camelCase(key) == name) return true;
    return false;
}

int runView(const ViewArgs& a) {
    if (a.input.empty() == a.demo.empty()) {
        std::string names;
        for (const std::string& n : demo::demoSceneNames()) names += (names.empty() ? "" : ", ") + n;
        fail("view: give a scene file or --demo NAME (", names, "), one of the two");
    }
    viewer::ViewSetup setup;
    if (!a.demo.empty()) {
        setup.scene = std::make_shared<const Scene>(demo::makeDemoScene(a.demo, a.meshes));
        setup.name = a.demo;
    } else {
        setup.scene = std::make_shared<const Scene>(loadScene(a.input));
        setup.sceneFile = a.input;
        setup.name = std::filesystem::path(a.input).filename().string();
    }
    const Scene& scene = *setup.scene;
    // The options as `voxfx render` makes them; a flag the chosen kind does not use says so once.
    RenderOptions o = renderOptionsFor(scene, a.flags.shadows, a.flags.glass);
    a.flags.apply(o, true);
    setup.shadows = std::string(shadowName(o.shadow));
    setup.glass = std::string(glassName(o.glass));
    // The window's size: the flags', the scene file's, else 960 x 540.
    setup.width = a.flags.find("width") || sceneSays(scene, "width") ? o.width : 960;
    setup.height = a.flags.find("height") || sceneSays(scene, "height") ? o.height : 540;
    const RenderFlags flags = a.flags;
    const std::shared_ptr<const Scene> scenePtr = setup.scene;
    setup.optionsFor = [flags, scenePtr](const std::string& shadows, const std::string& glass) {
        RenderOptions out = renderOptionsFor(*scenePtr, shadows, glass);
        flags.apply(out, false);
        return out;
    };
    setup.environmentRequest = a.environment;
    setup.environment = loadSceneEnvironment(scene, o, a.environment);
    // Orbit and pan about the scene, whatever target the file's camera had (the same image).
    setup.camera =
        aimAtScene(sceneCamera(scene, a.camera, double(setup.width) / double(setup.height)), scene);
    setup.previewScale = a.previewScale;
    setup.threads = a.threads;
    setup.overlay = !a.noOverlay;
    return viewer::runViewer(std::move(setup));
}

std::string viewFooter() {
    std::string out = "\nControls (in the window):\n";
    for (const std::string& line : viewer::controlLines()) out += "  " + line + "\n";
    out += R"(
While the camera moves, frames are previews (1/--preview-scale of the width and height, one sample
per pixel, no ambient occlusion), upscaled; 150 ms after it stops the full frame replaces them. The
info overlay shows the state, the frame's size and the time of each render pass; the window title
ends in "ready" once the full frame is shown. P writes view-NNN.png (the full frame, as render
writes it) and view-NNN.json in the current folder: a scene file that adds the camera and every
render setting to the scene (a demo scene is saved beside it as view-NNN.glb), so that
'voxfx render view-NNN.json -o out.png' gives the same image.
The render options below set the frames as 'voxfx render' takes them (the window is --width x
--height, default 960 x 540). Needs a display (X11 or Wayland; Xvfb on a headless machine).
)";
    return out + RenderFlags::footer();
}

const Command kView{
    "view", "A live window on a scene: orbit, pan, zoom, switch shadows/glass/AA/AO, save the view",
    [](CLI::App& app) {
        auto a = std::make_shared<ViewArgs>();
        app.footer(viewFooter());
        app.add_option("SCENE", a->input, "Scene: .gltf .glb .json, or a mesh file (or --demo)");
        std::string demos;
        for (const std::string& n : demo::demoSceneNames()) demos += (demos.empty() ? "" : ", ") + n;
        app.add_option("--demo", a->demo, "A demo scene instead of a file: " + demos);
        app.add_option("--meshes", a->meshes, "Folder of the demo scenes' meshes (bunny00.off, ...)")
            ->default_val("data/meshes");
        app.add_option("--camera", a->camera, "Index of the scene camera to start from (default 0)");
        app.add_option("--environment", a->environment, "Environment map: .exr .hdr .pfm .png, or 'sky'");
        app.add_option("--preview-scale", a->previewScale,
                       "A moving camera renders 1/N of the width and height (default 4)")
            ->check(CLI::Range(1, 16));
        app.add_flag("--no-overlay", a->noOverlay, "Start with the info overlay off (I toggles it)");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (identical output)")
            ->check(CLI::NonNegativeNumber);
        a->flags.add(app);
        return std::function<int()>([a] { return runView(*a); });
    }};

} // namespace
} // namespace voxfx::cli
