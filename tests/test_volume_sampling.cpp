// Tests of the renderer's sampling of scene volumes (src/render/volume_pass.cpp): ray casting
// composites volumes over the image and only there; a homogeneous slab against Beer–Lambert's
// closed form, with and without deep shadows; no rings (wood grain, #26 item 2) in a dense medium;
// jittered images independent of the thread count; each volume sampled at its own spacing, against
// a dense march; empty-space skipping, which skips only transparent samples and changes no pixel;
// and adaptive image-space refinement (volumeRefinement) against every pixel cast.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <utility>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "render/antialias.hpp"
#include "render/volume_pass.hpp"
#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/render.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::dsmrGroundAndSmoke;
using test::dsmrSmokeTransfer;
using test::homogeneousSlabScene;
using test::linearBlackOptions;

// Slab test of the ray eye + t d (t >= 0) against `box`: the parameter by which the ray misses it
// (the entry beyond the exit), <= 0 where it crosses.
double rayBoxGap(const Vec3d& eye, const Vec3d& d, const Box3d& box) {
    double t0 = 0, t1 = 1e30;
    for (int a = 0; a < 3; ++a) {
        double ta = (box.lo[a] - eye[a]) / d[a], tb = (box.hi[a] - eye[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 - t1;
}

TEST(DeepShadowRenderTest, RayCastingCompositesVolumesOverTheImageAndOnlyThere) {
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.shadow = NoShadowOptions{}; // the smoke's shadow on the ground is tested above
    o.background = {0, 0, 0};
    o.antiAliasing = AntiAliasing::Off; // one sample per pixel with and without the volume pass
    o.exposure = 1;                     // fixed: the two renders are compared pixel by pixel
    const RenderResult with = render(dsmrGroundAndSmoke(true), dsmrGroundAndSmoke(true).cameras[0], o);
    const RenderResult without = render(dsmrGroundAndSmoke(false), dsmrGroundAndSmoke(false).cameras[0], o);
    EXPECT_GT(with.volumeSamples, 1000);
    EXPECT_EQ(without.volumeSamples, 0);
    // Pixels whose camera ray misses the smoke's box are identical; some through it differ.
    const Frame cam = cameraFrame(dsmrGroundAndSmoke(true).cameras[0], 64, 48);
    const Box3d box{{-1, 0.5, -1}, {1, 1.5, 1}};
    int64_t differ = 0, same = 0;
    for (int64_t y = 0; y < 48; ++y)
        for (int64_t x = 0; x < 64; ++x) {
            const Vec3d eye = cam.eye(), p = cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0});
            const double gap = rayBoxGap(eye, p - eye, box);
            const Vec3f a = with.image.at(x, 47 - y), b = without.image.at(x, 47 - y);
            const bool diff = a.x != b.x || a.y != b.y || a.z != b.z;
            if (gap > 1e-3) {
                same += !diff;
                EXPECT_FALSE(diff) << x << ", " << y;
            } else {
                differ += diff;
            }
        }
    EXPECT_GT(differ, 50);
    EXPECT_GT(same, 500);
}

// ---- volume sampling: no wood grain (#26 item 2) -------------------------------------------------

// A homogeneous volume (every voxel 1; white, opacity 0.3 per 0.1 world units) filling the slab
// [-1, 1] x [0, 0.5] x [-1, 1], or a ball of radius 0.9 about (0, 0.25, 0), under a slanted sun,
// seen from above; the images are composited over black without ambient light.
constexpr double kUniformOpacity = 0.3, kUniformSun = 3;

Scene dsmrUniformScene(bool ball, double opacityLength) {
    Scene s = homogeneousSlabScene(kUniformOpacity, opacityLength, kUniformSun);
    if (!ball) return s;
    s.cameras[0].fovY = 0.45;
    const double h = 1.0 / 16;
    auto v = std::make_shared<Volume>(Vec3i{32, 32, 32}, Vec3d{-1, -0.75, -1}, Vec3d{h, h, h});
    std::fill(v->values().begin(), v->values().end(), 1.0f);
    auto vs = std::make_shared<VolumeScene>();
    VolumeSceneObject o;
    o.name = "ball";
    o.kind = ObjectKind::Volume;
    o.shape = vs->addLeaf(test::makeUvSphere({0, 0.25, 0}, 0.9, 48, 96));
    vs->volumes.push_back(v);
    o.volume = 0;
    o.transfer =
        TransferFunction({{0, {1, 1, 1}}, {2, {1, 1, 1}}}, {{0, kUniformOpacity}, {2, kUniformOpacity}});
    o.opacityLength = opacityLength;
    vs->addObject(o);
    s.volumeScene = vs;
    return s;
}

RenderOptions dsmrUniformOptions(bool deep, double epsilon = DeepShadowOptions{}.epsilon) {
    RenderOptions o = linearBlackOptions(96, 72); // what the closed form describes
    if (deep) {
        DeepShadowOptions d;
        d.resolution = 96;
        d.epsilon = epsilon;
        o.shadow = d;
    }
    return o;
}

// The slab's pixels whose ray enters through the top well inside and leaves through the bottom,
// with Beer-Lambert's closed form for each: through the slab (no shadows), and with the light
// itself attenuated on its way down from the top face (deep shadows). Returns (image value, closed
// form, closed form without shadows) per pixel.
struct DsmrSlabPixel {
    double value, deep, unshadowed;
};
std::vector<DsmrSlabPixel> dsmrSlabPixels(const Scene& s, const Image& image, double opacityLength) {
    const Frame cam = cameraFrame(s.cameras[0], image.width, image.height);
    const double sigma = -std::log(1 - kUniformOpacity) / opacityLength;
    const double cosL = std::abs(normalize(s.lights[0].direction).y);
    std::vector<DsmrSlabPixel> out;
    for (int64_t y = 0; y < image.height; ++y)
        for (int64_t x = 0; x < image.width; ++x) {
            const Vec3d eye = cam.eye();
            const Vec3d d = normalize(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
            const double tTop = (0.5 - eye.y) / d.y, tBottom = (0.0 - eye.y) / d.y;
            const Vec3d top = eye + d * tTop, bottom = eye + d * tBottom;
            if (std::max(std::abs(top.x), std::abs(top.z)) > 0.55 ||
                std::max(std::abs(bottom.x), std::abs(bottom.z)) > 0.55)
                continue;
            const double len = tBottom - tTop, cosC = std::abs(d.y), k = 1 + cosC / cosL;
            const double e = kUniformSun / M_PI;
            out.push_back({double(image.at(x, image.height - 1 - y).x),
                           e / k * (1 - std::exp(-sigma * k * len)), e * (1 - std::exp(-sigma * len))});
        }
    return out;
}

TEST(VolumeSamplingTest, AHomogeneousSlabMatchesBeerLambertsClosedForm) {
    const double len = 0.5; // optical depth 0.36 straight down
    const Scene s = dsmrUniformScene(false, len);
    const RenderResult lit = render(s, s.cameras[0], dsmrUniformOptions(false));
    const std::vector<DsmrSlabPixel> px = dsmrSlabPixels(s, lit.image, len);
    ASSERT_GT(px.size(), 1000u);
    double worst = 0;
    for (const DsmrSlabPixel& p : px) worst = std::max(worst, std::abs(p.value - p.unshadowed));
    EXPECT_LT(worst, 1e-4); // the pre-integrated intervals compose to Beer-Lambert exactly
    // Under deep shadows (epsilon 0.01) the light in the slab is Beer-Lambert from the top face
    // too: within about epsilon of the closed form. (The lookup a step towards the light, which keeps
    // a dense layer from shadowing its own front, made it 8.9 % brighter until the medium over that
    // step was put back.)
    const double epsilon = 0.01;
    const RenderResult deep = render(s, s.cameras[0], dsmrUniformOptions(true, epsilon));
    double meanErr = 0, worstDeep = 0;
    for (const DsmrSlabPixel& p : dsmrSlabPixels(s, deep.image, len)) {
        meanErr += std::abs(p.value - p.deep) / p.deep;
        worstDeep = std::max(worstDeep, std::abs(p.value - p.deep) / p.deep);
    }
    meanErr /= double(px.size());
    std::printf("slab: unshadowed worst %.3g, deep (epsilon %.2f) mean relative error %.4f, worst %.4f\n",
                worst, epsilon, meanErr, worstDeep);
    EXPECT_LT(meanErr, 1.2 * epsilon);
    EXPECT_LT(worstDeep, 2.5 * epsilon);
}

// #37: exact shadows are the reference every shadow kind is measured against, so in a volume they
// must be Beer-Lambert's closed form: the light in the homogeneous slab falls from the top face as
// exp(-sigma d / cos), integrated along the camera ray (dsmrSlabPixels). They were looked up a
// sample step towards the light, as the shadow maps are, which lit every sample as if it lay that
// step higher in the slab (4.2 % brighter), until the medium over that step was put back.
TEST(VolumeSamplingTest, ExactShadowsInAHomogeneousSlabMatchBeerLambertsClosedForm) {
    const double len = 0.5; // optical depth 0.36 straight down
    const Scene s = dsmrUniformScene(false, len);
    RenderOptions o = dsmrUniformOptions(false);
    o.shadow = ExactShadowOptions{};
    const RenderResult r = render(s, s.cameras[0], o);
    const std::vector<DsmrSlabPixel> px = dsmrSlabPixels(s, r.image, len);
    ASSERT_GT(px.size(), 1000u);
    double meanErr = 0, worst = 0, signedErr = 0;
    for (const DsmrSlabPixel& p : px) {
        const double e = (p.value - p.deep) / p.deep;
        meanErr += std::abs(e) / double(px.size());
        signedErr += e / double(px.size());
        worst = std::max(worst, std::abs(e));
    }
    std::printf("slab under exact shadows: mean relative error %.5f (signed %+.5f), worst %.5f\n", meanErr,
                signedErr, worst);
    EXPECT_LT(meanErr, 1e-3); // 8e-5; main: 0.042
    EXPECT_LT(worst, 1e-3);
}

// Rings are a pattern from pixel to pixel: the residual of each pixel against the mean of its
// eight neighbours, its root mean square over the pixels of `keep` (all neighbours kept too),
// relative to their mean value.
double dsmrRingContrast(const Image& image, const std::vector<uint8_t>& keep) {
    const int64_t W = image.width, H = image.height;
    double sum = 0, sum2 = 0;
    int64_t n = 0;
    for (int64_t y = 1; y + 1 < H; ++y)
        for (int64_t x = 1; x + 1 < W; ++x) {
            bool all = true;
            double mean = 0;
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx) {
                    all = all && keep[std::size_t((y + dy) * W + x + dx)];
                    if (dx || dy) mean += double(image.at(x + dx, y + dy).x) / 8;
                }
            if (!all) continue;
            const double v = image.at(x, y).x;
            sum += v;
            sum2 += (v - mean) * (v - mean);
            ++n;
        }
    EXPECT_GT(n, 500);
    return std::sqrt(sum2 / double(n)) / (sum / double(n));
}

// A dense medium (opacity 0.3 per 0.01 units: a step of 1/16 stops 89 %), where the light falls
// fast across the visible layer: samples at equal steps from each ray's entry drew its fall as
// rings.
TEST(VolumeSamplingTest, AUniformSlabAndBallShowNoRingsUnderDeepShadows) {
    for (const bool ball : {false, true}) {
        const Scene s = dsmrUniformScene(ball, 0.01);
        const RenderOptions o = dsmrUniformOptions(true);
        const RenderResult r = render(s, s.cameras[0], o);
        std::vector<uint8_t> keep(std::size_t(o.width * o.height), 0);
        const Frame cam = cameraFrame(s.cameras[0], o.width, o.height);
        for (int64_t y = 0; y < o.height; ++y)
            for (int64_t x = 0; x < o.width; ++x) {
                const Vec3d eye = cam.eye();
                const Vec3d d = normalize(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
                bool in = false;
                if (ball) { // rays passing well inside the ball
                    const Vec3d c{0, 0.25, 0};
                    in = length(c - (eye + d * dot(c - eye, d))) < 0.6;
                } else {
                    const Vec3d top = eye + d * ((0.5 - eye.y) / d.y), bottom = eye + d * (-eye.y / d.y);
                    in = std::max({std::abs(top.x), std::abs(top.z), std::abs(bottom.x),
                                   std::abs(bottom.z)}) < 0.55;
                }
                keep[std::size_t((o.height - 1 - y) * o.width + x)] = in;
            }
        const double contrast = dsmrRingContrast(r.image, keep);
        std::printf("%s: ring contrast %.5f\n", ball ? "ball" : "slab", contrast);
        // Equal unjittered steps gave 0.020 (slab) and 0.055 (ball); jittered, 0.0003 and 0.011;
        // with the medium over the lookup's step put back (#37), 0.0015 and 0.013. Putting it back at
        // the mean extinction of the step's two ends (d9cb3bd, reverted: it speckled the DSM demo's
        // skull) gave the ball 0.022.
        EXPECT_LT(contrast, ball ? 0.017 : 0.005) << (ball ? "ball" : "slab");
    }
}

TEST(VolumeSamplingTest, JitteredImagesAreTheSameForOneAndAllThreads) {
    const Scene s = dsmrUniformScene(true, 0.05);
    RenderOptions o = dsmrUniformOptions(true);
    o.threads = 1;
    const RenderResult one = render(s, s.cameras[0], o);
    o.threads = 0;
    const RenderResult all = render(s, s.cameras[0], o);
    EXPECT_GT(one.volumeSamples, 1000);
    EXPECT_EQ(one.volumeSamples, all.volumeSamples);
    EXPECT_EQ(one.image.pixels, all.image.pixels);
}

// ---- each volume at its own spacing (#34) --------------------------------------------------------

// Smoke (32³ voxels of 1/16 in [0.1, 2.1] x [-1, 1] x [-1, 1]) and, when `fine`, a uniform block of
// 1/64 voxels left of it ([-1.5, -1] x [-0.25, 0.25] x [-0.25, 0.25]), both black (they only absorb),
// seen from the front over a white background: a pixel is the transmittance of its ray.
constexpr double kFineSpacing = 1.0 / 64, kSmokeSpacing = 2.0 / 32;

Scene twoSpacingsScene(bool fine) {
    Scene s;
    Camera c;
    c.position = {0.3, 0.2, 5};
    c.target = {0.3, 0, 0};
    c.fovY = 0.55;
    s.cameras.push_back(c);
    const TransferFunction black({{0, {0, 0, 0}}, {1, {0, 0, 0}}}, {{0, 0}, {0.1, 0}, {1, 0.8}});
    auto vs = std::make_shared<VolumeScene>();
    SmokeParams sp;
    sp.dims = {32, 32, 32};
    sp.box = {{0.1, -1, -1}, {2.1, 1, 1}};
    vs->addVolumeBox(std::make_shared<Volume>(makeSmoke(sp)), black, 0.25, "smoke");
    if (fine) {
        auto v = std::make_shared<Volume>(Vec3i{32, 32, 32}, Vec3d{-1.5, -0.25, -0.25},
                                          Vec3d{kFineSpacing, kFineSpacing, kFineSpacing});
        std::fill(v->values().begin(), v->values().end(), 0.5f);
        vs->addVolumeBox(v, black, 0.25, "fine");
    }
    s.volumeScene = vs;
    return s;
}

RenderOptions twoSpacingsOptions() {
    RenderOptions o = linearBlackOptions(96, 64);
    o.background = {1, 1, 1};
    o.volumeShading = VolumeShading::None; // no white highlights: black volumes only absorb
    return o;
}

// The ray of pixel (x, y) (image rows, y down) and whether it crosses `box`.
bool twoSpacingsRayCrosses(const Frame& cam, int64_t x, int64_t y, const Box3d& box, Vec3d& from, Vec3d& to) {
    from = cam.eye();
    to = cam.worldFromGrid({double(x) + 0.5, double(cam.height() - 1 - y) + 0.5, 1.0});
    const Vec3d d = to - from;
    to = from + d * 20.0;
    return rayBoxGap(from, d, box) <= 1e-6;
}

// A volume is sampled at its own spacing whatever other volumes the scene holds: the smoke's pixels
// are the same with the fine block beside it (main sampled every volume at the finest spacing of
// any, 1/64 here: four times the smoke's samples, and other pixels).
TEST(VolumeSamplingTest, EachVolumeIsSampledAtItsOwnSpacingWhateverElseTheSceneHolds) {
    const RenderOptions o = twoSpacingsOptions();
    const Scene both = twoSpacingsScene(true), alone = twoSpacingsScene(false);
    const RenderResult a = render(both, both.cameras[0], o), b = render(alone, alone.cameras[0], o);
    // The smoke alone at the fine block's step, as main sampled it beside the block: what the
    // comparison below would see if the block set the smoke's step.
    RenderOptions finer = o;
    finer.volumeStep = kFineSpacing / kSmokeSpacing;
    const RenderResult c = render(alone, alone.cameras[0], finer);
    const Frame cam = cameraFrame(both.cameras[0], o.width, o.height);
    const Box3d fineBox{{-1.5, -0.25, -0.25}, {-1, 0.25, 0.25}}, smokeBox{{0.1, -1, -1}, {2.1, 1, 1}};
    int64_t smokePixels = 0, finePixels = 0, differAtTheFineStep = 0;
    for (int64_t y = 0; y < o.height; ++y)
        for (int64_t x = 0; x < o.width; ++x) {
            Vec3d from, to;
            const bool fine = twoSpacingsRayCrosses(cam, x, y, fineBox, from, to);
            finePixels += fine && a.image.at(x, y).x < 0.99f;
            if (fine || !twoSpacingsRayCrosses(cam, x, y, smokeBox, from, to)) continue;
            smokePixels += b.image.at(x, y).x < 0.99f;
            differAtTheFineStep += c.image.at(x, y).x != b.image.at(x, y).x;
            EXPECT_EQ(a.image.at(x, y).x, b.image.at(x, y).x) << x << ", " << y;
        }
    EXPECT_GT(smokePixels, 300);
    EXPECT_GT(finePixels, 20);
    EXPECT_GT(differAtTheFineStep, smokePixels / 2);
}

// The smoke's transmittance at its own spacing against a dense midpoint march (every 1/512, the
// reference of tests/support/volume_reference.hpp), and at the fine block's spacing (what main took
// for it beside the block): measured 0.0002 mean, 0.0047 worst at its own spacing against
// 0.00001 and 0.0003 at the fine one; transmittance, so absolute.
TEST(VolumeSamplingTest, AVolumeAtItsOwnSpacingMatchesADenseMarch) {
    const Scene alone = twoSpacingsScene(false);
    const Frame cam = cameraFrame(alone.cameras[0], 96, 64);
    const Box3d smokeBox{{0.1, -1, -1}, {2.1, 1, 1}};
    double worst[2] = {0, 0}, sum[2] = {0, 0};
    int64_t n = 0;
    for (int k = 0; k < 2; ++k) {
        RenderOptions o = twoSpacingsOptions();
        if (k == 1) o.volumeStep = kFineSpacing / kSmokeSpacing; // main's step beside the fine block
        o.volumeRefinement = 0; // every pixel cast: the march itself (VolumeRefinementTest: the rest)
        const RenderResult r = render(alone, alone.cameras[0], o);
        n = 0;
        for (int64_t y = 0; y < o.height; y += 2)
            for (int64_t x = 0; x < o.width; x += 2) {
                Vec3d from, to;
                if (!twoSpacingsRayCrosses(cam, x, y, smokeBox, from, to)) continue;
                const double ref = test::dsmrReferenceTransmittance(*alone.volumeScene, from, to, 1.0 / 512);
                if (ref < 0) continue; // the ray grazes an edge of the box
                const double e = std::abs(double(r.image.at(x, y).x) - ref);
                worst[k] = std::max(worst[k], e);
                sum[k] += e;
                ++n;
            }
    }
    ASSERT_GT(n, 150);
    std::printf("smoke against a dense march: own spacing (1/16) mean %.5f worst %.5f; "
                "the fine block's (1/64) mean %.5f worst %.5f\n",
                sum[0] / double(n), worst[0], sum[1] / double(n), worst[1]);
    EXPECT_LT(worst[0], 0.01);
    EXPECT_LT(sum[0] / double(n), 0.001);
}

TEST(DeepShadowEmptySpaceTest, SkippedSamplesAreTransparentAndSkippingChangesNoPixel) {
    // maxOpacity against the opacity sampled densely over random intervals (an upper bound that
    // the curve reaches).
    const TransferFunction tf = dsmrSmokeTransfer();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-0.3, 1.3);
    for (int i = 0; i < 200; ++i) {
        double a = u(rng), b = u(rng);
        if (a > b) std::swap(a, b);
        double dense = 0;
        for (int k = 0; k <= 400; ++k)
            dense = std::max(dense, tf.opacity(std::min(b, a + (b - a) * k / 400.0)));
        EXPECT_GE(tf.maxOpacity(a, b), dense);
        EXPECT_LE(tf.maxOpacity(a, b), dense + 0.6 * (b - a) / 400.0 / 0.9 + 1e-12);
    }
    // Every point the brick map calls empty samples to opacity 0 (random points, and points on
    // brick and voxel boundaries); the map is not trivially "never".
    SmokeParams sp;
    sp.dims = {21, 18, 20};
    sp.box = {{-1, 0.5, -1}, {1, 1.5, 1}};
    const Volume smoke = makeSmoke(sp);
    Volume turned = smoke; // and the same turned 40 degrees about z (about its lo corner)
    const double c = std::cos(0.7), n = std::sin(0.7);
    turned.setAxes({c, n, 0}, {-n, c, 0}, {0, 0, 1});
    for (const Volume* v : {&smoke, static_cast<const Volume*>(&turned)}) {
        const EmptySpace es(*v, tf);
        EXPECT_GT(es.emptyFraction(), 0.2);
        const Box3d box = v->box();
        std::uniform_real_distribution<double> x(box.lo.x, box.hi.x), y(box.lo.y, box.hi.y),
            fz(box.lo.z, box.hi.z);
        int64_t empty = 0;
        for (int i = 0; i < 20000; ++i) {
            Vec3d p{x(rng), y(rng), fz(rng)};
            if (i % 2) { // snap one voxel coordinate to a voxel boundary (every brick boundary is one)
                const int a = (i / 2) % 3;
                const double w = v->view().voxelCoordinate(p, a);
                p = p + v->axis(a) * ((std::round(w) - w) * v->spacing()[a]);
            }
            if (!es.empty(p)) continue;
            ++empty;
            ASSERT_EQ(tf.opacity(v->sample(p)), 0.0) << p.x << ", " << p.y << ", " << p.z;
        }
        EXPECT_GT(empty, 2000);
    }
    // Runs of empty bricks along rays (emptyRun, the camera's march leaps over them) against the
    // point test: every point of the ray before the run's end is in an empty brick, and just past
    // its end (unless it reached maxLength) the ray is in a brick that is not empty or outside the
    // box. Rays from random points in random directions, in both volumes.
    for (const Volume* v : {&smoke, static_cast<const Volume*>(&turned)}) {
        const EmptySpace es(*v, tf);
        const VolumeView view = v->view();
        const auto outside = [&](const Vec3d& p) {
            const int64_t dims[3] = {view.nx, view.ny, view.nz};
            for (int a = 0; a < 3; ++a) {
                const double w = view.voxelCoordinate(p, a);
                if (!(w >= 0 && w <= double(dims[a]))) return true;
            }
            return false;
        };
        const Box3d box = v->box();
        std::uniform_real_distribution<double> x(box.lo.x, box.hi.x), y(box.lo.y, box.hi.y),
            fz(box.lo.z, box.hi.z), d(-1, 1);
        int64_t runs = 0, ended = 0;
        for (int i = 0; i < 4000; ++i) {
            const Vec3d p{x(rng), y(rng), fz(rng)};
            Vec3d dir{d(rng), d(rng), d(rng)};
            if (length(dir) < 0.1) continue;
            dir = normalize(dir);
            const double maxLength = 1.5;
            const double run = es.emptyRun(p, dir, maxLength);
            if (outside(p) || !es.empty(p)) {
                EXPECT_EQ(run, 0.0);
                continue;
            }
            ASSERT_GT(run, 0.0);
            ++runs;
            for (int k = 0; k < 400; ++k) {
                const Vec3d q = p + dir * (run * (1 - 1e-9) * k / 400.0);
                ASSERT_TRUE(es.empty(q) && !outside(q)) << i << ": " << k;
            }
            if (run < maxLength) {
                const Vec3d q = p + dir * (run + 1e-7);
                EXPECT_TRUE(outside(q) || !es.empty(q)) << i;
                ended += !outside(q);
            }
        }
        EXPECT_GT(runs, 500);
        EXPECT_GT(ended, 50); // runs that end at a brick with matter, not at the box's side
    }
    // Rendering and deep shadows with and without skipping (the camera's leaps over empty runs
    // included): the same pixels, fewer samples.
    const Scene scene = dsmrGroundAndSmoke(true);
    RenderOptions o;
    o.width = 48;
    o.height = 36;
    DeepShadowOptions deep;
    deep.resolution = 48;
    o.shadow = deep;
    const RenderResult skipping = render(scene, scene.cameras[0], o);
    setRenderOption(o, "emptySpaceSkipping", false); // the camera's ray casting and the deep shadows
    const RenderResult sampling = render(scene, scene.cameras[0], o);
    EXPECT_LT(skipping.volumeSamples, sampling.volumeSamples);
    EXPECT_EQ(std::get<DeepShadowStats>(skipping.shadowStats).nodes,
              std::get<DeepShadowStats>(sampling.shadowStats).nodes);
    EXPECT_EQ(skipping.image.pixels, sampling.image.pixels);
}

// The lattice cells the volume pass skips without sampling (EmptySpace::transparentBetweenVoxel: both
// ends in cells of the sample lattice that share a centre and whose centres all have opacity 0):
// for pairs of points within a step of each other (random, some on voxel boundaries, in an upright
// and a turned smoke), wherever it holds, the pre-integrated extinction of the two samples is exactly
// 0 and the opacity is 0 at 200 values between them; it holds for many pairs the bricks do not skip
// (finer than EmptySpace::emptyBetween), and never for a point outside the box. The rendering test
// above (the same pixels with and without skipping) covers the march that uses it.
TEST(DeepShadowEmptySpaceTest, TransparentLatticeCellsHoldOnlyTransparentIntervals) {
    const TransferFunction tf = dsmrSmokeTransfer();
    const PreintegratedTransfer pre(tf, 0.1);
    SmokeParams sp;
    sp.dims = {21, 18, 20};
    sp.box = {{-1, 0.5, -1}, {1, 1.5, 1}};
    const Volume smoke = makeSmoke(sp);
    Volume turned = smoke;
    const double c = std::cos(0.7), n = std::sin(0.7);
    turned.setAxes({c, n, 0}, {-n, c, 0}, {0, 0, 1});
    std::mt19937 rng(23);
    for (const Volume* v : {&smoke, static_cast<const Volume*>(&turned)}) {
        const EmptySpace es(*v, tf);
        const VolumeView view = v->view();
        const Vec3i d = v->dims();
        std::uniform_real_distribution<double> u01(0, 1), step(-1.2, 1.2);
        int64_t held = 0, finer = 0;
        for (int i = 0; i < 40000; ++i) {
            Vec3d w{u01(rng) * d.x, u01(rng) * d.y, u01(rng) * d.z};
            if (i % 2) w[i / 2 % 3] = std::round(w[i / 2 % 3]); // a voxel boundary
            const Vec3d wq = w + Vec3d{step(rng), step(rng), step(rng)};
            const Vec3d p = v->worldFromVoxel(w), q = v->worldFromVoxel(wq);
            const Vec3d up = view.voxelCoordinates(p), uq = view.voxelCoordinates(q);
            if (!es.transparentBetweenVoxel(up, uq)) continue;
            ++held;
            finer += !es.emptyBetween(p, q);
            const double a = v->sample(p), b = v->sample(q);
            ASSERT_EQ(pre.extinction(a, b), 0.0) << w.x << " " << w.y << " " << w.z << ": " << a << ", " << b;
            for (int k = 0; k <= 200; ++k) ASSERT_EQ(tf.opacity(a + (b - a) * k / 200.0), 0.0);
        }
        std::printf(
            "transparent lattice cells: %lld of 40000 pairs, %lld of them not skipped by the bricks\n",
            (long long)held, (long long)finer);
        EXPECT_GT(held, 4000);
        EXPECT_GT(finer, 1000);
        // A point outside the box (its sample reads 0, which is transparent here) is left to the bricks.
        const Vec3d in = view.voxelCoordinates(v->worldFromVoxel({0.2, 0.2, 0.2}));
        EXPECT_FALSE(
            es.transparentBetweenVoxel(view.voxelCoordinates(v->worldFromVoxel({-0.1, 0.2, 0.2})), in));
    }
}

// ---- adaptive image-space refinement (#34) -------------------------------------------------------

// The ground and smoke (dsmrGroundAndSmoke) with a thin opaque pillar standing in front of the smoke
// ([-0.03, 0.03] x [0, 2.2] x [1.3, 1.36]: about two pixels wide at 160 x 120), under deep shadows.
constexpr double kPillarHalfWidth = 0.03;
const Box3d kPillar{{-kPillarHalfWidth, 0, 1.3}, {kPillarHalfWidth, 2.2, 1.36}};
const Box3d kRefinementSmoke{{-1, 0.5, -1}, {1, 1.5, 1}};

Scene pillarAndSmokeScene() {
    Scene s = dsmrGroundAndSmoke(true);
    Material m;
    m.baseColor = {0.7f, 0.2f, 0.2f};
    SceneMesh pillar;
    pillar.name = "pillar";
    pillar.mesh = boxMesh(kPillar);
    pillar.material = s.addMaterial(m);
    s.meshes.push_back(pillar);
    return s;
}

RenderOptions refinementOptions(double threshold) {
    RenderOptions o;
    o.width = 160;
    o.height = 120;
    DeepShadowOptions deep;
    deep.resolution = 96;
    o.shadow = deep;
    o.exposure = 1; // fixed: the images are compared pixel by pixel
    o.volumeRefinement = threshold;
    return o;
}

// The pixels (cells without anti-aliasing; x and y counted from the bottom left) refinement
// interpolates pixel (x, y) from, as RenderOptions::volumeRefinement describes its lattice: none for
// the pixels cast first (x and y multiples of 4); for the others the two h apart along x (y a multiple
// of 2h), along y (x a multiple of 2h) or the four diagonal ones, h = 2 where x and y are even, else 1.
std::vector<std::pair<int64_t, int64_t>> latticeNeighbours(int64_t x, int64_t y) {
    if (x % 4 == 0 && y % 4 == 0) return {};
    const int64_t h = x % 2 == 0 && y % 2 == 0 ? 2 : 1;
    if ((y / h) % 2 == 0) return {{x - h, y}, {x + h, y}};
    if ((x / h) % 2 == 0) return {{x, y - h}, {x, y + h}};
    return {{x - h, y - h}, {x + h, y - h}, {x - h, y + h}, {x + h, y + h}};
}

// Without anti-aliasing (one ray per pixel, no post-process): a pixel the pass interpolates takes the
// pixels of its lattice neighbours (latticeNeighbours) only where no edge lies between. The
// oracle for where edges lie is the geometry itself: each pixel's ray tested against the pillar's
// and the smoke box's boxes (slabs). Every pixel off the coarsest lattice whose ray and one of its
// lattice neighbours' are on different sides of the pillar or of the box must be cast: identical to
// the image with every pixel cast. Elsewhere the image
// stays within 0.05 of it (the refinement's threshold is in shown luma; the smoke's light varies
// smoothly but its jittered samples differ from pixel to pixel), and most pixels through the smoke
// are interpolated, with fewer volume samples.
TEST(VolumeRefinementTest, NoPixelIsInterpolatedAcrossAMeshOrVolumeEdge) {
    const Scene s = pillarAndSmokeScene();
    RenderOptions exactOptions = refinementOptions(0), fastOptions = refinementOptions(1.0 / 64);
    exactOptions.antiAliasing = fastOptions.antiAliasing = AntiAliasing::Off;
    const RenderResult exact = render(s, s.cameras[0], exactOptions);
    const RenderResult fast = render(s, s.cameras[0], fastOptions);
    EXPECT_EQ(exact.volumeInterpolated, 0);
    const int64_t W = 160, H = 120;
    const Frame cam = cameraFrame(s.cameras[0], W, H);
    // Per pixel (y up): -1 when the ray clearly misses `box`, +1 when it clearly crosses it, 0 near
    // its silhouette (where the rasterized lists and the slab test may disagree).
    const auto side = [&](const Box3d& box, int64_t x, int64_t y) {
        const Vec3d eye = cam.eye(), p = cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0});
        const double gap = rayBoxGap(eye, p - eye, box) / length(p - eye);
        return gap > 1e-4 ? -1 : gap < -1e-4 ? 1 : 0;
    };
    int64_t throughSmoke = 0, edgePixels = 0;
    double worst = 0;
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const Vec3f a = fast.image.at(x, H - 1 - y), b = exact.image.at(x, H - 1 - y);
            const double d = std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z)});
            worst = std::max(worst, d);
            throughSmoke += side(kRefinementSmoke, x, y) > 0 && side(kPillar, x, y) < 0;
            const auto neighbours = latticeNeighbours(x, y);
            if (neighbours.empty()) continue; // on the coarsest lattice: always cast
            bool acrossAnEdge = false;
            for (const auto& [nx, ny] : neighbours) {
                if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                for (const Box3d* box : {&kPillar, &kRefinementSmoke}) {
                    const int own = side(*box, x, y), other = side(*box, nx, ny);
                    acrossAnEdge |= own != 0 && other != 0 && own != other;
                }
            }
            if (!acrossAnEdge) continue;
            ++edgePixels;
            EXPECT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z) << x << ", " << y << ": " << d;
        }
    std::printf("refinement, no AA: %lld of %lld pixels through the smoke interpolated, %lld edge pixels "
                "cast; samples %lld against %lld; worst difference %.4f\n",
                (long long)fast.volumeInterpolated, (long long)throughSmoke, (long long)edgePixels,
                (long long)fast.volumeSamples, (long long)exact.volumeSamples, worst);
    EXPECT_GT(edgePixels, 100);
    EXPECT_GT(fast.volumeInterpolated, throughSmoke / 2);
    EXPECT_LT(double(fast.volumeSamples), 0.6 * double(exact.volumeSamples));
    EXPECT_LT(worst, 0.05);
}

// With adaptive anti-aliasing, the default: the image with refinement against the image with every
// pixel cast (the same anti-aliasing), mean and worst absolute difference per channel, and the
// volume samples it saves.
TEST(VolumeRefinementTest, WithAntiAliasingTheImageStaysCloseToEveryPixelCast) {
    const Scene s = pillarAndSmokeScene();
    const RenderResult exact = render(s, s.cameras[0], refinementOptions(0));
    const RenderResult fast = render(s, s.cameras[0], refinementOptions(1.0 / 64));
    double sum = 0, worst = 0;
    int64_t changed = 0;
    for (std::size_t i = 0; i < exact.image.pixels.size(); ++i) {
        const Vec3f a = fast.image.pixels[i], b = exact.image.pixels[i];
        const double d = std::max({std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(a.z - b.z)});
        sum += d, worst = std::max(worst, d), changed += d > 0;
    }
    const double mean = sum / double(exact.image.pixels.size());
    std::printf("refinement with AA: %lld interpolated, %lld pixels changed, mean %.5f, worst %.4f; samples "
                "%lld against %lld\n",
                (long long)fast.volumeInterpolated, (long long)changed, mean, worst,
                (long long)fast.volumeSamples, (long long)exact.volumeSamples);
    EXPECT_GT(fast.volumeInterpolated, 1000);
    EXPECT_LT(double(fast.volumeSamples), 0.7 * double(exact.volumeSamples));
    EXPECT_LT(mean, 0.003);
    EXPECT_LT(worst, 0.08);
}

// A CT-like volume (the DSM demo's skull in small): a ball of radius kHeadRadius about kHeadCentre
// whose value rises from 0 to 4 over kHeadRamp across its surface (the skull's transfer function:
// transparent below 2.8, 0.95 per 0.02 units from 2.95), less a cavity open towards the camera (an
// edge of matter in front of matter further away), 40^3 voxels of 0.05 over the ground under the sun,
// seen from (0, 3.2, 3.2): its silhouette lies against the ground.
const Vec3d kHeadCentre{0, 1, 0};
constexpr double kHeadRadius = 0.6, kHeadRamp = 0.1;

Scene ctLikeScene() {
    Scene s = test::sunlitGroundScene();
    s.cameras[0].position = {0, 3.2, 3.2};
    s.cameras[0].target = kHeadCentre;
    const double h = 0.05;
    auto v = std::make_shared<Volume>(Vec3i{40, 40, 40}, Vec3d{-1, 0, -1}, Vec3d{h, h, h});
    const Vec3d cavity{0.25, 1.25, 0.45};
    for (int64_t k = 0; k < 40; ++k)
        for (int64_t j = 0; j < 40; ++j)
            for (int64_t i = 0; i < 40; ++i) {
                const Vec3d p = v->worldFromVoxel({double(i) + 0.5, double(j) + 0.5, double(k) + 0.5});
                const auto ramp = [](double inside) {
                    return 4 * std::clamp(inside / kHeadRamp + 0.5, 0.0, 1.0);
                };
                v->at(i, j, k) = float(
                    std::min(ramp(kHeadRadius - length(p - kHeadCentre)), ramp(length(p - cavity) - 0.25)));
            }
    const TransferFunction tf({{2.8, {0.9, 0.85, 0.75}}, {4.0, {1.0, 0.97, 0.9}}},
                              {{2.8, 0.0}, {2.95, 0.95}, {6.0, 1.0}});
    auto vs = std::make_shared<VolumeScene>();
    vs->addVolumeBox(v, tf, 0.02, "head");
    s.volumeScene = vs;
    return s;
}

RenderOptions ctLikeOptions(double threshold, AntiAliasing aa, int64_t width = 192) {
    RenderOptions o;
    o.width = width;
    o.height = width * 3 / 4;
    DeepShadowOptions deep;
    deep.resolution = 96;
    o.shadow = deep;
    o.exposure = 1; // fixed: the images are compared pixel by pixel
    o.antiAliasing = aa;
    o.volumeRefinement = threshold;
    return o;
}

// The error refinement leaves, in the luma the image shows (filmic, gamma 2), against the same
// frame with every cell's ray marched (volumeRefinement 0), with the default adaptive anti-aliasing:
// mean and worst over the image, and the volume samples it saves.
TEST(VolumeRefinementTest, ACtLikeVolumeStaysWithinTheStatedShownLumaOfEveryCellMarched) {
    const Scene s = ctLikeScene();
    const RenderResult exact = render(s, s.cameras[0], ctLikeOptions(0, AntiAliasing::Full));
    const RenderResult fast = render(s, s.cameras[0], ctLikeOptions(1.0 / 64, AntiAliasing::Full));
    double sum = 0, worst = 0;
    int64_t over = 0;
    for (std::size_t i = 0; i < exact.image.pixels.size(); ++i) {
        const double d = std::abs(detail::shownLuma(fast.image.pixels[i], ToneMap::Filmic) -
                                  detail::shownLuma(exact.image.pixels[i], ToneMap::Filmic));
        sum += d, worst = std::max(worst, d), over += d > 1.0 / 255;
    }
    const double mean = sum / double(exact.image.pixels.size());
    std::printf(
        "CT-like volume: %lld interpolated; shown luma mean %.5f, worst %.4f, %lld pixels over 1/255; "
        "samples %lld against %lld\n",
        (long long)fast.volumeInterpolated, mean, worst, (long long)over, (long long)fast.volumeSamples,
        (long long)exact.volumeSamples);
    EXPECT_GT(fast.volumeInterpolated, 2000);
    EXPECT_LT(double(fast.volumeSamples), 0.6 * double(exact.volumeSamples));
    EXPECT_LT(mean, 0.0005);
    EXPECT_LT(worst, 0.06);
}

// The same frame of s lit per piece (detail::setVolumePrelit(false), switched back on whatever
// happens: the switch is process-wide) and pre-lit, and their difference in shown luma (filmic) per
// pixel: mean and worst over the image, the pixels over 1/255, and mean and worst over the pixels
// whose camera ray (eye, unit direction) `inRegion` picks.
struct PrelitAgainstPerPiece {
    RenderResult prelit, perPiece;
    double mean = 0, worst = 0, regionMean = 0, regionWorst = 0;
    int64_t over = 0, region = 0;
};
template <class Region>
PrelitAgainstPerPiece prelitAgainstPerPiece(const Scene& s, const RenderOptions& o, const Region& inRegion) {
    PrelitAgainstPerPiece r;
    {
        struct Restore {
            ~Restore() { detail::setVolumePrelit(true); }
        } restore;
        detail::setVolumePrelit(false);
        r.perPiece = render(s, s.cameras[0], o);
    }
    r.prelit = render(s, s.cameras[0], o);
    const Frame cam = cameraFrame(s.cameras[0], o.width, o.height);
    double sum = 0, regionSum = 0;
    for (int64_t y = 0; y < o.height; ++y)
        for (int64_t x = 0; x < o.width; ++x) {
            const double d =
                std::abs(detail::shownLuma(r.prelit.image.at(x, o.height - 1 - y), ToneMap::Filmic) -
                         detail::shownLuma(r.perPiece.image.at(x, o.height - 1 - y), ToneMap::Filmic));
            sum += d, r.worst = std::max(r.worst, d), r.over += d > 1.0 / 255;
            const Vec3d eye = cam.eye(),
                        dir = normalize(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
            if (inRegion(eye, dir)) regionSum += d, r.regionWorst = std::max(r.regionWorst, d), ++r.region;
        }
    r.mean = sum / double(r.prelit.image.pixels.size());
    r.regionMean = r.region > 0 ? regionSum / double(r.region) : 0;
    return r;
}

// The CT-like head's pixels: rays passing within its radius of its centre.
bool rayThroughHead(const Vec3d& eye, const Vec3d& dir) {
    const Vec3d c = kHeadCentre - eye;
    return length(c - dir * dot(c, dir)) < kHeadRadius;
}

// The pre-lit volume (the light x the deep shadow map's lookup x the volume's own transmittance over
// the lookup's step, made at the voxel corners and interpolated) against the same frame lit per piece
// (detail::setVolumePrelit(false): the light, the map's grid and the own transmittance at each lit
// piece), every cell's ray marched and no anti-aliasing, so only the lighting differs: shown luma
// (filmic, gamma 2) mean and worst over the image, over the head's pixels, and the count of pixels
// over 1/255. The CT-like head is the DSM demo's skull in miniature (its transfer function, a dense
// front within a voxel): the interpolated own transmittance blurs the light's fall across that front
// by a voxel. And the pre-lit frame takes the same volume samples (the lighting changes no walk).
TEST(VolumePrelitTest, ACtLikeVolumeLitFromThePrelitVolumeStaysWithinTheStatedShownLumaOfPerPieceLighting) {
    const Scene s = ctLikeScene();
    const RenderOptions o = ctLikeOptions(0, AntiAliasing::Off);
    ASSERT_TRUE(detail::volumePrelit()); // the default
    const PrelitAgainstPerPiece r = prelitAgainstPerPiece(s, o, rayThroughHead);
    std::printf(
        "CT-like volume, pre-lit against per-piece lighting: shown luma mean %.5f (head, %lld pixels: "
        "%.5f), worst %.4f, %lld pixels over 1/255\n",
        r.mean, (long long)r.region, r.regionMean, r.worst, (long long)r.over);
    EXPECT_GT(r.region, 2000);
    EXPECT_GT(r.worst, 0.0); // the pre-lit path was taken
    // Measured: mean 0.00005, over the head 0.00046, worst 0.022 (118 pixels over 1/255).
    EXPECT_LT(r.mean, 0.0002);
    EXPECT_LT(r.regionMean, 0.0015);
    EXPECT_LT(r.worst, 0.05);
    EXPECT_EQ(r.prelit.volumeSamples, r.perPiece.volumeSamples);
}

// Pieces inside two volumes (the DSM demo's skull inside its smoke): lit from the pre-lit grids, the
// first volume's light times the other's own transmittance (both made at their voxel corners), against
// the same frame lit per piece (setVolumePrelit(false): the light, the first volume's visibility grid
// and the own transmittance over both volumes at each piece). The CT-like head with a smoke box over
// its right half, every cell marched, no anti-aliasing: shown luma mean and worst over the image and
// over the pixels whose rays cross both boxes.
TEST(VolumePrelitTest, PiecesInsideTwoVolumesStayWithinTheStatedShownLumaOfPerPieceLighting) {
    Scene s = ctLikeScene();
    SmokeParams sp;
    sp.dims = {24, 24, 24};
    const Box3d smokeBox{{0.0, 0.6, -0.8}, {1.2, 1.8, 0.4}};
    sp.box = smokeBox;
    auto smoke = std::make_shared<Volume>(makeSmoke(sp));
    auto vs = std::make_shared<VolumeScene>(*s.volumeScene);
    vs->addVolumeBox(smoke, dsmrSmokeTransfer(), 0.1, "smoke");
    s.volumeScene = vs;
    const RenderOptions o = ctLikeOptions(0, AntiAliasing::Off);
    const Box3d both{{0.0, 0.6, -0.8},
                     {1.0, 1.8, 0.4}}; // the head's box [-1, 1] x [0, 2] x [-1, 1] and the smoke's
    const PrelitAgainstPerPiece r = prelitAgainstPerPiece(
        s, o, [&](const Vec3d& eye, const Vec3d& dir) { return rayBoxGap(eye, dir, both) < 0; });
    std::printf("head and smoke, pre-lit against per-piece lighting: shown luma mean %.5f, worst %.4f; over "
                "the %lld pixels crossing both boxes mean %.5f, worst %.4f\n",
                r.mean, r.worst, (long long)r.region, r.regionMean, r.regionWorst);
    EXPECT_GT(r.region, 2000);
    EXPECT_GT(r.regionWorst, 0.0); // the pre-lit path was taken there
    // Measured: mean 0.00004, worst 0.021; crossing both boxes mean 0.00011, worst 0.020 (without the
    // second volume's own transmittance, 0.00041 there).
    EXPECT_LT(r.mean, 0.0002);
    EXPECT_LT(r.regionMean, 0.00025);
    EXPECT_LT(r.worst, 0.05);
    EXPECT_EQ(r.prelit.volumeSamples, r.perPiece.volumeSamples);
}

// A second volume over the whole head whose matter is a small ball of fog in a corner of its box:
// the head's pieces lie in that volume's empty bricks, where its grid is not filled; they take the
// head's pre-lit light times 1 for it (its own transmittance there, as the per-piece path's smaller
// extinction of the step's ends gives), not the per-piece path. Against setVolumePrelit(false) the
// head's shown luma stays within what the head alone shows (VolumePrelitTest above: mean 0.00046
// over its pixels), and so does the rest.
TEST(VolumePrelitTest, PiecesInAnotherVolumesEmptyBricksTakeThePrelitLight) {
    Scene s = ctLikeScene();
    auto fog =
        std::make_shared<Volume>(Vec3i{24, 24, 24}, Vec3d{-1, 0, -1}, Vec3d{2.0 / 24, 2.0 / 24, 2.0 / 24});
    const Vec3d ball{0.7, 1.7, 0.6};
    for (int64_t k = 0; k < 24; ++k)
        for (int64_t j = 0; j < 24; ++j)
            for (int64_t i = 0; i < 24; ++i)
                fog->at(i, j, k) =
                    length(fog->voxelCenter(i, j, k) - ball) < 0.25 ? 0.8f : 0.0f; // outside: transparent
    auto vs = std::make_shared<VolumeScene>(*s.volumeScene);
    vs->addVolumeBox(fog, dsmrSmokeTransfer(), 0.1, "fog");
    s.volumeScene = vs;
    const RenderOptions o = ctLikeOptions(0, AntiAliasing::Off);
    const PrelitAgainstPerPiece r = prelitAgainstPerPiece(s, o, rayThroughHead);
    std::printf("head inside a mostly empty fog volume, pre-lit against per-piece lighting: shown luma mean "
                "%.5f (head, %lld pixels: %.5f), worst %.4f\n",
                r.mean, (long long)r.region, r.regionMean, r.worst);
    EXPECT_GT(r.region, 2000);
    EXPECT_GT(r.regionMean, 0.0001); // the head's pieces were pre-lit (per piece they would match exactly)
    EXPECT_LT(r.mean, 0.0002);
    EXPECT_LT(r.regionMean, 0.0015);
    EXPECT_LT(r.worst, 0.05);
}

// The volume's silhouette against what lies behind it is marched at full resolution: without
// anti-aliasing, every pixel whose ray clearly meets the head's matter while a lattice neighbour's
// clearly misses it (or the other way round) is cast, identical to the image with every pixel
// marched. The oracle is the ball itself: a ray meets the matter where it passes within
// kHeadRadius - 0.04 of the centre (its values reach 3.4 there, opaque over a chord of 0.27) and misses
// it beyond kHeadRadius - 0.015 (values below 2.6: transparent), a band of about 1.3 pixels; the box's
// faces, which the same rays cross, draw no edge between them. With the default threshold and with a
// threshold no luma difference reaches (1: the silhouette found by the rays' depths alone).
TEST(VolumeRefinementTest, TheSilhouetteOfAVolumesMatterIsMarchedAtFullResolution) {
    const Scene s = ctLikeScene();
    const int64_t W = 128, H = 96;
    const RenderResult exact = render(s, s.cameras[0], ctLikeOptions(0, AntiAliasing::Off, W));
    for (const double threshold : {1.0 / 64, 1.0}) {
        const RenderResult fast = render(s, s.cameras[0], ctLikeOptions(threshold, AntiAliasing::Off, W));
        const Frame cam = cameraFrame(s.cameras[0], W, H);
        // +1: the pixel's ray clearly meets the matter, -1: clearly misses it, 0: near the silhouette.
        const auto side = [&](int64_t x, int64_t y) {
            const Vec3d eye = cam.eye(),
                        d = normalize(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
            const Vec3d c = kHeadCentre - eye;
            const double distance = length(c - d * dot(c, d));
            return distance < kHeadRadius - 0.04 ? 1 : distance > kHeadRadius - 0.015 ? -1 : 0;
        };
        int64_t silhouette = 0, interpolated = 0;
        for (int64_t y = 0; y < H; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const int own = side(x, y);
                bool across = false;
                for (const auto& [nx, ny] : latticeNeighbours(x, y)) {
                    if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                    const int other = side(nx, ny);
                    across |= own != 0 && other != 0 && own != other;
                }
                const Vec3f a = fast.image.at(x, H - 1 - y), b = exact.image.at(x, H - 1 - y);
                const bool same = a.x == b.x && a.y == b.y && a.z == b.z;
                interpolated += !same;
                if (!across) continue;
                ++silhouette;
                EXPECT_TRUE(same) << x << ", " << y << " (threshold " << threshold << ")";
            }
        std::printf(
            "CT-like silhouette, no AA, threshold %.4f: %lld pixels across it cast; %lld pixels differ "
            "(interpolated), %lld interpolated in all\n",
            threshold, (long long)silhouette, (long long)interpolated, (long long)fast.volumeInterpolated);
        EXPECT_GT(silhouette, 40);
        EXPECT_GT(fast.volumeInterpolated, 2000);
    }
}

} // namespace
} // namespace voxfx
