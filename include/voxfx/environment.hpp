// voxfx — environment lighting: an equirectangular (latitude-longitude) radiance map with a
// prefiltered pyramid for blurred lookups, and a procedural sky used when no map is given.
//
// Directions are world space with +y up (glTF). A direction d maps to texture coordinates
//   u = 0.5 + atan2(d.x, -d.z) / (2 pi)   (u = 0.5 looks along -z, the default camera's view)
//   v = acos(d.y) / pi                     (v = 0 is the zenith, the image's top row)
// and texel (i, j) of a W x H level covers [i, i+1) / W x [j, j+1) / H.
//
// Pyramid: level 0 is the image; level k+1 has ceil(W/2) x ceil(H/2) texels, each the box average
// of the (up to) 2 x 2 texels of level k it covers, down to 1 x 1. The box average is over texels,
// not solid angle: texels near the poles weigh as much as those at the equator (what ED06's
// pre-filtered environment pyramid does too). A blurred lookup picks the level whose texel spans the
// requested cone angle and interpolates trilinearly (bilinear in u wrapping around, clamped in v).
//
// EXPERIMENTAL until the glass issue closes.
// Thread-safety: an Environment is a value; lookups are const and may run from any number of threads.
#pragma once

#include <array>
#include <vector>

#include "voxfx/image.hpp"
#include "voxfx/math.hpp"

namespace voxfx {

/// (u, v) in [0, 1]^2 of a direction (need not be unit; zero maps to (0.5, 0.5)). See the file comment.
void directionToEquirect(const Vec3d& d, double& u, double& v);
/// The unit direction of (u, v); the inverse of directionToEquirect for v in (0, 1).
Vec3d equirectToDirection(double u, double v);

struct SkyOptions {
    Vec3d sunDirection{0.35, 0.8, 0.45}; ///< towards the sun (normalized); also the default sun light's
    Vec3f zenith{0.25f, 0.45f, 0.95f};   ///< radiance straight up
    Vec3f horizon{0.85f, 0.9f, 1.0f};    ///< radiance at the horizon
    Vec3f ground{0.32f, 0.30f, 0.27f};   ///< radiance below the horizon
    Vec3f sun{40.0f, 38.0f, 34.0f};      ///< radiance of the sun's disc
    double sunAngularRadius = 0.02;      ///< radians (the real sun: 0.0047; wider reads better in images)
    int width = 512, height = 256;       ///< resolution of the baked map
};

class Environment {
public:
    /// A black environment (no light), one 1 x 1 level.
    Environment();
    /// Takes `image` as level 0 and builds the pyramid. Throws voxfx::Error for an empty image.
    explicit Environment(Image image);
    /// A procedural sky baked into a map: zenith-to-horizon gradient, a ground colour below the
    /// horizon (with a short blend), the sun as a disc with a glow.
    static Environment sky(const SkyOptions& options = {});

    int levels() const { return int(levels_.size()); }
    const Image& level(int k) const { return levels_[size_t(k)]; }
    /// Bilinear lookup in level k (u wraps, v clamps), k clamped to the pyramid.
    Vec3f sampleLevel(const Vec3d& d, int k) const;
    /// Radiance seen along d, blurred over a cone of `blurAngle` radians (0: level 0, bilinear).
    /// Trilinear between the two levels whose texel width brackets the angle.
    Vec3f lookup(const Vec3d& d, double blurAngle = 0) const;
    /// Diffuse approximation of the light arriving around normal n: the map blurred over about a
    /// hemisphere (the level of about 4 x 2 texels) looked up along n.
    Vec3f ambient(const Vec3d& n) const;
    /// Irradiance on a surface of unit normal n: the integral of radiance times max(0, cos) over
    /// the sphere, from the map's projection on the 9 real spherical harmonics of order <= 2 and the
    /// clamped cosine's coefficients pi, 2pi/3, pi/4 (Ramamoorthi & Hanrahan 2001). Exact for a map
    /// whose radiance is a polynomial of degree <= 2 in the direction (a uniform sky L gives pi L)
    /// up to the quadrature over texels (each weighed by its exact solid angle, sampled at its
    /// centre; the first level at most 1024 texels wide).
    Vec3f irradiance(const Vec3d& n) const;
    /// The projection's coefficients, in the order Y00, Y1-1 (y), Y10 (z), Y11 (x), Y2-2 (xy),
    /// Y2-1 (yz), Y20 (3z^2 - 1), Y21 (xz), Y22 (x^2 - y^2) of the world axes.
    const std::array<Vec3f, 9>& sphericalHarmonics() const { return sh_; }
    /// Mean of level 0's texels (the last level).
    Vec3f average() const { return levels_.back().pixels[0]; }
    /// The sun: a procedural sky's (its direction towards the sun); for a map the direction of its
    /// brightest region (the brightest texel of the first level at most 64 texels wide) when it is
    /// at least 4 times the map's mean luminance, else zero (a map without a sun).
    const Vec3d& sunDirection() const { return sunDirection_; }

private:
    void projectOnHarmonics();
    void findSun();
    std::vector<Image> levels_;
    Vec3d sunDirection_;
    std::array<Vec3f, 9> sh_{};
};

/// Level k+1 from level k (see the file comment). Exposed for tests.
Image downsampleEnvironmentLevel(const Image& level);

} // namespace voxfx
