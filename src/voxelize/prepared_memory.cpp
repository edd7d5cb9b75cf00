// voxfx — memory made ready ahead of a voxelization (see prepared_memory.hpp).
#include "voxfx/prepared_memory.hpp"

#include <new>
#include <thread>
#include <utility>

#include "voxfx/bitgrid.hpp"
#include "voxfx/page_memory.hpp"

namespace voxfx {

struct PreparedMemory::State {
    std::thread worker;
};

PreparedMemory::PreparedMemory() noexcept = default;
PreparedMemory::PreparedMemory(PreparedMemory&&) noexcept = default;
PreparedMemory& PreparedMemory::operator=(PreparedMemory&& o) noexcept {
    if (this != &o) {
        release();
        state_ = std::move(o.state_);
    }
    return *this;
}
PreparedMemory::~PreparedMemory() { release(); }

void PreparedMemory::wait() {
    if (state_ && state_->worker.joinable()) state_->worker.join();
}

void PreparedMemory::release() noexcept {
    if (!state_) return;
    if (state_->worker.joinable()) state_->worker.join();
    detail::releasePageReserve(state_.get()); // the reserve's owner tag is the state's address
    state_.reset();
}

uint64_t voxelizeMemoryBound(int64_t w, int64_t h, int64_t d) {
    // The grid in whole 2 MiB pages, and a dozen temporaries (the rasterizer's vertices, spans and
    // tile bins, the closed-mesh test's tables), each at least a 2 MiB page: 14-18 MiB of them for
    // armadillo and bunny00 at 512^3 and 1024^3 (measured with bench_step_profile ... prepare).
    constexpr uint64_t kPage = uint64_t(1) << 21, kTemporaries = uint64_t(24) << 20;
    const uint64_t grid = BitGrid::requiredBytes(w, h, d);
    if (grid > ~uint64_t(0) - kPage - kTemporaries) return ~uint64_t(0);
    return (grid + kPage - 1) / kPage * kPage + kTemporaries;
}

PreparedMemory prepareVoxelizeMemory(uint64_t bytes) {
    PreparedMemory m;
    if (bytes == 0) return m;
    m.state_ = std::make_unique<PreparedMemory::State>();
    const void* owner = m.state_.get();
    m.state_->worker = std::thread([bytes, owner] {
        try {
            detail::reservePages(static_cast<std::size_t>(bytes), owner);
        } catch (const std::bad_alloc&) {} // nothing prepared: the voxelization maps its own
    });
    return m;
}

} // namespace voxfx
