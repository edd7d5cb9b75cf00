// voxfx — huge-page mappings for large temporaries and bit grids (see page_memory.hpp).
#include "voxfx/page_memory.hpp"

#include <cstdint>

#include <sys/mman.h>

namespace voxfx::detail {

namespace {
constexpr std::size_t kHuge = std::size_t(1) << 21;
std::size_t roundedUp(std::size_t bytes) { return (bytes + kHuge - 1) / kHuge * kHuge; }
} // namespace

void* mapPages(std::size_t bytes) {
    if (bytes == 0 || bytes > std::size_t(-1) - 2 * kHuge) throw std::bad_alloc();
    const std::size_t size = roundedUp(bytes);
    // Map one huge page more and trim to a 2 MiB boundary: only aligned 2 MiB ranges get huge
    // pages (kernels before 6.7 do not align anonymous mappings themselves).
    void* m = mmap(nullptr, size + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) throw std::bad_alloc();
    const auto raw = reinterpret_cast<std::uintptr_t>(m);
    const std::uintptr_t aligned = (raw + kHuge - 1) / kHuge * kHuge;
    if (aligned > raw) munmap(m, aligned - raw);
    if (const std::size_t tail = raw + kHuge - aligned) munmap(reinterpret_cast<void*>(aligned + size), tail);
    void* p = reinterpret_cast<void*>(aligned);
    madvise(p, size, MADV_HUGEPAGE);
    return p;
}

void unmapPages(void* p, std::size_t bytes) noexcept {
    if (p) munmap(p, roundedUp(bytes));
}

} // namespace voxfx::detail
