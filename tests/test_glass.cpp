// Tests of what every glass method shares (voxfx/glass.hpp, the renderer's glass pass): the
// absorption constant on the exact tracer and the voxel march alike, the default lights of a scene
// without lights, the command line (render --glass, glass-error, CHANG's knobs and their bad
// values), the image error over the glass mask and the methods by name. Each method is tested on
// its own in test_glass_optics.cpp, test_exact_glass.cpp, test_voxel_glass.cpp and
// test_frosted_glass.cpp; glass shadows in test_exact_shadow.cpp and test_shadow_cross_technique.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "support/glass_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"

namespace voxfx {
namespace {

using test::glassTestScene;

// CHANG's absorption constant (#25 item 2): a constant k on the method is the material's
// attenuation coefficient times k, for the exact tracer and the voxel march alike: k = 2 renders
// as the same glass with half the attenuation distance, k = 0 as glass without attenuation, and
// more absorption never brightens a glass pixel.
TEST(GlassTest, AbsorptionConstantScalesEveryMediumsAttenuation) {
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.shadow = NoShadowOptions{};
    o.antiAliasing = AntiAliasing::Off;
    o.exposure = 1; // a fixed exposure: the renders are compared pixel by pixel
    MultiGlassOptions multi;
    multi.gridResolution = 48;
    for (const GlassOptions base : {GlassOptions(ExactGlassOptions{}), GlassOptions(multi)}) {
        const auto withConstant = [&](double k) {
            GlassOptions g = base;
            std::visit(
                [&](auto& m) {
                    if constexpr (requires { m.absorptionConstant; }) m.absorptionConstant = k;
                },
                g);
            return g;
        };
        const Scene s = glassTestScene();
        o.glass = withConstant(2);
        const RenderResult doubled = render(s, s.cameras[0], o);
        Scene half = s;
        half.materials[1].attenuationDistance = 0.5f;
        o.glass = base;
        const RenderResult byMaterial = render(half, half.cameras[0], o);
        o.glass = withConstant(0);
        const RenderResult none = render(s, s.cameras[0], o);
        Scene clear = s;
        clear.materials[1].attenuationDistance = std::numeric_limits<float>::infinity();
        o.glass = base;
        const RenderResult clearGlass = render(clear, clear.cameras[0], o);
        const RenderResult plain = render(s, s.cameras[0], o);
        int64_t glassPixels = 0, darker = 0;
        for (size_t i = 0; i < plain.image.pixels.size(); ++i) {
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(doubled.image.pixels[i][c], byMaterial.image.pixels[i][c], 1e-5f) << i;
                EXPECT_NEAR(none.image.pixels[i][c], clearGlass.image.pixels[i][c], 1e-5f) << i;
                EXPECT_LE(doubled.image.pixels[i][c], plain.image.pixels[i][c] + 1e-6f) << i;
                EXPECT_LE(plain.image.pixels[i][c], none.image.pixels[i][c] + 1e-6f) << i;
            }
            if (plain.glassMask.empty() || !plain.glassMask[i]) continue;
            ++glassPixels;
            darker += doubled.image.pixels[i].x < plain.image.pixels[i].x - 1e-3f;
        }
        EXPECT_GT(glassPixels, 300);
        EXPECT_GT(darker, glassPixels / 2); // the constant does act
    }
    GlassOptions bad = ExactGlassOptions{};
    std::get<ExactGlassOptions>(bad).absorptionConstant = std::nan("");
    o.glass = bad;
    const Scene s = glassTestScene();
    EXPECT_THROW(render(s, s.cameras[0], o), Error);
}

// #37: the constant scaled the camera's rays through the glass but not the shadow the same glass
// casts. One constant for both: with shadows on (exact, and the crossing-counting absorption and
// deep maps), k = 2 renders as the same glass with half the attenuation distance, shadow included,
// pixel for pixel, for the exact tracer and the voxel march; and the ground in the ball's shadow
// (seen past the ball, not through it) is darker than with k = 1.
TEST(GlassTest, AbsorptionConstantScalesTheGlasssShadowAsItScalesCameraRays) {
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    MultiGlassOptions multi;
    multi.gridResolution = 48;
    Scene s = glassTestScene();
    Light sun;
    sun.direction = normalize(Vec3d{-1, -1, 0}); // the ball's shadow falls at x < 0, beside it
    s.lights.push_back(sun);
    Scene half = s;
    half.materials[1].attenuationDistance = 0.5f;
    for (const char* shadows : {"exact", "absorption", "deep"})
        for (const GlassOptions base : {GlassOptions(ExactGlassOptions{}), GlassOptions(multi)}) {
            setRenderOption(o, "shadows", std::string(shadows));
            GlassOptions doubledGlass = base;
            std::visit(
                [&](auto& m) {
                    if constexpr (requires { m.absorptionConstant; }) m.absorptionConstant = 2;
                },
                doubledGlass);
            o.glass = doubledGlass;
            const RenderResult doubled = render(s, s.cameras[0], o);
            o.glass = base;
            const RenderResult byMaterial = render(half, half.cameras[0], o);
            const RenderResult plain = render(s, s.cameras[0], o);
            int64_t darkerGround = 0;
            for (size_t i = 0; i < plain.image.pixels.size(); ++i) {
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(doubled.image.pixels[i][c], byMaterial.image.pixels[i][c], 1e-5f)
                        << shadows << " " << glassName(base) << " pixel " << i;
                const bool glass = !plain.glassMask.empty() && plain.glassMask[i];
                darkerGround += !glass && doubled.image.pixels[i].x < plain.image.pixels[i].x - 1e-3f;
            }
            EXPECT_GT(darkerGround, 20) << shadows << " " << glassName(base); // the shadow does change
        }
}

TEST(GlassTest, ASceneWithoutLightsIsLitByTheDefaultSunAndSkyAmbient) {
    Scene s = glassTestScene();
    s.materials[1].transmission = 0; // opaque: plain shading
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.ambient = {0, 0, 0};
    o.sky = SkyKind::Flat; // black
    o.background = {0, 0, 0};
    o.shadow = NoShadowOptions{};
    o.defaultLights = false;
    o.toneMap = ToneMap::Clamp;
    o.exposure = 1;
    o.antiAliasing = AntiAliasing::Off;
    const RenderResult dark = render(s, s.cameras[0], o);
    for (const Vec3f& p : dark.image.pixels) EXPECT_EQ(p, (Vec3f{0, 0, 0}));
    o.defaultLights = true;
    o.sky = SkyKind::Procedural;
    const RenderResult lit = render(s, s.cameras[0], o);
    // A ground pixel: albedo / pi * the sky's irradiance on an upward face (ambient) + albedo / pi
    // * E * cos(sun), hand-derived with the default sun (the sky's: its irradiance, towards
    // SkyOptions' sun direction).
    const Vec3d p{1.2, 0, 0.3}; // beside the ball, in view
    const Vec3d g = cameraFrame(s.cameras[0], 64, 48).gridFromWorld(p);
    const int64_t x = int64_t(std::floor(g.x)), y = 47 - int64_t(std::floor(g.y));
    ASSERT_TRUE(x >= 0 && x < 64 && y >= 0 && y < 48) << x << " " << y;
    const Environment sky = Environment::sky();
    const Vec3d sun = normalize(SkyOptions{}.sunDirection);
    const Vec3f avg = sky.irradiance({0, 1, 0}) * float(1 / M_PI);
    const float albedo = 0.6f;
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(lit.image.at(x, y)[c], albedo * avg[c] + albedo / M_PI * sky.sunIrradiance()[c] * sun.y,
                    1e-3)
            << c;
}

// An octahedron of blue glass over a ground quad, in a JSON scene without lights: DIR/scene.json.
void writeGemScene(const test::TempDir& dir) {
    test::writeFile(dir.file("gem.off"),
                    "OFF\n6 8 0\n1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
                    "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n");
    test::writeFile(dir.file("ground.off"),
                    "OFF\n4 2 0\n-4 -1.2 -4\n4 -1.2 -4\n4 -1.2 4\n-4 -1.2 4\n3 0 2 1\n3 0 3 2\n");
    test::writeFile(dir.file("scene.json"),
                    R"({ "meshes": [ { "file": "gem.off", "material": { "transmission": 1, "ior": 1.5,
                                                                         "baseColor": [0.6, 0.8, 1] } },
                                     { "file": "ground.off" } ],
                         "cameras": [ { "position": [0, 1, 4], "target": [0, 0, 0], "fovYDegrees": 50 } ] })");
}

TEST(GlassTest, CommandLineRendersGlassAndComparesTheVoxelMethodsWithTheExactTracer) {
    test::TempDir dir;
    writeGemScene(dir);
    const auto r =
        test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("a.png") +
                                " --width 64 --height 48 --glass multi --glass-grid 32 --shadows exact");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("glass multi (glass-grid 32"), std::string::npos) << r.out;
    const Image img = readPng(dir.file("a.png"));
    EXPECT_EQ(img.width, 64);
    const auto e =
        test::runVoxfx(dir, "glass-error " + dir.file("scene.json") +
                                " --width 64 --height 48 --resolutions 16,32 --methods multi,two-surface");
    ASSERT_EQ(e.exitCode, 0) << e.err;
    EXPECT_NE(e.out.find("| multi | 32³ |"), std::string::npos) << e.out;
    EXPECT_NE(e.out.find("| two-surface | 16³ |"), std::string::npos) << e.out;
    const auto bad = test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("b.png") +
                                             " --glass frosty");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("exact, multi, two-surface"), std::string::npos) << bad.err;
}

// The voxel glass grid without --glass-grid (#37 item 6): about one voxel per 1.5 pixels of the
// glass object's extent on screen, rounded up to a multiple of 32 within 64..512. A cube of side 1
// straight ahead at distance d: its near face (at d - 0.5) spans 1 / (d - 0.5) / tan(fovY / 2) * H / 2
// pixels (pinhole projection, by hand).
TEST(GlassTest, AutoGlassGridFollowsTheGlassObjectsSizeOnScreen) {
    const double fovY = 0.8;
    Box3d cube;
    cube.extend(Vec3d{-0.5, -0.5, -0.5});
    cube.extend(Vec3d{0.5, 0.5, 0.5});
    auto frameAt = [&](double d, int64_t scale) {
        Camera c;
        c.position = {0, 0, d};
        c.target = {0, 0, 0};
        c.fovY = fovY;
        return cameraFrame(c, 320 * scale, 240 * scale);
    };
    auto onScreen = [&](double d) { return 1 / (d - 0.5) / std::tan(fovY / 2) * 120; };
    int64_t previous = 0;
    for (const double d : {20.0, 3.0, 1.6, 1.2}) {
        SCOPED_TRACE(d);
        const std::vector<Box3d> objects{cube};
        const GlassGridChoice g = chooseGlassGrid(0, objects, cube, frameAt(d, 1), 1.0);
        const double e = std::min(onScreen(d), 320.0); // clipped to the image
        EXPECT_NEAR(g.objectPixels, e, 0.01 * e);
        const double wanted = e / 1.5 + 2;
        EXPECT_GE(g.resolution, std::clamp(wanted, 64.0, 512.0) - 1e-9);
        EXPECT_LE(g.resolution, std::max(wanted + 32, 64.0));
        EXPECT_EQ(g.resolution % 32, 0);
        EXPECT_GE(g.resolution, previous); // nearer: never coarser
        previous = g.resolution;
        EXPECT_NE(g.reason.find("auto"), std::string::npos) << g.reason;
        // Supersampled frames count output pixels: the same grid.
        EXPECT_EQ(chooseGlassGrid(0, objects, cube, frameAt(d, 2), 0.5).resolution, g.resolution);
        // A given resolution is kept.
        const GlassGridChoice given = chooseGlassGrid(40, objects, cube, frameAt(d, 1), 1.0);
        EXPECT_EQ(given.resolution, 40);
        EXPECT_EQ(given.reason, "given");
    }
    EXPECT_EQ(chooseGlassGrid(0, std::vector<Box3d>{cube}, cube, frameAt(20, 1), 1.0).resolution, 64);
    EXPECT_GE(previous, 160);
    // Glass spread wider than the object: the voxel size carries over to the longest side of all the
    // glass (twice as long: about twice the voxels), within the 2^24-voxel budget.
    Box3d wide = cube;
    wide.extend(Vec3d{1.5, 0.5, 0.5});
    const int64_t one = chooseGlassGrid(0, std::vector<Box3d>{cube}, cube, frameAt(3, 1), 1.0).resolution;
    const GlassGridChoice two = chooseGlassGrid(0, std::vector<Box3d>{cube}, wide, frameAt(3, 1), 1.0);
    EXPECT_GE(two.resolution, 2 * one - 64);
    EXPECT_LE(two.resolution, 2 * one + 32);
    Box3d huge = cube;
    huge.extend(Vec3d{30, 30, 30});
    const GlassGridChoice capped = chooseGlassGrid(0, std::vector<Box3d>{cube}, huge, frameAt(1.2, 1), 1.0);
    EXPECT_LE(double(capped.resolution) * capped.resolution * capped.resolution, double(int64_t(1) << 24));
    EXPECT_GE(capped.resolution, 64);
}

TEST(GlassTest, RenderSizesTheGlassGridFromTheScreenAndSaysWhich) {
    // The gem (an octahedron of side sqrt 2) fills more pixels of a larger image: a finer grid; the
    // command's summary names the grid and why, and a --glass-grid given is the grid used.
    test::TempDir dir;
    writeGemScene(dir);
    const Scene s = loadScene(dir.file("scene.json"));
    RenderOptions o;
    o.shadow = NoShadowOptions{};
    o.antiAliasing = AntiAliasing::Off;
    o.glass = MultiGlassOptions{};
    int64_t grid[2];
    for (int k = 0; k < 2; ++k) {
        o.width = k ? 400 : 64;
        o.height = k ? 300 : 48;
        grid[k] = render(s, s.cameras[0], o).glass.grid;
    }
    EXPECT_EQ(grid[0], 64);
    EXPECT_GT(grid[1], 96);
    const auto r = test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("a.png") +
                                           " --width 64 --height 48 --glass multi --shadows none");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("glass grid 64 (auto: the largest glass object spans"), std::string::npos) << r.out;
    const auto given =
        test::runVoxfx(dir, "render " + dir.file("scene.json") + " -o " + dir.file("b.png") +
                                " --width 64 --height 48 --glass multi --glass-grid 40 --shadows none");
    ASSERT_EQ(given.exitCode, 0) << given.err;
    EXPECT_NE(given.out.find("glass grid 40 (given)"), std::string::npos) << given.out;
}

TEST(GlassTest, CommandLineGlassKnobsChangeTheImageAndBadValuesSayWhich) {
    // CHANG's knobs on the render command line (--glass-grid, --glass-coverage, --angle-threshold,
    // --slab-overlap, --max-events, --no-scene-behind: CHANG's environment-only lookup after the last exit):
    // each is parsed, most change the multi image of a glass octahedron over a ground quad, and a bad value
    // exits non-zero naming the flag, with no image written.
    test::TempDir dir;
    writeGemScene(dir);
    const std::string base =
        "render " + dir.file("scene.json") + " --width 48 --height 36 --shadows none --glass multi ";
    auto renderWith = [&](const std::string& flags, const std::string& png) {
        const auto r = test::runVoxfx(dir, base + flags + " -o " + dir.file(png));
        EXPECT_EQ(r.exitCode, 0) << flags << ": " << r.err;
        return readPng(dir.file(png));
    };
    const Image plain = renderWith("--glass-grid 24", "plain.png");
    for (const char* flags :
         {"--glass-grid 12", "--glass-grid 24 --glass-coverage center", "--glass-grid 24 --max-events 1",
          "--glass-grid 24 --no-scene-behind", "--glass-grid 24 --glass-coverage center --slab-overlap 1"}) {
        const Image other = renderWith(flags, "other.png");
        EXPECT_NE(other.pixels, plain.pixels) << flags << " changed nothing";
    }
    // The defaults, given. (The angle threshold changes nothing on this gem: with the media stack a
    // voxel of the surface just crossed is no new event whatever the threshold.)
    EXPECT_EQ(
        renderWith("--glass-grid 24 --angle-threshold 0.35 --slab-overlap 0 --max-events 16 --scene-behind",
                   "same.png")
            .pixels,
        plain.pixels);
    for (const auto& [flags, says] :
         std::vector<std::pair<std::string, std::string>>{{"--angle-threshold abc", "--angle-threshold"},
                                                          {"--angle-threshold 4", "angle"},
                                                          {"--max-events 0", "max"},
                                                          {"--slab-overlap -1", "slab"},
                                                          {"--glass-grid 1", "glass"},
                                                          {"--glass-coverage most", "conservative"}}) {
        const auto r = test::runVoxfx(dir, base + flags + " -o " + dir.file("bad.png"));
        EXPECT_NE(r.exitCode, 0) << flags << ": " << r.err;
        EXPECT_EQ(r.err.find("terminate called"), std::string::npos) << flags << ": " << r.err; // "abc" did
        EXPECT_NE(r.err.find(says), std::string::npos) << flags << ": " << r.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("bad.png"))) << flags;
    }
}

TEST(GlassTest, ImageErrorIsTheMeanAbsoluteAndPsnrOverTheMask) {
    Image a(2, 1), b(2, 1);
    a.at(0, 0) = {0.5f, 0.5f, 0.5f};
    b.at(0, 0) = {0.6f, 0.4f, 0.5f};
    a.at(1, 0) = {9, 9, 9}; // masked out
    const ImageError e = imageError(a, b, {1, 0});
    EXPECT_EQ(e.pixels, 1);
    EXPECT_NEAR(e.mae, 0.2 / 3, 1e-6);
    EXPECT_NEAR(e.psnr, 10 * std::log10(1 / (0.02 / 3)), 1e-4);
    EXPECT_THROW(imageError(a, b, {1}), Error);
    EXPECT_TRUE(std::holds_alternative<TwoSurfaceGlassOptions>(glassOptionsNamed("two-surface")));
    EXPECT_THROW(glassOptionsNamed("frosty"), Error);
}

} // namespace
} // namespace voxfx
