// voxfx — numbers as text, the way the library's messages and summaries write them (and the
// command line prints them).
// Thread-safety: pure functions.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace voxfx {

/// 1234567 -> "1,234,567".
inline std::string countText(int64_t v) {
    // The magnitude as unsigned: -v overflows for INT64_MIN.
    std::string s = std::to_string(v < 0 ? uint64_t(0) - uint64_t(v) : uint64_t(v));
    for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(size_t(i), 1, ',');
    if (v < 0) s.insert(0, 1, '-'); // not "-" + s: GCC 12 warns falsely (-Wrestrict) once inlined
    return s;
}

/// %g with `precision` significant digits.
inline std::string numberText(double v, int precision = 3) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    return buf;
}

/// "12.3 ms" or "1.23 s".
inline std::string msText(double ms) {
    char buf[64];
    if (ms < 1000)
        std::snprintf(buf, sizeof buf, "%.1f ms", ms);
    else
        std::snprintf(buf, sizeof buf, "%.2f s", ms / 1000);
    return buf;
}

} // namespace voxfx
