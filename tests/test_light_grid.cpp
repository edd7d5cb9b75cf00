// Tests of what the light-grid shadows share (voxfx/light_grid.hpp: transmittance, ED06 §3.1, and
// absorption, CHANG §3) against exact light transport (tests/support/shadow_reference.hpp) and
// hand-derived cases: stacked layers multiply (transmittance) and add optical depth per crossing
// (absorption), spot and point lights (cube faces and their seams), the self-shadowing bias, and
// the filtered (bilinear) lookups against the own-column one.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "render/light_grid_lookup.hpp"
#include "support/shadow_reference.hpp"
#include "test_util.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/light_grid.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {
namespace {

using test::appendQuad;
using test::ErrorStats;
using test::exactCrossings;
using test::exactReference;
using test::exactTransmittance;
using test::gridOptions;
using test::leafMaterial;
using test::leafScene;
using test::oneLeafScene;
using test::Reference;
using test::setShadowOption;
using test::shadowError;
using test::sun;
using test::visibilityOf;

TEST(ShadowTest, StackedLayersMultiplyAndAbsorptionAddsPerCrossing) {
    // Three horizontal layers 0.5 apart: transmittance t^3; absorption exp(-3 sigma).
    Scene s;
    SceneMesh leaves;
    leaves.name = "layers";
    for (const double y : {1.0, 1.5, 2.0}) appendQuad(leaves.mesh, {0, y, 0}, {0, 0, 1}, {1, 0, 0});
    leaves.material = s.addMaterial(leafMaterial({0.3f, 0.3f, 0.3f}, 0.6f, 0.0f)); // grey: t = 0.4
    s.meshes.push_back(leaves);
    const LightShadow tr = buildLightShadow(s, sun({0, -1, 0}), gridOptions("transmittance", 32));
    const LightShadow ab = buildLightShadow(s, sun({0, -1, 0}), gridOptions("absorption", 32));
    const float sigma = -std::log(0.4f);
    EXPECT_NEAR(absorptionPerCrossing(s.materials[0], 8).x, sigma, 1e-5f);
    for (const double y : {0.0, 1.25, 1.75, 2.5}) {
        const int layers = (y < 1.0) + (y < 1.5) + (y < 2.0);
        EXPECT_NEAR(visibilityOf(tr, {0.2, y, -0.3}, {0, 0, 0}).x, std::pow(0.4f, float(layers)), 1e-5f) << y;
        EXPECT_NEAR(visibilityOf(ab, {0.2, y, -0.3}, {0, 0, 0}).x, std::exp(-sigma * float(layers)), 1e-5f)
            << y;
    }
}

TEST(ShadowTest, SpotLightShadowsThroughALeaf) {
    const Scene s = oneLeafScene({0, 2, 0}, {0, 0, 1}, {1, 0, 0},
                                 leafMaterial({0.3f, 0.3f, 0.3f}, 0.5f, 0.0f)); // t = 0.5
    Light spot;
    spot.type = LightType::Spot;
    spot.position = {0, 4, 0};
    spot.direction = {0, -1, 0};
    spot.outerConeAngle = 1.0;
    for (const std::string_view kind : {"transmittance", "absorption"}) {
        const LightShadow sh = buildLightShadow(s, spot, gridOptions(kind, 128));
        // Ground points whose ray to the light crosses the leaf: |x| < 2 at y = 0 (similar triangles).
        EXPECT_NEAR(visibilityOf(sh, {1.5, 0, 0.3}, {0, 0, 0}).x, 0.5f, 1e-5f) << kind;
        EXPECT_NEAR(visibilityOf(sh, {-1.0, 0, -1.7}, {0, 0, 0}).x, 0.5f, 1e-5f) << kind;
        EXPECT_EQ(visibilityOf(sh, {2.5, 0, 0}, {0, 0, 0}).x, 1.0f) << kind;
        EXPECT_EQ(visibilityOf(sh, {0, 3, 0}, {0, 0, 0}).x, 1.0f) << kind;
    }
}

// The cube face by its definition: the first of +x, -x, +y, -y, +z, -z (in that order) whose axis
// has the largest positive dot product with p - eye; -1 where none is positive.
int cubeFaceByDefinition(const Vec3d& eye, const Vec3d& p) {
    const Vec3d axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    int best = -1;
    double bestDot = 0;
    for (int k = 0; k < 6; ++k)
        if (dot(p - eye, axes[k]) > bestDot) best = k, bestDot = dot(p - eye, axes[k]);
    return best;
}

TEST(ShadowTest, PointLightCubeFaceFromTheLargestComponentIsTheFrustumsFace) {
    // viewIndexFor picks a point light's cube face from the largest component of p - eye. On points
    // all around the light (random directions, the faces' seams and corners where two or three
    // components tie, one float step either side of them, the axes, signed zeros, the eye itself):
    // the face equals the brute-force definition above, the face's frustum covers p (LightView::locate,
    // the frustum test), no face covers p that the definition ranks lower unless p lies on their
    // seam, and the same views without their cube tags (the six-dot-product search) agree, also on
    // non-finite points.
    Light lamp;
    lamp.type = LightType::Point;
    lamp.position = {0.3, 1.7, -2.1};
    const std::vector<LightView> views = makeLightViews(lamp, Box3d{{-5, -5, -5}, {5, 5, 5}}, 64, 1);
    ASSERT_EQ(views.size(), 6u);
    for (int k = 0; k < 6; ++k) ASSERT_EQ(views[size_t(k)].cubeFace, k);
    std::vector<LightView> untagged = views;
    for (LightView& v : untagged) v.cubeFace = -1;
    const Vec3d eye = lamp.position;

    std::vector<Vec3d> offsets;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1, 1), scale(1e-3, 40);
    for (int i = 0; i < 20000; ++i) offsets.push_back(Vec3d{u(rng), u(rng), u(rng)} * scale(rng));
    const double up = std::nextafter(1.0, 2.0), down = std::nextafter(1.0, 0.0);
    for (int i = 0; i < 4000; ++i) {
        // Seams: two components of equal magnitude (either sign), the third smaller; corners: three.
        const double a = scale(rng), c = u(rng) * a;
        const double sx = u(rng) < 0 ? -1 : 1, sy = u(rng) < 0 ? -1 : 1, sz = u(rng) < 0 ? -1 : 1;
        for (const double t : {1.0, up, down}) {
            offsets.push_back({sx * a, sy * a * t, c});
            offsets.push_back({sx * a * t, c, sz * a});
            offsets.push_back({c, sy * a, sz * a * t});
            offsets.push_back({sx * a, sy * a, sz * a * t});
            offsets.push_back({sx * a * t, sy * a, sz * a});
        }
    }
    for (const double a : {1.0, 7.5})
        for (const Vec3d& d : {Vec3d{a, 0, 0}, Vec3d{-a, 0, 0}, Vec3d{0, a, 0}, Vec3d{0, -a, 0},
                               Vec3d{0, 0, a}, Vec3d{0, 0, -a}, Vec3d{-0.0, a, -0.0}, Vec3d{-0.0, -0.0, -a}})
            offsets.push_back(d);
    offsets.push_back({0, 0, 0});
    int64_t ties = 0;
    for (const Vec3d& d : offsets) {
        const Vec3d p = eye + d;
        const int want = cubeFaceByDefinition(eye, p);
        const int got = viewIndexFor(views, p);
        ASSERT_EQ(got, want) << d.x << ", " << d.y << ", " << d.z;
        ASSERT_EQ(viewIndexFor(untagged, p), want) << d.x << ", " << d.y << ", " << d.z;
        if (p == eye) {
            ASSERT_EQ(got, -1);
            continue;
        }
        ASSERT_GE(got, 0);
        ASSERT_TRUE(views[size_t(got)].covers(p)) << d.x << ", " << d.y << ", " << d.z;
        // Any other face whose frustum takes p holds it on a shared border (a seam within the frustum
        // test's tolerance): its component is as large as the chosen one's, to 1e-6.
        const Vec3d r = p - eye;
        const double comp[3] = {std::abs(r.x), std::abs(r.y), std::abs(r.z)};
        for (int k = 0; k < 6; ++k)
            if (k != got && views[size_t(k)].covers(p)) {
                EXPECT_GE(comp[k / 2], comp[got / 2] * (1 - 1e-6)) << d.x << ", " << d.y << ", " << d.z;
                ++ties;
            }
    }
    EXPECT_GT(ties, 10000); // the seams were reached
    // Non-finite points: the tagged views leave them to the six-dot-product search.
    const double inf = std::numeric_limits<double>::infinity(),
                 nan = std::numeric_limits<double>::quiet_NaN();
    for (const Vec3d& d : {Vec3d{inf, 1, 0}, Vec3d{inf, inf, 0}, Vec3d{-inf, 2, inf}, Vec3d{nan, 1, 0},
                           Vec3d{1, nan, 5}, Vec3d{1e308, 1e308, 1e308}})
        EXPECT_EQ(viewIndexFor(views, eye + d), viewIndexFor(untagged, eye + d));
    // Tags in order but two eyes (faces 3-5 of another light's cube): no shared eye, so the faces'
    // own dot products decide, each with its own eye.
    Light other = lamp;
    other.position = {0.3, 1.2, -2.1};
    std::vector<LightView> mixed = views;
    const std::vector<LightView> otherViews = makeLightViews(other, Box3d{{-5, -5, -5}, {5, 5, 5}}, 64, 1);
    for (int k = 3; k < 6; ++k) mixed[size_t(k)] = otherViews[size_t(k)];
    for (const Vec3d& d : offsets) {
        const Vec3d p = eye + d;
        int want = -1;
        double bestDot = 0;
        for (int k = 0; k < 6; ++k) {
            const double dd = dot(p - mixed[size_t(k)].frame.eye(), mixed[size_t(k)].frame.forward());
            if (dd > bestDot) want = k, bestDot = dd;
        }
        ASSERT_EQ(viewIndexFor(mixed, p), want) << d.x << ", " << d.y << ", " << d.z;
    }
}

TEST(ShadowTest, PointLightInsideALeafBoxDimsEveryDirectionOnce) {
    // A box of six leaf faces around a point light: every point outside is behind exactly one face
    // (cube-face views, each one perspective frame). Points near a box edge may fall on a column the
    // neighbouring face's leaf covers; the exact reference decides, and >= 97 % must agree.
    Scene s;
    SceneMesh box;
    box.name = "leafbox";
    box.mesh = test::makeBox({-1, -1, -1}, {1, 1, 1});
    box.material = s.addMaterial(leafMaterial({0.3f, 0.3f, 0.3f}, 0.5f, 0.0f));
    s.meshes.push_back(box);
    Light lamp;
    lamp.type = LightType::Point;
    lamp.position = {0.1, -0.05, 0.07};
    for (const std::string_view kind : {"transmittance", "absorption"}) {
        const LightShadow sh = buildLightShadow(s, lamp, gridOptions(kind, 128));
        ASSERT_EQ(shadowName(shadowOptionsNamed(kind)), kind);
        ASSERT_EQ(sh.index(), shadowOptionsNamed(kind).index());
        std::mt19937_64 rng(5);
        int agree = 0, total = 0;
        for (int i = 0; i < 600; ++i) {
            Vec3d d{std::normal_distribution<double>()(rng), std::normal_distribution<double>()(rng),
                    std::normal_distribution<double>()(rng)};
            const Vec3d p = lamp.position + normalize(d) * 3.0;
            const float ref = exactTransmittance(s, lamp, p).x;
            EXPECT_EQ(exactCrossings(s, lamp, p), 1);
            agree += std::abs(visibilityOf(sh, p, {0, 0, 0}).x - ref) < 1e-4f;
            ++total;
        }
        EXPECT_GE(agree, total * 97 / 100) << kind;
    }
}

TEST(ShadowTest, PointLightLookupsOffsetAcrossACubeFaceSeamStayShadowed) {
    // A leaf roof at y = 1 over a point light at the origin; receivers on a wall x = 3 facing the
    // light, around the seam y = x between the +X and +Y cube faces. The normal offset (towards the
    // light, -x) moves a lookup from the +X face's frustum into the +Y one for y just below 3: the
    // lookup must then use the +Y face, not report "outside the view" (full light). Every ray from
    // these points to the light crosses the roof exactly once (checked by the exact reference).
    const Scene s = oneLeafScene({0, 1, 0}, {0, 0, 3}, {3, 0, 0},
                                 leafMaterial({0.3f, 0.3f, 0.3f}, 0.5f, 0.0f)); // t = 0.5
    Light lamp;
    lamp.type = LightType::Point;
    lamp.position = {0, 0, 0};
    const Vec3d wallNormal{-1, 0, 0};
    for (const std::string_view kind : {"transmittance", "absorption"}) {
        const LightShadow sh = buildLightShadow(s, lamp, gridOptions(kind, 64));
        int wrong = 0;
        for (int i = 0; i < 200; ++i) {
            const Vec3d p{3.0, 2.0 + 0.998 * double(i) / 200.0, 0.2 - 0.002 * i};
            ASSERT_EQ(exactCrossings(s, lamp, p), 1);
            const float ref = exactTransmittance(s, lamp, p).x;
            wrong += !(std::abs(visibilityOf(sh, p, wallNormal).x - ref) < 1e-4f);
        }
        EXPECT_EQ(wrong, 0) << kind;
    }
}

TEST(ShadowTest, PointsOnALeafAreNotShadowedByTheirOwnLeaf) {
    // Self-shadowing bias: normal offset towards the light plus the skipped own cell. Leaves turned
    // about 20, 50 and 70 degrees from facing the light.
    for (const double tilt : {0.4, 1.5, 3.0}) {
        const Vec3d c{0, 2, 0}, u = normalize(Vec3d{1, tilt, 0}), v = normalize(Vec3d{0, 0.3, 1});
        const Scene s = oneLeafScene(c, u, v, leafMaterial({0.3f, 0.3f, 0.3f}, 0.5f, 0.0f));
        Vec3d n = normalize(cross(u, v));
        const Light light = sun({0.2, -1, 0.1});
        if (dot(n, -light.direction) < 0) n = -n;
        // Own-column and filtered lookups: the filtered one reads each neighbouring column where the
        // leaf's own plane crosses it (receiver-plane depth).
        for (const std::string_view kind : {"transmittance", "absorption"})
            for (const bool conservative : {false, true})
                for (const bool bilinear : {false, true}) {
                    ShadowOptions o = gridOptions(kind, 128);
                    if (conservative) {
                        setShadowOption(o, "voxelMode", std::string("conservative"));
                        setShadowOption(o, "coverage", std::string("conservative"));
                    }
                    setShadowOption(o, "bilinear", bilinear);
                    const LightShadow sh = buildLightShadow(s, light, o);
                    std::mt19937_64 rng(2);
                    std::uniform_real_distribution<double> w(-0.9, 0.9);
                    int lit = 0;
                    for (int i = 0; i < 500; ++i) // 1 within float rounding of the filter's weights
                        lit += visibilityOf(sh, c + u * w(rng) + v * w(rng), n).x >= 1.0f - 1e-6f;
                    std::printf("tilt %.1f %s%s%s: %d of 500 lit\n", tilt, std::string(kind).c_str(),
                                conservative ? " conservative" : "", bilinear ? " bilinear" : "", lit);
                    EXPECT_GE(lit, 495)
                        << "tilt " << tilt << " " << kind << (conservative ? " conservative" : " centre")
                        << (bilinear ? " bilinear" : " own column");
                }
    }
}

// ---- Filtered lookups (the default) -------------------------------------------------------------

/// Stair-stepping of a shadow edge: an opaque box turned 17 degrees about the vertical under a sun
/// straight down, so its shadow edge on the ground runs across the light grid's columns. Along the
/// edge, at `rows` positions, the ground is sampled across it (1/16 of a column apart) and the
/// crossing of visibility 0.5 is found; the exact edge is the box's side. `wiggle` is the RMS of
/// the crossing's distance from the edge about its mean (the staircase), `offset` that mean, both
/// in columns.
struct EdgeSteps {
    double wiggle = 0, offset = 0;
};

EdgeSteps edgeSteps(std::string_view kind, int64_t n, bool bilinear, double sharpness = 1) {
    const double angle = 17.0 * 3.14159265358979 / 180.0, c = std::cos(angle), sn = std::sin(angle);
    Scene s;
    SceneMesh ground;
    ground.name = "ground";
    appendQuad(ground.mesh, {0, 0, 0}, {0, 0, 4}, {4, 0, 0});
    ground.material = s.addMaterial(Material{});
    ground.castsShadow = false;
    s.meshes.push_back(ground);
    SceneMesh box;
    box.name = "box";
    box.mesh = test::makeBox({-1, 1, -1}, {1, 2, 1});
    for (Vec3f& p : box.mesh.positions) p = Vec3f(float(c * p.x - sn * p.z), p.y, float(sn * p.x + c * p.z));
    // Nearly opaque tissue (0.05 per crossing): a partial occluder, so transmittance looks it up in
    // its light grid (an opaque box would go to its standard shadow map).
    box.material = s.addMaterial(leafMaterial({0.5f, 0.5f, 0.5f}, 0.95f, 0.0f));
    s.meshes.push_back(box);
    ShadowOptions o = gridOptions(kind, n);
    setShadowOption(o, "bilinear", bilinear);
    setShadowOption(o, "sharpness", sharpness);
    const LightShadow sh = buildLightShadow(s, sun({0, -1, 0}), o);
    // The box's +x side after the turn: (1, z') maps to (c - sn z', sn + c z'); outward normal (c, sn).
    const Vec3d u{c, 0, sn}, along{-sn, 0, c};
    const Vec3d edge0{c, 0, sn};
    // The column width of the light view the technique fits to its casters (the turned box).
    Box3d bounds;
    for (const Vec3f& p : s.meshes[1].mesh.positions) bounds.extend(Vec3d(p));
    const double column = makeLightViews(sun({0, -1, 0}), bounds, n, n).at(0).columnWorldSize(edge0);
    std::vector<double> d;
    const int rows = 400;
    for (int r = 0; r < rows; ++r) {
        const double t = -0.8 + 1.6 * (r + 0.5) / rows;
        const Vec3d base = edge0 + along * t;
        double prev = -1, prevX = 0, hit = std::nan("");
        for (int k = -64; k <= 64; ++k) {
            const double x = double(k) / 16 * column;
            const double v = visibilityOf(sh, base + u * x, {0, 1, 0}).x;
            if (prev >= 0 && prev < 0.5 && v >= 0.5) {
                hit = prevX + (0.5 - prev) / (v - prev) * (x - prevX);
                break;
            }
            prev = v;
            prevX = x;
        }
        if (std::isfinite(hit)) d.push_back(hit / column);
    }
    EdgeSteps e;
    if (d.size() < size_t(rows) * 9 / 10) return {1e9, 1e9};
    for (const double x : d) e.offset += x;
    e.offset /= double(d.size());
    for (const double x : d) e.wiggle += (x - e.offset) * (x - e.offset);
    e.wiggle = std::sqrt(e.wiggle / double(d.size()));
    return e;
}

// Issue 26 item 6: filtered (bilinear) light-grid lookups by default (BENCHMARKS.md, "Filtered
// light-grid lookups"): filtering shortens the staircase of a shadow edge across the columns and
// lowers the 95th percentile of the error against exact transport on foliage; the price is a
// somewhat higher mean at 128 and 256 columns (a column's width of blur at every leaf's edge).
// Tilted leaves do not shadow themselves (PointsOnALeafAreNotShadowedByTheirOwnLeaf, bilinear).
// --no-bilinear gives ED06's own-column lookup.
TEST(ShadowTest, FilteredLookupsShortenTheEdgeStaircaseAndBlurTheFoliage) {
    EXPECT_TRUE(LightGridOptions{}.bilinear);
    for (const std::string_view kind : {"transmittance", "absorption"}) {
        for (const int64_t n : {64, 128}) {
            const EdgeSteps nearest = edgeSteps(kind, n, false), filtered = edgeSteps(kind, n, true);
            std::printf("%s %lld: edge staircase (RMS of the 0.5 crossing about the edge) nearest %.3f, "
                        "filtered %.3f columns (mean offset %.3f, %.3f)\n",
                        std::string(kind).c_str(), (long long)n, nearest.wiggle, filtered.wiggle,
                        nearest.offset, filtered.offset);
            EXPECT_GT(nearest.wiggle, 0.2) << kind << " " << n; // a step a column: about 1 / sqrt(12)
            EXPECT_LT(filtered.wiggle, 0.85 * nearest.wiggle) << kind << " " << n;
        }
    }
    const Scene s = leafScene(500, 2, 51);
    const Light light = sun();
    const Reference pts = exactReference(s, light, 1500, 6);
    for (const std::string_view kind : {"transmittance", "absorption"})
        for (const int64_t n : {64, 128, 256}) {
            ShadowOptions nearest = gridOptions(kind, n), filtered = gridOptions(kind, n);
            setShadowOption(nearest, "bilinear", false);
            setShadowOption(filtered, "bilinear", true);
            const ErrorStats en = shadowError(s, light, pts, nearest),
                             ef = shadowError(s, light, pts, filtered);
            std::printf("%s %lld: error against exact, mean nearest %.4f, filtered %.4f; p95 %.4f, %.4f\n",
                        std::string(kind).c_str(), (long long)n, en.mean, ef.mean, en.p95, ef.p95);
            EXPECT_LT(ef.p95, en.p95) << kind << " " << n;
            EXPECT_LT(ef.mean, 1.3 * en.mean) << kind << " " << n;
            if (n >= 128) { EXPECT_GT(ef.mean, en.mean) << kind << " " << n; } // the blur's price
        }
}

// The mean error against exact transport (ExactShadow: every leaf crossed, its transmission
// multiplied in) over `count` ground points (y = 0, in the square of half size `half`) that the
// exact shadow darkens, of the lookups named: own column (nearest), or bilinear with a sharpness.
struct FoliageFilter {
    const char* name;
    bool bilinear;
    double sharpness;
};
std::vector<double> foliageErrors(const Scene& s, std::string_view kind, int64_t n, double half, int count,
                                  std::span<const FoliageFilter> filters) {
    const Light& light = s.lights.at(0);
    const LightShadow exact = buildLightShadow(s, light, ExactShadowOptions{});
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-half, half);
    std::vector<Vec3d> pts;
    std::vector<Vec3f> ref;
    for (int tries = 0; int(pts.size()) < count && tries < 100 * count; ++tries) {
        const Vec3d p{u(rng), 0, u(rng)};
        const Vec3f e = visibilityOf(exact, p, {0, 1, 0});
        if (std::max({e.x, e.y, e.z}) > 0.999f) continue;
        pts.push_back(p);
        ref.push_back(e);
    }
    EXPECT_EQ(int(pts.size()), count);
    std::vector<double> out;
    for (const FoliageFilter& f : filters) {
        ShadowOptions o = gridOptions(kind, n);
        setShadowOption(o, "bilinear", f.bilinear);
        setShadowOption(o, "sharpness", f.sharpness);
        const LightShadow sh = buildLightShadow(s, light, o);
        double sum = 0;
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const Vec3f v = visibilityOf(sh, pts[i], {0, 1, 0}), e = ref[i];
            sum += (std::abs(v.x - e.x) + std::abs(v.y - e.y) + std::abs(v.z - e.z)) / 3;
        }
        out.push_back(sum / double(pts.size()));
    }
    return out;
}

// #37: plain bilinear lookups cut the staircase but raised the mean error against exact by 12-22 %
// on random leaves looked up without a normal (a column wide ramp at every leaf's edge, where the own
// column puts a step at the midpoint: in one dimension the ramp's error is 1/3 of a column per edge,
// the step's 1/4). On the demo tree and a forest of 9 trees, looked up with the ground's normal as
// the renderer does, the default (plain bilinear) keeps the short staircase and does not raise the
// mean: within 3 % of the own column's in every case (both kinds, 128 and 256 columns) and lower on
// average. The table of filters in BENCHMARKS.md is this test's output: sharpening the blend
// (LightGridOptions::sharpness) brings the random leaves' mean down but raises the forest's at 128
// columns, and it breaks a property the default keeps (MoreLeafLayersNeverMakeAPointBrighter).
TEST(ShadowTest, BilinearLookupsKeepTheShortStaircaseWithoutRaisingTheMeanErrorOnTheDemoFoliage) {
    EXPECT_TRUE(LightGridOptions{}.bilinear);
    EXPECT_EQ(LightGridOptions{}.sharpness, 1);
    const FoliageFilter filters[] = {{"own column", false, 1},     {"bilinear", true, 1},
                                     {"sharpened 1.5", true, 1.5}, {"sharpened 2", true, 2},
                                     {"sharpened 4", true, 4},     {"sharpened 8", true, 8},
                                     {"step", true, 1e6}};
    for (const std::string_view kind : {"transmittance", "absorption"}) {
        const EdgeSteps nearest = edgeSteps(kind, 128, false), filtered = edgeSteps(kind, 128, true);
        std::printf("%s 128: staircase own column %.3f, bilinear %.3f, sharpened 2 %.3f\n",
                    std::string(kind).c_str(), nearest.wiggle, filtered.wiggle,
                    edgeSteps(kind, 128, true, 2).wiggle);
        EXPECT_LT(filtered.wiggle, 0.85 * nearest.wiggle) << kind;
    }
    demo::TreeOptions t;
    t.leaves = 1500;
    demo::ForestOptions f;
    f.trees = 9;
    f.leavesPerTree = 300;
    Scene leaves = leafScene(500, 2, 51);
    leaves.lights = {sun()};
    const std::pair<const char*, Scene> scenes[] = {
        {"tree", demo::makeTreeScene(t)}, {"forest", demo::makeForestScene(f)}, {"leaves", leaves}};
    double ratioSum = 0;
    int ratios = 0;
    for (const auto& [name, s] : scenes)
        for (const std::string_view kind : {"transmittance", "absorption"})
            for (const int64_t n : {128, 256}) {
                const bool demoScene = std::string_view(name) != "leaves";
                const std::vector<double> e =
                    foliageErrors(s, kind, n, std::string_view(name) == "forest" ? 7.0 : 3.0, 400, filters);
                std::printf("%s %s %lld: mean error", name, std::string(kind).c_str(), (long long)n);
                for (std::size_t i = 0; i < e.size(); ++i) std::printf(" | %s %.4f", filters[i].name, e[i]);
                std::printf("\n");
                if (!demoScene) continue;
                EXPECT_LE(e[1], 1.03 * e[0]) << name << " " << kind << " " << n;
                ratioSum += e[1] / e[0];
                ++ratios;
            }
    EXPECT_LT(ratioSum / ratios, 1.0); // lower than the own column's on average
}

TEST(ShadowTest, ReceiverPlaneDepthIsWhereThePlaneCrossesTheColumnWithinTwoFootprints) {
    // The bilinear lookups read each column at the depth where the receiver's plane (through q,
    // normal n) crosses the column's centre line, kept within two column footprints of q's depth.
    // By its definition, in world space: the centre line L(d) = worldFromGrid(x, y, d) is affine in
    // d, so the crossing is d* = qz - n.(L(qz) - Q) / n.(L(qz + 1) - L(qz)), clamped to
    // +-2 |L(x + 1) - L(x)| / |L(qz + 1) - L(qz)| about qz (both at q's depth). Orthographic (sun) and
    // perspective (spot) views; normals facing the light (crossings inside the reach) and nearly
    // along its rays (clamped at the reach), both many times.
    const Box3d bounds{{-2, 0, -2}, {2, 2, 2}};
    Light spot;
    spot.type = LightType::Spot;
    spot.position = {0.5, 6, 0.3};
    spot.direction = {0, -1, 0};
    spot.outerConeAngle = 0.9;
    std::mt19937_64 rng(21);
    std::uniform_real_distribution<double> unit(-1, 1), at(0, 1);
    for (const Light& light : {sun({0.3, -1, 0.2}), spot}) {
        const LightView view = makeLightViews(light, bounds, 64, 48)[0];
        const Frame& f = view.frame;
        const bool perspective = f.isPerspective();
        int inside = 0, clamped = 0;
        for (int i = 0; i < 20000; ++i) {
            const Vec3d qGrid{at(rng) * double(f.width()), at(rng) * double(f.height()),
                              perspective ? 2 + 4 * at(rng) : at(rng) * double(f.depth())};
            // Half the normals nearly perpendicular to the view's depth axis: a plane nearly along the
            // light's rays, whose crossings run far along the neighbouring columns.
            Vec3d n = normalize(Vec3d{unit(rng), unit(rng), unit(rng)});
            if (i % 2) n = normalize(n - f.forward() * (dot(n, f.forward()) * (1 - 1e-3 * at(rng))));
            const detail::ReceiverPlane plane(view, qGrid, n);
            const Vec3d Q = f.worldFromGrid(qGrid);
            for (int k = 0; k < 4; ++k) {
                const double x = std::floor(qGrid.x - 0.5) + 0.5 + double(k & 1),
                             y = std::floor(qGrid.y - 0.5) + 0.5 + double(k >> 1);
                const Vec3d L0 = f.worldFromGrid({x, y, qGrid.z}), L1 = f.worldFromGrid({x, y, qGrid.z + 1});
                const double slope = dot(n, L1 - L0);
                const double footprint = length(f.worldFromGrid(qGrid + Vec3d{1, 0, 0}) - Q);
                const double reach = 2 * footprint / length(L1 - L0);
                const double free = -dot(n, L0 - Q) / slope;
                const double want = qGrid.z + std::clamp(free, -reach, reach);
                const double got = plane.depthAt(x, y);
                ASSERT_NEAR(got, want, 1e-7 * (1 + std::abs(want)))
                    << (perspective ? "spot" : "sun") << " point " << i << " column " << k;
                (std::abs(free) < reach ? inside : clamped) += 1;
            }
        }
        EXPECT_GT(inside, 15000) << (perspective ? "spot" : "sun");
        EXPECT_GT(clamped, 15000) << (perspective ? "spot" : "sun");
    }
}

} // namespace
} // namespace voxfx
