// voxfx — equirectangular environment maps with a box-filtered pyramid, and the procedural sky.
#include "voxfx/environment.hpp"

#include <algorithm>
#include <cmath>

#include "voxfx/error.hpp"

namespace voxfx {

void directionToEquirect(const Vec3d& d, double& u, double& v) {
    const double len = length(d);
    if (!(len > 0)) {
        u = v = 0.5;
        return;
    }
    u = 0.5 + std::atan2(d.x, -d.z) / (2 * M_PI);
    v = std::acos(std::clamp(d.y / len, -1.0, 1.0)) / M_PI;
    if (u >= 1) u -= 1;
    if (u < 0) u += 1;
}

Vec3d equirectToDirection(double u, double v) {
    const double phi = (u - 0.5) * 2 * M_PI, theta = v * M_PI;
    const double s = std::sin(theta);
    return {s * std::sin(phi), std::cos(theta), -s * std::cos(phi)};
}

Image downsampleEnvironmentLevel(const Image& in) {
    const int64_t w = std::max<int64_t>(1, (in.width + 1) / 2), h = std::max<int64_t>(1, (in.height + 1) / 2);
    Image out(w, h);
    for (int64_t j = 0; j < h; ++j)
        for (int64_t i = 0; i < w; ++i) {
            Vec3f sum;
            int n = 0;
            for (int64_t y = 2 * j; y < std::min(in.height, 2 * j + 2); ++y)
                for (int64_t x = 2 * i; x < std::min(in.width, 2 * i + 2); ++x) {
                    sum += in.at(x, y);
                    ++n;
                }
            out.at(i, j) = sum * (1.0f / float(n));
        }
    return out;
}

Environment::Environment() : levels_{Image(1, 1)} {}

Environment::Environment(Image image) {
    if (image.width <= 0 || image.height <= 0) fail("an environment map needs at least one texel");
    levels_.push_back(std::move(image));
    while (levels_.back().width > 1 || levels_.back().height > 1)
        levels_.push_back(downsampleEnvironmentLevel(levels_.back()));
    projectOnHarmonics();
    findSun();
}

namespace {

// The 9 real spherical harmonics of order <= 2 at unit direction d (see sphericalHarmonics()).
std::array<double, 9> harmonics(const Vec3d& d) {
    const double x = d.x, y = d.y, z = d.z;
    return {0.282095,
            0.488603 * y,
            0.488603 * z,
            0.488603 * x,
            1.092548 * x * y,
            1.092548 * y * z,
            0.315392 * (3 * z * z - 1),
            1.092548 * x * z,
            0.546274 * (x * x - y * y)};
}

double luminance(const Vec3f& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

} // namespace

void Environment::projectOnHarmonics() {
    std::size_t k = 0;
    while (k + 1 < levels_.size() && levels_[k].width > 1024) ++k;
    const Image& im = levels_[k];
    // Quadrature cells: the texels, or a 64 x 32 grid over a smaller map (each cell takes the texel
    // holding its centre), so that a tiny map's one texel is not read as one direction.
    const int64_t W = std::max<int64_t>(im.width, 64), H = std::max<int64_t>(im.height, 32);
    std::array<Vec3d, 9> sum{};
    const double dPhi = 2 * M_PI / double(W);
    for (int64_t j = 0; j < H; ++j) {
        // Row j covers polar angles [j, j + 1] pi / H: solid angle dPhi (cos theta0 - cos theta1).
        const double omega =
            dPhi * (std::cos(double(j) * M_PI / double(H)) - std::cos(double(j + 1) * M_PI / double(H)));
        std::array<Vec3d, 9> row{};
        for (int64_t i = 0; i < W; ++i) {
            const std::array<double, 9> y =
                harmonics(equirectToDirection((double(i) + 0.5) / double(W), (double(j) + 0.5) / double(H)));
            const Vec3d c(im.at(i * im.width / W, j * im.height / H));
            for (int b = 0; b < 9; ++b) row[size_t(b)] += c * y[size_t(b)];
        }
        for (int b = 0; b < 9; ++b) sum[size_t(b)] += row[size_t(b)] * omega;
    }
    for (int b = 0; b < 9; ++b) sh_[size_t(b)] = Vec3f(sum[size_t(b)]);
}

void Environment::findSun() {
    sunDirection_ = {0, 0, 0};
    std::size_t k = 0;
    while (k + 1 < levels_.size() && levels_[k].width > 64) ++k;
    const Image& im = levels_[k];
    double best = -1, mean = 0;
    int64_t bi = 0, bj = 0;
    for (int64_t j = 0; j < im.height; ++j)
        for (int64_t i = 0; i < im.width; ++i) {
            const double l = luminance(im.at(i, j));
            mean += l;
            if (l > best) best = l, bi = i, bj = j;
        }
    mean /= double(im.width * im.height);
    if (best > 4 * mean && best > 0)
        sunDirection_ = equirectToDirection((double(bi) + 0.5) / double(im.width),
                                            (double(bj) + 0.5) / double(im.height));
}

Vec3f Environment::irradiance(const Vec3d& n) const {
    const std::array<double, 9> y = harmonics(normalize(n));
    // The clamped cosine's coefficients per band: pi, 2 pi / 3, pi / 4.
    constexpr double a[9] = {M_PI,     2 * M_PI / 3, 2 * M_PI / 3, 2 * M_PI / 3, M_PI / 4,
                             M_PI / 4, M_PI / 4,     M_PI / 4,     M_PI / 4};
    Vec3d e{0, 0, 0};
    for (int b = 0; b < 9; ++b) e += Vec3d(sh_[size_t(b)]) * (a[b] * y[size_t(b)]);
    return Vec3f{float(std::max(0.0, e.x)), float(std::max(0.0, e.y)), float(std::max(0.0, e.z))};
}

Environment Environment::sky(const SkyOptions& o) {
    if (o.width < 2 || o.height < 2) fail("the sky map needs at least 2 x 2 texels");
    const Vec3d sun = normalize(o.sunDirection);
    Image img(o.width, o.height);
    const double cosSun = std::cos(o.sunAngularRadius);
    for (int64_t j = 0; j < img.height; ++j)
        for (int64_t i = 0; i < img.width; ++i) {
            const Vec3d d = equirectToDirection((double(i) + 0.5) / double(img.width),
                                                (double(j) + 0.5) / double(img.height));
            const double up = d.y;
            Vec3f c;
            if (up >= 0) {
                const float t = float(std::pow(1.0 - up, 3.0)); // horizon band
                c = o.zenith * (1 - t) + o.horizon * t;
            } else {
                const float t = float(std::min(1.0, -up * 8.0)); // short blend into the ground
                c = o.horizon * (1 - t) + o.ground * t;
            }
            const double cs = dot(d, sun);
            if (up > -0.02) {
                if (cs >= cosSun)
                    c = o.sun;
                else // glow: a narrow lobe around the disc
                    c += o.sun * float(0.02 * std::pow(std::max(0.0, cs), 64.0));
            }
            img.at(i, j) = c;
        }
    Environment env(std::move(img));
    env.sunDirection_ = sun;
    return env;
}

Vec3f Environment::sampleLevel(const Vec3d& d, int k) const {
    const Image& im = levels_[size_t(std::clamp(k, 0, levels() - 1))];
    double u, v;
    directionToEquirect(d, u, v);
    const double x = u * double(im.width) - 0.5, y = v * double(im.height) - 0.5;
    const double fx = std::floor(x), fy = std::floor(y);
    const float ax = float(x - fx), ay = float(y - fy);
    auto wrapX = [&](int64_t i) { return ((i % im.width) + im.width) % im.width; };
    auto clampY = [&](int64_t j) { return std::clamp<int64_t>(j, 0, im.height - 1); };
    const int64_t x0 = wrapX(int64_t(fx)), x1 = wrapX(int64_t(fx) + 1);
    const int64_t y0 = clampY(int64_t(fy)), y1 = clampY(int64_t(fy) + 1);
    const Vec3f top = im.at(x0, y0) * (1 - ax) + im.at(x1, y0) * ax;
    const Vec3f bottom = im.at(x0, y1) * (1 - ax) + im.at(x1, y1) * ax;
    return top * (1 - ay) + bottom * ay;
}

Vec3f Environment::lookup(const Vec3d& d, double blurAngle) const {
    if (!(blurAngle > 0) || levels() == 1) return sampleLevel(d, 0);
    // Level k has a texel width of 2 pi * 2^k / W radians.
    const double texel0 = 2 * M_PI / double(levels_[0].width);
    const double lk = std::clamp(std::log2(blurAngle / texel0), 0.0, double(levels() - 1));
    const int k0 = int(std::floor(lk));
    const float a = float(lk - k0);
    if (a == 0 || k0 + 1 >= levels()) return sampleLevel(d, k0);
    return sampleLevel(d, k0) * (1 - a) + sampleLevel(d, k0 + 1) * a;
}

Vec3f Environment::ambient(const Vec3d& n) const {
    int k = 0;
    while (k + 1 < levels() && levels_[size_t(k)].width > 4) ++k;
    return sampleLevel(n, k);
}

} // namespace voxfx
