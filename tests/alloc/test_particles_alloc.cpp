// The particle step loop allocates nothing per particle (issue #3: "a million particles step
// without allocation in the loop"). A program of its own: it replaces the global operator new
// and delete to count allocations, which must not leak into the main test program. Every form
// forwards to malloc / aligned_alloc and free, so AddressSanitizer (which intercepts those)
// still checks every heap access.
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/particles.hpp"
#include "voxfx/voxelize.hpp"

namespace {
std::atomic<bool> gCountAllocations{false};
std::atomic<int64_t> gAllocations{0};

void* countedMalloc(std::size_t n) noexcept {
    if (gCountAllocations.load(std::memory_order_relaxed))
        gAllocations.fetch_add(1, std::memory_order_relaxed);
    return std::malloc(n ? n : 1);
}
void* countedAlignedMalloc(std::size_t n, std::align_val_t al) noexcept {
    if (gCountAllocations.load(std::memory_order_relaxed))
        gAllocations.fetch_add(1, std::memory_order_relaxed);
    const std::size_t a = std::max(static_cast<std::size_t>(al), sizeof(void*));
    return std::aligned_alloc(a, (std::max<std::size_t>(n, 1) + a - 1) / a * a); // size: a multiple of a
}
} // namespace

// Every form is replaced, so that each new pairs with a delete that frees the same way.
void* operator new(std::size_t n) {
    if (void* p = countedMalloc(n)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
    if (void* p = countedMalloc(n)) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t n, std::align_val_t al) {
    if (void* p = countedAlignedMalloc(n, al)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t al) {
    if (void* p = countedAlignedMalloc(n, al)) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return countedMalloc(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return countedMalloc(n); }
void* operator new(std::size_t n, std::align_val_t al, const std::nothrow_t&) noexcept {
    return countedAlignedMalloc(n, al);
}
void* operator new[](std::size_t n, std::align_val_t al, const std::nothrow_t&) noexcept {
    return countedAlignedMalloc(n, al);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

namespace voxfx {
namespace {

TEST(ParticlesAllocTest, CountingAllocatorSeesAllocations) {
    // The replacement is in effect (else the test below would pass vacuously).
    gAllocations = 0;
    gCountAllocations = true;
    auto* v = new std::vector<int>(1000);
    gCountAllocations = false;
    delete v;
    EXPECT_GE(gAllocations.load(), 2);
}

TEST(ParticlesAllocTest, AMillionParticlesStepWithoutPerParticleAllocation) {
    // A ball over a floor slab in a 64 x 64 x 48 grid of unit cells.
    Mesh m = test::makeUvSphere({32, 32, 20}, 12, 24, 48);
    test::appendBox(m, {2, 2, 1}, {62, 62, 5});
    const ParticleCollider collider(
        voxelize(m.view(), Frame::orthographic({{0, 0, 0}, {64, 64, 48}}, Axis::Z, 64, 64, 48)));
    // Emitted just above the floor (its top at z = 5), with strong gravity: the counted steps bounce.
    Particles ps = emitParticles(collider, 1000000, {{2, 2, 5.05}, {62, 62, 6}}, 10);
    ASSERT_EQ(ps.size(), 1000000u);
    ParticleOptions o;
    o.gravity = {0, 0, -3000};
    o.dt = 1.0 / 60;
    stepParticles(ps, collider, o); // warm up the thread pool
    gAllocations = 0;
    gCountAllocations = true;
    int64_t bounces = 0;
    for (int step = 0; step < 3; ++step) bounces += stepParticles(ps, collider, o).bounces;
    gCountAllocations = false;
    EXPECT_GT(bounces, 0); // the steps did collide
    // The parallel loop's bookkeeping allocates a handful of objects per call, independent of
    // the 10^6 particles.
    EXPECT_LT(gAllocations.load(), 3 * 16);
}

} // namespace
} // namespace voxfx
