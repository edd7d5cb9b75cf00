// Tests of the glass pass's adaptive image-space refinement (RenderOptions::glassRefinement,
// src/render/glass_pass.cpp): a glass ball over a checkered ground, rendered with the lattice and
// with every pixel traced (glassRefinement 0: the full-resolution exact glass), compared pixel by
// pixel in shown luma; where the refracted checker's edges pass (found independently: the exact
// tracer's path through each pixel centre and the ground's plane in closed form) the lattice must
// trace the pixel or stay within the refinement's contrast.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "support/glass_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/exact_glass.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/render.hpp"

namespace voxfx {
namespace {

constexpr double kTile = 0.5; // the checker's tiles, over [-3, 3]^2 at y = 0

// The glass ball of glassTestScene (mesh 2, a tinted clear glass) over a checkered ground of two
// meshes (light and dark tiles), lit by a sun from the side (the ball's shadow lies on the checker).
Scene ballOverAChecker() {
    const Scene ball = test::glassTestScene();
    Scene s;
    for (int k = 0; k < 2; ++k) {
        Material m;
        m.baseColor = k == 0 ? Vec3f{0.8f, 0.8f, 0.75f} : Vec3f{0.08f, 0.1f, 0.12f};
        m.specular = 0;
        SceneMesh tiles;
        tiles.material = s.addMaterial(m);
        tiles.castsShadow = false;
        for (int i = -6; i < 6; ++i)
            for (int j = -6; j < 6; ++j)
                if ((i + j + 12) % 2 == k)
                    test::appendQuad(tiles.mesh, {(i + 0.5) * kTile, 0, (j + 0.5) * kTile}, {0, 0, kTile / 2},
                                     {kTile / 2, 0, 0});
        s.meshes.push_back(tiles);
    }
    SceneMesh glass = ball.meshes[1];
    glass.material = s.addMaterial(ball.materials[ball.meshes[1].material]);
    s.meshes.push_back(glass);
    Light sun;
    sun.direction = normalize(Vec3d{0.5, -1, -0.3});
    s.lights.push_back(sun);
    s.cameras = ball.cameras;
    return s;
}

RenderOptions refinementOptions(double threshold) {
    RenderOptions o;
    o.width = 320;
    o.height = 240;
    o.glass = glassOptionsNamed("exact");
    o.toneMap = ToneMap::Filmic;
    o.exposure = 1; // fixed: the images are compared pixel by pixel
    o.glassRefinement = threshold;
    return o;
}

// The perceptual luma (gamma 2) of a shown pixel (the image is after the output transform).
double shownLuma(const Vec3f& c) {
    const auto k = [](float v) { return double(std::clamp(v, 0.0f, 1.0f)); };
    return std::sqrt(0.299 * k(c.x) + 0.587 * k(c.y) + 0.114 * k(c.z));
}

// Per output pixel (row 0 on top): the checker tile the exact path through its centre lands on
// (0 light, 1 dark), 2 where it leaves into the sky, -1 where the centre misses the ball: the exact
// tracer on the scene's glass triangles, the ground's plane and tiles in closed form.
std::vector<int> tilesSeenThroughTheBall(const Scene& s, int64_t W, int64_t H) {
    const SceneGeometry g = flattenScene(s);
    Mesh glass;
    glass.positions = g.mesh.positions;
    std::vector<uint32_t> medium;
    std::vector<GlassMedium> media;
    for (const Material& m : s.materials) media.push_back(glassMedium(m));
    for (size_t t = 0; t < g.mesh.triangleCount(); ++t) {
        if (!s.materials[g.triangleMaterial[t]].isGlass()) continue;
        for (int k = 0; k < 3; ++k) glass.indices.push_back(g.mesh.indices[3 * t + size_t(k)]);
        medium.push_back(g.triangleMaterial[t]);
    }
    const ExactGlass exact(glass.view(), g.normals, medium, media);
    const Frame frame = cameraFrame(s.cameras[0], W, H);
    const Vec3d eye = frame.eye();
    std::vector<int> tile(size_t(W * H), -1);
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const Vec3d d = normalize(frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye);
            const GlassPath p = exact.trace(eye, d, ExactGlassOptions{}.maxEvents);
            if (!p.hit) continue;
            int& out = tile[size_t((H - 1 - y) * W + x)];
            out = 2;
            if (!(p.exitDir.y < 0)) continue;
            const Vec3d at = p.exitPoint + p.exitDir * (-p.exitPoint.y / p.exitDir.y);
            if (std::abs(at.x) >= 3 || std::abs(at.z) >= 3) continue;
            out = int(std::floor(at.x / kTile) + std::floor(at.z / kTile) + 12) % 2;
        }
    return tile;
}

// Shown-luma differences of `fast` against `exact` over the pixels showing glass.
struct LumaDifference {
    int64_t glassPixels = 0, changed = 0, overContrast = 0;
    double mean = 0, worst = 0;
};
LumaDifference lumaDifference(const RenderResult& fast, const RenderResult& exact) {
    LumaDifference out;
    double sum = 0;
    for (std::size_t i = 0; i < exact.image.pixels.size(); ++i) {
        if (!exact.glassMask[i]) continue;
        const double d = std::abs(shownLuma(fast.image.pixels[i]) - shownLuma(exact.image.pixels[i]));
        ++out.glassPixels, sum += d, out.worst = std::max(out.worst, d);
        out.changed += d > 0, out.overContrast += d > 1.0 / 32;
    }
    out.mean = sum / double(std::max<int64_t>(1, out.glassPixels));
    return out;
}

// One ray per pixel (no anti-aliasing: what the lattice alone does) against every pixel traced: every
// pixel where the refracted checker's edge passes (its centre's exact path lands on another tile, or
// the sky, than a neighbour's: the oracle above) is within the refinement's contrast (1/32) of the
// full-resolution image: the lattice interpolates only between paths that land on one ground triangle
// or two sharing an edge, so not across a tile, nor past a checker's corner where two tiles of one
// colour meet (comparing the meshes alone let 4 pixels there through, by up to 0.33). Over all the
// glass, the mean and the largest difference, and the paths saved.
TEST(GlassRefinementTest, WhereTheRefractedCheckersEdgesPassThePixelsStayWithinTheContrast) {
    const Scene s = ballOverAChecker();
    RenderOptions exactOptions = refinementOptions(0), fastOptions = refinementOptions(1.0 / 32);
    exactOptions.antiAliasing = fastOptions.antiAliasing = AntiAliasing::Off;
    const RenderResult exact = render(s, s.cameras[0], exactOptions);
    const RenderResult fast = render(s, s.cameras[0], fastOptions);
    const int64_t W = fast.image.width, H = fast.image.height;
    EXPECT_EQ(exact.glass.interpolated, 0);
    const std::vector<int> tile = tilesSeenThroughTheBall(s, W, H);
    double worstOnEdge = 0;
    int64_t edgePixels = 0;
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const size_t i = size_t(y * W + x);
            if (!exact.glassMask[i]) continue;
            bool edge = false;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int64_t nx = x + dx, ny = y + dy;
                    if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                    const int a = tile[i], b = tile[size_t(ny * W + nx)];
                    edge |= a >= 0 && b >= 0 && a != b;
                }
            if (!edge) continue;
            ++edgePixels;
            const double d = std::abs(shownLuma(fast.image.pixels[i]) - shownLuma(exact.image.pixels[i]));
            worstOnEdge = std::max(worstOnEdge, d);
            EXPECT_LE(d, 1.0 / 32) << x << ", " << y;
        }
    const LumaDifference all = lumaDifference(fast, exact);
    std::printf("glass lattice, no AA: %lld of %lld glass pixels interpolated; shown luma mean %.5f, worst "
                "%.4f, worst on the checker's %lld edge pixels %.4f; paths %lld against %lld\n",
                (long long)fast.glass.interpolated, (long long)all.glassPixels, all.mean, all.worst,
                (long long)edgePixels, worstOnEdge, (long long)fast.glass.paths,
                (long long)exact.glass.paths);
    EXPECT_GT(all.glassPixels, 8000);
    EXPECT_GT(edgePixels, 1000);
    EXPECT_GT(fast.glass.interpolated, all.glassPixels / 3);
    EXPECT_LT(double(fast.glass.paths), 0.7 * double(exact.glass.paths));
    EXPECT_LT(all.mean, 0.0005);
    EXPECT_LT(all.worst, 1.0 / 32);
}

// The default anti-aliasing (the glass demo's case) against every pixel traced with it: the mean and
// the largest difference in shown luma over the glass, and the paths saved. Besides the lattice's
// own error, the N-rooks samples (where a cell's light bends between its neighbours') and the
// post-process (FXAA's thresholds on the neighbourhood's luma) decide on slightly different values,
// which moves a few pixels at the ball's rim by more than the contrast. And the same image for 1 and
// 2 threads.
TEST(GlassRefinementTest, WithAntiAliasingTheImageStaysCloseToEveryPixelTraced) {
    const Scene s = ballOverAChecker();
    const RenderResult exact = render(s, s.cameras[0], refinementOptions(0));
    const RenderResult fast = render(s, s.cameras[0], refinementOptions(1.0 / 32));
    const LumaDifference d = lumaDifference(fast, exact);
    std::printf("glass lattice with AA: %lld of %lld glass pixels interpolated, %lld differ, %lld by more "
                "than 1/32; shown luma mean %.5f, worst %.4f; paths %lld against %lld\n",
                (long long)fast.glass.interpolated, (long long)d.glassPixels, (long long)d.changed,
                (long long)d.overContrast, d.mean, d.worst, (long long)fast.glass.paths,
                (long long)exact.glass.paths);
    EXPECT_EQ(exact.glass.interpolated, 0);
    EXPECT_GT(fast.glass.interpolated, d.glassPixels / 3);
    EXPECT_LT(double(fast.glass.paths), 0.75 * double(exact.glass.paths));
    EXPECT_LT(d.mean, 0.0005);
    EXPECT_LT(d.overContrast, d.glassPixels / 1000);
    EXPECT_LT(d.worst, 0.08);

    RenderOptions one = refinementOptions(1.0 / 32);
    one.threads = 1;
    const RenderResult single = render(s, s.cameras[0], one);
    EXPECT_TRUE(single.image.pixels == fast.image.pixels);
}

// Anti-aliasing inside glass against a brute-force reference: the same frame with 4 x 4 samples in
// every pixel, each traced (supersample 4, glassRefinement 0, no adaptive samples, no post-process).
// Anti-aliasing inside glass must be worth its paths: with every cell traced and N-rooks samples
// wherever the light bends by more than 1/32 (the smallest step the post-process blends: the densest
// setting), the image is closer to the reference than the post-process alone (antiAliasing post, one
// sample per pixel); the lattice (glassRefinement 1/32) may give back at most a third of that gain,
// for a third fewer paths. The default glassSampleContrast (1/16, frames-glass8) traces fewer paths
// than 1/32 and stays within 10 % of its error and below the post-process alone's (1/8 does neither
// here: 0.00536 against 0.00470 and 0.00525); and glassSampleContrast trades: at 1/4 (with the
// lattice too), fewer paths and a larger error.
TEST(GlassRefinementTest, AntiAliasingInsideGlassStaysCloseToASupersampledReference) {
    const Scene s = ballOverAChecker();
    RenderOptions ref = refinementOptions(0);
    ref.supersample = 4;
    ref.antiAliasing = AntiAliasing::Off;
    const RenderResult reference = render(s, s.cameras[0], ref);
    RenderOptions post = refinementOptions(0), coarse = refinementOptions(1.0 / 32),
                  every = refinementOptions(0), dense = refinementOptions(1.0 / 32);
    post.antiAliasing = AntiAliasing::Post;
    coarse.glassSampleContrast = 1.0 / 4;
    every.glassSampleContrast = dense.glassSampleContrast = 1.0 / 32;
    const RenderResult all = render(s, s.cameras[0], every);
    const RenderResult lattice = render(s, s.cameras[0], dense);
    const RenderResult fast = render(s, s.cameras[0], refinementOptions(1.0 / 32)); // the defaults
    const RenderResult postOnly = render(s, s.cameras[0], post);
    const RenderResult fewer = render(s, s.cameras[0], coarse);
    const LumaDifference dAll = lumaDifference(all, reference), dLattice = lumaDifference(lattice, reference),
                         dFast = lumaDifference(fast, reference), dPost = lumaDifference(postOnly, reference),
                         dFewer = lumaDifference(fewer, reference);
    std::printf("glass AA against 16 traced samples per pixel (%lld glass pixels), mean shown luma error: "
                "every cell traced %.5f (%lld paths), with the lattice %.5f (%lld paths), the defaults "
                "(contrast 1/16) %.5f (%lld paths), post-process alone %.5f, N-rooks samples at contrast "
                "1/4 %.5f (%lld paths); pixels over 1/32: %lld, %lld, %lld, %lld, %lld\n",
                (long long)dAll.glassPixels, dAll.mean, (long long)all.glass.paths, dLattice.mean,
                (long long)lattice.glass.paths, dFast.mean, (long long)fast.glass.paths, dPost.mean,
                dFewer.mean, (long long)fewer.glass.paths, (long long)dAll.overContrast,
                (long long)dLattice.overContrast, (long long)dFast.overContrast,
                (long long)dPost.overContrast, (long long)dFewer.overContrast);
    EXPECT_GT(dPost.mean, dAll.mean * 1.1); // anti-aliasing inside glass matters here
    EXPECT_LT(dLattice.mean, dAll.mean + (dPost.mean - dAll.mean) / 3);
    EXPECT_LT(double(lattice.glass.paths), 0.7 * double(all.glass.paths));
    EXPECT_LT(fast.glass.paths, lattice.glass.paths);
    EXPECT_LT(dFast.mean, 1.1 * dLattice.mean);
    EXPECT_LT(dFast.mean, dPost.mean);
    EXPECT_LT(fewer.glass.paths, fast.glass.paths);
    EXPECT_GT(dFewer.mean, dFast.mean);
}

} // namespace
} // namespace voxfx
