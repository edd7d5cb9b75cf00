// voxfx — equirectangular environment maps with a box-filtered pyramid, their ambient harmonics
// and their sun (the procedural sky: daylight.cpp).
#include "voxfx/environment.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "render/tabled_atan.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

void directionToEquirect(const Vec3d& d, double& u, double& v) {
    const double len = length(d);
    if (!(len > 0)) {
        u = v = 0.5;
        return;
    }
    // atan2 by table and series (within a few ulps of libm's, at a fraction of its cost and of
    // acos's: every background pixel and reflection comes here); the polar angle as the atan2 of
    // the horizontal length and y, which is acos(y / len) without its loss near the poles.
    u = 0.5 + detail::tabledAtan2(d.x, -d.z) / (2 * M_PI);
    v = detail::tabledAtan2(std::sqrt(d.x * d.x + d.z * d.z), d.y) / M_PI;
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
    levels_.clear();
    buildLevels(std::move(image));
    // The ambient light: the first level at most 1024 texels wide, less its sun.
    std::size_t k = 0;
    while (k + 1 < levels_.size() && levels_[k].width > 1024) ++k;
    Image ambient = levels_[k];
    extractSun(ambient);
    projectOnHarmonics(ambient);
}

void Environment::buildLevels(Image image) {
    levels_.push_back(std::move(image));
    while (levels_.back().width > 1 || levels_.back().height > 1)
        levels_.push_back(downsampleEnvironmentLevel(levels_.back()));
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

void Environment::projectOnHarmonics(const Image& im) {
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

void Environment::extractSun(Image& im) {
    sunDirection_ = {0, 0, 0};
    sunIrradiance_ = {0, 0, 0};
    const int64_t W = im.width, H = im.height;
    if (W < 8 || H < 4) return;
    std::vector<double> omega(static_cast<size_t>(H)), lum(static_cast<size_t>(W * H));
    double mean = 0, best = -1;
    int64_t bi = 0, bj = 0;
    for (int64_t j = 0; j < H; ++j) {
        omega[size_t(j)] =
            2 * M_PI / double(W) *
            (std::cos(double(j) * M_PI / double(H)) - std::cos(double(j + 1) * M_PI / double(H)));
        for (int64_t i = 0; i < W; ++i) {
            const double l = luminance(im.at(i, j));
            lum[size_t(j * W + i)] = l;
            mean += l * omega[size_t(j)];
            if (l > best) best = l, bi = i, bj = j;
        }
    }
    mean /= 4 * M_PI;
    if (!(best > 4 * mean && best > 0)) return;
    // The region: texels 8-connected to the brightest (u wraps) at least the threshold bright.
    const double threshold = std::max(4 * mean, best / 20);
    std::vector<uint8_t> state(size_t(W * H), 0); // 1: in the region, 2: around it
    std::vector<std::pair<int64_t, int64_t>> stack{{bi, bj}}, region, ring;
    state[size_t(bj * W + bi)] = 1;
    double regionOmega = 0;
    while (!stack.empty()) {
        const auto [i, j] = stack.back();
        stack.pop_back();
        region.emplace_back(i, j);
        regionOmega += omega[size_t(j)];
        if (regionOmega > 0.2) return; // a bright part of the sky, not a sun
        for (int64_t dj = -1; dj <= 1; ++dj)
            for (int64_t di = -1; di <= 1; ++di) {
                const int64_t y = j + dj, x = ((i + di) % W + W) % W;
                if (y < 0 || y >= H || state[size_t(y * W + x)] != 0) continue;
                const bool in = lum[size_t(y * W + x)] >= threshold;
                state[size_t(y * W + x)] = in ? 1 : 2;
                (in ? stack : ring).emplace_back(x, y);
            }
    }
    Vec3d around{0, 0, 0};
    double aroundOmega = 0;
    for (const auto& [i, j] : ring) {
        around += Vec3d(im.at(i, j)) * omega[size_t(j)];
        aroundOmega += omega[size_t(j)];
    }
    const Vec3f fill = aroundOmega > 0 ? Vec3f(around / aroundOmega) : Vec3f{0, 0, 0};
    Vec3d energy{0, 0, 0}, centroid{0, 0, 0};
    for (const auto& [i, j] : region) {
        const Vec3f excess = im.at(i, j) - fill;
        energy += Vec3d(excess) * omega[size_t(j)];
        centroid += equirectToDirection((double(i) + 0.5) / double(W), (double(j) + 0.5) / double(H)) *
                    (luminance(excess) * omega[size_t(j)]);
        im.at(i, j) = fill;
    }
    if (!(length(centroid) > 0)) return;
    sunDirection_ = normalize(centroid);
    sunIrradiance_ =
        Vec3f{float(std::max(0.0, energy.x)), float(std::max(0.0, energy.y)), float(std::max(0.0, energy.z))};
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

Vec3f Environment::sampleLevel(const Vec3d& d, int k) const {
    const Image& im = levels_[size_t(std::clamp(k, 0, levels() - 1))];
    double u, v;
    directionToEquirect(d, u, v);
    const double x = u * double(im.width) - 0.5, y = v * double(im.height) - 0.5;
    const double fx = std::floor(x), fy = std::floor(y);
    const float ax = float(x - fx), ay = float(y - fy);
    // u in [0, 1) puts the columns in [-1, width]: one add or subtract wraps them (the remainder,
    // an integer division each, only for what no unit direction gives).
    auto wrapX = [&](int64_t i) {
        if (i >= 0 && i < im.width) return i;
        if (i < 0 && i >= -im.width) return i + im.width;
        if (i >= im.width && i < 2 * im.width) return i - im.width;
        return ((i % im.width) + im.width) % im.width;
    };
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
