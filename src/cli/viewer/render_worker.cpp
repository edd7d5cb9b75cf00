// voxfx view — the render thread (render_worker.hpp).
#include "render_worker.hpp"

#include <new>

namespace voxfx::cli::viewer {

RenderWorker::RenderWorker(FrameRenderer& renderer, std::function<void()> frameReady)
    : renderer_(renderer), frameReady_(std::move(frameReady)), thread_([this] { run(); }) {}

RenderWorker::~RenderWorker() {
    {
        const std::lock_guard lock(mutex_);
        stop_ = true;
        cancel_.requested = true;
    }
    wake_.notify_all();
    thread_.join();
}

void RenderWorker::submit(FrameRequest request) {
    {
        const std::lock_guard lock(mutex_);
        if (running_ && (runningOptions_ != request.optionsVersion ||
                         (!runningPreview_ && runningGeneration_ != request.generation)))
            cancel_.requested = true;
        pending_ = std::move(request);
    }
    wake_.notify_all();
}

std::vector<Frame> RenderWorker::takeFinished() {
    const std::lock_guard lock(mutex_);
    std::vector<Frame> out;
    out.swap(finished_);
    return out;
}

bool RenderWorker::busy() const {
    const std::lock_guard lock(mutex_);
    return running_ || pending_.has_value();
}

void RenderWorker::run() {
    for (;;) {
        FrameRequest request;
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [this] { return stop_ || pending_.has_value(); });
            if (stop_) return;
            request = std::move(*pending_);
            pending_.reset();
            running_ = true;
            runningPreview_ = request.preview;
            runningGeneration_ = request.generation;
            runningOptions_ = request.optionsVersion;
            cancel_.requested = false;
        }
        Frame frame;
        frame.generation = request.generation;
        frame.preview = request.preview;
        frame.camera = request.camera;
        frame.options = request.options;
        frame.options.progress = nullptr;
        frame.width = request.options.width;
        frame.height = request.options.height;
        bool cancelled = false;
        try {
            RenderOptions o = request.options;
            o.progress = &cancel_;
            RenderResult r = renderer_.render(request.camera, o);
            frame.rgb = toSrgb8(r.image);
            frame.timings = std::move(r.timings);
            if (!frame.preview) frame.image = std::move(r.image);
        } catch (const Error& e) {
            cancelled = cancel_.requested.load();
            frame.error = e.what();
        } catch (const std::bad_alloc&) { frame.error = "out of memory"; }
        {
            const std::lock_guard lock(mutex_);
            running_ = false;
            if (!cancelled) finished_.push_back(std::move(frame));
        }
        if (!cancelled) frameReady_();
    }
}

} // namespace voxfx::cli::viewer
