// voxfx — atan2 by a table and a short series (internal): the environment's lookups turn every
// background pixel's direction into equirectangular coordinates, and libm's atan2 and acos were
// 3-4 % of a sky-filled frame.
#pragma once

#include <cmath>

namespace voxfx::detail {

/// atan(k / 64), k = 0..64, correctly rounded (CPython's math.atan).
inline constexpr double kAtanTable[65] = {0.0,
                                          0.015623728620476831,
                                          0.031239833430268277,
                                          0.046840712915969654,
                                          0.06241880999595735,
                                          0.0779666338315423,
                                          0.09347678115858947,
                                          0.10894195698986579,
                                          0.12435499454676144,
                                          0.13970887428916365,
                                          0.15499674192394097,
                                          0.1702119252854744,
                                          0.18534794999569476,
                                          0.2003985538258785,
                                          0.21535769969773805,
                                          0.23021958727684372,
                                          0.24497866312686414,
                                          0.2596296294082575,
                                          0.2741674511196588,
                                          0.2885873618940774,
                                          0.3028848683749714,
                                          0.31705575320914703,
                                          0.3310960767041321,
                                          0.34500217720710513,
                                          0.35877067027057225,
                                          0.3723984466767542,
                                          0.38588266939807375,
                                          0.39922076957525254,
                                          0.4124104415973873,
                                          0.42544963737004227,
                                          0.43833655985795783,
                                          0.4510696559885235,
                                          0.4636476090008061,
                                          0.4760693303227612,
                                          0.48833395105640554,
                                          0.5004408131472942,
                                          0.5123894603107377,
                                          0.5241796287829132,
                                          0.5358112379604637,
                                          0.5472843809874369,
                                          0.5585993153435624,
                                          0.5697564534829784,
                                          0.5807563535676704,
                                          0.5915997103351114,
                                          0.6022873461349642,
                                          0.6128202021652414,
                                          0.6231993299340659,
                                          0.6334258829691446,
                                          0.6435011087932844,
                                          0.6534263411807619,
                                          0.6632029927060933,
                                          0.6728325475937632,
                                          0.6823165548747481,
                                          0.6916566218531999,
                                          0.7008544078844502,
                                          0.7099116184635249,
                                          0.7188299996216245,
                                          0.7276113326265107,
                                          0.7362574289814281,
                                          0.7447701257160751,
                                          0.7531512809621944,
                                          0.7614027698055784,
                                          0.7695264804056583,
                                          0.7775243103733478,
                                          0.7853981633974483};

/// atan2(y, x) for finite, not both zero y and x, within a few ulps of std::atan2: the ratio
/// t = min / max of |y| and |x| in [0, 1], atan(t) = atan(c) + atan((t - c) / (1 + t c)) with c the
/// nearest k / 64 (table) and the second by its series to r^7 (|r| <= 1/128: the next term is below
/// 2^-70 of it), then the octant. Zeros, infinities and NaN go to std::atan2 (its signed-zero rules).
inline double tabledAtan2(double y, double x) {
    const double ax = std::fabs(x), ay = std::fabs(y);
    if (!(ax > 0 && ay > 0 && ax < INFINITY && ay < INFINITY)) return std::atan2(y, x);
    const bool steep = ay > ax;
    const double t = steep ? ax / ay : ay / ax;
    const int k = int(t * 64 + 0.5);
    const double c = double(k) * (1.0 / 64);
    const double r = (t - c) / (1 + t * c), r2 = r * r;
    double a = kAtanTable[k] + (r + r * r2 * (-1.0 / 3 + r2 * (1.0 / 5 - r2 * (1.0 / 7))));
    if (steep) a = M_PI / 2 - a;
    if (x < 0) a = M_PI - a;
    return y < 0 ? -a : a;
}

} // namespace voxfx::detail
