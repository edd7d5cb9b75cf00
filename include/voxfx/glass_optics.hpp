// voxfx — what every glass method (voxfx/glass.hpp) shares: optics in closed form (Snell, the exact
// dielectric Fresnel factor, Beer–Lambert), the medium of a glass material, the path of one camera
// ray through glass, and the options common to the methods.
//
// Attenuation: KHR_materials_volume's sigma = -ln(attenuationColor) / attenuationDistance per
// channel (attenuationCoefficient, voxfx/scene.hpp; zero when the distance is infinite).
//
// Thread-safety: pure functions and values.
#pragma once

#include <cstdint>

#include "voxfx/glass_options.hpp"
#include "voxfx/math.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {

/// Mirror direction of d about the unit normal n.
inline Vec3d reflectDirection(const Vec3d& d, const Vec3d& n) { return d - n * (2 * dot(d, n)); }
/// Snell's law: the refracted direction of unit d at a surface whose unit normal n faces the
/// incoming ray (dot(d, n) < 0), with eta = n_incident / n_transmitted. False (out untouched) under
/// total internal reflection.
bool refractDirection(const Vec3d& d, const Vec3d& n, double eta, Vec3d& out);
// fresnelDielectric(cosI, etaI, etaT) and beerLambert(sigma, length): voxfx/scene.hpp (shared with
// the shadows).

/// What one kind of glass does to light: index of refraction, Beer–Lambert coefficient per world unit
/// and the tint applied once where light enters (KHR_materials_transmission: the base colour).
struct GlassMedium {
    float ior = 1.5f;
    Vec3f sigma{0, 0, 0};
    Vec3f tint{1, 1, 1};
};
/// The medium of a material (ior, attenuationCoefficient, baseColor).
GlassMedium glassMedium(const Material& m);

/// One camera ray through glass.
struct GlassPath {
    bool hit = false;       ///< false: the ray met no glass (the other fields are meaningless)
    Vec3d reflectDir;       ///< mirror direction at the first surface
    float reflectance = 0;  ///< Fresnel F at the first surface
    Vec3d exitPoint;        ///< where the ray last left glass (or the last event)
    Vec3d exitDir;          ///< direction the transmitted light comes from, reversed
    Vec3f throughput;       ///< fraction of the environment along exitDir that arrives (without F)
    int events = 0;         ///< refractions and reflections followed (the first surface included)
    bool truncated = false; ///< stopped at maxEvents: leaves along its current direction
    double blurAngle = 0;   ///< frosted: the cone the environment is averaged over (radians)
    /// What the path crossed, in order (exact: a hash of each event's faces, their media and sides,
    /// and whether it refracted or reflected totally; 0 for the other methods): two neighbouring
    /// paths with the same value went through the same objects the same way (the glass pass's
    /// lattice interpolates only between such paths).
    uint64_t crossed = 0;

    /// Stops the path after maxEvents: it leaves at `at` along its current direction with what it
    /// carries (black pixels where a ray is trapped by total internal reflection would be a worse
    /// guess).
    void truncate(const Vec3d& at, const Vec3d& dir, const Vec3f& carried) {
        truncated = true;
        exitPoint = at;
        exitDir = dir;
        throughput = carried;
    }
};

/// Where a camera ray meets glass: the eye, the unit direction, the G-buffer's surface point there
/// with its unit normal (any side) and the medium (index into the media the method was built with).
struct GlassHit {
    Vec3d eye, dir, entry, normal;
    uint32_t medium = 0;
};

} // namespace voxfx
