// Tests of the transmittance shadow (ED06 §3.1: voxfx/transmittance_shadow.hpp, technique
// "transmittance") against exact light transport (the brute-force crossing counter of
// tests/support/shadow_reference.hpp): one leaf layer transmits exactly its factor, a conservative
// grid counts a tilted leaf once and errs about as little as the surface grid, bad input, no
// casters. What it shares with absorption (the light grid's lookups) is tested in
// test_light_grid.cpp; the techniques against each other in test_shadow_cross_technique.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "support/shadow_reference.hpp"
#include "test_util.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/transmittance_shadow.hpp"

namespace voxfx {
namespace {

using test::ErrorStats;
using test::exactReference;
using test::gridOptions;
using test::leafMaterial;
using test::leafScene;
using test::oneLeafScene;
using test::Reference;
using test::shadowError;
using test::sun;
using test::visibilityOf;

TEST(ShadowTest, OneLeafLayerTransmitsExactlyItsFactor) {
    // A horizontal leaf over [-1, 1]^2 at y = 2, the sun straight down: every ground point under
    // it receives t = (1 - a) + a * tr * colour, points outside receive 1.
    const Scene s =
        oneLeafScene({0, 2, 0}, {0, 0, 1}, {1, 0, 0}, leafMaterial({0.2f, 0.5f, 0.1f}, 0.5f, 0.5f));
    const Vec3f t = s.materials[0].crossingTransmittance();
    EXPECT_NEAR(t.y, 0.5f + 0.5f * 0.5f * 0.5f, 1e-6f); // hand: 0.625
    // Surface (ED06): one cell per leaf and column, exactly t. Conservative: the run of cells the
    // leaf touches (two when it lies on a slice boundary) is one crossing: exactly t too.
    for (const VoxelizeMode mode : {VoxelizeMode::Surface, VoxelizeMode::Conservative})
        for (const Slicing slicing : {Slicing::Uniform, Slicing::Local}) {
            const LightShadow sh =
                buildLightShadow(s, sun({0, -1, 0}), gridOptions("transmittance", 64, slicing, mode));
            const std::string what = std::string(toString(mode)) + " " + toString(slicing);
            for (const double x : {-0.8, -0.3, 0.0, 0.5, 0.9}) {
                const Vec3f v = visibilityOf(sh, {x, 0, 0.1 * x}, {0, 0, 0});
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], t[c], 1e-5f) << what;
            }
            EXPECT_EQ(visibilityOf(sh, {1.5, 0, 0}, {0, 0, 0}).y, 1.0f) << what;
            EXPECT_EQ(visibilityOf(sh, {0, 2.5, 0}, {0, 0, 0}).y, 1.0f) << what; // above the leaf
        }
}

TEST(ShadowTest, ConservativeGridsCountATiltedLeafOnce) {
    // A leaf tilted 45 degrees across the sun's rays fills 2-3 consecutive cells of a column in a
    // conservative grid; it is one crossing, so the ground under it receives exactly t, as in the
    // surface grid (hand: one leaf, t = (1 - a) + a * tr * colour).
    const Scene s =
        oneLeafScene({0, 2, 0}, {0, 0, 1}, {0.7, 0.7, 0}, leafMaterial({0.2f, 0.5f, 0.1f}, 0.5f, 0.5f));
    const Vec3f t = s.materials[0].crossingTransmittance();
    for (const VoxelizeMode mode : {VoxelizeMode::Surface, VoxelizeMode::Conservative})
        for (const Slicing slicing : {Slicing::Uniform, Slicing::Local}) {
            const LightShadow sh =
                buildLightShadow(s, sun({0, -1, 0}), gridOptions("transmittance", 64, slicing, mode));
            const std::string what = std::string(toString(mode)) + " " + toString(slicing);
            for (const double x : {-0.5, -0.2, 0.0, 0.3, 0.55})
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(visibilityOf(sh, {x, 0, 0.3}, {0, 0, 0})[c], t[c], 1e-5f) << what;
        }
}

TEST(ShadowTest, ConservativeTransmittanceIsAboutAsCloseToExactAsSurface) {
    // Against exact transport on foliage: the conservative grid, which fills every cell a leaf
    // touches, counts each leaf once, so it errs about as little as ED06's surface grid; what it
    // adds is its coverage (a leaf darkens every column it touches: about a column's width around
    // each leaf, less at a finer grid). Counting cells made it 2-3 times as dark (mean error
    // 0.20 at 64 and 0.18 at 128 here, against the surface grid's 0.12 and 0.06; now 0.14 and 0.09).
    const Scene s = leafScene(500, 2, 51);
    const Light light = sun();
    const Reference pts = exactReference(s, light, 1500, 6);
    double previous = 1;
    for (const int64_t n : {64, 128}) {
        const ErrorStats surface = shadowError(s, light, pts, gridOptions("transmittance", n));
        const ErrorStats conservative = shadowError(
            s, light, pts, gridOptions("transmittance", n, Slicing::Uniform, VoxelizeMode::Conservative));
        std::printf("transmittance %lld: surface mean %.4f, conservative mean %.4f\n", (long long)n,
                    surface.mean, conservative.mean);
        EXPECT_LT(conservative.mean, 1.5 * surface.mean) << n;
        EXPECT_LT(conservative.mean, previous) << n;
        previous = conservative.mean;
    }
}

// Channel k's factor to the power of its cells in front of `depth` in column `column` (conservative:
// of its runs of consecutive cells that end there), over every channel: ED06's count, bit by bit.
Vec3f columnByDefinition(const TransmittanceShadowMap& map, std::span<const Vec3f> factors, bool runs,
                         int64_t column, double depth, int64_t skip) {
    Vec3f out{1, 1, 1};
    for (std::size_t k = 0; k < map.channels().size(); ++k) {
        const VoxelGrid& g = map.channels()[k].grid;
        const int64_t D = g.frame.depth();
        const double z = g.frame.depthToSlice(column)(depth);
        const int64_t end =
            z >= 0 ? std::clamp<int64_t>((z >= double(D) ? D : int64_t(z)) - skip + 1, 0, D) : 0;
        const uint64_t* bits = g.bits.column(column);
        auto filled = [&](int64_t i) { return i < D && ((bits[i >> 6] >> (i & 63)) & 1u) != 0; };
        int n = 0;
        for (int64_t i = 0; i < end; ++i) n += filled(i) && (!runs || !filled(i + 1));
        Vec3f power;
        for (int c = 0; c < 3; ++c) power[c] = std::pow(factors[k][c], float(n));
        out = out * power;
    }
    return out;
}

// Three groups of foliage (600 leaves) as separate casters, their crossing factors and the sun's
// 64 x 48 view of them.
struct LeafGroups {
    Scene scene = leafScene(600, 3, 11);
    std::vector<MeshView> groups;
    std::vector<Vec3f> factors;
    LightView view;
    LeafGroups() {
        Box3d bounds;
        for (std::size_t g = 1; g <= 3; ++g) {
            groups.push_back(scene.meshes[g].mesh.view());
            factors.push_back(scene.materials[scene.meshes[g].material].shadowCrossingTransmittance());
            bounds.extend(computeBounds(groups.back()));
        }
        view = makeLightViews(sun(), bounds, 64, 48)[0];
    }
};

TEST(ShadowTest, TransmittanceIsEachChannelsFactorToThePowerOfItsCellsInFront) {
    // Three colour channels of foliage, surface and conservative grids: at random points the lookup
    // must be the product over the channels of each one's factor to the power of its cells in front
    // of p's skipped cells, counted bit by bit; the bilinear lookup with no normal (each column at
    // p's depth) the weighted sum of those products over the four columns around p.
    const LeafGroups leaves;
    const std::vector<MeshView>& groups = leaves.groups;
    const std::vector<Vec3f>& factors = leaves.factors;
    const LightView& view = leaves.view;
    const int64_t W = view.frame.width(), H = view.frame.height();
    for (const VoxelizeMode mode : {VoxelizeMode::Surface, VoxelizeMode::Conservative}) {
        const TransmittanceShadowMap map =
            TransmittanceShadowMap::build(view, groups, factors, mode, Slicing::Uniform);
        const bool runs = mode == VoxelizeMode::Conservative;
        int shaded = 0;
        test::forEachCoveredPoint(
            view, [&](int i, const Vec3d& p, const Vec3d& g, int64_t column, int64_t skip) {
                const Vec3f want = columnByDefinition(map, factors, runs, column, g.z, skip);
                const Vec3f got = map.transmittance(p, skip);
                const Vec3f blend = test::bilinearByDefinition(
                    W, H, g, [&](int64_t c) { return columnByDefinition(map, factors, runs, c, g.z, skip); });
                const Vec3f gotBlend = map.transmittanceBilinear(p, skip);
                for (int c = 0; c < 3; ++c) {
                    ASSERT_NEAR(got[c], want[c], 1e-6f) << toString(mode) << " point " << i;
                    ASSERT_NEAR(gotBlend[c], blend[c], 1e-5f) << toString(mode) << " point " << i;
                }
                shaded += want.y < 1;
            });
        EXPECT_GT(shaded, 500) << toString(mode);
    }
}

TEST(ShadowTest, TheSunsBilinearLookupWithANormalReadsEachColumnWhereTheReceiverPlaneCrossesIt) {
    // The sun's lookups (an oriented orthographic view, uniform slices: the fast path of
    // transmittanceBilinear, whose plane steps come from the view's cell steps) with a normal: the
    // blend of the four columns around p, each counted bit by bit at the depth where the plane
    // through p with normal n crosses the column's centre line, solved in world space (the centre
    // line L(d) = worldFromGrid(x, y, d) is affine in d), kept within two column footprints of p's
    // depth. Points whose crossing lies within 1e-9 slices of a slice boundary are left out (the
    // rounding of either side may put it on the other); they must be few.
    const LeafGroups leaves;
    const std::vector<MeshView>& groups = leaves.groups;
    const std::vector<Vec3f>& factors = leaves.factors;
    const LightView& view = leaves.view;
    ASSERT_TRUE(view.frame.isOriented());
    const Frame& f = view.frame;
    const int64_t W = f.width(), H = f.height();
    std::mt19937_64 rng(17);
    for (const VoxelizeMode mode : {VoxelizeMode::Surface, VoxelizeMode::Conservative}) {
        const TransmittanceShadowMap map =
            TransmittanceShadowMap::build(view, groups, factors, mode, Slicing::Uniform);
        const bool runs = mode == VoxelizeMode::Conservative;
        int compared = 0, shaded = 0, onBoundary = 0, tilted = 0;
        test::forEachCoveredPoint(view, [&](int i, const Vec3d& p, const Vec3d& g, int64_t, int64_t skip) {
            // Half the normals nearly along the light's rays (crossings clamped at the reach).
            const Vec3d n = test::randomReceiverNormal(rng, f, i);
            bool boundary = false;
            const auto depthOf = [&](int64_t c) {
                return test::receiverPlaneDepth(f, p, g, n, c, boundary, tilted);
            };
            const Vec3f want = test::bilinearByDefinition(W, H, g, [&](int64_t c) {
                return columnByDefinition(map, factors, runs, c, depthOf(c), skip);
            });
            if (boundary) {
                ++onBoundary;
                return;
            }
            const Vec3f got = map.transmittanceBilinear(p, skip, n);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(got[c], want[c], 1e-5f) << toString(mode) << " point " << i;
            ++compared;
            shaded += want.y < 1;
        });
        std::printf(
            "%s: %d lookups with a normal compared (%d shadowed, %d columns read more than half a slice "
            "off p's depth), %d left out on a slice boundary\n",
            toString(mode), compared, shaded, tilted, onBoundary);
        EXPECT_GT(shaded, 500) << toString(mode);
        EXPECT_GT(tilted, 1000) << toString(mode);
        EXPECT_LT(onBoundary, compared / 100) << toString(mode);
    }
}

TEST(ShadowTest, RejectsBadInput) {
    EXPECT_THROW(shadowOptionsNamed("soft"), Error);
    try {
        shadowOptionsNamed("soft");
    } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("transmittance"), std::string::npos); }
    EXPECT_THROW(makeLightViews(sun(), Box3d{}, 64, 64), Error);
    const Scene s = leafScene(10, 1, 1);
    EXPECT_THROW(gridOptions("transmittance", 0), Error); // the option's range
    TransmittanceShadowOptions zero;
    zero.grid.resolution = 0; // set directly: the technique checks it too
    EXPECT_THROW(buildLightShadow(s, sun(), zero), Error);
    ShadowOptions o = gridOptions("transmittance", 32);
    std::get<TransmittanceShadowOptions>(o).voxelMode = VoxelizeMode::Solid;
    EXPECT_THROW(buildLightShadow(s, sun(), o), Error);
}

TEST(ShadowTest, NoCastersMeansFullLight) {
    Scene s = leafScene(10, 1, 1);
    for (SceneMesh& m : s.meshes) m.castsShadow = false;
    const LightShadow sh = buildLightShadow(s, sun(), gridOptions("transmittance", 32));
    EXPECT_TRUE(visibilityOf(sh, {0, 0, 0}, {0, 1, 0}) == (Vec3f{1, 1, 1}));
}

} // namespace
} // namespace voxfx
