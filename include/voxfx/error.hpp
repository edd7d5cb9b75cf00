// voxfx — errors and checks.
//
// Invalid input is a user error: it raises voxfx::Error, whose message says what is wrong and
// where (file, line, triangle, vertex...). Programmer errors are checks: VOXFX_CHECK is always on,
// VOXFX_DCHECK only in debug builds. Kernels neither throw nor allocate; validation happens at the
// boundary (io/, public functions) and the CLI is the only place that catches.
// Thread-safety: fail/Error and the checks hold no state; use from any thread.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace voxfx {

/// The one error type of the library: a user-facing message, one line, no trailing period.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// A refusal for want of memory: a size checked against the memory available (or the budget,
/// VOXFX_MEMORY_LIMIT) before allocating, or a budget a growing structure outgrew. The Python
/// module raises it as voxfx.MemoryLimitError, a MemoryError.
class MemoryLimitError : public Error {
public:
    using Error::Error;
};

namespace detail {
template <class... Args> std::string concat(const Args&... args) {
    std::ostringstream out;
    (out << ... << args);
    return out.str();
}
[[noreturn]] void checkFailed(const char* expr, const char* file, int line);
} // namespace detail

/// Throws voxfx::Error with the arguments streamed into one message.
template <class... Args> [[noreturn]] void fail(const Args&... args) { throw Error(detail::concat(args...)); }

/// Throws voxfx::MemoryLimitError with the arguments streamed into one message.
template <class... Args> [[noreturn]] void failMemory(const Args&... args) {
    throw MemoryLimitError(detail::concat(args...));
}

} // namespace voxfx

#define VOXFX_CHECK(cond)                                                                                    \
    do {                                                                                                     \
        if (!(cond)) ::voxfx::detail::checkFailed(#cond, __FILE__, __LINE__);                                \
    } while (false)

#ifdef NDEBUG
#define VOXFX_DCHECK(cond)                                                                                   \
    do {                                                                                                     \
    } while (false)
#else
#define VOXFX_DCHECK(cond) VOXFX_CHECK(cond)
#endif

// Marks functions that can later be compiled for a CUDA device as well as the host.
#if defined(__CUDACC__)
#define VOXFX_HOSTDEV __host__ __device__
#else
#define VOXFX_HOSTDEV
#endif

// Marks the small projections that the shadow lookups call several times per shaded sample (world
// to grid, grid to world, a light view's locate): GCC left them out of line, a call and a Vec3d
// through memory each, about a fifth of a transmittance lookup. Inlining changes no result
// (-ffp-contract=off: the same operations in the same order).
#if defined(__GNUC__) && !defined(__CUDACC__)
#define VOXFX_ALWAYS_INLINE __attribute__((always_inline))
#else
#define VOXFX_ALWAYS_INLINE
#endif
