// voxfx — fuzz targets (fuzz/fuzz_*.cpp): one per reader and parser, written once with
// VOXFX_FUZZ_TARGET(name) { ... } and compiled two ways:
//  - a libFuzzer program per target (VOXFX_FUZZ_LIBFUZZER, clang, scripts/fuzz.sh): the body is
//    LLVMFuzzerTestOneInput;
//  - voxfx_fuzz_replay (the test build, any compiler): every target registers itself by name, and
//    replay_main.cpp feeds it each file of fuzz/corpus/<name>/ and tests/regress/<name>/.
// The contract a target checks: bad input ends in voxfx::Error (caught here) and nothing else. Any
// other exception escapes (std::bad_alloc, nlohmann::json errors, std::out_of_range...) and is a
// finding, as are sanitizer reports, leaks and the properties a target asserts with require().
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/error.hpp"

namespace voxfx::fuzz {

using TargetFn = void (*)(std::span<const uint8_t>);
struct Target {
    const char* name;
    TargetFn run;
};
inline std::vector<Target>& targets() {
    static std::vector<Target> all;
    return all;
}
inline bool registerTarget(const char* name, TargetFn run) {
    targets().push_back({name, run});
    return true;
}

/// Runs f; a voxfx::Error is the promised outcome for bad input and ends the case quietly.
template <class F> void expectCleanError(F&& f) {
    try {
        f();
    } catch (const voxfx::Error&) {}
}

/// A property every accepted input must have; aborts (a finding) with the message otherwise.
inline void require(bool ok, const char* what) {
    if (!ok) {
        std::fprintf(stderr, "voxfx fuzz: property violated: %s\n", what);
        std::abort();
    }
}

/// A memory budget for what one input may make voxfx allocate (VOXFX_MEMORY_LIMIT, see
/// availableMemoryBytes), unless the environment sets one: a few bytes of .vdb tiles can describe
/// a valid grid of gigabytes, which the machine's memory would allow and libFuzzer's 2 GB limit
/// would report as an out-of-memory finding (tests/regress/vdb/tiles-of-a-4.5GiB-grid.vdb).
inline void applyMemoryBudget() { setenv("VOXFX_MEMORY_LIMIT", "256M", 0); }

inline std::string_view asText(std::span<const uint8_t> data) {
    return {reinterpret_cast<const char*>(data.data()), data.size()};
}

} // namespace voxfx::fuzz

#ifdef VOXFX_FUZZ_LIBFUZZER
#define VOXFX_FUZZ_TARGET(name)                                                                              \
    extern "C" int LLVMFuzzerInitialize(int*, char***) {                                                     \
        ::voxfx::fuzz::applyMemoryBudget();                                                                  \
        return 0;                                                                                            \
    }                                                                                                        \
    static void voxfxFuzz_##name(std::span<const uint8_t> data);                                             \
    extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {                               \
        voxfxFuzz_##name({bytes, size});                                                                     \
        return 0;                                                                                            \
    }                                                                                                        \
    static void voxfxFuzz_##name(std::span<const uint8_t> data)
#else
#define VOXFX_FUZZ_TARGET(name)                                                                              \
    static void voxfxFuzz_##name(std::span<const uint8_t> data);                                             \
    [[maybe_unused]] static const bool voxfxFuzzRegistered_##name =                                          \
        ::voxfx::fuzz::registerTarget(#name, voxfxFuzz_##name);                                              \
    static void voxfxFuzz_##name(std::span<const uint8_t> data)
#endif
