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

/// The unit of the procedural sky's radiance: radiance 1 (linear sRGB whose luminance is 1) is this
/// many cd/m^2, so that the sun at the default elevation gives about irradiance 3 (the old default
/// sun's) and a white plane under sun and sky about radiance 1.
inline constexpr double kSkyLuminanceUnit = 30000;
/// The solar illuminance outside the atmosphere, lux (Darula et al. 2005's 128 klx).
inline constexpr double kSolarIlluminance = 128000;
inline constexpr double kDefaultSunElevation = 54.5; ///< degrees above the horizon
inline constexpr double kDefaultSunAzimuth = 142;    ///< degrees from -z (north) towards +x (east)
inline constexpr double kDefaultTurbidity = 2;       ///< Preetham's T: 2 very clear .. 10 hazy

/// The unit direction towards a sun `elevationDegrees` above the horizon (+y up) and
/// `azimuthDegrees` from -z (the default camera's view) turning towards +x.
Vec3d sunDirectionFromAngles(double elevationDegrees, double azimuthDegrees);

struct SkyOptions {
    /// Towards the sun (normalized); the sky's light and the default sun both come from it. Its
    /// elevation is clamped to at least 1 degree (the model is fitted for a sun above the horizon).
    Vec3d sunDirection = sunDirectionFromAngles(kDefaultSunElevation, kDefaultSunAzimuth);
    double turbidity = kDefaultTurbidity; ///< 1.7 .. 10 (clamped)
    /// The ground below the horizon: a Lambertian plane of this albedo under the sun and the sky.
    Vec3f groundAlbedo{0.3f, 0.3f, 0.3f};
    /// How that ground is lit: by skyLight's share of the sky's irradiance, by the sky's sun when
    /// groundSun, and by groundLight (irradiance on an upward face, linear RGB, sky units). The
    /// renderer sets them as it lights the scene (the scene's directional lights, or the sky's sun
    /// when it has none; RenderOptions::ambient and skyLight), so the sky's ground is the scene's
    /// ground lit as the scene lights it, far from its spot and point lights.
    double groundSkyLight = 1;
    bool groundSun = true;
    Vec3f groundLight{0, 0, 0};
    double sunAngularRadius = 0.02; ///< radians of the disc drawn (the real sun: 0.0047; wider reads better)
    int width = 512, height = 256;  ///< resolution of the baked map
};

/// What the procedural sky is made of, in the sky's units (kSkyLuminanceUnit).
struct Daylight {
    /// Irradiance of the sun's direct light on a face towards it, linear sRGB: the extraterrestrial
    /// sun (a 5778 K black body of kSolarIlluminance) through Preetham's Rayleigh and aerosol
    /// transmittance along the Kasten air mass.
    Vec3f sunIrradiance;
    Vec3f zenith; ///< the sky's radiance straight up
    Vec3f ground; ///< the radiance below the horizon: groundAlbedo / pi * (sun + sky) irradiance
    double skyHorizontalIrradiance = 0; ///< luminance-weighted, sky's units: the diffuse part
    double sunHorizontalIrradiance = 0; ///< the direct part on a horizontal face
};

/// Preetham, Shirley & Smits 1999, "A Practical Analytic Model for Daylight": the sky's radiance
/// (linear sRGB, sky units) along unit direction d above the horizon, for the sun towards unit
/// `sun` and turbidity T: the Perez distribution of Y, x and y relative to the zenith's, the
/// zenith's luminance and chromaticity from the paper's fits, xyY -> XYZ -> linear sRGB.
Vec3f preethamSkyRadiance(const Vec3d& d, const Vec3d& sun, double turbidity);

class Environment {
public:
    /// A black environment (no light), one 1 x 1 level.
    Environment();
    /// Takes `image` as level 0 and builds the pyramid. Throws voxfx::Error for an empty image.
    explicit Environment(Image image);
    /// The procedural daylight sky baked into a map: Preetham's sky above the horizon
    /// (preethamSkyRadiance), a Lambertian ground of SkyOptions::groundAlbedo lit by that sun and
    /// sky below it, the sun as a disc. The sun's light is sunIrradiance() along sunDirection()
    /// (the disc is seen, in glass, but left out of the ambient harmonics, which it would count twice).
    static Environment sky(const SkyOptions& options = {}, Daylight* daylight = nullptr);

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
    /// The sun: a procedural sky's (its direction towards the sun); for a map, its sun region when
    /// it has one: the texels connected to the brightest one that are at least max(4 x the map's
    /// mean, 1/20 of the brightest) luminance, within 0.2 sr (at the first level at most 1024
    /// texels wide). The region is taken out of the ambient light (its texels replaced by the mean
    /// of the texels around it before the projection on harmonics) and becomes the sun: direction
    /// the luminance-weighted centroid of what was removed, irradiance (sunIrradiance) the removed
    /// radiance times the texels' solid angles. Zero for a map without a sun.
    const Vec3d& sunDirection() const { return sunDirection_; }
    /// The sun's irradiance on a face towards it (linear RGB); zero without a sun. The irradiance on
    /// a face of normal n is irradiance(n) + sunIrradiance() * max(0, n . sunDirection()).
    const Vec3f& sunIrradiance() const { return sunIrradiance_; }

private:
    void buildLevels(Image image);
    void projectOnHarmonics(const Image& im);
    /// The sun region of `im` (see sunDirection()), taken out of `im`.
    void extractSun(Image& im);
    std::vector<Image> levels_;
    Vec3d sunDirection_;
    Vec3f sunIrradiance_;
    std::array<Vec3f, 9> sh_{};
};

/// Level k+1 from level k (see the file comment). Exposed for tests.
Image downsampleEnvironmentLevel(const Image& level);

} // namespace voxfx
