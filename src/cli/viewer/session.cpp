// voxfx view — the viewer's state, its frames' options, its texts and saving (session.hpp).
#include "session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "framebuffer.hpp"

namespace voxfx::cli::viewer {

namespace fs = std::filesystem;

const std::vector<std::string>& controlLines() {
    static const std::vector<std::string> lines = {
        "left drag            orbit about the target",
        "right or middle drag pan (or shift + left drag)",
        "wheel                zoom (dolly towards the target)",
        "S / shift+S          next / previous shadow kind",
        "G / shift+G          next / previous glass method",
        "A                    anti-aliasing on / off",
        "O                    ambient occlusion on / off",
        "R                    reset the camera",
        "P or F12             save view-NNN.png and view-NNN.json",
        "I                    info overlay on / off",
        "H                    this help",
        "Esc or Q             quit",
    };
    return lines;
}

namespace {

template <class Names> std::vector<std::string> strings(const Names& names) {
    std::vector<std::string> out;
    for (const auto& n : names) out.emplace_back(n);
    return out;
}

size_t indexOf(const std::vector<std::string>& names, const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? 0 : size_t(it - names.begin());
}

// `path` as the file in `dir` names it: relative when both lie under one root, else absolute.
std::string pathFrom(const std::string& path, const std::string& dir) {
    const fs::path p = fs::weakly_canonical(fs::absolute(path));
    const fs::path d = fs::weakly_canonical(fs::absolute(dir));
    const fs::path rel = p.lexically_relative(d);
    return rel.empty() ? p.string() : rel.generic_string();
}

} // namespace

ViewState::ViewState(ViewSetup setup)
    : camera(setup.camera), width(setup.width), height(setup.height), setup_(std::move(setup)) {
    shadowNames_ = strings(shadowNames());
    glassNames_ = strings(glassNames());
    const RenderOptions o = setup_.optionsFor(setup_.shadows, setup_.glass);
    shadow_ = indexOf(shadowNames_, std::string(shadowName(o.shadow)));
    glass_ = indexOf(glassNames_, std::string(glassName(o.glass)));
    aa_ = o.antiAliasing != AntiAliasing::Off;
    if (aa_) aaOn_ = o.antiAliasing;
    ao_ = o.ambientOcclusion != Occlusion::Off;
    if (ao_) aoOn_ = o.ambientOcclusion;
}

void ViewState::cycleShadows(int step) {
    const int n = int(shadowNames_.size());
    shadow_ = size_t((int(shadow_) + step % n + n) % n);
    ++optionsVersion;
}

void ViewState::cycleGlass(int step) {
    const int n = int(glassNames_.size());
    glass_ = size_t((int(glass_) + step % n + n) % n);
    ++optionsVersion;
}

RenderOptions ViewState::frameOptions(bool preview) const {
    RenderOptions o = setup_.optionsFor(shadowNames_[shadow_], glassNames_[glass_]);
    o.width = width;
    o.height = height;
    o.antiAliasing = aa_ ? aaOn_ : AntiAliasing::Off;
    o.ambientOcclusion = ao_ ? aoOn_ : Occlusion::Off;
    o.environment = setup_.environment;
    o.threads = setup_.threads;
    return preview ? previewOptions(o, setup_.previewScale) : o;
}

std::string ViewState::stateText() const {
    return "shadows " + shadowNames_[shadow_] + ", glass " + glassNames_[glass_] + ", aa " +
           (aa_ ? toString(aaOn_) : "off") + ", ao " + (ao_ ? toString(aoOn_) : "off");
}

std::vector<std::string> ViewState::save(const Frame& frame) const {
    VOXFX_CHECK(!frame.preview && frame.image.width > 0);
    const fs::path dir = setup_.saveDir;
    std::string stem;
    for (int n = 1;; ++n) {
        char name[32];
        std::snprintf(name, sizeof name, "view-%03d", n);
        stem = name;
        if (!fs::exists(dir / (stem + ".png")) && !fs::exists(dir / (stem + ".json")) &&
            !fs::exists(dir / (stem + ".glb")))
            break;
    }
    std::vector<std::string> written;
    // The names as printed: plain in the current folder.
    auto file = [&](const char* ext) {
        return setup_.saveDir == "." ? stem + ext : (dir / (stem + ext)).string();
    };
    writePng(frame.image, file(".png"));
    written.push_back(file(".png"));
    SceneView view;
    if (setup_.sceneFile.empty()) {
        writeGltf(*setup_.scene, file(".glb"));
        written.push_back(file(".glb"));
        view.scene = stem + ".glb";
    } else {
        view.scene = pathFrom(setup_.sceneFile, setup_.saveDir);
    }
    Camera c = frame.camera;
    c.name = stem;
    view.cameras = {c};
    view.render = renderSettings(frame.options);
    if (!setup_.environmentRequest.empty())
        view.environmentMap = setup_.environmentRequest == "sky"
                                  ? std::string("sky")
                                  : pathFrom(setup_.environmentRequest, setup_.saveDir);
    writeSceneView(view, file(".json"));
    written.push_back(file(".json"));
    return written;
}

std::string timingText(const RenderTimings& t) {
    std::string out;
    for (const PassTime& p : t.passes)
        if (p.ms >= 0.05)
            out += std::string(p.name) + " " +
                   (p.ms < 100 ? numberText(p.ms, 2) : std::to_string(int64_t(std::llround(p.ms)))) + ", ";
    return out + "total " + msText(t.totalMs);
}

std::vector<std::string> infoLines(const ViewState& state, const Frame* shown, const std::string& message,
                                   int maxChars) {
    std::vector<std::string> lines = wrapWords(state.stateText() + "; H: help", maxChars);
    if (shown && shown->width > 0) {
        const std::string frame = std::string(shown->preview ? "preview " : "full ") +
                                  std::to_string(shown->width) + " x " + std::to_string(shown->height) +
                                  ": " + timingText(shown->timings);
        for (const std::string& l : wrapWords(frame, maxChars)) lines.push_back(l);
    }
    if (!message.empty())
        for (const std::string& l : wrapWords(message, maxChars)) lines.push_back(l);
    return lines;
}

} // namespace voxfx::cli::viewer
