// Tests of what every glass method shares (voxfx/glass.hpp, the renderer's glass pass): the
// absorption constant on the exact tracer and the voxel march alike, the default lights of a scene
// without lights, the command line (render --glass, glass-error, CHANG's knobs and their bad
// values), the image error over the glass mask and the methods by name. Each method is tested on
// its own in test_glass_optics.cpp, test_exact_glass.cpp, test_voxel_glass.cpp and
// test_frosted_glass.cpp; glass shadows in test_exact_shadow.cpp and test_shadow_cross_technique.cpp.
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
