// Tests of the standard shadow map (voxfx/shadow_map.hpp, technique "map") and of the maps built in
// light views (voxfx/light_view.hpp): binary shadows under a box; the map's depths and the ED06
// slicemap's cells against brute-force rays through each texel's centre (Moller–Trumbore, sharing
// no code with the rasterizer); opaque leaves, which the transmittance technique puts in its own
// standard map, shadowed exactly where those rays are blocked.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <random>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "render/float_threshold.hpp"
#include "support/shadow_reference.hpp"
#include "test_util.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/shadow_map.hpp"
#include "voxfx/transmittance_shadow.hpp"

namespace voxfx {
namespace {

using test::gridOptions;
using test::leafScene;
using test::rayTriangle;
using test::sun;
using test::visibilityOf;

TEST(ShadowTest, StandardShadowMapIsBinaryUnderABox) {
    Scene s;
    SceneMesh box;
    box.name = "box";
    box.mesh = test::makeBox({-0.5, 1, -0.5}, {0.5, 2, 0.5});
    box.material = s.addMaterial(Material{});
    s.meshes.push_back(box);
    ShadowOptions o = gridOptions("map", 256);
    const LightShadow sh = buildLightShadow(s, sun({0, -1, 0}), o);
    EXPECT_EQ(visibilityOf(sh, {0, 0, 0}, {0, 1, 0}).x, 0.0f);
    EXPECT_EQ(visibilityOf(sh, {0.4, 0, -0.4}, {0, 1, 0}).x, 0.0f);
    EXPECT_EQ(visibilityOf(sh, {0.8, 0, 0}, {0, 1, 0}).x, 1.0f);
    EXPECT_EQ(visibilityOf(sh, {0, 2.2, 0}, {0, 1, 0}).x, 1.0f); // above the box
    EXPECT_EQ(visibilityOf(sh, {0, 2.0, 0}, {0, 1, 0}).x, 1.0f); // on its lit top face: no acne
    EXPECT_EQ(visibilityOf(sh, {0, 0, 0}, {0, 1, 0}).y, 0.0f);
}

// The ray through the centre of texel (i, j) of a light view, from its near plane.
void texelRay(const LightView& v, int64_t i, int64_t j, Vec3d& origin, Vec3d& dir) {
    origin = v.frame.worldFromGrid({double(i) + 0.5, double(j) + 0.5, 0.0});
    dir = normalize(v.frame.worldFromGrid({double(i) + 0.5, double(j) + 0.5, 1.0}) - origin);
}

/// Whether the ray through the centre of texel (i, j) of `view` hits a triangle of `mesh`
/// (Moller–Trumbore on every triangle).
bool texelRayHits(const LightView& view, int64_t i, int64_t j, const Mesh& mesh) {
    Vec3d o, d;
    texelRay(view, i, j, o, d);
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        if (rayTriangle(o, d, Vec3d(mesh.positions[mesh.indices[3 * t]]),
                        Vec3d(mesh.positions[mesh.indices[3 * t + 1]]),
                        Vec3d(mesh.positions[mesh.indices[3 * t + 2]])) >= 0)
            return true;
    return false;
}

TEST(ShadowTest, AllLeavesOpaqueGiveBinaryShadowsWhereRaysThroughTheTexelsAreBlocked) {
    // Opaque leaves: the map and the transmittance technique (whose opaque casters go to its standard
    // map, and which then builds no light grid) must give 0 where the rays through every texel
    // centre around a ground point's texel hit a leaf and 1 where none does (every leaf lies above
    // the ground, so a hit is a caster in front of the point). The oracle casts those rays against
    // the leaves by brute force; points whose 5 x 5 texels disagree (a shadow's edge, where PCF
    // blends) are left out.
    const Scene s = leafScene(300, 2, 21, 1.0f);
    for (const Material& m : s.materials) EXPECT_TRUE(m.isOpaque());
    Mesh leaves = s.meshes[1].mesh; // both colour groups' quads
    for (const Vec3f& v : s.meshes[2].mesh.positions) leaves.positions.push_back(v);
    for (const uint32_t i : s.meshes[2].mesh.indices)
        leaves.indices.push_back(i + uint32_t(s.meshes[1].mesh.positions.size()));
    const Light light = sun();
    const LightShadow tr = buildLightShadow(s, light, gridOptions("transmittance", 256));
    const LightShadow map = buildLightShadow(s, light, gridOptions("map", 256));
    EXPECT_TRUE(std::get<TransmittanceShadow>(tr).maps().empty());
    const LightView& view = std::get<MapShadow>(map).views().at(0);
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(-3, 3);
    int tested = 0, dark = 0;
    for (int i = 0; i < 1500; ++i) {
        const Vec3d p{u(rng), 0, u(rng)};
        const Vec3d g = view.gridFromWorld(p);
        int hits = 0;
        for (int64_t dy = -2; dy <= 2; ++dy)
            for (int64_t dx = -2; dx <= 2; ++dx)
                hits +=
                    texelRayHits(view, int64_t(std::floor(g.x)) + dx, int64_t(std::floor(g.y)) + dy, leaves);
        if (hits != 0 && hits != 25) continue;
        ++tested;
        dark += hits == 25;
        const float expected = hits == 25 ? 0.0f : 1.0f;
        for (const LightShadow* sh : {&tr, &map})
            ASSERT_TRUE(visibilityOf(*sh, p, {0, 1, 0}) == (Vec3f{expected, expected, expected}))
                << i << " at " << p.x << ", " << p.z << (sh == &tr ? " (transmittance)" : " (map)");
    }
    EXPECT_GT(tested, 1000);
    EXPECT_GT(dark, 100);
}

TEST(ShadowTest, ShadowMapAndSlicemapHoldWhatTheRayThroughEachTexelCentreHits) {
    // Centre-sampled coverage: a caster covers a texel exactly when the ray through the texel's
    // centre hits it. The brute-force oracle casts that ray against every leaf triangle
    // (Moller–Trumbore, no shared code): the standard map must hold the nearest hit's depth, and
    // the ED06 slicemap must have a filled cell in exactly the columns the ray hits, at the hit's
    // slice.
    const Scene s = leafScene(400, 1, 31);
    const Mesh& leaves = s.meshes[1].mesh;
    const Light light = sun();
    const Box3d bounds = computeBounds(leaves.view());
    const LightView mapView = makeLightViews(light, bounds, 160, 1)[0];
    const LightView gridView = makeLightViews(light, bounds, 160, 64)[0];
    const ShadowMap map = ShadowMap::build(leaves.view(), mapView);
    const MeshView groups[1] = {leaves.view()};
    const Vec3f zero[1] = {{0, 0, 0}};
    const TransmittanceShadowMap grid =
        TransmittanceShadowMap::build(gridView, groups, zero, VoxelizeMode::Surface, Slicing::Uniform);
    const BitGrid& bits = grid.channels()[0].grid.bits;
    int64_t covered = 0;
    for (int64_t j = 0; j < mapView.frame.height(); ++j)
        for (int64_t i = 0; i < mapView.frame.width(); ++i) {
            Vec3d o, d;
            texelRay(mapView, i, j, o, d);
            double nearest = std::numeric_limits<double>::infinity();
            for (size_t t = 0; t < leaves.triangleCount(); ++t) {
                const double h = rayTriangle(o, d, Vec3d(leaves.positions[leaves.indices[3 * t]]),
                                             Vec3d(leaves.positions[leaves.indices[3 * t + 1]]),
                                             Vec3d(leaves.positions[leaves.indices[3 * t + 2]]));
                if (h >= 0) nearest = std::min(nearest, h);
            }
            const float depth = map.depthAt(i, j);
            if (!std::isfinite(nearest)) {
                ASSERT_TRUE(std::isinf(depth)) << i << ", " << j;
                ASSERT_EQ(countColumnRange(bits.column(j * gridView.frame.width() + i), bits.depth(), 0,
                                           bits.depth()),
                          0)
                    << i << ", " << j;
                continue;
            }
            ++covered;
            const Vec3d hit = o + d * nearest;
            // The tolerance from the oracle's depth (one from the map's would be infinite where the
            // map missed the caster).
            const double expected = mapView.gridFromWorld(hit).z;
            ASSERT_NEAR(depth, expected, 1e-4 * (1 + std::abs(expected))) << i << ", " << j;
            // The slicemap: the slice of the nearest hit is filled (same view, same columns).
            const int64_t slice = int64_t(std::floor(gridView.gridFromWorld(hit).z));
            const uint64_t* col = bits.column(j * gridView.frame.width() + i);
            bool near = false; // the hit's slice, or its neighbour for a hit within 1e-6 slices of a boundary
            for (int64_t k = std::max<int64_t>(0, slice - 1);
                 k <= std::min<int64_t>(bits.depth() - 1, slice + 1); ++k)
                near = near || ((col[k >> 6] >> (k & 63)) & 1);
            ASSERT_TRUE(near) << i << ", " << j << " slice " << slice;
        }
    EXPECT_GT(covered, 2000);
}

} // namespace
} // namespace voxfx

namespace voxfx {
namespace {

// The percentage-closer filter by its definition, from the map's depths: the fraction of the
// (2r+1)^2 texels around p's (clamped to the map) whose depth is not in front of p by more than
// `bias` world units.
float pcfByDefinition(const ShadowMap& map, const Vec3d& p, int r, double bias) {
    const LightView& v = map.view();
    const Vec3d g = v.gridFromWorld(p);
    const int64_t W = v.frame.width(), H = v.frame.height();
    const int64_t cx = std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, W - 1),
                  cy = std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, H - 1);
    int lit = 0;
    for (int64_t y = cy - r; y <= cy + r; ++y)
        for (int64_t x = cx - r; x <= cx + r; ++x)
            lit += double(map.depthAt(std::clamp<int64_t>(x, 0, W - 1), std::clamp<int64_t>(y, 0, H - 1))) >=
                   g.z - bias / v.worldPerDepthUnit();
    return float(lit) / float((2 * r + 1) * (2 * r + 1));
}

TEST(ShadowTest, FloatThresholdComparesFloatsAsTheDoubleLimitDoes) {
    // The PCF taps compare float depths d with float f = leastFloatAtLeast(limit) in place of
    // double(d) >= limit. For each limit (random doubles over 2^-30..2^30 of either sign, floats
    // exactly, midpoints between floats and one double step either side, zeros, the float range's
    // ends, infinities, NaN), every float within four steps of float(limit), and the special
    // floats, must get the same answer from both compares.
    std::vector<double> limits;
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> expo(-30, 30), unit(-1, 1);
    for (int i = 0; i < 20000; ++i) {
        const double x = std::copysign(std::exp2(expo(rng)), unit(rng));
        const auto f = float(x);
        const double mid =
            0.5 * (double(f) + double(std::nextafter(f, std::numeric_limits<float>::infinity())));
        limits.insert(limits.end(),
                      {x, double(f), mid, std::nextafter(mid, 0.0), std::nextafter(mid, 1e300)});
    }
    const double fmax = std::numeric_limits<float>::max(), dinf = std::numeric_limits<double>::infinity();
    limits.insert(limits.end(),
                  {0.0, -0.0, fmax, -fmax, std::nextafter(fmax, dinf), std::nextafter(-fmax, -dinf),
                   std::nextafter(fmax, 0.0), 1e300, -1e300, dinf, -dinf,
                   std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::denorm_min(),
                   -std::numeric_limits<double>::denorm_min(),
                   double(std::numeric_limits<float>::denorm_min()) * 0.5});
    constexpr float finf = std::numeric_limits<float>::infinity();
    int64_t lit = 0, dark = 0;
    for (const double limit : limits) {
        const float f = detail::leastFloatAtLeast(limit);
        std::vector<float> ds = {
            0.0f, -0.0f, finf, -finf, std::numeric_limits<float>::quiet_NaN(), float(fmax), -float(fmax)};
        if (!std::isnan(limit)) {
            float d =
                std::isinf(float(limit)) ? float(fmax) * std::copysign(1.0f, float(limit)) : float(limit);
            for (int k = 0; k < 4; ++k) d = std::nextafter(d, -finf);
            for (int k = 0; k < 9; ++k, d = std::nextafter(d, finf)) ds.push_back(d);
        }
        for (const float d : ds) {
            const bool want = double(d) >= limit;
            ASSERT_EQ(d >= f, want) << "limit " << limit << " depth " << d;
            (want ? lit : dark) += 1;
        }
    }
    EXPECT_GT(lit, 200000); // both answers, many times, next to each limit
    EXPECT_GT(dark, 200000);
}

// One caster mesh: leafScene's ground and leaves, and a 0.2 x 2 x 0.2 box standing at each of `trunks`.
Mesh groundLeavesAndTrunks(const Scene& s, std::initializer_list<Vec3d> trunks) {
    Mesh casters = s.meshes[0].mesh; // the ground
    auto add = [&](const Mesh& m) {
        const auto base = uint32_t(casters.positions.size());
        casters.positions.insert(casters.positions.end(), m.positions.begin(), m.positions.end());
        for (const uint32_t i : m.indices) casters.indices.push_back(base + i);
    };
    add(s.meshes[1].mesh);
    for (const Vec3d& at : trunks) add(test::makeBox(at - Vec3d{0.1, 0, 0.1}, at + Vec3d{0.1, 2, 0.1}));
    return casters;
}

TEST(ShadowTest, ShadowMapLookupIsItsFilterByDefinitionOnGroundTrunksAndLeaves) {
    // A ground that casts (as a forest's floor does), lit at a slant, boxes standing on it like
    // trunks and leaves above: the lookup (which may answer "every tap lit" from a bound of the depths around
    // a block of texels) must equal the filter counted tap by tap, for points on the ground, just
    // above it, on the boxes' sides and among the leaves, with every PCF radius and bias.
    const Scene s = leafScene(300, 1, 7, 1.0f);
    const Mesh casters = groundLeavesAndTrunks(s, {Vec3d{-1, 0, -1}, Vec3d{1.2, 0, 0.3}, Vec3d{0, 0, 1.5}});
    const Light light = sun({0.55, -1, 0.35});
    const LightView view = makeLightViews(light, computeBounds(casters.view()), 300, 1)[0];
    const ShadowMap map = ShadowMap::build(casters.view(), view);
    const double texel = view.columnWorldSize({0, 0, 0});
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-3.2, 3.2), h(0, 3);
    int64_t lit = 0, dark = 0, partial = 0;
    for (int i = 0; i < 20000; ++i) {
        // Half on the ground (lifted by 0 to 2 texels, the lookup's own offsets), half anywhere.
        const Vec3d p = i % 2 ? Vec3d{u(rng), h(rng), u(rng)} : Vec3d{u(rng), texel * (i % 5) * 0.5, u(rng)};
        for (const int r : {0, 1, 2})
            for (const double bias : {0.0, 1.0, 2.5}) {
                const float got = map.visibility(p, r, bias * texel),
                            want = pcfByDefinition(map, p, r, bias * texel);
                ASSERT_EQ(got, want) << p.x << ", " << p.y << ", " << p.z << " r " << r << " bias " << bias;
                (want == 1 ? lit : want == 0 ? dark : partial) += 1;
            }
    }
    // Each kind of answer is well represented.
    EXPECT_GT(lit, 20000);
    EXPECT_GT(dark, 5000);
    EXPECT_GT(partial, 2000);
}

TEST(ShadowTest, ShadowMapLookupUnderAWideCasterIsItsFilterByDefinition) {
    // A roof over the ground, wider than many blocks of texels: ground points under it lie behind
    // every tap around them (the lookup may answer "every tap dark" from the greatest depth of a
    // block), points near its edges see both. The lookup must equal the filter counted tap by tap.
    const Scene s = leafScene(10, 1, 7, 1.0f);
    Mesh casters = s.meshes[0].mesh; // the ground
    const Mesh roof = test::makeBox({-1.5, 1.0, -1.2}, {1.3, 1.1, 1.4});
    const auto base = uint32_t(casters.positions.size());
    casters.positions.insert(casters.positions.end(), roof.positions.begin(), roof.positions.end());
    for (const uint32_t i : roof.indices) casters.indices.push_back(base + i);
    const LightView view = makeLightViews(sun({0.55, -1, 0.35}), computeBounds(casters.view()), 300, 1)[0];
    const ShadowMap map = ShadowMap::build(casters.view(), view);
    const double texel = view.columnWorldSize({0, 0, 0});
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(-3.2, 3.2);
    int64_t dark = 0, other = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3d p{u(rng), texel * (i % 5) * 0.5, u(rng)};
        for (const int r : {0, 1, 2})
            for (const double bias : {0.0, 1.0, 2.5}) {
                const float got = map.visibility(p, r, bias * texel),
                            want = pcfByDefinition(map, p, r, bias * texel);
                ASSERT_EQ(got, want) << p.x << ", " << p.y << ", " << p.z << " r " << r << " bias " << bias;
                (want == 0 ? dark : other) += 1;
            }
    }
    EXPECT_GT(dark, 15000); // the roof's shadow: about a sixth of the ground
    EXPECT_GT(other, 30000);
}

TEST(ShadowTest, MapShadowLookupIsTheFilterAtTheNormalOffsetPointWithItsBias) {
    // MapShadow moves p by normalOffset texel footprints along n and counts casters depthBias
    // footprints in front (its orthographic views take that bias in depth units once per view):
    // its answer must be the filter counted tap by tap at p + n * offset * texel with a bias of
    // depthBias * texel world units, for points on the ground, on the boxes and among the leaves,
    // with normals up, towards the light and at random, every PCF radius, offset and bias.
    const Scene s = leafScene(300, 1, 7, 1.0f);
    const Mesh casters = groundLeavesAndTrunks(s, {Vec3d{-1, 0, -1}, Vec3d{1.2, 0, 0.3}});
    const Light light = sun({0.55, -1, 0.35});
    const Vec3d toLight = normalize(Vec3d{-0.55, 1, -0.35});
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> u(-3.2, 3.2), h(0, 3), unit(-1, 1);
    int64_t lit = 0, dark = 0, partial = 0;
    for (const int r : {0, 1, 2})
        for (const double offset : {0.0, 1.0, 2.5})
            for (const double bias : {0.0, 1.0, 2.5}) {
                ShadowMapOptions o;
                o.resolution = 300;
                o.pcfRadius = r;
                o.normalOffset = offset;
                o.depthBias = bias;
                const MapShadow shadow = MapShadow::build(light, casters.view(), o);
                ASSERT_EQ(shadow.maps().size(), 1u);
                const ShadowMap& map = shadow.maps()[0];
                const double texel = map.view().columnWorldSize({0, 0, 0});
                for (int i = 0; i < 3000; ++i) {
                    const Vec3d p = i % 2 ? Vec3d{u(rng), h(rng), u(rng)} : Vec3d{u(rng), 0, u(rng)};
                    const Vec3d n = i % 3 == 0   ? Vec3d{0, 1, 0}
                                    : i % 3 == 1 ? toLight
                                                 : normalize(Vec3d{unit(rng), unit(rng), unit(rng)});
                    const float got = shadow.visibility(p, n);
                    const Vec3d q = p + n * (offset * texel);
                    // Outside the view (p, or q beyond its border): full light.
                    const float want = map.view().covers(p) && map.view().covers(q)
                                           ? pcfByDefinition(map, q, r, bias * texel)
                                           : 1.0f;
                    ASSERT_EQ(got, want) << p.x << ", " << p.y << ", " << p.z << " r " << r << " offset "
                                         << offset << " bias " << bias;
                    (want == 1 ? lit : want == 0 ? dark : partial) += 1;
                }
            }
    EXPECT_GT(lit, 20000);
    EXPECT_GT(dark, 5000);
    EXPECT_GT(partial, 1000);
}

} // namespace
} // namespace voxfx
