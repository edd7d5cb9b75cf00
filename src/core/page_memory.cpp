// voxfx — huge-page mappings for large temporaries and bit grids (see page_memory.hpp).
#include "voxfx/page_memory.hpp"

#include <cstdint>
#include <mutex>
#include <vector>

#include <sys/mman.h>

namespace voxfx::detail {

namespace {
constexpr std::size_t kHuge = std::size_t(1) << 21;
std::size_t roundedUp(std::size_t bytes) { return (bytes + kHuge - 1) / kHuge * kHuge; }

// Pages reservePages has touched and no mapPages has taken: each block is the unclaimed tail of
// one reservation (2 MiB aligned, whole huge pages, still zero: nothing but zeros was written).
struct ReservedBlock {
    char* begin;
    std::size_t size;
    const void* owner;
};
struct PageReserve {
    std::mutex mutex;
    std::vector<ReservedBlock> blocks;
};
PageReserve& pageReserve() {
    static PageReserve r;
    return r;
}

// The front `size` bytes of a reserved block that holds them, or nullptr.
void* takeReserved(std::size_t size) {
    PageReserve& r = pageReserve();
    std::lock_guard<std::mutex> lock(r.mutex);
    for (auto it = r.blocks.begin(); it != r.blocks.end(); ++it) {
        if (it->size < size) continue;
        char* p = it->begin;
        it->begin += size;
        it->size -= size;
        if (it->size == 0) r.blocks.erase(it);
        return p;
    }
    return nullptr;
}

void* mapFresh(std::size_t size) {
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
} // namespace

void* mapPages(std::size_t bytes) {
    if (bytes == 0 || bytes > std::size_t(-1) - 2 * kHuge) throw std::bad_alloc();
    const std::size_t size = roundedUp(bytes);
    if (void* p = takeReserved(size)) return p;
    return mapFresh(size);
}

void unmapPages(void* p, std::size_t bytes) noexcept {
    if (p) munmap(p, roundedUp(bytes));
}

void reservePages(std::size_t bytes, const void* owner) {
    if (bytes == 0) return;
    if (bytes > std::size_t(-1) - 2 * kHuge) throw std::bad_alloc();
    const std::size_t size = roundedUp(bytes);
    char* p = static_cast<char*>(mapFresh(size));
    // One write per 4 KiB page: with transparent huge pages the first of each 2 MiB faults in the
    // whole huge page and the rest hit memory; without them every page needs its own fault.
    for (std::size_t i = 0; i < size; i += 4096) static_cast<volatile char*>(p)[i] = 0;
    PageReserve& r = pageReserve();
    std::lock_guard<std::mutex> lock(r.mutex);
    r.blocks.push_back({p, size, owner});
}

void releasePageReserve(const void* owner) noexcept {
    PageReserve& r = pageReserve();
    std::lock_guard<std::mutex> lock(r.mutex);
    std::erase_if(r.blocks, [&](const ReservedBlock& b) {
        if (b.owner != owner) return false;
        munmap(b.begin, b.size);
        return true;
    });
}

std::size_t reservedPageBytes() noexcept {
    PageReserve& r = pageReserve();
    std::lock_guard<std::mutex> lock(r.mutex);
    std::size_t total = 0;
    for (const ReservedBlock& b : r.blocks) total += b.size;
    return total;
}

} // namespace voxfx::detail
