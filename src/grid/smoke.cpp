// voxfx — procedural smoke: a deterministic density volume for demos (makeSmoke).
//
// Value noise on an integer lattice (each lattice value a hash of its coordinates and the seed,
// so nothing depends on call order or threads), summed over octaves as fractional Brownian
// motion, domain-warped once for wisps, and shaped by a plume: a soft-edged cone that rises along
// +z from the bottom centre of the box, fading in at the bottom and out towards the top.
#include "voxfx/smoke.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "voxfx/bitgrid.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace {

uint32_t mix(uint32_t h) {
    // Murmur3's finalizer: every input bit flips about half the output bits.
    h ^= h >> 16;
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    h ^= h >> 16;
    return h;
}

double latticeValue(int64_t x, int64_t y, int64_t z, uint32_t seed) {
    uint32_t h = mix(seed ^ 0x9e3779b9u);
    h = mix(h ^ uint32_t(x));
    h = mix(h ^ uint32_t(y) * 0x27d4eb2fu);
    h = mix(h ^ uint32_t(z) * 0x165667b1u);
    return double(h >> 8) * (1.0 / double(1u << 24)); // [0, 1)
}

double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

// Trilinear value noise with quintic fade, in [0, 1).
double valueNoise(const Vec3d& p, uint32_t seed) {
    const double fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
    const auto x = int64_t(fx), y = int64_t(fy), z = int64_t(fz);
    const double u = fade(p.x - fx), v = fade(p.y - fy), w = fade(p.z - fz);
    const auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
    const auto c = [&](int dx, int dy, int dz) { return latticeValue(x + dx, y + dy, z + dz, seed); };
    return lerp(lerp(lerp(c(0, 0, 0), c(1, 0, 0), u), lerp(c(0, 1, 0), c(1, 1, 0), u), v),
                lerp(lerp(c(0, 0, 1), c(1, 0, 1), u), lerp(c(0, 1, 1), c(1, 1, 1), u), v), w);
}

// Fractional Brownian motion: octaves of halving amplitude and doubling frequency, in [0, 1).
double fbm(Vec3d p, int octaves, uint32_t seed) {
    double sum = 0, amplitude = 1, total = 0;
    for (int o = 0; o < octaves; ++o) {
        sum += amplitude * valueNoise(p, seed + uint32_t(o) * 1013u);
        total += amplitude;
        amplitude *= 0.5;
        p = p * 2.0 + Vec3d(17.3, -9.1, 5.7); // shifted so octaves do not share lattice points
    }
    return sum / total;
}

double smoothstep(double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

} // namespace

Volume makeSmoke(const SmokeParams& params) {
    if (params.octaves < 1 || params.octaves > 16)
        fail("smoke octaves must be in [1, 16], got ", params.octaves);
    if (!(std::isfinite(params.frequency) && params.frequency > 0))
        fail("smoke frequency must be positive and finite, got ", params.frequency);
    const Box3d& b = params.box;
    if (!isFinite(b.lo) || !isFinite(b.hi) || !(b.lo.x < b.hi.x && b.lo.y < b.hi.y && b.lo.z < b.hi.z))
        fail("smoke box must be finite and non-empty");
    const Vec3i n = params.dims;
    if (n.x < 1 || n.y < 1 || n.z < 1)
        fail("smoke dimensions must be at least 1, got ", n.x, " x ", n.y, " x ", n.z);
    // Checked against the memory available before allocating (a scene file can ask for any size);
    // sizes past 2^40 voxels are left to the volume's own limit.
    if (n.x <= kMaxVolumeVoxels && n.y <= kMaxVolumeVoxels / n.x && n.z <= kMaxVolumeVoxels / (n.x * n.y)) {
        const std::string what = detail::concat("a smoke volume of ", n.x, " x ", n.y, " x ", n.z, " voxels");
        checkMemory(uint64_t(n.x * n.y * n.z) * sizeof(float), what.c_str());
    }
    const Vec3d spacing = b.extent() * Vec3d(1.0 / double(n.x), 1.0 / double(n.y), 1.0 / double(n.z));
    Volume vol(n, b.lo, spacing, ScalarType::Float32);
    const uint32_t seed = params.seed;
    const int octaves = params.octaves;
    const double freq = params.frequency;
    parallelFor(0, n.z, 1, [&](int64_t k0, int64_t k1) {
        for (int64_t k = k0; k < k1; ++k)
            for (int64_t j = 0; j < n.y; ++j)
                for (int64_t i = 0; i < n.x; ++i) {
                    // Normalized position in the box, [0, 1]^3.
                    const Vec3d q{(double(i) + 0.5) / double(n.x), (double(j) + 0.5) / double(n.y),
                                  (double(k) + 0.5) / double(n.z)};
                    const double h = q.z;
                    const double radius = 0.12 + 0.3 * h;
                    const double dx = q.x - 0.5, dy = q.y - 0.5;
                    const double d = std::sqrt(dx * dx + dy * dy);
                    const double plume = (1 - smoothstep(0.4 * radius, radius, d)) *
                                         smoothstep(0.0, 0.08, h) * (1 - smoothstep(0.55, 0.92, h));
                    if (plume <= 0) continue;
                    // Rising noise: stretched along z, warped sideways once.
                    const Vec3d p = Vec3d{q.x, q.y, q.z * 0.6} * freq;
                    const double warp = fbm(p + Vec3d(3.1, 7.4, 1.3), 3, seed ^ 0x5bd1e995u) - 0.5;
                    const double noise = fbm(p + Vec3d(warp, -warp, 0.5 * warp) * 1.5, octaves, seed);
                    const double density = plume * std::clamp((noise - 0.3) * 2.5, 0.0, 1.0);
                    vol.at(i, j, k) = float(std::clamp(density, 0.0, 1.0));
                }
    });
    return vol;
}

} // namespace voxfx
