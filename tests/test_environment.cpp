// Tests of src/render/environment.cpp and the HDR image readers of src/io/image.cpp: the
// equirectangular mapping against its definition, RGBE against hand-computed values, the pyramid
// against a brute-force box average, EXR read against plain OpenEXR.
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <OpenEXR/ImfRgbaFile.h>
#include <gtest/gtest.h>

#include "render/tabled_atan.hpp"
#include "test_util.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/environment_io.hpp"
#include "voxfx/image_io.hpp"

namespace voxfx {
namespace {

TEST(EnvironmentTest, EquirectMapsKnownDirectionsWhereTheDefinitionSays) {
    double u, v;
    directionToEquirect({0, 0, -1}, u, v); // the default view direction: centre of the map
    EXPECT_NEAR(u, 0.5, 1e-12);
    EXPECT_NEAR(v, 0.5, 1e-12);
    directionToEquirect({0, 1, 0}, u, v); // zenith: top row
    EXPECT_NEAR(v, 0.0, 1e-12);
    directionToEquirect({0, -2, 0}, u, v); // nadir, not unit
    EXPECT_NEAR(v, 1.0, 1e-12);
    directionToEquirect({1, 0, 0}, u, v); // +x is a quarter turn from -z: atan2(1, 0) = pi/2
    EXPECT_NEAR(u, 0.75, 1e-12);
    directionToEquirect({-1, 0, 0}, u, v);
    EXPECT_NEAR(u, 0.25, 1e-12);
}

// The table-and-series atan2 the equirectangular lookups use (render/tabled_atan.hpp) against
// libm's: within 4 ulps of the result over every octant and magnitudes 2^-30..2^30 apart, the
// table's nodes (t = k / 64) and the half-way points between them, and the same value where an
// argument is zero or infinite (signed zeros included).
TEST(EnvironmentTest, TabledAtan2IsLibmsAtan2WithinAFewUlps) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(-1, 1);
    std::uniform_int_distribution<int> scale(-30, 30);
    auto check = [](double y, double x) {
        const double want = std::atan2(y, x), got = detail::tabledAtan2(y, x);
        const double ulp = std::nextafter(std::fabs(want), INFINITY) - std::fabs(want);
        ASSERT_LE(std::fabs(got - want), 4 * ulp) << "atan2(" << y << ", " << x << ")";
    };
    for (int i = 0; i < 400000; ++i) check(std::ldexp(unit(rng), scale(rng)), unit(rng));
    for (int k = 0; k <= 128; ++k)
        for (const double sy : {1.0, -1.0})
            for (const double sx : {1.0, -1.0}) {
                check(sy * k / 128.0, sx * 1.0); // nodes (k even) and half-way (odd)
                check(sy * 1.0, sx * k / 128.0);
                check(sy * std::nextafter(k / 128.0, 1.0), sx * 3.0);
            }
    const double inf = std::numeric_limits<double>::infinity();
    for (const double y : {0.0, -0.0, 1.0, -1.0, inf, -inf})
        for (const double x : {0.0, -0.0, 2.0, -2.0, inf, -inf}) {
            const double want = std::atan2(y, x), got = detail::tabledAtan2(y, x);
            EXPECT_EQ(got, want) << y << " " << x;
            EXPECT_EQ(std::signbit(got), std::signbit(want)) << y << " " << x;
        }
}

TEST(EnvironmentTest, TexelCentresRoundTripThroughDirections) {
    const int W = 64, H = 32;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const double u0 = (i + 0.5) / W, v0 = (j + 0.5) / H;
            const Vec3d d = equirectToDirection(u0, v0);
            EXPECT_NEAR(length(d), 1.0, 1e-12);
            double u, v;
            directionToEquirect(d, u, v);
            EXPECT_EQ(int(std::floor(u * W)), i);
            EXPECT_EQ(int(std::floor(v * H)), j);
            EXPECT_NEAR(u, u0, 1e-9);
            EXPECT_NEAR(v, v0, 1e-9);
        }
    std::mt19937 rng(7);
    std::normal_distribution<double> g;
    for (int k = 0; k < 1000; ++k) {
        const Vec3d d = normalize(Vec3d{g(rng), g(rng), g(rng)});
        double u, v;
        directionToEquirect(d, u, v);
        const Vec3d back = equirectToDirection(u, v);
        EXPECT_NEAR(length(back - d), 0.0, 1e-9);
    }
}

TEST(EnvironmentTest, RgbeDecodesAsRadianceDoes) {
    // e = 129: f = 2^(129 - 136) = 1/128; channel = (byte + 0.5) / 128.
    const Vec3f a = decodeRgbe(128, 64, 0, 129);
    EXPECT_FLOAT_EQ(a.x, 128.5f / 128.0f);
    EXPECT_FLOAT_EQ(a.y, 64.5f / 128.0f);
    EXPECT_FLOAT_EQ(a.z, 0.5f / 128.0f);
    // e = 136: f = 1.
    const Vec3f b = decodeRgbe(1, 2, 255, 136);
    EXPECT_FLOAT_EQ(b.x, 1.5f);
    EXPECT_FLOAT_EQ(b.z, 255.5f);
    EXPECT_EQ(decodeRgbe(200, 100, 50, 0), (Vec3f{0, 0, 0})); // e = 0 is black whatever the bytes
}

std::string envHdrHeader(int w, int h) {
    return "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " + std::to_string(h) + " +X " + std::to_string(w) +
           "\n";
}

TEST(EnvironmentTest, HdrReadsFlatAndRunLengthScanlines) {
    test::TempDir dir;
    // Width 8: run-length scanlines are allowed. Row 0 run-length: R is a run of 8 x 128, G literal
    // 0..7, B a run of 8 x 0, E a run of 8 x 130 (f = 2^-6). Row 1 flat: pixel x = (x, 0, 0, 137).
    std::string bytes = envHdrHeader(8, 2);
    bytes += std::string("\x02\x02\x00\x08", 4);
    bytes += std::string("\x88\x80", 2);
    bytes += std::string("\x08", 1);
    for (char c = 0; c < 8; ++c) bytes += c;
    bytes += std::string("\x88\x00", 2);
    bytes += std::string("\x88\x82", 2);
    for (int x = 0; x < 8; ++x) bytes += std::string{char(x), 0, 0, char(137)};
    const std::string path = test::writeFile(dir.file("a.hdr"), bytes);
    const Image im = readHdr(path);
    ASSERT_EQ(im.width, 8);
    ASSERT_EQ(im.height, 2);
    for (int x = 0; x < 8; ++x) {
        EXPECT_FLOAT_EQ(im.at(x, 0).x, 128.5f / 64.0f);
        EXPECT_FLOAT_EQ(im.at(x, 0).y, (float(x) + 0.5f) / 64.0f);
        EXPECT_FLOAT_EQ(im.at(x, 0).z, 0.5f / 64.0f);
        EXPECT_FLOAT_EQ(im.at(x, 1).x, (float(x) + 0.5f) * 2.0f);
    }
    EXPECT_THROW(readHdr(test::writeFile(dir.file("b.hdr"), "#?RADIANCE\n\n+Y 2 +X 2\n")), Error);
    EXPECT_THROW(readHdr(test::writeFile(dir.file("c.hdr"), envHdrHeader(8, 2) + "\x02\x02")), Error);
}

TEST(EnvironmentTest, PfmReadsWhatWritePfmWrote) {
    test::TempDir dir;
    Image a(5, 3);
    for (int64_t y = 0; y < 3; ++y)
        for (int64_t x = 0; x < 5; ++x) a.at(x, y) = {float(x), float(y) * 10.0f, -1.5f};
    writePfm(a, dir.file("a.pfm"));
    const Image b = readPfm(dir.file("a.pfm"));
    ASSERT_EQ(b.width, 5);
    ASSERT_EQ(b.height, 3);
    EXPECT_EQ(a.pixels, b.pixels);
    // A big-endian grey file written by hand: 1 x 2, bottom row first: 2.0 then 0.5.
    std::string bytes = "Pf\n1 2\n1.0\n";
    bytes += std::string("\x40\x00\x00\x00\x3f\x00\x00\x00", 8);
    const Image g = readPfm(test::writeFile(dir.file("g.pfm"), bytes));
    EXPECT_EQ(g.at(0, 0), (Vec3f{0.5f, 0.5f, 0.5f}));
    EXPECT_EQ(g.at(0, 1), (Vec3f{2.0f, 2.0f, 2.0f}));
}

TEST(EnvironmentTest, ExrReadsAFileWrittenByPlainOpenExrWithAnOffsetDataWindow) {
    test::TempDir dir;
    const std::string path = dir.file("a.exr");
    {
        const Imath::Box2i display({0, 0}, {9, 9}), data({3, 2}, {6, 4}); // 4 x 3 pixels
        Imf::RgbaOutputFile out(path.c_str(), Imf::Header(display, data), Imf::WRITE_RGBA);
        std::vector<Imf::Rgba> px(12);
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 4; ++x)
                px[size_t(y * 4 + x)] = Imf::Rgba(half(float(x)), half(float(y)), half(0.25f), 1);
        out.setFrameBuffer(px.data() - 3 - 2 * 4, 1, 4);
        out.writePixels(3);
    }
    const Image im = readExr(path);
    ASSERT_EQ(im.width, 4);
    ASSERT_EQ(im.height, 3);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) EXPECT_EQ(im.at(x, y), (Vec3f{float(x), float(y), 0.25f}));
    EXPECT_EQ(readImage(path).pixels, im.pixels);
}

TEST(EnvironmentTest, PyramidLevelsAreBoxAveragesOfTheLevelBelow) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> U(0, 4);
    Image base(37, 19); // odd sizes: edge texels average fewer texels
    for (Vec3f& p : base.pixels) p = {U(rng), U(rng), U(rng)};
    const Environment env(base);
    ASSERT_GE(env.levels(), 2);
    EXPECT_EQ(env.level(env.levels() - 1).width, 1);
    EXPECT_EQ(env.level(env.levels() - 1).height, 1);
    for (int k = 1; k < env.levels(); ++k) {
        const Image& lo = env.level(k - 1);
        const Image& hi = env.level(k);
        EXPECT_EQ(hi.width, (lo.width + 1) / 2);
        EXPECT_EQ(hi.height, (lo.height + 1) / 2);
        for (int64_t j = 0; j < hi.height; ++j)
            for (int64_t i = 0; i < hi.width; ++i) {
                double sum[3] = {0, 0, 0};
                int n = 0;
                for (int64_t y = 2 * j; y <= 2 * j + 1; ++y)
                    for (int64_t x = 2 * i; x <= 2 * i + 1; ++x)
                        if (x < lo.width && y < lo.height) {
                            ++n;
                            for (int c = 0; c < 3; ++c) sum[c] += lo.at(x, y)[c];
                        }
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(hi.at(i, j)[c], sum[c] / n, 1e-5);
            }
    }
    // Power-of-two sizes: the 1 x 1 level is the mean of the whole image.
    Image pow2(16, 8);
    double mean = 0;
    for (Vec3f& p : pow2.pixels) {
        p = {U(rng), 0, 0};
        mean += p.x;
    }
    EXPECT_NEAR(Environment(pow2).average().x, mean / 128, 1e-5);
}

TEST(EnvironmentTest, BlurredLookupsApproachTheMeanAndSharpOnesTheTexel) {
    Image im(64, 32, {0.1f, 0.1f, 0.1f});
    im.at(40, 10) = {100, 100, 100};
    const Environment env(im);
    const Vec3d d = equirectToDirection(40.5 / 64, 10.5 / 32);
    EXPECT_NEAR(env.lookup(d).x, 100.0f, 1e-3f); // texel centre: bilinear gives the texel
    EXPECT_NEAR(env.lookup(d, 10.0).x, env.average().x, 1e-4f);
    EXPECT_LT(env.lookup(d, 0.3).x, 100.0f);
    EXPECT_GT(env.lookup(d, 0.3).x, env.average().x);
}

TEST(EnvironmentTest, SkyIsBrightestAtTheSunAndGroundColouredBelow) {
    SkyOptions o;
    o.width = 128;
    o.height = 64;
    o.sunAngularRadius = 0.06;
    const Environment sky = Environment::sky(o);
    const Vec3d sun = normalize(o.sunDirection);
    EXPECT_NEAR(length(sky.sunDirection() - sun), 0.0, 1e-12);
    EXPECT_GT(sky.lookup(sun).x, 10 * sky.lookup({0, 1, 0}).x);
    // Below the horizon the ground, in proportion to its albedo (test_daylight checks its value).
    const Vec3f down = sky.lookup({0, -1, 0});
    o.groundAlbedo = o.groundAlbedo * 2.0f;
    const Vec3f twice = Environment::sky(o).lookup({0, -1, 0});
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(twice[c], 2 * down[c], 1e-5f);
    EXPECT_THROW(loadEnvironment("missing-file.hdr"), Error);
    EXPECT_THROW(Environment(Image{}), Error);
}

// A map whose texel (i, j) holds f(direction of its centre).
template <class F> Environment mapOf(int W, int H, F f) {
    Image img(W, H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const double v = f(equirectToDirection((i + 0.5) / W, (j + 0.5) / H));
            img.at(i, j) = Vec3f{float(v), float(2 * v), float(0.5 * v)};
        }
    return Environment(std::move(img));
}

TEST(EnvironmentTest, UniformSkyGivesIrradiancePiLOnEveryFace) {
    // E(n) = integral of L max(0, cos) over the sphere = pi L, whatever n; from a 1 x 1 map too.
    for (const Environment& env : {mapOf(256, 128, [](const Vec3d&) { return 0.7; }),
                                   Environment(Image(1, 1, Vec3f{0.7f, 1.4f, 0.35f}))})
        for (const Vec3d n : {Vec3d{0, 1, 0}, Vec3d{0, -1, 0}, Vec3d{1, 0, 0}, Vec3d{0.3, 0.5, -0.8}}) {
            const Vec3f e = env.irradiance(n);
            EXPECT_NEAR(e.x, M_PI * 0.7, 2e-3) << n.x << "," << n.y << "," << n.z;
            EXPECT_NEAR(e.y, M_PI * 1.4, 4e-3);
            EXPECT_NEAR(e.z, M_PI * 0.35, 1e-3);
        }
}

TEST(EnvironmentTest, GradientSkyGivesTheCosineWeightedIntegral) {
    // L(d) = a + b d.y: E(up) = pi a + 2 pi b / 3, E(down) = pi a - 2 pi b / 3, E(horizontal) = pi a
    // (integrals of (a + b cos t) cos t over a hemisphere). L = d.y^2: E(up) = pi / 2, E(x) = pi / 4.
    const double a = 0.5, b = 0.3;
    const Environment linear = mapOf(256, 128, [&](const Vec3d& d) { return a + b * d.y; });
    EXPECT_NEAR(linear.irradiance({0, 1, 0}).x, M_PI * a + 2 * M_PI * b / 3, 2e-3);
    EXPECT_NEAR(linear.irradiance({0, -1, 0}).x, M_PI * a - 2 * M_PI * b / 3, 2e-3);
    EXPECT_NEAR(linear.irradiance({1, 0, 0}).x, M_PI * a, 2e-3);
    EXPECT_NEAR(linear.irradiance({0, 0, 1}).y, 2 * M_PI * a, 4e-3);
    // Tilted by t from up: pi a + 2 pi b cos(t) / 3.
    EXPECT_NEAR(linear.irradiance({std::sin(0.6), std::cos(0.6), 0}).x,
                M_PI * a + 2 * M_PI * b * std::cos(0.6) / 3, 2e-3);
    const Environment quadratic = mapOf(256, 128, [&](const Vec3d& d) { return d.y * d.y; });
    EXPECT_NEAR(quadratic.irradiance({0, 1, 0}).x, M_PI / 2, 2e-3);
    // Horizontal face: the integral of y^2 x over x > 0 is pi / 4.
    EXPECT_NEAR(quadratic.irradiance({1, 0, 0}).x, M_PI / 4, 2e-3);
}

TEST(EnvironmentTest, SunOfAMapIsItsBrightestRegion) {
    // A dim map with a bright patch around direction s: the default sun points there (within the
    // 64-texel level's resolution); a map without a bright region has no sun.
    const Vec3d s = normalize(Vec3d{-0.4, 0.6, 0.7});
    const Environment withSun =
        mapOf(512, 256, [&](const Vec3d& d) { return dot(d, s) > std::cos(0.05) ? 500.0 : 0.2 + 0.1 * d.y; });
    ASSERT_GT(length(withSun.sunDirection()), 0.5);
    EXPECT_GT(dot(withSun.sunDirection(), s), std::cos(0.1));
    const Environment overcast = mapOf(512, 256, [&](const Vec3d& d) { return 0.5 + 0.2 * d.y; });
    EXPECT_EQ(length(overcast.sunDirection()), 0.0);
}

} // namespace
} // namespace voxfx
