// voxfx — the procedural daylight sky (voxfx/environment.hpp): Preetham, Shirley & Smits 1999, "A
// Practical Analytic Model for Daylight", for the sky (Perez distributions of Y, x, y; the zenith's
// luminance and chromaticity) and the sun's attenuation (Appendix A.2: Rayleigh and aerosol
// transmittance along the air mass; ozone, mixed gases and water vapour, a few per cent in the red,
// are left out), a Lambertian ground below the horizon lit by both.
#include <algorithm>
#include <cmath>

#include "voxfx/environment.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

Vec3d sunDirectionFromAngles(double elevationDegrees, double azimuthDegrees) {
    const double e = elevationDegrees * M_PI / 180, a = azimuthDegrees * M_PI / 180;
    return {std::cos(e) * std::sin(a), std::sin(e), -std::cos(e) * std::cos(a)};
}

namespace {

// The Perez et al. 1993 sky luminance distribution, coefficients A..E.
struct PerezCoefficients {
    double a, b, c, d, e;
    double operator()(double cosTheta, double gamma) const {
        const double cg = std::cos(gamma);
        return (1 + a * std::exp(b / std::max(cosTheta, 1e-3))) * (1 + c * std::exp(d * gamma) + e * cg * cg);
    }
};

// Preetham's Table 2 (Appendix A.2): the coefficients of Y, x and y, linear in the turbidity.
struct PreethamSky {
    PerezCoefficients Y, x, y;
    double zenithY, zenithX, zenithYChroma, thetaSun;

    PreethamSky(double T, double thetaS) : thetaSun(thetaS) {
        Y = {0.1787 * T - 1.4630, -0.3554 * T + 0.4275, -0.0227 * T + 5.3251, 0.1206 * T - 2.5771,
             -0.0670 * T + 0.3703};
        x = {-0.0193 * T - 0.2592, -0.0665 * T + 0.0008, -0.0004 * T + 0.2125, -0.0641 * T - 0.8989,
             -0.0033 * T + 0.0452};
        y = {-0.0167 * T - 0.2608, -0.0950 * T + 0.0092, -0.0079 * T + 0.2102, -0.0441 * T - 1.6537,
             -0.0109 * T + 0.0529};
        // The zenith: luminance in kcd/m^2, chromaticity [T^2 T 1] M [thetaS^3 thetaS^2 thetaS 1]^T.
        const double chi = (4.0 / 9.0 - T / 120.0) * (M_PI - 2 * thetaS);
        zenithY = (4.0453 * T - 4.9710) * std::tan(chi) - 0.2155 * T + 2.4192;
        const double t3 = thetaS * thetaS * thetaS, t2 = thetaS * thetaS;
        auto poly = [&](const double(&m)[3][4]) {
            double r = 0;
            const double tp[3] = {T * T, T, 1};
            for (int i = 0; i < 3; ++i)
                r += tp[i] * (m[i][0] * t3 + m[i][1] * t2 + m[i][2] * thetaS + m[i][3]);
            return r;
        };
        constexpr double mx[3][4] = {{0.00166, -0.00375, 0.00209, 0},
                                     {-0.02903, 0.06377, -0.03202, 0.00394},
                                     {0.11693, -0.21196, 0.06052, 0.25886}};
        constexpr double my[3][4] = {{0.00275, -0.00610, 0.00317, 0},
                                     {-0.04214, 0.08970, -0.04153, 0.00516},
                                     {0.15346, -0.26756, 0.06670, 0.26688}};
        zenithX = poly(mx);
        zenithYChroma = poly(my);
    }

    // xyY (Y in kcd/m^2) along a direction at zenith angle theta (its cosine) and angle gamma from the sun.
    Vec3d xyY(double cosTheta, double gamma) const {
        return {zenithX * x(cosTheta, gamma) / x(1, thetaSun),
                zenithYChroma * y(cosTheta, gamma) / y(1, thetaSun),
                zenithY * Y(cosTheta, gamma) / Y(1, thetaSun)};
    }
};

// CIE XYZ -> linear sRGB (IEC 61966-2-1, D65 white).
Vec3d linearSrgbFromXyz(const Vec3d& c) {
    return {3.2404542 * c.x - 1.5371385 * c.y - 0.4985314 * c.z,
            -0.9692660 * c.x + 1.8760108 * c.y + 0.0415560 * c.z,
            0.0556434 * c.x - 0.2040259 * c.y + 1.0572252 * c.z};
}

Vec3f skyUnits(const Vec3d& xyz) {
    const Vec3d rgb = linearSrgbFromXyz(xyz) * (1.0 / kSkyLuminanceUnit);
    return {float(std::max(0.0, rgb.x)), float(std::max(0.0, rgb.y)), float(std::max(0.0, rgb.z))};
}

Vec3d xyzFromXyY(const Vec3d& c) {
    const double y = std::max(c.y, 1e-6);
    return {c.x * c.z / y, c.z, (1 - c.x - c.y) * c.z / y};
}

// Wyman, Sloan & Shirley 2013's multi-lobe fit of the CIE 1931 colour matching functions (nm).
double lobe(double l, double mu, double s1, double s2) {
    const double t = (l - mu) / (l < mu ? s1 : s2);
    return std::exp(-0.5 * t * t);
}
Vec3d colourMatching(double l) {
    return {1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) -
                0.065 * lobe(l, 501.1, 20.4, 26.2),
            0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1),
            1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8)};
}

// The sun's direct irradiance (XYZ, lux) on a face towards it at zenith angle thetaS: a 5778 K
// black body scaled to kSolarIlluminance, times Preetham's Rayleigh and aerosol transmittance
// (Angstrom alpha 1.3, beta 0.04608 T - 0.04586) along Kasten's relative air mass.
Vec3d sunIrradianceXyz(double T, double thetaS) {
    const double deg = thetaS * 180 / M_PI;
    const double m = 1 / (std::cos(thetaS) + 0.15 * std::pow(93.885 - deg, -1.253));
    const double beta = 0.04608365 * T - 0.04586025, alpha = 1.3;
    Vec3d through{0, 0, 0};
    double outside = 0;
    for (double l = 380; l <= 780; l += 5) {
        const double lm = l * 1e-9, um = l * 1e-3;
        const double planck = 1 / (std::pow(lm, 5) * (std::exp(1.4388e-2 / (lm * 5778)) - 1));
        const double tau =
            std::exp(-0.008735 * std::pow(um, -4.08) * m) * std::exp(-beta * std::pow(um, -alpha) * m);
        const Vec3d cmf = colourMatching(l);
        through += cmf * (planck * tau);
        outside += planck * cmf.y;
    }
    return through * (kSolarIlluminance / outside);
}

// Solid angle of the texel rows j of an H-row equirectangular map, per texel of a W-wide row.
double skyTexelSolidAngle(int64_t j, int64_t W, int64_t H) {
    return 2 * M_PI / double(W) *
           (std::cos(double(j) * M_PI / double(H)) - std::cos(double(j + 1) * M_PI / double(H)));
}

} // namespace

Vec3f preethamSkyRadiance(const Vec3d& d, const Vec3d& sun, double turbidity) {
    const double T = std::clamp(turbidity, 1.7, 10.0);
    const PreethamSky sky(T, std::acos(std::clamp(sun.y, -1.0, 1.0)));
    const double gamma = std::acos(std::clamp(dot(d, sun), -1.0, 1.0));
    Vec3d c = sky.xyY(d.y, gamma);
    c.z *= 1000; // kcd/m^2 -> cd/m^2
    return skyUnits(xyzFromXyY(c));
}

Environment Environment::sky(const SkyOptions& o, Daylight* daylight) {
    if (o.width < 2 || o.height < 2) fail("the sky map needs at least 2 x 2 texels");
    if (!(o.turbidity > 0)) fail("the sky's turbidity must be positive, got ", o.turbidity);
    Vec3d sun = normalize(o.sunDirection);
    const double minElevation = std::sin(M_PI / 180);
    if (!(sun.y >= minElevation)) {
        const double h = std::hypot(sun.x, sun.z);
        sun = h > 0 ? Vec3d{sun.x / h * std::cos(M_PI / 180), minElevation, sun.z / h * std::cos(M_PI / 180)}
                    : Vec3d{0, 1, 0};
    }
    Image img(o.width, o.height);
    Vec3d skyHorizontal{0, 0, 0}; // the sky's irradiance on an upward face, linear RGB
    for (int64_t j = 0; j < img.height; ++j) {
        const double omega = skyTexelSolidAngle(j, img.width, img.height);
        for (int64_t i = 0; i < img.width; ++i) {
            const Vec3d d = equirectToDirection((double(i) + 0.5) / double(img.width),
                                                (double(j) + 0.5) / double(img.height));
            if (d.y <= 0) continue;
            img.at(i, j) = preethamSkyRadiance(d, sun, o.turbidity);
            skyHorizontal += Vec3d(img.at(i, j)) * (d.y * omega);
        }
    }
    const Vec3f sunE = skyUnits(sunIrradianceXyz(std::clamp(o.turbidity, 1.7, 10.0), std::acos(sun.y)));
    const Vec3d direct = Vec3d(o.groundLight) + (o.groundSun ? Vec3d(sunE) * sun.y : Vec3d{0, 0, 0});
    const Vec3f ground = o.groundAlbedo * Vec3f(skyHorizontal * o.groundSkyLight + direct) * float(1 / M_PI);
    for (int64_t j = 0; j < img.height; ++j)
        for (int64_t i = 0; i < img.width; ++i)
            if (equirectToDirection((double(i) + 0.5) / double(img.width),
                                    (double(j) + 0.5) / double(img.height))
                    .y <= 0)
                img.at(i, j) = ground;
    // The disc, drawn at the radiance that gives the sun's irradiance over the texels it covers (the
    // texel holding the sun when no texel centre is within the radius).
    Image withDisc = img;
    const double cosSun = std::cos(o.sunAngularRadius);
    double discOmega = 0;
    std::vector<std::pair<int64_t, int64_t>> disc;
    for (int64_t j = 0; j < img.height; ++j)
        for (int64_t i = 0; i < img.width; ++i)
            if (dot(equirectToDirection((double(i) + 0.5) / double(img.width),
                                        (double(j) + 0.5) / double(img.height)),
                    sun) >= cosSun) {
                disc.emplace_back(i, j);
                discOmega += skyTexelSolidAngle(j, img.width, img.height);
            }
    if (disc.empty()) {
        double u, v;
        directionToEquirect(sun, u, v);
        const int64_t i = std::min(img.width - 1, int64_t(u * double(img.width)));
        const int64_t j = std::min(img.height - 1, int64_t(v * double(img.height)));
        disc.emplace_back(i, j);
        discOmega = skyTexelSolidAngle(j, img.width, img.height);
    }
    for (const auto& [i, j] : disc) withDisc.at(i, j) = sunE * float(1 / discOmega);
    Environment env;
    env.levels_.clear();
    env.buildLevels(std::move(withDisc));
    env.projectOnHarmonics(img);
    env.sunDirection_ = sun;
    env.sunIrradiance_ = sunE;
    if (daylight) {
        auto lum = [](const Vec3d& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; };
        daylight->sunIrradiance = sunE;
        daylight->zenith = preethamSkyRadiance({0, 1, 0}, sun, o.turbidity);
        daylight->ground = ground;
        daylight->skyHorizontalIrradiance = lum(skyHorizontal);
        daylight->sunHorizontalIrradiance = lum(Vec3d(sunE)) * sun.y;
    }
    return env;
}

} // namespace voxfx
