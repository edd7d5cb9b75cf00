// The shadow techniques against each other and against exact light transport, reached by name
// through the closed set's dispatch (voxfx/shadow.hpp) as the renderer reaches them: on foliage
// (the brute-force crossing counter of tests/support/shadow_reference.hpp: more leaves never
// brighten a point, results independent of the thread count, error that shrinks with resolution,
// the full error-versus-resolution table as the Slow case); through glass (the crossing-counting
// techniques, transmittance, absorption and deep shadows, against exact shadows: Fresnel, the tint
// and Beer–Lambert over the chord); and through volumes (deep shadows converging to exact shadows
// as epsilon shrinks).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "support/glass_scenes.hpp"
#include "support/shadow_reference.hpp"
#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {
namespace {

using namespace voxfx::demo;
using test::dsmrGroundAndSmoke;
using test::ErrorStats;
using test::exactCrossings;
using test::exactReference;
using test::glassTestScene;
using test::gridOptions;
using test::leafScene;
using test::Reference;
using test::setShadowOption;
using test::shadowError;
using test::sun;
using test::visibilityOf;

// ---- Foliage, against exact light transport ---------------------------------------------------

TEST(ShadowTest, MoreLeafLayersNeverMakeAPointBrighter) {
    // Extra leaves inside the same bounds (so the light frames do not move) can only add filled cells
    // (transmittance, map) or writes (absorption). Uniform slicing: local slicing moves cell boundaries
    // when a column's range changes.
    const Scene base = leafScene(300, 2, 11);
    Scene more = base;
    const Scene extra = leafScene(300, 2, 12);
    for (size_t k = 1; k < extra.meshes.size(); ++k) {
        Mesh& to = more.meshes[k].mesh;
        const auto b = uint32_t(to.positions.size());
        for (const Vec3f& p : extra.meshes[k].mesh.positions)
            to.positions.push_back(Vec3f(std::clamp(p.x, -1.8f, 1.8f), std::clamp(p.y, 1.7f, 2.8f),
                                         std::clamp(p.z, -1.8f, 1.8f)));
        for (const uint32_t i : extra.meshes[k].mesh.indices) to.indices.push_back(b + i);
    }
    ASSERT_TRUE(base.bounds(true) == more.bounds(true));
    const Light light = sun();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-3, 3), uy(0, 3.2);
    for (const std::string_view kind : {"map", "transmittance", "absorption"}) {
        const LightShadow a = buildLightShadow(base, light, gridOptions(kind, 96));
        const LightShadow b = buildLightShadow(more, light, gridOptions(kind, 96));
        int darker = 0;
        for (int i = 0; i < 3000; ++i) {
            const Vec3d p{u(rng), uy(rng), u(rng)};
            const Vec3f va = visibilityOf(a, p, {0, 0, 0}), vb = visibilityOf(b, p, {0, 0, 0});
            for (int c = 0; c < 3; ++c) ASSERT_LE(vb[c], va[c] + 1e-6f) << kind << " at " << i;
            darker += vb.y < va.y;
        }
        EXPECT_GT(darker, 100) << kind; // the extra leaves do shadow something
    }
}

TEST(ShadowTest, ResultDoesNotDependOnThreadCount) {
    const Scene s = leafScene(500, 3, 41);
    for (const std::string_view kind : {"map", "transmittance", "absorption"}) {
        LightShadow one, two;
        withThreads(1, [&] { one = buildLightShadow(s, sun(), gridOptions(kind, 128)); });
        withThreads(2, [&] { two = buildLightShadow(s, sun(), gridOptions(kind, 128)); });
        std::mt19937_64 rng(4);
        std::uniform_real_distribution<double> u(-3, 3), uy(0, 3.2);
        for (int i = 0; i < 1000; ++i) {
            const Vec3d p{u(rng), uy(rng), u(rng)};
            ASSERT_TRUE(visibilityOf(one, p, {0, 1, 0}) == visibilityOf(two, p, {0, 1, 0}));
        }
    }
}

TEST(ShadowTest, ErrorAgainstExactTransportShrinksWithResolution) {
    const Scene s = leafScene(500, 2, 51);
    const Light light = sun();
    const Reference pts = exactReference(s, light, 1500, 6);
    const ErrorStats t64 = shadowError(s, light, pts, gridOptions("transmittance", 64));
    const ErrorStats t256 = shadowError(s, light, pts, gridOptions("transmittance", 256));
    const ErrorStats a64 = shadowError(s, light, pts, gridOptions("absorption", 64));
    const ErrorStats a256 = shadowError(s, light, pts, gridOptions("absorption", 256));
    const ErrorStats m256 = shadowError(s, light, pts, gridOptions("map", 256));
    EXPECT_LT(t256.mean, 0.75 * t64.mean);
    EXPECT_LT(a256.mean, 0.75 * a64.mean);
    EXPECT_LT(t256.mean, 0.05);
    EXPECT_LT(a256.mean, 0.05);
    // The binary map cannot represent partial light: several times worse on foliage.
    EXPECT_GT(m256.mean, 3 * t256.mean);
    EXPECT_GT(m256.mean, 3 * a256.mean);
}

void errorTable(int leaves);

TEST(ShadowTest, ErrorTableAgainstExactTransportSlow) {
    // The table reported in BENCHMARKS.md: mean and 95th percentile of |visibility - exact| over
    // ground points that at least one leaf shadows.
    // Two canopies: dense (1,500 leaves, most shadowed points behind several) and sparse (300).
    for (const int leaves : {1500, 300}) errorTable(leaves);
}

void errorTable(int leaves) {
    const Scene s = leafScene(leaves, 3, 61);
    const Light light = sun();
    const Reference pts = exactReference(s, light, 4000, 7);
    double crossings = 0;
    for (const Vec3d& p : pts.points) crossings += exactCrossings(s, light, p);
    std::printf("%d leaves, %zu shadowed ground points, %.2f crossings on average\n", leaves,
                pts.points.size(), crossings / double(pts.points.size()));
    std::printf("%-40s %6s %9s %9s\n", "kind", "N", "mean", "p95");
    struct Row {
        const char* name;
        std::string_view kind;
        Slicing slicing;
        VoxelizeMode mode;
    };
    const Row rows[] = {
        {"transmittance surface uniform", "transmittance", Slicing::Uniform, VoxelizeMode::Surface},
        {"transmittance surface local", "transmittance", Slicing::Local, VoxelizeMode::Surface},
        {"transmittance conservative uniform", "transmittance", Slicing::Uniform, VoxelizeMode::Conservative},
        {"absorption uniform", "absorption", Slicing::Uniform, VoxelizeMode::Surface},
        {"absorption local", "absorption", Slicing::Local, VoxelizeMode::Surface},
        {"shadow map (PCF 3x3)", "map", Slicing::Uniform, VoxelizeMode::Surface},
        {"transmittance surface uniform bilinear", "transmittance", Slicing::Uniform, VoxelizeMode::Surface},
        {"absorption uniform bilinear", "absorption", Slicing::Uniform, VoxelizeMode::Surface}};
    for (const Row& row : rows) {
        double previous = 1e9;
        for (const int64_t n : {32, 64, 128, 256, 512}) {
            ShadowOptions o = gridOptions(row.kind, n, row.slicing, row.mode);
            setShadowOption(o, "bilinear", std::string(row.name).find("bilinear") != std::string::npos);
            const ErrorStats e = shadowError(s, light, pts, o);
            std::printf("%-40s %6lld %9.4f %9.4f\n", row.name, (long long)n, e.mean, e.p95);
            if (row.kind != "map" && n >= 64 && row.mode == VoxelizeMode::Surface) {
                EXPECT_LT(e.mean, previous) << row.name << " " << n;
            }
            previous = e.mean;
        }
    }
}

// ---- Through glass, against exact shadows ------------------------------------------------------

TEST(GlassTest, CrossingCountingShadowsPassWhatExactShadowsPassThroughGlass) {
    // The ball of glassTestScene under the sun (a thicknessFactor of its diameter, which the
    // methods no longer use): transmittance, absorption and deep shadow maps multiply two
    // crossings of sqrt(tint) (1 - F0) and Beer–Lambert over the chord between them, which must
    // agree with the exact tracer's Fresnel x tint x Beer–Lambert under the ball's centre in every
    // channel, and not pass the tint twice with no Fresnel (what every crossing passed before).
    Scene s = glassTestScene();
    s.materials[1].thickness = 1.4f;
    s.materials[1].attenuationColor = {0.3f, 0.5f, 0.4f}; // far from the tint alone
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0, -1, 0};
    auto luminance = [](const Vec3f& v) { return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z; };
    const Vec3d under{0.05, 0, 0.03};
    const Vec3f exact = shadowVisibility(buildLightShadow(s, sun, ExactShadowOptions{}), under, {0, 1, 0});
    const Vec3f tint = s.materials[1].crossingTransmittance();
    for (const std::string_view kind : {"transmittance", "absorption", "deep"}) {
        RenderOptions o;
        setRenderOption(o, "shadows", std::string(kind));
        for (const char* name : {"gridResolution", "gridDepth", "dsmResolution"})
            setRenderOption(o, name, int64_t(64));
        setRenderOption(o, "epsilon", 0.0);
        const Vec3f v = shadowVisibility(buildLightShadow(s, sun, o.shadow), under, {0, 1, 0});
        EXPECT_NEAR(luminance(v), luminance(exact), 0.03) << kind;
        EXPECT_GT(std::abs(luminance(v) - luminance(tint * tint)), 0.1) << kind;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], exact[c], 0.03) << kind << " channel " << c;
    }
    // A leaf's transmission (opacity < 1) is a sheet, not glass: the tree renders without glass.
    TreeOptions t;
    t.leaves = 50;
    const Scene tree = makeTreeScene(t);
    EXPECT_TRUE(std::holds_alternative<NoGlassOptions>(defaultGlass(tree)));
    for (const Material& m : tree.materials)
        if (m.transmission > 0) {
            EXPECT_FALSE(m.isGlass()) << m.name;
            EXPECT_EQ(m.shadowCrossingTransmittance(), m.crossingTransmittance()) << m.name;
        }
}

// The Fresnel equations (unpolarized) from air into n = 1.5 at incidence cosine ci, written out here.
double fresnelIntoGlass15(double ci) {
    const double n = 1.5, st = std::sqrt(1 - ci * ci) / n, ct = std::sqrt(1 - st * st);
    const double rs = (ci - n * ct) / (ci + n * ct), rp = (ct - n * ci) / (ct + n * ci);
    return 0.5 * (rs * rs + rp * rp);
}

// Clear glass of index 1.5 (no tint, no attenuation).
Material clearGlass15() {
    Material clear;
    clear.baseColor = {1, 1, 1};
    clear.transmission = 1;
    clear.ior = 1.5f;
    return clear;
}

// #37: glass shadows gave every crossing Fresnel at normal incidence, (1 - F0), so the rim of a glass
// ball's shadow was as light as its centre. A ball of clear glass (no tint, no attenuation) under a
// sun straight down: the light reaching the ground at distance r from the centre crossed the sphere
// at incidence cos = sqrt(1 - (r / R)^2) on the way in and out (a shadow ray is not bent), so it
// passes (1 - F(cos))^2 (closed form; the exact tracer's Fresnel product). Absorption, transmittance
// and deep shadows take each crossing's Fresnel from its triangle's normal and the light's
// direction. Means over rings of points.
TEST(GlassTest, GlassShadowsDarkenTowardsTheRimByEachCrossingsFresnel) {
    Scene s = test::greyGroundScene();
    const Material clear = clearGlass15();
    const double R = 0.6;
    s.meshes.push_back({"ball", test::makeUvSphere({0, 1, 0}, R, 96, 192), {}, s.addMaterial(clear), true});
    Light sun;
    sun.direction = {0, -1, 0};
    auto ringMean = [&](const LightShadow& ls, double r) {
        double sum = 0;
        for (int k = 0; k < 32; ++k) {
            const double a = 2 * M_PI * (k + 0.5) / 32;
            sum += shadowVisibility(ls, {r * std::cos(a), 0, r * std::sin(a)}, {0, 1, 0}).y;
        }
        return sum / 32;
    };
    const LightShadow exact = buildLightShadow(s, sun, ExactShadowOptions{});
    for (const std::string_view kind : {"exact", "absorption", "transmittance", "deep"}) {
        RenderOptions o;
        setRenderOption(o, "shadows", std::string(kind));
        if (kind != "exact") {
            for (const char* name : {"gridResolution", "gridDepth", "dsmResolution"})
                setRenderOption(o, name, int64_t(256));
            setRenderOption(o, "epsilon", 0.0);
        }
        const LightShadow ls = kind == "exact" ? exact : buildLightShadow(s, sun, o.shadow);
        for (const double f : {0.0, 0.5, 0.8, 0.9}) {
            const double c = std::sqrt(1 - f * f), pass = 1 - fresnelIntoGlass15(c);
            const double got = ringMean(ls, f * R);
            std::printf("%s at r = %.1f R: %.4f (closed form %.4f)\n", std::string(kind).c_str(), f, got,
                        pass * pass);
            EXPECT_NEAR(got, pass * pass, 0.02) << kind << " at r = " << f << " R";
        }
        // The rim darker than the centre by what the closed form says (0.785 against 0.922).
        EXPECT_LT(ringMean(ls, 0.9 * R), ringMean(ls, 0) - 0.1) << kind;
    }
}

// #37: the same for a flat pane: a slab of clear glass (1.2 x 0.1 x 1.2, n 1.5) turned 70 degrees
// about z over the ground, under a sun straight down. The light reaching the ground under the middle
// of the pane crossed its two large faces at cos 70 degrees, so it passes (1 - F(cos 70))^2 = 0.687
// (closed form; normal incidence would pass 0.922), and every shadow method must agree with the
// exact tracer there; means over a grid of ground points.
TEST(GlassTest, AGlassPaneTiltedToTheLightPassesTheFresnelOfItsAngle) {
    Scene s = test::greyGroundScene();
    const Material clear = clearGlass15();
    Mesh pane = test::makeBox({-0.6, -0.05, -0.6}, {0.6, 0.05, 0.6});
    const double a = 70 * M_PI / 180, c = std::cos(a), sn = std::sin(a);
    for (Vec3f& v : pane.positions) // about z, then up to y = 1
        v = Vec3f{float(c * v.x - sn * v.y), float(sn * v.x + c * v.y + 1), v.z};
    s.meshes.push_back({"pane", pane, {}, s.addMaterial(clear), true});
    Light sun;
    sun.direction = {0, -1, 0};
    const double pass = 1 - fresnelIntoGlass15(c), closed = pass * pass;
    auto mean = [&](const LightShadow& ls) {
        double sum = 0;
        for (int i = 0; i < 8; ++i)
            for (int k = 0; k < 8; ++k) // |x| < 0.1: under both large faces (they span |x| < 0.158)
                sum += shadowVisibility(ls, {-0.1 + 0.2 * (i + 0.5) / 8, 0, -0.4 + 0.8 * (k + 0.5) / 8},
                                        {0, 1, 0})
                           .y;
        return sum / 64;
    };
    const double exact = mean(buildLightShadow(s, sun, ExactShadowOptions{}));
    EXPECT_NEAR(exact, closed, 0.005);
    for (const std::string_view kind : {"absorption", "transmittance", "deep"}) {
        RenderOptions o;
        setRenderOption(o, "shadows", std::string(kind));
        setRenderOption(o, "epsilon", 0.0);
        const double got = mean(buildLightShadow(s, sun, o.shadow));
        std::printf("%s: %.4f (exact %.4f, closed form %.4f)\n", std::string(kind).c_str(), got, exact,
                    closed);
        EXPECT_NEAR(got, exact, 0.02) << kind;
    }
}

// #37: with each crossing's Fresnel taken from its triangle's flat normal, the rim of a glass ball's
// shadow under a sun at an angle darkened in beads: around the rim the silhouette cuts the sphere's
// triangles at varying distances from their centres, so neighbouring triangles passed very
// different Fresnel (cos 0.10 against 0.17 is 0.55 against 0.43 at n = 1.5). The stored (smoothed)
// normals give the sphere's. A clear ball (no tint, no attenuation; the demo's 48 x 96
// tessellation) under the glass-sun example's light: light reaching the ground through the point at
// distance r from the ball's axis along the light crossed the sphere twice at cos = sqrt(1 - (r/R)^2),
// so it passes (1 - F(cos))^2 (closed form, written here). Sampled on 48 radii x 48 distances r <=
// 0.95 R. A round ball's shadow is the same at every azimuth; the lookup's normal offset shifts it
// a little (a smooth swing over the azimuths, not a bead), so a bead is a sample that leaves the mean
// of its two azimuthal neighbours by more than 0.006 (the flat normals: 0.022); the profile darkens
// outward (rises summing to under 0.01) and the mean error against the closed form stays under 0.01.
// Transmittance and absorption shadows; deep shadows (the dsm layer's per-fragment Fresnel) printed.
TEST(GlassTest, AGlassBallsShadowDarkensSmoothlyTowardsItsRim) {
    Scene s = test::greyGroundScene();
    const Vec3d c{0, 0.8, 0};
    const double R = 0.5;
    s.meshes.push_back({"ball", test::makeUvSphere(c, R, 48, 96), {}, s.addMaterial(clearGlass15()), true});
    Light sun;
    sun.direction = normalize(Vec3d{0.35, -0.7, 0.62});
    const Vec3d d = sun.direction, e1 = normalize(cross(d, Vec3d{1, 0, 0})), e2 = cross(d, e1);
    // The ground point whose ray to the light passes at distance r from the axis, at azimuth a.
    auto groundPoint = [&](double r, double a) {
        const Vec3d p = c + (e1 * std::cos(a) + e2 * std::sin(a)) * r;
        return p + d * (-p.y / d.y);
    };
    const int azimuths = 48, radii = 48;
    for (const std::string_view kind : {"transmittance", "absorption", "deep"}) {
        const LightShadow ls = buildLightShadow(s, sun, shadowOptionsNamed(kind));
        std::vector<std::vector<double>> v(azimuths, std::vector<double>(radii));
        double worstRise = 0, worstSpread = 0, worstBead = 0, error = 0;
        for (int k = 0; k < azimuths; ++k) {
            double rise = 0;
            for (int i = 0; i < radii; ++i) {
                const double f = 0.95 * i / (radii - 1), cs = std::sqrt(1 - f * f);
                const double pass = 1 - fresnelIntoGlass15(cs);
                v[k][i] =
                    shadowVisibility(ls, groundPoint(f * R, 2 * M_PI * (k + 0.5) / azimuths), {0, 1, 0}).y;
                error += std::abs(v[k][i] - pass * pass);
                if (i > 0) rise += std::max(0.0, v[k][i] - v[k][i - 1]);
            }
            worstRise = std::max(worstRise, rise);
        }
        for (int i = 0; i < radii; ++i) {
            double lo = 1, hi = 0;
            for (int k = 0; k < azimuths; ++k) {
                lo = std::min(lo, v[k][i]);
                hi = std::max(hi, v[k][i]);
            }
            worstSpread = std::max(worstSpread, hi - lo);
            for (int k = 0; k < azimuths; ++k) {
                const double mid = 0.5 * (v[(k + azimuths - 1) % azimuths][i] + v[(k + 1) % azimuths][i]);
                worstBead = std::max(worstBead, std::abs(v[k][i] - mid));
            }
        }
        error /= azimuths * radii;
        std::printf("%s: summed rise %.4f, spread over azimuths %.4f, bead %.4f, mean error %.4f\n",
                    std::string(kind).c_str(), worstRise, worstSpread, worstBead, error);
        if (kind == "deep") continue;
        EXPECT_LT(worstBead, 0.006) << kind;
        EXPECT_LT(worstRise, 0.01) << kind;
        EXPECT_LT(error, 0.01) << kind;
    }
}

// The glass shadow of a scene's casters on its ground (y = 0, normal up) under `sun`, sampled on a
// grid of points over [-half, half]^2: the mean absolute error per channel of `kind` against the
// exact tracer (the reference: Fresnel at each crossing, the tint, Beer–Lambert over the true chord),
// over the points that either shadows darkens, with no shadow's error over the same points.
struct GlassShadowError {
    double method = 0, none = 0;
    int64_t points = 0;
};
GlassShadowError glassShadowError(const Scene& s, const Light& sun, std::string_view kind, double half) {
    const LightShadow exact = buildLightShadow(s, sun, ExactShadowOptions{});
    const LightShadow method = buildLightShadow(s, sun, shadowOptionsNamed(kind));
    GlassShadowError e;
    const int n = 100;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const Vec3d p{-half + 2 * half * (i + 0.5) / n, 0, -half + 2 * half * (j + 0.5) / n};
            const Vec3f r = shadowVisibility(exact, p, {0, 1, 0}), v = shadowVisibility(method, p, {0, 1, 0});
            if (std::min({r.x, r.y, r.z, v.x, v.y, v.z}) > 0.999f) continue;
            ++e.points;
            for (int c = 0; c < 3; ++c) {
                e.method += std::abs(double(v[c]) - double(r[c]));
                e.none += std::abs(1.0 - double(r[c]));
            }
        }
    e.method /= double(3 * std::max<int64_t>(e.points, 1));
    e.none /= double(3 * std::max<int64_t>(e.points, 1));
    return e;
}

// A green glass box and an amber glass ball (white tint: all their colour from KHR_materials_volume
// attenuation, no thicknessFactor) over the ground of glassTestScene, under a tilted sun.
Scene tintedGlassScene() {
    Scene s = glassTestScene();
    s.meshes.resize(1); // the ground
    s.meshes[0].mesh = Mesh{};
    test::appendQuad(s.meshes[0].mesh, {0, 0, 0}, {0, 0, 3}, {3, 0, 0});
    Material green = s.materials[1], amber = s.materials[1];
    green.attenuationColor = {0.3f, 0.8f, 0.4f};
    green.attenuationDistance = 0.5f;
    amber.attenuationColor = {0.95f, 0.6f, 0.15f};
    amber.attenuationDistance = 0.6f;
    SceneMesh box, ball;
    box.mesh = test::makeBox({-1.4, 0.2, -0.5}, {-0.4, 1.0, 0.5});
    box.material = s.addMaterial(green);
    ball.mesh = test::makeUvSphere({0.9, 0.8, 0}, 0.6, 48, 96);
    ball.material = s.addMaterial(amber);
    s.meshes.push_back(box);
    s.meshes.push_back(ball);
    return s;
}

TEST(GlassTest, CrossingMethodsShadowTintedGlassByTheChordAsExactDoes) {
    // Transmittance, absorption and deep shadow maps against the exact tracer on the ground under a
    // green glass box and an amber glass ball with no thicknessFactor (mean absolute error per
    // channel over the 725 points either shadow darkens). Each crossing passing only Fresnel left
    // the shadow grey at 0.92 (before: transmittance 0.423, absorption 0.423, deep 0.419 against no
    // shadow's 0.681); with Beer–Lambert over the chord between paired crossings (cells of the
    // light grid, fragments of the deep shadow map) the error is a fraction of it (after:
    // transmittance 0.060, absorption 0.060, deep 0.074).
    const Scene s = tintedGlassScene();
    for (const std::string_view kind : {"transmittance", "absorption", "deep"}) {
        const GlassShadowError e = glassShadowError(s, sun(), kind, 3);
        RecordProperty(std::string(kind) + "Error", std::to_string(e.method));
        RecordProperty(std::string(kind) + "NoShadowError", std::to_string(e.none));
        EXPECT_GT(e.points, 500) << kind;
        EXPECT_GT(e.none, 0.3) << kind;
        EXPECT_LT(e.method, 0.25 * e.none) << kind << ": " << e.method << " against no shadow's " << e.none;
    }
}

TEST(GlassTest, CrossingMethodsShadowTheGlassDemoNearExactShadows) {
    // The glass demo (glass bunny, green torus knot, amber and blue block; white tints, colour from
    // the attenuation) under its default sun: the ground's shadow error against exact shadows
    // (before: transmittance 0.319, absorption 0.314, deep 0.324 against no shadow's 0.397; after:
    // transmittance 0.085, absorption 0.085, deep 0.092).
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Scene s = makeDemoScene("glass", test::dataPath("meshes"));
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = -normalize(SkyOptions{}.sunDirection);
    for (const std::string_view kind : {"transmittance", "absorption", "deep"}) {
        const GlassShadowError e = glassShadowError(s, sun, kind, 4);
        RecordProperty(std::string(kind) + "Error", std::to_string(e.method));
        RecordProperty(std::string(kind) + "NoShadowError", std::to_string(e.none));
        EXPECT_GT(e.points, 500) << kind;
        EXPECT_LT(e.method, 0.3 * e.none) << kind << ": " << e.method << " against no shadow's " << e.none;
    }
}

TEST(GlassTest, AbsorptionAndDeepShadowsAreColouredUnderTintedLeavesAndGlass) {
    // A green leaf (a sheet: gaps plus tissue of its base colour) and the green glass box of
    // tintedGlassScene: exact shadows under each are green; absorption and deep shadows, grey
    // before (one visibility for all channels), must be green too and near exact per channel.
    Scene s = tintedGlassScene();
    s.meshes.resize(2); // ground and box
    Material leaf;
    leaf.baseColor = {0.2f, 0.8f, 0.15f};
    leaf.opacity = 0.7f;
    leaf.transmission = 0.7f;
    SceneMesh quad;
    test::appendQuad(quad.mesh, {1.2, 1.0, 0}, {0, 0, 0.5}, {0.5, 0, 0}); // centre (1.2, 1, 0)
    quad.material = s.addMaterial(leaf);
    s.meshes.push_back(quad);
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0, -1, 0};
    const LightShadow exact = buildLightShadow(s, sun, ExactShadowOptions{});
    for (const Vec3d under : {Vec3d{1.2, 0, 0.02}, Vec3d{-0.9, 0, 0.02}}) {
        const Vec3f r = shadowVisibility(exact, under, {0, 1, 0});
        ASSERT_GT(r.y, r.x + 0.1f);
        ASSERT_GT(r.y, r.z + 0.1f);
        for (const std::string_view kind : {"absorption", "deep"}) {
            const Vec3f v =
                shadowVisibility(buildLightShadow(s, sun, shadowOptionsNamed(kind)), under, {0, 1, 0});
            EXPECT_GT(v.y, v.x + 0.1f) << kind << " at x " << under.x;
            EXPECT_GT(v.y, v.z + 0.1f) << kind << " at x " << under.x;
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], r[c], 0.05) << kind << " channel " << c;
        }
    }
}

// ---- Through volumes, against exact shadows ----------------------------------------------------

// Deep shadows of the smoke over the ground against the exact reference through the volume: the
// compression adds at most epsilon per texel (DeepShadowTest above), so the mean error at epsilon
// stays within epsilon of the uncompressed map's, and shrinks with epsilon towards that floor (the
// bilinear filter across texels and the pre-integrated one-voxel steps: about 0.001 on this smooth
// smoke at 64^2 and 256^2 alike).
TEST(ExactShadowVolumeTest, DeepShadowsConvergeToTheExactReferenceAsEpsilonShrinks) {
    const Scene s = dsmrGroundAndSmoke(true);
    const LightShadow exact = buildLightShadow(s, s.lights[0], ExactShadowOptions{});
    ASSERT_GT(std::get<ExactShadow>(exact).stats().volumeObjects, 0);
    std::vector<Vec3d> points;
    for (double x = -1.5; x <= 1.5; x += 0.1)
        for (double z = -1.5; z <= 1.5; z += 0.1) points.push_back({x, 0, z});
    std::vector<float> ref;
    int64_t shadowed = 0;
    for (const Vec3d& p : points) {
        ref.push_back(shadowVisibility(exact, p, {0, 1, 0}).x);
        shadowed += ref.back() < 0.9f;
    }
    EXPECT_GT(shadowed, 100);
    auto error = [&](int64_t resolution, double epsilon) {
        DeepShadowOptions so;
        so.resolution = resolution;
        so.epsilon = epsilon;
        const LightShadow deep = buildLightShadow(s, s.lights[0], so);
        double sum = 0;
        for (std::size_t i = 0; i < points.size(); ++i)
            sum += std::abs(double(shadowVisibility(deep, points[i], {0, 0, 0}).x) - double(ref[i]));
        return sum / double(points.size());
    };
    const double floor64 = error(64, 0), floor256 = error(256, 0);
    std::printf("mean |deep - exact|: uncompressed 64^2 %.4f, 256^2 %.4f\n", floor64, floor256);
    EXPECT_LT(floor64, 0.005);
    EXPECT_LT(floor256, 0.005);
    double previous = 1;
    for (const double epsilon : {0.2, 0.1, 0.05, 0.01}) {
        const double e = error(256, epsilon);
        std::printf("  epsilon %.2f: %.4f\n", epsilon, e);
        EXPECT_LE(e, floor256 + epsilon) << epsilon;
        EXPECT_LE(e, previous + 1e-3) << epsilon; // no worse than at the larger epsilon
        previous = e;
    }
    EXPECT_LT(error(256, 0.01), error(256, 0.2));
}

} // namespace
} // namespace voxfx
