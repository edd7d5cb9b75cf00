// voxfx — the pieces of NRRD header syntax shared by the bit-grid reader (nrrd.cpp) and the
// scalar volume reader (volume_nrrd.cpp): trimming, numbers and "(a,b,c)" vectors.
#pragma once

#include <charconv>
#include <string_view>

#include "voxfx/math.hpp"

namespace voxfx::detail::nrrd {

inline std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
}

/// Parses a number at the start of `s` (after blanks and an optional '+') and advances past it.
template <class T> bool parseNumber(std::string_view& s, T& v) {
    s = trim(s);
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr == s.data()) return false;
    s.remove_prefix(std::size_t(r.ptr - s.data()));
    return true;
}

/// "(a,b,c)" with optional spaces; advances s past the closing parenthesis.
inline bool parseVector(std::string_view& s, Vec3d& v) {
    s = trim(s);
    if (s.empty() || s.front() != '(') return false;
    s.remove_prefix(1);
    for (int i = 0; i < 3; ++i) {
        double d;
        if (!parseNumber(s, d)) return false;
        v[i] = d;
        s = trim(s);
        const char expected = i < 2 ? ',' : ')';
        if (s.empty() || s.front() != expected) return false;
        s.remove_prefix(1);
    }
    return true;
}

} // namespace voxfx::detail::nrrd
