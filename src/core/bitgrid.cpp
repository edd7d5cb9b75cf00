#include "voxfx/bitgrid.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <optional>
#include <string>
#include <vector>

#include <unistd.h>

#include "voxfx/page_memory.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace {
// Columns handled per parallel chunk when touching whole grids: large enough to amortize a task.
constexpr int64_t kWordsPerChunk = int64_t(1) << 16;

std::string gib(uint64_t bytes) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(2) << double(bytes) / double(uint64_t(1) << 30) << " GiB";
    return s.str();
}

// VOXFX_MEMORY_LIMIT: bytes, or a number with K, M, G or T (powers of 1024, "B" or "iB" may
// follow: 512M, 1.5GiB).
std::optional<uint64_t> memoryBudgetBytes() {
    const char* text = std::getenv("VOXFX_MEMORY_LIMIT");
    if (!text || !*text) return std::nullopt;
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text, &end);
    std::string unit(end ? end : "");
    for (char& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
    double scale = 0;
    for (const auto& [name, s] : {std::pair<const char*, double>{"", 1},
                                  {"B", 1},
                                  {"K", 0x1p10},
                                  {"M", 0x1p20},
                                  {"G", 0x1p30},
                                  {"T", 0x1p40}})
        for (const char* tail : {"", "B", "IB"})
            if (unit == std::string(name) + (*name && *name != 'B' ? tail : "")) scale = s;
    if (end == text || errno != 0 || scale == 0 || !(value >= 0) || value * scale >= 0x1p64)
        fail("VOXFX_MEMORY_LIMIT must be bytes or a size with K, M, G or T (powers of 1024), got '", text,
             "'");
    return uint64_t(value * scale);
}
// A number of bytes from a cgroup file ("max" or unreadable: none).
std::optional<uint64_t> cgroupValue(const char* path) {
    std::ifstream in(path);
    std::string text;
    if (!(in >> text) || text.empty() || !std::isdigit(static_cast<unsigned char>(text[0])))
        return std::nullopt;
    errno = 0;
    const unsigned long long v = std::strtoull(text.c_str(), nullptr, 10);
    if (errno != 0) return std::nullopt;
    return uint64_t(v);
}

// What the container's memory limit leaves: cgroup v2's memory.max less memory.current, or v1's
// memory.limit_in_bytes less memory.usage_in_bytes (v1 writes a huge number for no limit).
std::optional<uint64_t> cgroupAvailableBytes() {
    std::optional<uint64_t> limit = cgroupValue("/sys/fs/cgroup/memory.max");
    std::optional<uint64_t> used = cgroupValue("/sys/fs/cgroup/memory.current");
    if (!limit) {
        limit = cgroupValue("/sys/fs/cgroup/memory/memory.limit_in_bytes");
        used = cgroupValue("/sys/fs/cgroup/memory/memory.usage_in_bytes");
        if (limit && *limit >= (uint64_t(1) << 62)) limit.reset();
    }
    if (!limit) return std::nullopt;
    const uint64_t u = used.value_or(0);
    return *limit > u ? *limit - u : 0;
}
} // namespace

uint64_t availableMemoryBytes() {
    const std::optional<uint64_t> budget = memoryBudgetBytes();
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    uint64_t kib = 0;
    std::string unit;
    uint64_t available = ~uint64_t(0);
    bool found = false;
    while (!found && meminfo >> key >> kib >> unit)
        if (key == "MemAvailable:") {
            available = kib * 1024;
            found = true;
        }
    if (!found) {
        const long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
        if (pages > 0 && pageSize > 0) available = uint64_t(pages) * uint64_t(pageSize);
    }
    // In a container the cgroup's limit caps it (MemAvailable is the host's).
    if (const std::optional<uint64_t> cgroup = cgroupAvailableBytes())
        available = std::min(available, *cgroup);
    return budget ? std::min(available, *budget) : available;
}

void checkMemory(uint64_t bytes, const char* what) {
    const uint64_t available = availableMemoryBytes();
    if (bytes > available)
        failMemory(what, " needs ", gib(bytes), ", but only ", gib(available), " of memory is available",
                   memoryBudgetBytes() ? " (VOXFX_MEMORY_LIMIT)" : "");
}

uint64_t BitGrid::requiredBytes(int64_t w, int64_t h, int64_t d) {
    if (w <= 0 || h <= 0 || d <= 0) return 0;
    // Saturates instead of overflowing, so absurd requests fail the memory check cleanly.
    uint64_t bytes = 8;
    for (const uint64_t f : {uint64_t(w), uint64_t(h), uint64_t((d + 63) / 64)}) {
        if (bytes > ~uint64_t(0) / f) return ~uint64_t(0);
        bytes *= f;
    }
    return bytes;
}

void BitGrid::Free::operator()(uint64_t* p) const {
    if (mappedBytes)
        detail::unmapPages(p, mappedBytes);
    else
        std::free(p);
}

BitGrid::BitGrid(int64_t w, int64_t h, int64_t d) {
    if (w <= 0 || h <= 0 || d <= 0) fail("grid dimensions must be positive, got ", w, " x ", h, " x ", d);
    const uint64_t bytes = requiredBytes(w, h, d);
    std::ostringstream what;
    what << "a " << w << " x " << h << " x " << d << " grid";
    checkMemory(bytes, what.str().c_str());
    // Fresh mappings are zero, so large grids skip the clearing pass, and huge pages cut the page
    // faults of first touch by 512x (they dominate on virtual machines): page_memory.hpp.
    uint64_t* p = nullptr;
    Free deleter{0};
    if (bytes >= (uint64_t(1) << 21)) {
        try {
            p = static_cast<uint64_t*>(detail::mapPages(bytes));
        } catch (const std::bad_alloc&) {
            fail(what.str(), " needs ", gib(bytes), ", and mapping that much memory failed");
        }
        deleter.mappedBytes = bytes;
    } else {
        p = static_cast<uint64_t*>(std::aligned_alloc(64, (bytes + 63) / 64 * 64));
        if (!p) fail(what.str(), " needs ", gib(bytes), ", and the allocation failed");
    }
    w_ = w;
    h_ = h;
    d_ = d;
    wpc_ = (d + 63) / 64;
    words_ = std::unique_ptr<uint64_t[], Free>(p, deleter);
    if (!deleter.mappedBytes) clear();
}

BitGrid::BitGrid(const BitGrid& o) : BitGrid() {
    if (o.empty()) return;
    *this = BitGrid(o.w_, o.h_, o.d_);
    std::memcpy(words_.get(), o.words_.get(), o.byteCount());
}

BitGrid& BitGrid::operator=(const BitGrid& o) {
    if (this != &o) *this = BitGrid(o);
    return *this;
}

void BitGrid::clear() {
    // Parallel first touch: each chunk's pages get faulted in by the thread that zeroes them.
    uint64_t* w = words_.get();
    parallelFor(0, wordCount(), kWordsPerChunk,
                [w](int64_t b, int64_t e) { std::memset(w + b, 0, size_t(e - b) * sizeof(uint64_t)); });
}

int64_t BitGrid::count() const {
    const uint64_t* w = words_.get();
    return parallelReduce(
        0, wordCount(), kWordsPerChunk, int64_t(0),
        [w](int64_t b, int64_t e) {
            int64_t s = 0;
            for (int64_t i = b; i < e; ++i) s += std::popcount(w[i]);
            return s;
        },
        std::plus<>());
}

bool BitGrid::operator==(const BitGrid& o) const {
    if (w_ != o.w_ || h_ != o.h_ || d_ != o.d_) return false;
    return empty() || std::memcmp(words_.get(), o.words_.get(), byteCount()) == 0;
}

} // namespace voxfx
