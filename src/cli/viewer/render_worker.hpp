// voxfx view — the thread that renders the viewer's frames (internal to cli/), so that the window
// stays responsive while a frame takes seconds.
//
// One frame renders at a time; a request waits in one slot, and a newer request replaces the one
// waiting (a dragged camera asks for many previews: the worker renders the latest when it is free).
// The frame in flight is cancelled (through RenderOptions::progress) when a request arrives for
// other options (a key switched the shadow kind: its frame is of no use), and a full frame when a
// request arrives for another view; a preview of another camera is left to finish: it shows the
// motion, and cancelling each one as the mouse moves would show none.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "session.hpp"

namespace voxfx::cli::viewer {

struct FrameRequest {
    uint64_t generation = 0;
    uint64_t optionsVersion = 0;
    bool preview = false;
    Camera camera;
    RenderOptions options;
};

class RenderWorker {
public:
    /// `frameReady` is called on the worker thread after each frame finishes (it must be
    /// thread-safe: SDL_PushEvent is).
    RenderWorker(FrameRenderer& renderer, std::function<void()> frameReady);
    /// Cancels what runs and joins the thread.
    ~RenderWorker();
    RenderWorker(const RenderWorker&) = delete;
    RenderWorker& operator=(const RenderWorker&) = delete;

    void submit(FrameRequest request);
    /// The frames finished since the last call, oldest first (cancelled ones are dropped).
    std::vector<Frame> takeFinished();
    /// Whether a frame is rendering or waiting.
    bool busy() const;

private:
    // Cancels the render in flight when asked (polled between tiles of every pass).
    struct Cancel : Progress {
        std::atomic<bool> requested{false};
        bool update(double) override { return !requested.load(std::memory_order_relaxed); }
    };

    void run();

    FrameRenderer& renderer_;
    std::function<void()> frameReady_;
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::optional<FrameRequest> pending_;
    bool running_ = false, runningPreview_ = false, stop_ = false;
    uint64_t runningGeneration_ = 0, runningOptions_ = 0;
    std::vector<Frame> finished_;
    Cancel cancel_;
    std::thread thread_; // last: started once the members above exist
};

} // namespace voxfx::cli::viewer
