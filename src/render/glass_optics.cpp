// voxfx — glass optics in closed form (Snell, Fresnel, Beer–Lambert), the medium of a material, and
// the image error used to compare the glass methods with the exact reference.
#include "voxfx/glass_optics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"

namespace voxfx {

bool refractDirection(const Vec3d& d, const Vec3d& n, double eta, Vec3d& out) {
    const double cosI = -dot(d, n);
    const double sin2T = eta * eta * std::max(0.0, 1 - cosI * cosI);
    if (sin2T > 1) return false;
    const double cosT = std::sqrt(1 - sin2T);
    out = normalize(d * eta + n * (eta * cosI - cosT));
    return true;
}

GlassMedium glassMedium(const Material& m) {
    GlassMedium g;
    g.ior = std::max(1.0f, m.ior);
    g.sigma = attenuationCoefficient(m);
    g.tint = m.baseColor;
    return g;
}

ImageError imageError(const Image& test, const Image& reference, const std::vector<uint8_t>& mask) {
    if (test.width != reference.width || test.height != reference.height ||
        mask.size() != reference.pixels.size())
        fail("image error: the images and the mask differ in size");
    ImageError e;
    double sumAbs = 0, sumSq = 0;
    for (size_t i = 0; i < mask.size(); ++i) {
        if (!mask[i]) continue;
        ++e.pixels;
        for (int c = 0; c < 3; ++c) {
            const double a = std::clamp(double(test.pixels[i][c]), 0.0, 1.0);
            const double b = std::clamp(double(reference.pixels[i][c]), 0.0, 1.0);
            sumAbs += std::abs(a - b);
            sumSq += (a - b) * (a - b);
        }
    }
    if (e.pixels == 0) return e;
    const double n = 3.0 * double(e.pixels);
    e.mae = sumAbs / n;
    e.psnr = sumSq > 0 ? 10 * std::log10(1.0 / (sumSq / n)) : std::numeric_limits<double>::infinity();
    return e;
}

} // namespace voxfx
