// Tests of the volume pass's grids (src/render/volume_light_grid.hpp): the deep-shadow visibility
// grid is the map's own lookup at the voxel corners, interpolated (recomputed here from the
// corners' lookups, an upright and a turned volume, under a spot light); against the map's lookup
// at random points in a homogeneous slab, within a bound from the grid spacing (the closed form's
// second derivative) plus the map's own departure from that closed form; and the frames that build
// it and reuse it from a RenderCache give the uncached image; the gradient grid (phong's normals) is
// Volume::gradient inside the volume and defers to it near the faces.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "render/shading.hpp"
#include "render/volume_light_grid.hpp"
#include "support/volume_reference.hpp"
#include "test_util.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/render.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using detail::LightCone;
using detail::LightVisibilityGrid;

// The map's lookup as the volume pass makes it at sample p, a step towards the light.
Vec3f vlgLookup(const DeepShadow& deep, const Light& light, const Vec3d& p, double step, double& texel) {
    Vec3d toLight;
    detail::lightIrradiance(light, p, toLight);
    return deep.visibility(p + toLight * step, toLight, texel);
}

// Smoke (24 x 20 x 16 voxels unless told, turned about y by 30 degrees when `turned`) under a spot light.
struct VlgSmoke {
    Scene scene;
    std::shared_ptr<Volume> volume;
    Light light;
};
VlgSmoke vlgSmoke(bool turned, Vec3i dims = {24, 20, 16}) {
    VlgSmoke s;
    SmokeParams sp;
    sp.dims = dims;
    sp.box = {{-0.6, 0, -0.4}, {0.6, 1.0, 0.4}};
    sp.seed = 7;
    s.volume = std::make_shared<Volume>(makeSmoke(sp));
    if (turned) {
        const double c = std::cos(M_PI / 6), sn = std::sin(M_PI / 6);
        s.volume->setAxes({c, 0, -sn}, {0, 1, 0}, {sn, 0, c});
    }
    auto vs = std::make_shared<VolumeScene>();
    const TransferFunction tf({{0, {1, 1, 1}}, {1, {1, 1, 1}}}, {{0.05, 0}, {0.5, 0.6}, {1, 0.9}});
    vs->addVolumeBox(s.volume, tf, 0.1, "smoke");
    s.scene.volumeScene = vs;
    s.light.type = LightType::Spot;
    s.light.position = {-1.5, 2.5, 1.0};
    s.light.direction = normalize(Vec3d{0, 0.5, 0} - s.light.position);
    s.light.intensity = 10;
    s.light.innerConeAngle = 0.4;
    s.light.outerConeAngle = 0.6;
    return s;
}

// The smoke's deep shadow map at 128 x 128 texels.
DeepShadow vlgDeepShadow(const VlgSmoke& s) {
    DeepShadowOptions o;
    o.resolution = 128;
    return DeepShadow::build(s.scene, s.light, o);
}

// Calls f(corner, weight) for the eight voxel corners around voxel coordinate u of `volume` (dims n),
// with u's trilinear weights: the interpolation the grids are checked against, written out.
template <class F> void forEachCorner(const Volume& volume, const Vec3i& n, const Vec3d& u, const F& f) {
    const int64_t i0[3] = {std::min<int64_t>(int64_t(u.x), n.x - 1), std::min<int64_t>(int64_t(u.y), n.y - 1),
                           std::min<int64_t>(int64_t(u.z), n.z - 1)};
    const double t[3] = {u.x - double(i0[0]), u.y - double(i0[1]), u.z - double(i0[2])};
    for (int c = 0; c < 8; ++c) {
        const int d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
        double w = 1;
        for (int a = 0; a < 3; ++a) w *= d[a] ? t[a] : 1 - t[a];
        f(volume.worldFromVoxel({double(i0[0] + d[0]), double(i0[1] + d[1]), double(i0[2] + d[2])}), w);
    }
}

// The grid at p is the trilinear interpolation of the map's lookups at the eight voxel corners
// around p (recomputed here from the volume's placement, in double): within float rounding.
TEST(VolumeLightGridTest, TheGridIsTheMapsLookupAtTheVoxelCornersInterpolated) {
    for (const bool turned : {false, true}) {
        const VlgSmoke s = vlgSmoke(turned);
        const DeepShadow deep = vlgDeepShadow(s);
        const double step = 0.05;
        const LightVisibilityGrid grid =
            LightVisibilityGrid::build(*s.volume, deep, s.light, LightCone(s.light), step);
        const Vec3i n = s.volume->dims();
        EXPECT_EQ(grid.nodeCounts().x, n.x + 1);
        EXPECT_EQ(grid.nodeCounts().y, n.y + 1);
        EXPECT_EQ(grid.nodeCounts().z, n.z + 1);
        std::mt19937_64 rng(11);
        std::uniform_real_distribution<double> U(0, 1);
        double worst = 0, worstTexel = 0, lo = 1, hi = 0;
        for (int k = 0; k < 2000; ++k) {
            const Vec3d u{U(rng) * double(n.x), U(rng) * double(n.y), U(rng) * double(n.z)};
            const Vec3d p = s.volume->worldFromVoxel(u);
            Vec3d want{0, 0, 0};
            double wantTexel = 0;
            forEachCorner(*s.volume, n, u, [&](const Vec3d& corner, double w) {
                double texel = 0;
                const Vec3f v = vlgLookup(deep, s.light, corner, step, texel);
                want = want + Vec3d(v) * w;
                wantTexel += texel * w;
            });
            Vec3f got;
            double gotTexel = 0;
            // A point within a ten-thousandth of a voxel of the box's faces may fall either side.
            ASSERT_TRUE(grid.lookup(p, got, gotTexel)) << u.x << " " << u.y << " " << u.z;
            worst = std::max(worst, length(Vec3d(got) - want));
            worstTexel = std::max(worstTexel, std::abs(gotTexel - wantTexel) / wantTexel);
            lo = std::min(lo, want.x), hi = std::max(hi, want.x);
        }
        std::printf("%s: grid against the corners' lookups interpolated: worst %.3g (texel %.3g relative); "
                    "visibility %.3f-%.3f\n",
                    turned ? "turned" : "upright", worst, worstTexel, lo, hi);
        EXPECT_LT(worst, 2e-6);
        EXPECT_LT(worstTexel, 2e-6);
        EXPECT_LT(lo, 0.6); // the smoke shadows itself: the comparison sees more than a constant
        // No value outside the box, where the volume pass looks the map up itself.
        Vec3f v;
        double texel = 0;
        EXPECT_FALSE(grid.lookup(s.volume->worldFromVoxel({-0.01, 1, 1}), v, texel));
        EXPECT_FALSE(grid.lookup(s.volume->worldFromVoxel({1, double(n.y) + 0.01, 1}), v, texel));
        EXPECT_FALSE(grid.lookup(Vec3d{std::nan(""), 0, 0}, v, texel));
    }
}

// The pre-lit volume (built with an own-transmittance function) at p is the trilinear interpolation,
// over the eight voxel corners around p, of the light's irradiance x the map's lookup x that function
// at the corner (recomputed here: lightIrradiance, the map's lookup, the function; in double), within
// float rounding relative to the largest light; the function is given the corner, the direction to
// the light and the lookup's texel footprint; the own transmittance alone is that function at the
// corners interpolated (within float rounding). Without the function there is no pre-lit volume.
TEST(VolumeLightGridTest, ThePrelitVolumeIsTheLightAtTheVoxelCornersInterpolated) {
    for (const bool turned : {false, true}) {
        const VlgSmoke s = vlgSmoke(turned);
        const DeepShadow deep = vlgDeepShadow(s);
        const double step = 0.05;
        // Any function of the corner, the direction and the footprint: one that varies with all three.
        const auto ownOf = [&](const Vec3d& c, const Vec3d& toLight, double texel) {
            return std::exp(-0.7 * (c.y + 0.6) - 0.3 * toLight.x - 20 * texel);
        };
        const LightVisibilityGrid::OwnTransmittance own = ownOf;
        const LightCone cone(s.light);
        const LightVisibilityGrid grid =
            LightVisibilityGrid::build(*s.volume, deep, s.light, cone, step, nullptr, 0, &own);
        EXPECT_TRUE(grid.prelit());
        EXPECT_FALSE(LightVisibilityGrid::build(*s.volume, deep, s.light, cone, step).prelit());
        const Vec3i n = s.volume->dims();
        std::mt19937_64 rng(13);
        std::uniform_real_distribution<double> U(0, 1);
        double worst = 0, largest = 0, lo = 1e30, worstOwn = 0, ownLo = 1, ownHi = 0;
        for (int k = 0; k < 2000; ++k) {
            const Vec3d u{U(rng) * double(n.x), U(rng) * double(n.y), U(rng) * double(n.z)};
            const Vec3d p = s.volume->worldFromVoxel(u);
            Vec3d want{0, 0, 0};
            double wantOwn = 0;
            forEachCorner(*s.volume, n, u, [&](const Vec3d& corner, double w) {
                Vec3d toLight;
                const Vec3f e = detail::lightIrradiance(s.light, corner, toLight);
                double texel = 0;
                const Vec3f v = deep.visibility(corner + toLight * step, toLight, texel);
                want = want + Vec3d(e) * Vec3d(v) * (ownOf(corner, toLight, texel) * w);
                wantOwn += ownOf(corner, toLight, texel) * w;
            });
            Vec3f got;
            float ownGot = -1;
            ASSERT_TRUE(grid.lookupLight(p, got, &ownGot)) << u.x << " " << u.y << " " << u.z;
            // The own transmittance alone (what a sample inside this volume and another takes from it).
            worstOwn = std::max(worstOwn, std::abs(double(ownGot) - wantOwn));
            ownLo = std::min(ownLo, wantOwn), ownHi = std::max(ownHi, wantOwn);
            worst = std::max(worst, length(Vec3d(got) - want));
            largest = std::max(largest, length(want));
            lo = std::min(lo, length(want));
        }
        std::printf("%s: pre-lit volume against the corners' light interpolated: worst %.3g (largest %.3g, "
                    "smallest %.3g)\n",
                    turned ? "turned" : "upright", worst, largest, lo);
        EXPECT_GT(largest, 2 * lo); // the light varies: the comparison sees more than a constant
        EXPECT_LT(worst, 2e-6 * largest);
        std::printf("  own transmittance against the corners' interpolated: worst %.3g (values %.3f-%.3f)\n",
                    worstOwn, ownLo, ownHi);
        EXPECT_LT(worstOwn, 2e-6);
        EXPECT_GT(ownHi, 1.5 * ownLo); // it varies
        // Through the voxel-coordinate entry the same values.
        const Vec3d pm = s.volume->worldFromVoxel({3.3, 2.7, 5.1});
        Vec3f a, b;
        ASSERT_TRUE(grid.lookupLight(pm, a));
        ASSERT_TRUE(grid.lookupLightVoxel(s.volume->view().voxelCoordinates(pm), b));
        EXPECT_EQ(a, b);
        Vec3f v;
        EXPECT_FALSE(grid.lookupLight(s.volume->worldFromVoxel({-0.01, 1, 1}), v));
        EXPECT_FALSE(grid.lookupLight(Vec3d{std::nan(""), 0, 0}, v));
    }
}

// With the volume's empty bricks the grid fills only the nodes near matter: wherever the march can
// light a piece (a point within a step of a brick that is not empty) the lookup has the full grid's
// value, bit for bit; elsewhere it may return false (the volume pass then looks the map up).
TEST(VolumeLightGridTest, NodesAwayFromMatterAreLeftToTheMapAndTheRestAreTheFullGrids) {
    const VlgSmoke s = vlgSmoke(false, {64, 56, 48}); // bricks enough that some lie far from matter
    const DeepShadow deep = vlgDeepShadow(s);
    const VolumeSceneObject& obj = s.scene.volumeScene->objects[0];
    const EmptySpace skip(*s.volume, obj.transfer);
    const double step = s.volume->spacing().x; // the march's step: a voxel
    const LightCone cone(s.light);
    const LightVisibilityGrid full = LightVisibilityGrid::build(*s.volume, deep, s.light, cone, step);
    const LightVisibilityGrid sparse =
        LightVisibilityGrid::build(*s.volume, deep, s.light, cone, step, &skip, step);
    const Vec3i n = s.volume->dims();
    EXPECT_EQ(full.filledNodes(), (n.x + 1) * (n.y + 1) * (n.z + 1));
    EXPECT_LT(sparse.filledNodes(), full.filledNodes());
    EXPECT_GT(skip.emptyFraction(), 0.2);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> U(0, 1), D(-1, 1);
    int64_t nearMatter = 0, left = 0;
    for (int k = 0; k < 4000; ++k) {
        const Vec3d p =
            s.volume->worldFromVoxel({U(rng) * double(n.x), U(rng) * double(n.y), U(rng) * double(n.z)});
        // A point within a step of p in a brick with matter: the march may light p.
        const Vec3d q = p + Vec3d{D(rng), D(rng), D(rng)} * (step / std::sqrt(3.0));
        Vec3f a, b;
        double ta = 0, tb = 0;
        ASSERT_TRUE(full.lookup(p, a, ta));
        if (sparse.lookup(p, b, tb)) {
            EXPECT_EQ(a.x, b.x);
            EXPECT_EQ(a.y, b.y);
            EXPECT_EQ(a.z, b.z);
            EXPECT_EQ(ta, tb);
        } else {
            ++left;
            EXPECT_TRUE(skip.empty(q)) << p.x << " " << p.y << " " << p.z;
        }
        nearMatter += !skip.empty(q);
    }
    std::printf("smoke: %lld of %lld nodes filled (%.0f %% of the bricks empty); %lld of 4000 random points "
                "left to the map, %lld within a step of matter\n",
                static_cast<long long>(sparse.filledNodes()), static_cast<long long>(full.filledNodes()),
                100 * skip.emptyFraction(), static_cast<long long>(left), static_cast<long long>(nearMatter));
    EXPECT_GT(left, 0);
    EXPECT_GT(nearMatter, 500);
}

// In a homogeneous slab (extinction sigma) under a sun, the light at depth d below the top face
// falls as g = exp(-sigma d / cos): along the light's way, the grid's trilinear interpolation of
// g departs from it by at most h^2 / 8 max|g''| = h^2 (sigma / cos)^2 / 8 (g depends on y alone, so
// only the interpolation along y errs). The map's lookup f is not exactly g (its nodes, its
// epsilon): f - g at p and at the eight corners (measured here, independent of the grid) adds at
// most |f - g|(p) + max |f - g|(corners). Points are kept where the lookup and its corners' lie
// below the top face (the light's fall has no kink between them) and away from the slab's sides.
TEST(VolumeLightGridTest, AgainstTheMapsLookupInAHomogeneousSlabWithinTheGridSpacingsBound) {
    const double opacity = 0.3, opacityLength = 0.1; // sigma 3.57 per unit
    const Scene s = test::homogeneousSlabScene(opacity, opacityLength, 3);
    const Volume& volume = *s.volumeScene->volumes[0];
    const Light& light = s.lights[0];
    DeepShadowOptions o;
    o.resolution = 128;
    o.epsilon = 0.001;
    o.stepVoxels = 0.25; // the map's nodes a quarter voxel apart: its own error stays small
    const DeepShadow deep = DeepShadow::build(s, light, o);
    const double h = volume.spacing().x, step = h; // the volume pass's step: one voxel
    const LightVisibilityGrid grid = LightVisibilityGrid::build(volume, deep, light, LightCone(light), step);
    const double sigma = -std::log(1 - opacity) / opacityLength;
    const Vec3d toLight = -normalize(light.direction);
    const double cosL = toLight.y, top = 0.5;
    // The closed form at the lookup's point: q = p + toLight (step + (normalOffset + depthBias)
    // texel), depth top - q.y along y (0 above the top face).
    const auto closed = [&](const Vec3d& p, double texel) {
        const Vec3d q = p + toLight * (step + (o.normalOffset + o.depthBias) * texel);
        return std::exp(-sigma * std::max(0.0, top - q.y) / cosL);
    };
    const double second = h * h / 8 * (sigma / cosL) * (sigma / cosL);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> U(-0.5, 0.5), Y(0, top);
    int64_t n = 0;
    double worst = 0, mean = 0, worstMapError = 0, worstSlack = 1;
    for (int k = 0; k < 20000 && n < 3000; ++k) {
        const Vec3d p{U(rng), Y(rng), U(rng)};
        double texel = 0;
        const double f = vlgLookup(deep, light, p, step, texel).x;
        // The corners of p's voxel; each corner's lookup point below the top face by a margin.
        const Vec3d u{volume.view().voxelCoordinate(p, 0), volume.view().voxelCoordinate(p, 1),
                      volume.view().voxelCoordinate(p, 2)};
        double mapError = std::abs(f - closed(p, texel));
        bool below = true;
        for (int c = 0; c < 8; ++c) {
            const Vec3d corner =
                volume.worldFromVoxel({std::floor(u.x) + (c & 1), std::floor(u.y) + ((c >> 1) & 1),
                                       std::floor(u.z) + ((c >> 2) & 1)});
            double ct = 0;
            const double fc = vlgLookup(deep, light, corner, step, ct).x;
            below = below && corner.y + toLight.y * (step + 2 * ct) < top - 0.01;
            mapError = std::max(mapError, std::abs(fc - closed(corner, ct)));
        }
        if (!below) continue;
        Vec3f got;
        double gotTexel = 0;
        ASSERT_TRUE(grid.lookup(p, got, gotTexel));
        const double e = std::abs(double(got.x) - f);
        const double bound = second + 2 * mapError + 1e-5;
        EXPECT_LE(e, bound) << p.x << " " << p.y << " " << p.z;
        worst = std::max(worst, e);
        worstMapError = std::max(worstMapError, mapError);
        worstSlack = std::min(worstSlack, bound - e);
        mean += e;
        ++n;
    }
    ASSERT_GT(n, 1000);
    mean /= double(n);
    std::printf("slab (sigma %.2f, h %.4f): grid against the map's lookup over %lld points: mean %.2e, "
                "worst %.2e; bound h^2 (sigma/cos)^2 / 8 = %.2e plus twice the map's own error "
                "(worst %.2e)\n",
                sigma, h, static_cast<long long>(n), mean, worst, second, worstMapError);
    // The map itself is close to the closed form here, so the bound is tight enough to catch a
    // grid displaced by half a voxel (an error of about sigma h / 2 cos = 0.13 of the light).
    EXPECT_LT(worstMapError, 0.01);
    EXPECT_LT(mean, second);
}

// Phong's normals: the gradient grid at random points of the volume's interior is the volume's own
// gradient (central differences of the trilinear samples one voxel either side) within float
// rounding, upright and turned; within a voxel and a half of a face (one-sided differences) the
// grid has no value.
TEST(VolumeLightGridTest, TheGradientGridIsTheVolumesGradientInsideAndDefersNearTheFaces) {
    for (const bool turned : {false, true}) {
        const VlgSmoke s = vlgSmoke(turned);
        const detail::GradientGrid grid(*s.volume);
        const Vec3i n = s.volume->dims();
        std::mt19937_64 rng(3);
        std::uniform_real_distribution<double> U(0, 1);
        double worst = 0, largest = 0;
        int64_t inside = 0, deferred = 0;
        for (int k = 0; k < 4000; ++k) {
            const Vec3d u{U(rng) * double(n.x), U(rng) * double(n.y), U(rng) * double(n.z)};
            const Vec3d p = s.volume->worldFromVoxel(u);
            // Lattice coordinates u - 1/2 within [1, n - 2) on every axis (a margin against rounding).
            const auto interior = [&](double m) {
                return u.x - 0.5 >= 1 + m && u.x - 0.5 < double(n.x - 2) - m && u.y - 0.5 >= 1 + m &&
                       u.y - 0.5 < double(n.y - 2) - m && u.z - 0.5 >= 1 + m &&
                       u.z - 0.5 < double(n.z - 2) - m;
            };
            Vec3d g;
            const bool got = grid.lookup(p, g);
            if (interior(1e-9)) {
                ASSERT_TRUE(got) << u.x << " " << u.y << " " << u.z;
                const Vec3d want = s.volume->gradient(p);
                worst = std::max(worst, length(g - want));
                largest = std::max(largest, length(want));
                ++inside;
            } else if (!interior(-1e-9)) {
                EXPECT_FALSE(got) << u.x << " " << u.y << " " << u.z;
                ++deferred;
            }
        }
        std::printf("%s: gradient grid against Volume::gradient at %lld interior points: worst %.3g (largest "
                    "|g| %.3g); %lld points near the faces deferred\n",
                    turned ? "turned" : "upright", static_cast<long long>(inside), worst, largest,
                    static_cast<long long>(deferred));
        EXPECT_GT(inside, 1000);
        EXPECT_GT(deferred, 500);
        EXPECT_GT(largest, 1.0);
        EXPECT_LT(worst, 1e-5 * largest);
    }
}

bool vlgCached(const RenderResult& r, std::string_view pass) {
    for (const PassTime& p : r.timings.passes)
        if (p.name == pass) return p.cached;
    return false;
}

// The first frame builds the grids (its ray casting is not "cached"), the next reuses them; a
// changed light builds new ones. Every frame is the image render() gives without a cache.
TEST(VolumeLightGridTest, FramesThatBuildOrReuseTheGridsGiveTheUncachedImage) {
    Scene s = test::homogeneousSlabScene(0.3, 0.1, 3);
    RenderOptions o = test::linearBlackOptions(64, 48);
    DeepShadowOptions d;
    d.resolution = 96;
    o.shadow = d;
    const RenderResult uncached = render(s, s.cameras[0], o);
    RenderCache cache;
    const RenderResult first = render(s, s.cameras[0], o, cache);
    const RenderResult second = render(s, s.cameras[0], o, cache);
    EXPECT_FALSE(vlgCached(first, "ray casting"));
    EXPECT_TRUE(vlgCached(second, "ray casting"));
    EXPECT_EQ(first.image.pixels, uncached.image.pixels);
    EXPECT_EQ(second.image.pixels, uncached.image.pixels);
    s.lights[0].direction = normalize(Vec3d{-0.4, -1, 0.2});
    const RenderResult moved = render(s, s.cameras[0], o, cache);
    EXPECT_FALSE(vlgCached(moved, "ray casting"));
    EXPECT_EQ(moved.image.pixels, render(s, s.cameras[0], o).image.pixels);
    EXPECT_NE(moved.image.pixels, uncached.image.pixels);
}

} // namespace
} // namespace voxfx
