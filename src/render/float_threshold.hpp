// voxfx — a double threshold as a float one: for float values compared with a double limit
// (the shadow map's depths against a lookup's biased depth), the float compare that gives the
// same answer, so that a row of taps is compared in float.
#pragma once

#include <cmath>
#include <limits>

namespace voxfx::detail {

/// The least float f with double(f) >= limit: for every float d (NaN included), d >= f exactly
/// where double(d) >= limit. +inf where no finite float reaches limit, -inf for -inf, NaN for NaN.
/// A float rounded to nearest lies within one step of limit; the step up is taken where it
/// rounded down.
inline float leastFloatAtLeast(double limit) {
    constexpr float inf = std::numeric_limits<float>::infinity(), top = std::numeric_limits<float>::max();
    if (std::isnan(limit)) return std::numeric_limits<float>::quiet_NaN();
    if (limit > double(top)) return inf;
    if (limit < -double(top)) return limit == -double(inf) ? -inf : -top;
    const float f = float(limit);
    return double(f) >= limit ? f : std::nextafter(f, inf);
}

} // namespace voxfx::detail
