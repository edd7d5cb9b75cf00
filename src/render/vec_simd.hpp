// voxfx — per-component vector arithmetic of the shading passes in one SIMD instruction (internal).
//
// Each function gives the same IEEE result per component as the scalar expression it names (one
// operation per lane, in the same order, no contraction: -ffp-contract=off), so swapping one for
// the other changes no bit of any image; it only turns three dependent divisions (13+ cycles each)
// into one. Builds without SSE2 / AVX use the scalar expressions.
#pragma once

#include <algorithm>

#include "voxfx/math.hpp"

namespace voxfx {
float filmicToneMap(float x); // voxfx/render.hpp
} // namespace voxfx

#if defined(__SSE2__) && !defined(__CUDACC__)
#include <immintrin.h>
#define VOXFX_VEC_SIMD_SSE 1
#endif
#if defined(__AVX__) && !defined(__CUDACC__)
#define VOXFX_VEC_SIMD_AVX 1
#endif

namespace voxfx::detail {

/// v / s (Vec3f::operator/).
inline Vec3f dividedBy(const Vec3f& v, float s) {
#ifdef VOXFX_VEC_SIMD_SSE
    const __m128 q = _mm_div_ps(_mm_setr_ps(v.x, v.y, v.z, 0.0f), _mm_setr_ps(s, s, s, 1.0f));
    alignas(16) float r[4];
    _mm_store_ps(r, q);
    return {r[0], r[1], r[2]};
#else
    return v / s;
#endif
}

/// v / s (Vec3d::operator/).
inline Vec3d dividedBy(const Vec3d& v, double s) {
#ifdef VOXFX_VEC_SIMD_AVX
    const __m256d q = _mm256_div_pd(_mm256_setr_pd(v.x, v.y, v.z, 0.0), _mm256_setr_pd(s, s, s, 1.0));
    alignas(32) double r[4];
    _mm256_store_pd(r, q);
    return {r[0], r[1], r[2]};
#else
    return v / s;
#endif
}

/// normalize(v) (voxfx/math.hpp): v / length(v), zero where the length is not positive.
template <class T> inline Vec3<T> normalized(const Vec3<T>& v) {
    const T l = length(v);
    return l > T(0) ? dividedBy(v, l) : Vec3<T>{};
}

/// filmicToneMap (voxfx/render.hpp) of each component: the same rational curve, its three
/// divisions in one instruction.
inline Vec3f filmicToneMapped(const Vec3f& c) {
#ifdef VOXFX_VEC_SIMD_SSE
    const __m128 x = _mm_setr_ps(c.x, c.y, c.z, 0.0f);
    const __m128 v = _mm_mul_ps(_mm_set1_ps(0.6f), x);
    const __m128 num = _mm_mul_ps(v, _mm_add_ps(_mm_mul_ps(_mm_set1_ps(2.51f), v), _mm_set1_ps(0.03f)));
    const __m128 den = _mm_add_ps(
        _mm_mul_ps(v, _mm_add_ps(_mm_mul_ps(_mm_set1_ps(2.43f), v), _mm_set1_ps(0.59f))), _mm_set1_ps(0.14f));
    // std::min(1.0f, y) is y < 1 ? y : 1 (1 for NaN), as minps(y, 1); !(x > 0) gives 0.
    const __m128 y = _mm_min_ps(_mm_div_ps(num, den), _mm_set1_ps(1.0f));
    const __m128 out = _mm_and_ps(y, _mm_cmpgt_ps(x, _mm_setzero_ps()));
    alignas(16) float r[4];
    _mm_store_ps(r, out);
    return {r[0], r[1], r[2]};
#else
    return {filmicToneMap(c.x), filmicToneMap(c.y), filmicToneMap(c.z)};
#endif
}

} // namespace voxfx::detail
