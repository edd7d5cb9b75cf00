#include "voxfx/error.hpp"

#include <cstdio>
#include <cstdlib>

namespace voxfx::detail {

void checkFailed(const char* expr, const char* file, int line) {
    // A failed check is a bug in voxfx, not bad input: report it and stop.
    std::fprintf(stderr, "voxfx: internal check failed: %s at %s:%d\n", expr, file, line);
    std::abort();
}

} // namespace voxfx::detail
