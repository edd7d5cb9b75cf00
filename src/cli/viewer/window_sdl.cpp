// voxfx view — the SDL2 window (viewer.hpp): a software framebuffer copied into the window's
// surface, mouse and keys turned into camera moves and option changes, and the refinement rule:
// every change asks for a preview at once and, once nothing has changed for kRefineAfter and the
// preview is shown, for the full frame.
//
// SDL2 is opened with dlopen() when the window opens, not linked: linked, it put SDL and the ~45
// libraries it needs (X11, Wayland, PulseAudio, D-Bus, ...) into every voxfx command's global
// scope, and each later dlopen() of a module (OpenVDB's 69K relocations, Embree) looked its
// symbols up through all of them: the .vdb module took ~1.6x as long to load.
#define SDL_MAIN_HANDLED // voxfx's own main() stays main (SDL would rename it to SDL_main)
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <optional>

#include <SDL.h>
#include <dlfcn.h>

#include "framebuffer.hpp"
#include "render_worker.hpp"
#include "viewer.hpp"

namespace voxfx::cli::viewer {

namespace {

// The SDL functions the window calls, looked up in libSDL2 once (see the file's comment). One per
// line, unformatted: clang-format 14 reflows a run of macro calls differently on each pass.
// clang-format off
#define VOXFX_SDL_FUNCTIONS(X)                                                                               \
    X(SDL_ConvertPixels)                                                                                     \
    X(SDL_CreateWindow)                                                                                      \
    X(SDL_DestroyWindow)                                                                                     \
    X(SDL_GetError)                                                                                          \
    X(SDL_GetModState)                                                                                       \
    X(SDL_GetMouseState)                                                                                     \
    X(SDL_GetWindowSurface)                                                                                  \
    X(SDL_Init)                                                                                              \
    X(SDL_LockSurface)                                                                                       \
    X(SDL_PollEvent)                                                                                         \
    X(SDL_PushEvent)                                                                                         \
    X(SDL_Quit)                                                                                              \
    X(SDL_RegisterEvents)                                                                                    \
    X(SDL_SetMainReady)                                                                                      \
    X(SDL_SetWindowTitle)                                                                                    \
    X(SDL_UnlockSurface)                                                                                     \
    X(SDL_UpdateWindowSurface)                                                                               \
    X(SDL_WaitEventTimeout)
// clang-format on
struct SdlApi {
#define VOXFX_SDL_MEMBER(name) decltype(&::name) name = nullptr;
    VOXFX_SDL_FUNCTIONS(VOXFX_SDL_MEMBER)
#undef VOXFX_SDL_MEMBER
};

constexpr const char* kSdlLibrary = "libSDL2-2.0.so.0";

SdlApi loadSdl() {
    void* handle = dlopen(kSdlLibrary, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        const char* why = dlerror();
        fail("voxfx view needs SDL2's library ", kSdlLibrary,
             " (Debian: libsdl2-2.0-0): ", why ? why : "dlopen failed");
    }
    SdlApi api;
#define VOXFX_SDL_LOOKUP(name)                                                                               \
    api.name = reinterpret_cast<decltype(api.name)>(dlsym(handle, #name));                                   \
    if (!api.name) fail("voxfx view: ", kSdlLibrary, " has no ", #name, " (SDL 2.0.10 or newer is needed)");
    VOXFX_SDL_FUNCTIONS(VOXFX_SDL_LOOKUP)
#undef VOXFX_SDL_LOOKUP
    return api; // the library stays loaded for the process
}

/// SDL, loaded on first use; throws voxfx::Error when it is missing.
const SdlApi& sdl() {
    static const SdlApi api = loadSdl();
    return api;
}

using Clock = std::chrono::steady_clock;
/// How long the view must stay still before the full frame is rendered.
constexpr auto kRefineAfter = std::chrono::milliseconds(150);

struct SdlSession {
    SdlSession() = default;
    SdlSession(const SdlSession&) = delete;
    SdlSession& operator=(const SdlSession&) = delete;
    ~SdlSession() { sdl().SDL_Quit(); }
};

struct WindowHandle {
    SDL_Window* window = nullptr;
    WindowHandle(const WindowHandle&) = delete;
    WindowHandle& operator=(const WindowHandle&) = delete;
    explicit WindowHandle(SDL_Window* w) : window(w) {}
    ~WindowHandle() {
        if (window) sdl().SDL_DestroyWindow(window);
    }
};

bool hasDisplay() {
    for (const char* name : {"DISPLAY", "WAYLAND_DISPLAY"})
        if (const char* v = std::getenv(name); v && *v) return true;
    return false;
}

enum class Drag { None, Orbit, Pan };

class Viewer {
public:
    Viewer(SDL_Window* window, ViewState& state)
        : window_(window), state_(state), renderer_(state.setup().scene),
          frameEvent_(sdl().SDL_RegisterEvents(1)), worker_(renderer_, [event = frameEvent_] {
              SDL_Event e{};
              e.type = event;
              sdl().SDL_PushEvent(&e);
          }) {
        overlay_ = state.setup().overlay;
    }

    int run() {
        requestPreview();
        while (!quit_) {
            int timeout = 250;
            if (!fullRequested_) {
                const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                    lastChange_ + kRefineAfter - Clock::now());
                timeout = int(std::clamp<int64_t>(left.count(), 1, 250));
            }
            changed_ = false;
            SDL_Event e;
            if (sdl().SDL_WaitEventTimeout(&e, timeout)) {
                handle(e);
                while (sdl().SDL_PollEvent(&e)) handle(e);
            }
            if (changed_) requestPreview();
            takeFrames();
            if (!fullRequested_ && Clock::now() - lastChange_ >= kRefineAfter && !worker_.busy()) {
                worker_.submit({state_.generation, state_.optionsVersion, false, state_.camera,
                                state_.frameOptions(false)});
                fullRequested_ = true;
                dirty_ = true;
            }
            if (saveRequested_ && shown_ && !shown_->preview && shown_->generation == state_.generation)
                save();
            if (dirty_) draw();
        }
        return 0;
    }

private:
    // A change of what the frame shows: a new generation, its preview at once.
    void requestPreview() {
        ++state_.generation;
        lastChange_ = Clock::now();
        fullRequested_ = false;
        error_.clear();
        if (!saveRequested_) message_.clear();
        worker_.submit(
            {state_.generation, state_.optionsVersion, true, state_.camera, state_.frameOptions(true)});
        dirty_ = true;
    }

    void takeFrames() {
        for (Frame& f : worker_.takeFinished()) {
            dirty_ = true;
            if (!f.error.empty()) {
                if (f.generation != state_.generation) continue;
                error_ = f.error;
                if (saveRequested_ && !f.preview) {
                    message_ = "not saved: the frame failed";
                    saveRequested_ = false;
                }
                continue;
            }
            if (!shown_ || f.generation > shown_->generation ||
                (f.generation == shown_->generation && !f.preview))
                shown_ = std::move(f);
        }
    }

    void save() {
        saveRequested_ = false;
        try {
            const std::vector<std::string> files = state_.save(*shown_);
            std::string list;
            for (const std::string& f : files) list += (list.empty() ? "" : " ") + f;
            message_ = "saved " + list;
            std::cout << message_ << std::endl;
        } catch (const Error& e) {
            message_ = std::string("not saved: ") + e.what();
            std::cerr << "voxfx: " << message_ << std::endl;
        }
        dirty_ = true;
    }

    // A camera move that may throw (a camera looking along its up axis): the message says so.
    template <class F> void moveCamera(F&& f) {
        try {
            state_.camera = f(state_.camera);
            changed_ = true;
        } catch (const Error& e) {
            message_ = e.what();
            dirty_ = true;
        }
    }

    void handle(const SDL_Event& e) {
        if (e.type == frameEvent_) return; // takeFrames() collects them
        switch (e.type) {
        case SDL_QUIT:
            quit_ = true;
            break;
        case SDL_WINDOWEVENT:
            if (e.window.event == SDL_WINDOWEVENT_SIZE_CHANGED && e.window.data1 > 0 && e.window.data2 > 0 &&
                (e.window.data1 != state_.width || e.window.data2 != state_.height)) {
                state_.resize(e.window.data1, e.window.data2);
                changed_ = true;
            }
            dirty_ = true;
            break;
        case SDL_MOUSEBUTTONDOWN:
            if (e.button.button == SDL_BUTTON_LEFT && !(sdl().SDL_GetModState() & KMOD_SHIFT))
                drag_ = Drag::Orbit;
            else if (e.button.button == SDL_BUTTON_LEFT || e.button.button == SDL_BUTTON_RIGHT ||
                     e.button.button == SDL_BUTTON_MIDDLE)
                drag_ = Drag::Pan;
            break;
        case SDL_MOUSEBUTTONUP:
            if (!(sdl().SDL_GetMouseState(nullptr, nullptr) &
                  (SDL_BUTTON(SDL_BUTTON_LEFT) | SDL_BUTTON(SDL_BUTTON_RIGHT) |
                   SDL_BUTTON(SDL_BUTTON_MIDDLE))))
                drag_ = Drag::None;
            break;
        case SDL_MOUSEMOTION: {
            if (drag_ == Drag::None || (e.motion.xrel == 0 && e.motion.yrel == 0)) break;
            const double h = double(state_.height), dx = e.motion.xrel, dy = e.motion.yrel;
            // Orbit: a drag across the window's height turns the view by half a turn; the scene
            // follows the mouse (drag right: it turns right; drag down: the eye rises over it).
            if (drag_ == Drag::Orbit)
                moveCamera([&](const Camera& c) { return orbitCamera(c, -dx * M_PI / h, dy * M_PI / h); });
            else // the point under the mouse at the target's depth follows it
                moveCamera([&](const Camera& c) { return panCamera(c, -dx / h, dy / h); });
            break;
        }
        case SDL_MOUSEWHEEL: {
            const int y = e.wheel.direction == SDL_MOUSEWHEEL_FLIPPED ? -e.wheel.y : e.wheel.y;
            if (y != 0) moveCamera([&](const Camera& c) { return dollyCamera(c, std::pow(0.85, y)); });
            break;
        }
        case SDL_KEYDOWN:
            key(e.key.keysym.sym, (e.key.keysym.mod & KMOD_SHIFT) != 0);
            break;
        default:
            break;
        }
    }

    void key(SDL_Keycode k, bool shift) {
        switch (k) {
        case SDLK_ESCAPE:
        case SDLK_q:
            quit_ = true;
            break;
        case SDLK_s:
            state_.cycleShadows(shift ? -1 : 1);
            changed_ = true;
            break;
        case SDLK_g:
            state_.cycleGlass(shift ? -1 : 1);
            changed_ = true;
            break;
        case SDLK_a:
            state_.toggleAntiAliasing();
            changed_ = true;
            break;
        case SDLK_o:
            state_.toggleOcclusion();
            changed_ = true;
            break;
        case SDLK_r:
            state_.resetCamera();
            changed_ = true;
            break;
        case SDLK_p:
        case SDLK_F12:
            saveRequested_ = true;
            message_ = "saving when the full frame is ready...";
            lastChange_ = Clock::now() - kRefineAfter; // no need to wait for the view to settle
            dirty_ = true;
            break;
        case SDLK_h:
            help_ = !help_;
            dirty_ = true;
            break;
        case SDLK_i:
            overlay_ = !overlay_;
            dirty_ = true;
            break;
        default:
            break;
        }
    }

    std::string status() const {
        if (!error_.empty()) return "error";
        if (shown_ && shown_->generation == state_.generation) return shown_->preview ? "preview" : "ready";
        return "rendering";
    }

    void draw() {
        dirty_ = false;
        std::string title = "voxfx view: " + state_.setup().name + " | " + state_.stateText() + " | " +
                            std::to_string(state_.width) + " x " + std::to_string(state_.height);
        if (shown_ && shown_->generation == state_.generation)
            title += " | " + msText(shown_->timings.totalMs);
        sdl().SDL_SetWindowTitle(window_, (title + " | " + status()).c_str());

        SDL_Surface* surface = sdl().SDL_GetWindowSurface(window_);
        if (!surface) return; // minimized, or being resized: the next event redraws
        if (fb_.width != surface->w || fb_.height != surface->h) fb_ = Framebuffer(surface->w, surface->h);
        if (shown_)
            blitRgb(fb_, shown_->rgb.data(), int(shown_->width), int(shown_->height));
        else
            std::fill(fb_.pixels.begin(), fb_.pixels.end(), 0xff202020u);
        const int scale = fb_.width >= 1200 ? 2 : 1;
        const int maxChars = std::max(16, (fb_.width - 6 * scale) / (kGlyphAdvance * scale));
        std::string note = shown_ ? message_ : "rendering the first frame...";
        if (!error_.empty()) note = "cannot render this: " + error_;
        if (overlay_)
            drawPanel(fb_, 0, 0, infoLines(state_, shown_ ? &*shown_ : nullptr, note, maxChars), scale);
        if (help_) {
            const std::vector<std::string>& lines = controlLines();
            int w = 0;
            for (const std::string& l : lines) w = std::max(w, textWidth(l, scale));
            const int h = int(lines.size()) * kLineHeight * scale;
            drawPanel(fb_, std::max(0, (fb_.width - w) / 2), std::max(0, (fb_.height - h) / 2), lines, scale);
        }
        if (SDL_MUSTLOCK(surface)) sdl().SDL_LockSurface(surface);
        sdl().SDL_ConvertPixels(fb_.width, fb_.height, SDL_PIXELFORMAT_ARGB8888, fb_.pixels.data(),
                                fb_.width * 4, surface->format->format, surface->pixels, surface->pitch);
        if (SDL_MUSTLOCK(surface)) sdl().SDL_UnlockSurface(surface);
        sdl().SDL_UpdateWindowSurface(window_);
    }

    SDL_Window* window_;
    ViewState& state_;
    FrameRenderer renderer_;
    Uint32 frameEvent_;
    RenderWorker worker_;
    Framebuffer fb_;
    std::optional<Frame> shown_;
    std::string message_, error_;
    Clock::time_point lastChange_ = Clock::now();
    Drag drag_ = Drag::None;
    bool quit_ = false, dirty_ = true, changed_ = false, fullRequested_ = false, saveRequested_ = false;
    bool overlay_ = true, help_ = false;
};

} // namespace

int runViewer(ViewSetup setup) {
    if (!hasDisplay())
        fail("no display: $DISPLAY is not set, and voxfx view opens a window (on a machine without a "
             "screen, run it under Xvfb: xvfb-run -s '-screen 0 1280x1024x24' voxfx view ...)");
    sdl().SDL_SetMainReady();
    if (sdl().SDL_Init(SDL_INIT_VIDEO) != 0) fail("voxfx view cannot open a window: ", sdl().SDL_GetError());
    SdlSession session;
    ViewState state(std::move(setup));
    WindowHandle window(sdl().SDL_CreateWindow(("voxfx view: " + state.setup().name).c_str(),
                                               SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                                               int(state.width), int(state.height), SDL_WINDOW_RESIZABLE));
    if (!window.window) fail("voxfx view cannot open a window: ", sdl().SDL_GetError());
    std::cout << "voxfx view: " << state.setup().name << ", " << state.width << " x " << state.height
              << " (H in the window lists the keys)" << std::endl;
    // The worker joins (cancelling what it renders) before the window and SDL go.
    Viewer viewer(window.window, state);
    return viewer.run();
}

} // namespace voxfx::cli::viewer
