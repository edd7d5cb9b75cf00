// voxfx — memory for large temporaries in whole huge pages (internal to the library; public only
// because RasterSetup and TileBins hold such vectors).
//
// A fresh 4 KiB page costs a fault on first touch, and on virtual machines a fault costs far more
// than the work that touches the page: the first voxelization in a process (one `voxfx voxelize`)
// took ~1,000 faults in its scratch arrays and ran ~2x slower than later calls (#39). Blocks of
// at least kPageBlockBytes are mapped aligned to 2 MiB with transparent huge pages advised, as
// the bit grid is: one fault per 2 MiB. Smaller blocks come from operator new.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace voxfx::detail {

/// Blocks at least this large are mapped in whole 2 MiB huge pages.
inline constexpr std::size_t kPageBlockBytes = std::size_t(64) << 10;

/// `bytes` (rounded up to 2 MiB) of zeroed memory aligned to 2 MiB, huge pages advised; throws
/// std::bad_alloc when the mapping fails. Give it back with unmapPages(p, bytes).
void* mapPages(std::size_t bytes);
/// Unmaps what mapPages(bytes) returned (the same `bytes`).
void unmapPages(void* p, std::size_t bytes) noexcept;

/// std::allocator with mapPages for blocks of kPageBlockBytes or more.
template <class T> struct PageAllocator {
    using value_type = T;
    PageAllocator() noexcept = default;
    template <class U> PageAllocator(const PageAllocator<U>&) noexcept {}
    T* allocate(std::size_t n) {
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_alloc();
        const std::size_t bytes = n * sizeof(T);
        if (bytes >= kPageBlockBytes) return static_cast<T*>(mapPages(bytes));
        return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
    }
    void deallocate(T* p, std::size_t n) noexcept {
        const std::size_t bytes = n * sizeof(T);
        if (bytes >= kPageBlockBytes)
            unmapPages(p, bytes);
        else
            ::operator delete(p, std::align_val_t(alignof(T)));
    }
    template <class U> bool operator==(const PageAllocator<U>&) const noexcept { return true; }
};

/// A vector for large temporaries (see above).
template <class T> using PageVector = std::vector<T, PageAllocator<T>>;

} // namespace voxfx::detail
