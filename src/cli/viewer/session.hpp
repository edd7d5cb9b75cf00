// voxfx view — what the viewer shows and how it changes, apart from the window (internal to cli/):
// the scene and its camera, the shadow kind, glass method, anti-aliasing and ambient occlusion the
// keys switch, the options of full and preview frames, the texts of the overlay and the title, and
// saving a frame with the view that reproduces it.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "voxfx/voxfx.hpp"

namespace voxfx::cli::viewer {

/// The controls, one line each ("keys  what"), as --help and the help overlay show them.
const std::vector<std::string>& controlLines();

/// What `voxfx view` was asked to show (cmd_view.cpp fills it from the command line).
struct ViewSetup {
    std::shared_ptr<const Scene> scene;
    std::string name;      ///< the scene's name in the title ("tree", "scene.glb")
    std::string sceneFile; ///< the file it was loaded from; empty for a demo scene (saved as .glb)
    Camera camera;         ///< the camera it starts from (R goes back to it)
    /// The options of a frame with the shadow kind and glass method named: the scene file's
    /// settings, then the command's flags (as `voxfx render` makes them).
    std::function<RenderOptions(const std::string& shadows, const std::string& glass)> optionsFor;
    std::string shadows, glass; ///< the kind and method it starts with
    int64_t width = 960, height = 540;
    std::string environmentRequest; ///< --environment as given (the saved view names it), or empty
    std::shared_ptr<const Environment> environment;
    int previewScale = 4; ///< a moving camera renders 1/scale of the width and height
    int threads = 0;
    bool overlay = true;       ///< the info overlay at start (I toggles it)
    std::string saveDir = "."; ///< where P writes view-NNN.*
};

/// A frame rendered by the worker: the request it answers and its pixels.
struct Frame {
    uint64_t generation = 0; ///< the view it shows (ViewState::generation when requested)
    bool preview = false;
    Camera camera;
    RenderOptions options;
    Image image;              ///< linear (full frames only: what is saved)
    std::vector<uint8_t> rgb; ///< 8-bit sRGB, as writePng stores it
    int64_t width = 0, height = 0;
    RenderTimings timings;
    std::string error; ///< the render failed (the options refuse the scene): why
};

/// The state the keys and the mouse change.
class ViewState {
public:
    explicit ViewState(ViewSetup setup);
    const ViewSetup& setup() const { return setup_; }

    Camera camera;
    int64_t width, height;
    /// Increased by every change of what a frame shows (camera, options, size).
    uint64_t generation = 1;
    /// Increased by every change but the camera's (a key, the window's size): a frame of other
    /// options is of no use once they changed, a frame of another camera still shows the motion.
    uint64_t optionsVersion = 1;

    void cycleShadows(int step);
    void cycleGlass(int step);
    void toggleAntiAliasing() {
        aa_ = !aa_;
        ++optionsVersion;
    }
    void toggleOcclusion() {
        ao_ = !ao_;
        ++optionsVersion;
    }
    void resize(int64_t w, int64_t h) {
        width = w;
        height = h;
        ++optionsVersion;
    }
    void resetCamera() { camera = setup_.camera; }

    /// The options of a frame of the current state: full, or the preview of a moving camera.
    RenderOptions frameOptions(bool preview) const;
    /// "shadows map, glass none, aa full, ao field".
    std::string stateText() const;

    /// Writes `frame` (full) as view-NNN.png in the save folder, the smallest NNN from 001 whose
    /// files do not exist yet, and view-NNN.json, the scene file `voxfx render` reproduces it from
    /// (the scene it adds to, the frame's camera and every render setting; a demo scene is written
    /// beside it as view-NNN.glb). Each file is written atomically, the .json last. Returns the
    /// names written.
    std::vector<std::string> save(const Frame& frame) const;

private:
    ViewSetup setup_;
    std::vector<std::string> shadowNames_, glassNames_;
    size_t shadow_ = 0, glass_ = 0;
    bool aa_ = true, ao_ = true;
    AntiAliasing aaOn_ = AntiAliasing::Full; ///< what "aa on" means (the flags' or scene's choice)
    Occlusion aoOn_ = Occlusion::Screen;
};

/// The overlay's lines: the state, the frame's size and its passes' times, and `message`.
std::vector<std::string> infoLines(const ViewState& state, const Frame* shown, const std::string& message,
                                   int maxChars);
/// "12 ms" per pass that took any time, then the total.
std::string timingText(const RenderTimings& t);

} // namespace voxfx::cli::viewer
