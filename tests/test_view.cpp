// Tests of interactive viewing (voxfx/view.hpp) and what `voxfx view` saves: camera moves against
// closed forms (a rotation about up by Rodrigues' formula, the view height at the target's
// distance), the preview's counted work, the options as settings through a scene file and back
// (every technique and method, every field perturbed), a saved view rendering the very image of
// the view, the scene files that add to other scene files ("scene"), the 8-bit conversion against
// plain libpng, the viewer's framebuffer and saving (src/cli/viewer/, without a window), and the
// command's errors (the window itself: tests/view_window_test.py, under Xvfb).
#include <cmath>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <png.h>

#include "demo/demo_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/view.hpp"

#ifdef VOXFX_HAVE_VIEWER_LIBRARY
#include "cli/viewer/framebuffer.hpp"
#include "cli/viewer/session.hpp"
#endif

namespace voxfx {
namespace {

Camera testCamera() {
    Camera c;
    c.name = "c";
    c.position = {3, 2, 5};
    c.target = {0.5, 0.25, -0.5};
    c.up = {0, 1, 0};
    c.fovY = 0.7;
    c.nearDepth = 0.05;
    c.farDepth = 100;
    return c;
}

double angle(const Vec3d& a, const Vec3d& b) {
    return std::acos(std::clamp(dot(normalize(a), normalize(b)), -1.0, 1.0));
}

// Rodrigues' rotation of v about the unit axis k by theta.
Vec3d rotate(const Vec3d& v, const Vec3d& k, double theta) {
    return v * std::cos(theta) + cross(k, v) * std::sin(theta) + k * (dot(k, v) * (1 - std::cos(theta)));
}

void expectNear(const Vec3d& a, const Vec3d& b, double tol, const char* what) {
    EXPECT_LT(length(a - b), tol) << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x
                                  << ", " << b.y << ", " << b.z << ")";
}

TEST(ViewTest, OrbitTurnsTheEyeAboutUpAroundTheTarget) {
    const Camera c = testCamera();
    const Vec3d offset = c.position - c.target;
    for (const double yaw : {0.3, -1.2, 2.5, M_PI}) {
        const Camera o = orbitCamera(c, yaw, 0);
        EXPECT_EQ(o.target, c.target);
        EXPECT_EQ(o.up, c.up);
        EXPECT_EQ(o.fovY, c.fovY);
        // Yaw alone: the offset rotated about up by yaw (a right-handed turn).
        expectNear(o.position - o.target, rotate(offset, {0, 1, 0}, yaw), 1e-12, "yaw");
    }
    // Any turn keeps the distance; a whole turn comes back.
    const Camera p = orbitCamera(c, 0.7, -0.4);
    EXPECT_NEAR(length(p.position - p.target), length(offset), 1e-12);
    expectNear(orbitCamera(c, 2 * M_PI, 0).position, c.position, 1e-12, "full turn");
    // Pitch raises the eye by the angle: the angle between the offset and up shrinks by it.
    const double before = angle(offset, c.up);
    EXPECT_NEAR(angle(orbitCamera(c, 0, 0.25).position - c.target, c.up), before - 0.25, 1e-12);
    EXPECT_NEAR(angle(orbitCamera(c, 0, -0.25).position - c.target, c.up), before + 0.25, 1e-12);
    // A pitch then its opposite comes back (inside the poles' margin).
    expectNear(orbitCamera(orbitCamera(c, 0, 0.3), 0, -0.3).position, c.position, 1e-12, "pitch back");
}

TEST(ViewTest, OrbitStopsShortOfThePoles) {
    const Camera c = testCamera();
    const Camera top = orbitCamera(c, 0, 10); // far past straight above
    EXPECT_NEAR(angle(top.position - top.target, c.up), kMinPoleAngle, 1e-12);
    const Camera bottom = orbitCamera(c, 0, -10);
    EXPECT_NEAR(angle(bottom.position - bottom.target, c.up), M_PI - kMinPoleAngle, 1e-12);
    // At the pole the horizontal direction is kept: turning back down retraces the path.
    const double start = angle(c.position - c.target, c.up);
    expectNear(orbitCamera(top, 0, -(start - kMinPoleAngle)).position, c.position, 1e-9,
               "back from the pole");
    Camera along = c;
    along.position = c.target + Vec3d{0, 4, 0};
    EXPECT_THROW(orbitCamera(along, 0.1, 0), Error);
    Camera same = c;
    same.position = same.target;
    EXPECT_THROW(orbitCamera(same, 0.1, 0), Error);
    EXPECT_THROW(orbitCamera(c, NAN, 0), Error);
}

TEST(ViewTest, PanMovesEyeAndTargetAcrossTheViewByViewHeights) {
    const Camera c = testCamera();
    const double d = length(c.target - c.position), viewHeight = 2 * d * std::tan(c.fovY / 2);
    const Vec3d forward = normalize(c.target - c.position);
    const Camera p = panCamera(c, 0.25, -0.1);
    const Vec3d move = p.target - c.target;
    expectNear(p.position - c.position, move, 1e-12, "eye and target move alike");
    EXPECT_NEAR(dot(move, forward), 0, 1e-12);                            // across the view
    EXPECT_NEAR(length(move), std::hypot(0.25, 0.1) * viewHeight, 1e-12); // in view heights
    // In the moved camera's own frame the old target lies left of and above the centre: the
    // camera went right and down.
    const Vec3d right = normalize(cross(forward, c.up)), up = cross(right, forward);
    EXPECT_NEAR(dot(c.target - p.position, right), -0.25 * viewHeight, 1e-12);
    EXPECT_NEAR(dot(c.target - p.position, up), 0.1 * viewHeight, 1e-12);
    EXPECT_THROW(panCamera(c, INFINITY, 0), Error);
}

TEST(ViewTest, DollyScalesTheDistanceToTheTargetAndTheClipPlanes) {
    const Camera c = testCamera();
    const Camera d = dollyCamera(c, 0.85);
    EXPECT_EQ(d.target, c.target);
    EXPECT_NEAR(length(d.position - d.target), 0.85 * length(c.position - c.target), 1e-12);
    EXPECT_NEAR(angle(d.target - d.position, c.target - c.position), 0, 1e-7);
    EXPECT_DOUBLE_EQ(d.nearDepth, 0.85 * c.nearDepth);
    EXPECT_DOUBLE_EQ(d.farDepth, 0.85 * c.farDepth);
    for (const double bad : {0.0, -1.0, double(INFINITY), double(NAN)})
        EXPECT_THROW(dollyCamera(c, bad), Error);
}

demo::TreeOptions smallTree() {
    demo::TreeOptions t;
    t.leaves = 300;
    return t;
}

TEST(ViewTest, APreviewRendersAFractionOfTheSamplesWithoutOcclusion) {
    const Scene scene = demo::makeTreeScene(smallTree());
    RenderOptions full;
    full.width = 160;
    full.height = 90;
    EXPECT_THROW(previewOptions(full, 0), Error);
    const RenderOptions preview = previewOptions(full, 4);
    EXPECT_EQ(preview.width, 40);
    EXPECT_EQ(preview.height, 23); // rounded up
    EXPECT_EQ(preview.antiAliasing, AntiAliasing::Off);
    EXPECT_EQ(preview.ambientOcclusion, Occlusion::Off);
    EXPECT_EQ(preview.supersample, 1);
    EXPECT_EQ(shadowName(preview.shadow), shadowName(full.shadow));
    FrameRenderer renderer(std::make_shared<const Scene>(scene));
    const RenderResult a = renderer.render(scene.cameras[0], full);
    const RenderResult b = renderer.render(scene.cameras[0], preview);
    EXPECT_EQ(b.image.width, 40);
    EXPECT_EQ(b.image.height, 23);
    // Counted work, not time: samples that showed geometry (full: 2x2 per pixel of a 4x4 larger
    // image, so some 64 times more) and edge pixels refined.
    ASSERT_GT(b.coveredPixels, 0);
    EXPECT_GT(a.coveredPixels, 40 * b.coveredPixels) << a.coveredPixels << " vs " << b.coveredPixels;
    EXPECT_GT(a.refinedPixels, 0);
    EXPECT_EQ(b.refinedPixels, 0);
}

// The catalog's range and choices of a name, for perturbing a value within them.
const RenderOptionInfo& catalogInfo(const std::string& name) {
    static const std::vector<RenderOptionInfo> catalog = renderOptionCatalog();
    for (const RenderOptionInfo& i : catalog)
        if (i.name == name) return i;
    ADD_FAILURE() << "no catalog entry for " << name;
    return catalog.front();
}

// Another value than v that the option takes.
OptionValue perturbed(const std::string& name, const OptionValue& v, std::mt19937& rng) {
    const RenderOptionInfo& info = catalogInfo(name);
    return std::visit(
        [&]<class T>(const T& x) -> OptionValue {
            if constexpr (std::is_same_v<T, bool>) {
                return !x;
            } else if constexpr (std::is_same_v<T, int64_t>) {
                return x + 1 <= int64_t(info.hi) ? x + 1 : x - 1;
            } else if constexpr (std::is_same_v<T, double>) {
                // a value with all 52 bits of mantissa in use, inside the range
                const double lo = info.lo, hi = std::min(info.hi, lo + 10);
                double y = lo + (hi - lo) * std::uniform_real_distribution<double>(0.05, 0.95)(rng);
                return y == x ? std::nextafter(y, hi) : y;
            } else if constexpr (std::is_same_v<T, std::string>) {
                std::stringstream in(info.choices);
                std::string choice;
                while (std::getline(in, choice, '|')) {
                    choice.erase(0, choice.find_first_not_of(' '));
                    choice.erase(choice.find_last_not_of(' ') + 1);
                    if (choice != x) return choice;
                }
                ADD_FAILURE() << name << ": no other choice than " << x;
                return x;
            } else {
                const double lo = info.lo, hi = std::min(info.hi, lo + 10);
                std::uniform_real_distribution<double> u(lo, hi);
                return Vec3d{u(rng), u(rng), u(rng)};
            }
        },
        v);
}

TEST(ViewTest, EverySettingOfEveryTechniqueGoesThroughASceneFileAndBack) {
    test::TempDir dir;
    writeGltf(demo::makeTreeScene(smallTree()), dir.file("tree.glb"));
    std::mt19937 rng(7);
    int files = 0;
    for (const std::string_view kind : shadowNames())
        for (const std::string_view method : glassNames()) {
            SCOPED_TRACE(std::string(kind) + " / " + std::string(method));
            RenderOptions o;
            o.shadow = shadowOptionsNamed(kind);
            o.glass = glassOptionsNamed(method);
            for (const auto& [name, value] : renderSettings(o)) {
                if (name == "shadows" || name == "glass") continue;
                ASSERT_TRUE(setRenderOption(o, name, perturbed(name, value, rng))) << name;
            }
            const auto settings = renderSettings(o);
            SceneView view;
            view.scene = "tree.glb";
            Camera c = orbitCamera(testCamera(), 0.123456789, 0.0987654321);
            c.fovY = 0.7123456789012345;
            c.name = "saved";
            view.cameras = {c};
            view.render = settings;
            const std::string path = dir.file("view-" + std::to_string(files++) + ".json");
            writeSceneView(view, path);
            const Scene back = loadScene(path);
            ASSERT_GE(back.cameras.size(), 2u); // ours first, then the glTF's
            const Camera& b = back.cameras[0];
            EXPECT_EQ(b.name, "saved");
            EXPECT_EQ(b.position, c.position); // bit for bit
            EXPECT_EQ(b.target, c.target);
            EXPECT_EQ(b.up, c.up);
            EXPECT_EQ(b.fovY, c.fovY);
            EXPECT_EQ(b.nearDepth, c.nearDepth);
            EXPECT_EQ(b.farDepth, c.farDepth);
            const auto again = renderSettings(renderOptionsFor(back));
            ASSERT_EQ(again.size(), settings.size());
            for (std::size_t i = 0; i < settings.size(); ++i) {
                EXPECT_EQ(again[i].first, settings[i].first);
                EXPECT_TRUE(again[i].second == settings[i].second)
                    << settings[i].first << ": wrote " << formatOption(settings[i].second) << ", read "
                    << formatOption(again[i].second);
            }
        }
}

TEST(ViewTest, ASavedViewRendersTheImageOfTheView) {
    test::TempDir dir;
    const Scene scene = demo::makeTreeScene(smallTree());
    writeGltf(scene, dir.file("tree.glb"));
    const Camera camera = panCamera(dollyCamera(orbitCamera(scene.cameras[0], 0.6, 0.2), 0.8), 0.05, 0.02);
    RenderOptions o = renderOptionsFor(scene, "transmittance");
    o.width = 96;
    o.height = 54;
    setRenderOption(o, "gridResolution", int64_t(64));
    setRenderOption(o, "gridDepth", int64_t(64));
    o.antiAliasing = AntiAliasing::Adaptive;
    SceneView view;
    view.scene = "tree.glb";
    view.cameras = {camera};
    view.render = renderSettings(o);
    writeSceneView(view, dir.file("view.json"));
    const Scene saved = loadScene(dir.file("view.json"));
    const RenderOptions so = renderOptionsFor(saved);
    const Image a = render(scene, camera, o).image;
    const Image b = render(saved, sceneCamera(saved, 0, 1), so).image;
    ASSERT_EQ(b.width, 96);
    ASSERT_EQ(b.height, 54);
    int64_t differ = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) differ += !(a.pixels[i] == b.pixels[i]);
    EXPECT_EQ(differ, 0) << "pixels differ between the view and its saved scene";
}

TEST(ViewTest, ASceneFileAddsToAnotherAndItsSettingsWin) {
    test::TempDir dir;
    std::filesystem::create_directories(dir.path() / "base");
    writeGltf(demo::makeTreeScene(smallTree()), dir.file("base/tree.glb"));
    test::writeFile(dir.file("base/base.json"), R"({"gltf": "tree.glb",
        "cameras": [{"name": "base-cam", "position": [0, 1, 9], "target": [0, 1, 0]}],
        "render": {"shadows": "deep", "dsmResolution": 300, "gridResolution": 77, "aa": "post"},
        "environmentMap": "sky.pfm"})");
    test::writeFile(dir.file("top.json"), R"({"scene": "base/base.json",
        "cameras": [{"name": "top-cam", "position": [1, 2, 3], "target": [0, 1, 0], "fovY": 0.5}],
        "render": {"shadows": "transmittance", "gridResolution": 64, "antiAliasing": "off"},
        "environmentMap": "sky"})");
    const Scene s = loadScene(dir.file("top.json"));
    ASSERT_EQ(s.cameras.size(), 3u); // top's, base's, the glTF's
    EXPECT_EQ(s.cameras[0].name, "top-cam");
    EXPECT_EQ(s.cameras[0].fovY, 0.5);
    EXPECT_EQ(s.cameras[1].name, "base-cam");
    EXPECT_EQ(s.meshes.size(), demo::makeTreeScene(smallTree()).meshes.size());
    const RenderOptions o = renderOptionsFor(s);
    EXPECT_EQ(shadowName(o.shadow), "transmittance"); // the top file's kind, not the base's
    OptionValue grid;
    for (const auto& [name, value] : renderSettings(o))
        if (name == "gridResolution") grid = value;
    EXPECT_TRUE(grid == OptionValue(int64_t(64)));
    EXPECT_EQ(o.antiAliasing, AntiAliasing::Off); // its alias "aa" in the base gives way too
    EXPECT_EQ(s.settings.environmentMap, "sky");  // the procedural sky, not a file "sky"
    // Without a top-level environment the base's map, resolved against the base's folder.
    test::writeFile(dir.file("plain.json"), R"({"scene": "base/base.json"})");
    EXPECT_EQ(std::filesystem::path(loadScene(dir.file("plain.json")).settings.environmentMap),
              dir.path() / "base" / "sky.pfm");
    EXPECT_EQ(shadowName(renderOptionsFor(loadScene(dir.file("plain.json"))).shadow), "deep");
}

std::string errorOf(const std::string& path) {
    try {
        loadScene(path);
    } catch (const Error& e) { return e.what(); }
    return "(no error)";
}

TEST(ViewTest, SceneFilesThatIncludeThemselvesOrSayTooMuchAreRefused) {
    test::TempDir dir;
    test::writeFile(dir.file("self.json"), R"({"scene": "self.json"})");
    EXPECT_NE(errorOf(dir.file("self.json")).find("includes itself"), std::string::npos)
        << errorOf(dir.file("self.json"));
    test::writeFile(dir.file("a.json"), R"({"scene": "b.json"})");
    test::writeFile(dir.file("b.json"), R"({"scene": "./a.json"})");
    EXPECT_NE(errorOf(dir.file("a.json")).find("includes itself"), std::string::npos)
        << errorOf(dir.file("a.json"));
    test::writeFile(dir.file("missing.json"), R"({"scene": "nowhere.glb"})");
    const std::string missing = errorOf(dir.file("missing.json"));
    EXPECT_NE(missing.find("missing.json: scene"), std::string::npos) << missing;
    EXPECT_NE(missing.find("nowhere.glb"), std::string::npos) << missing;
    test::writeFile(dir.file("both.json"), R"({"scene": "x.glb", "gltf": "x.glb"})");
    EXPECT_NE(errorOf(dir.file("both.json")).find("not both"), std::string::npos);
    writeGltf(demo::makeTreeScene(smallTree()), dir.file("tree.glb"));
    test::writeFile(dir.file("fov.json"), R"({"scene": "tree.glb", "cameras": [{"position": [0, 1, 5],
        "target": [0, 0, 0], "fovY": 0.5, "fovYDegrees": 30}]})");
    EXPECT_NE(errorOf(dir.file("fov.json")).find("not both"), std::string::npos)
        << errorOf(dir.file("fov.json"));

    SceneView view;
    view.scene = "tree.glb";
    EXPECT_THROW(writeSceneView(view, dir.file("view.txt")), Error);
    Camera bad = testCamera();
    bad.position.x = NAN;
    view.cameras = {bad};
    EXPECT_THROW(writeSceneView(view, dir.file("nan.json")), Error);
    EXPECT_FALSE(std::filesystem::exists(dir.file("nan.json"))); // nothing half written
}

TEST(ViewTest, TheEightBitImageIsWhatWritePngStores) {
    Image img(37, 5);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-0.2f, 1.3f); // clamped below 0 and above 1
    for (Vec3f& p : img.pixels) p = {u(rng), u(rng), u(rng)};
    img.pixels[0] = {0.0031308f, 0.5f, 1.0f};
    test::TempDir dir;
    writePng(img, dir.file("a.png"));
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    ASSERT_NE(png_image_begin_read_from_file(&png, dir.file("a.png").c_str()), 0) << png.message;
    png.format = PNG_FORMAT_RGB;
    std::vector<uint8_t> stored(PNG_IMAGE_SIZE(png));
    ASSERT_NE(png_image_finish_read(&png, nullptr, stored.data(), 0, nullptr), 0) << png.message;
    EXPECT_EQ(toSrgb8(img), stored);
}

TEST(ViewCommandTest, HelpTeachesTheControls) {
    test::TempDir dir;
    const test::CommandRun r = test::runVoxfx(dir, "view --help");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* text : {"left drag", "orbit", "right or middle drag", "wheel", "shift+S", "P or F12",
                             "view-NNN.json", "Esc or Q", "--demo", "--preview-scale", "--shadows"})
        EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
}

TEST(ViewCommandTest, BadInputIsAClearErrorWithoutAWindow) {
    test::TempDir dir;
    test::writeFile(dir.file("bad.json"), "{\"meshes\": [");
    const test::CommandRun bad = test::runVoxfx(dir, "view " + dir.file("bad.json"));
    EXPECT_EQ(bad.exitCode, 1);
    EXPECT_NE(bad.err.find("bad.json: malformed JSON"), std::string::npos) << bad.err;
    const test::CommandRun none = test::runVoxfx(dir, "view");
    EXPECT_EQ(none.exitCode, 1);
    EXPECT_NE(none.err.find("give a scene file or --demo NAME (tree, bunny, cgal, glass)"), std::string::npos)
        << none.err;
    const test::CommandRun unknown = test::runVoxfx(dir, "view --demo meadow");
    EXPECT_EQ(unknown.exitCode, 1);
    EXPECT_NE(unknown.err.find("unknown demo scene 'meadow'"), std::string::npos) << unknown.err;
}

TEST(ViewCommandTest, WithoutADisplayItSaysSoAndFails) {
    test::TempDir dir;
    // The display variables removed for this run only (runVoxfx runs the command through the shell).
    const std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(VOXFX_CLI_PATH) +
                            " view --demo tree --width 32 --height 18 >" + dir.file("out.txt") + " 2>" +
                            dir.file("err.txt") + " </dev/null";
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 1);
    const std::string err = test::readFileBytes(dir.file("err.txt"));
    // A build without SDL2 says that first; a build with it names the missing display.
    EXPECT_TRUE(err.find("no display: $DISPLAY is not set") != std::string::npos ||
                err.find("needs SDL2") != std::string::npos)
        << err;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "view-001.png"));
}

#ifdef VOXFX_HAVE_VIEWER_LIBRARY

TEST(ViewerTest, TheFrameIsShownOneToOneAndAPreviewInBlocks) {
    using namespace cli::viewer;
    std::vector<uint8_t> rgb(6 * 4 * 3);
    for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = uint8_t(i * 7);
    Framebuffer same(6, 4);
    blitRgb(same, rgb.data(), 6, 4);
    for (int i = 0; i < 24; ++i)
        EXPECT_EQ(same.pixels[size_t(i)], 0xff000000u | uint32_t(rgb[3 * i]) << 16 |
                                              uint32_t(rgb[3 * i + 1]) << 8 | uint32_t(rgb[3 * i + 2]))
            << i;
    // A preview of a quarter of the size: each of its pixels fills a 4 x 4 block, rounded up sizes
    // (the 5 x 3 preview of a 18 x 10 window) clipped at the right and bottom.
    Framebuffer big(18, 10);
    blitRgb(big, rgb.data(), 5, 3);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 18; ++x) {
            const int sx = x * 5 / 18, sy = y * 3 / 10, i = sy * 5 + sx;
            ASSERT_EQ(big.pixels[size_t(y * 18 + x)] & 0xffffffu,
                      uint32_t(rgb[3 * i]) << 16 | uint32_t(rgb[3 * i + 1]) << 8 | uint32_t(rgb[3 * i + 2]));
        }
}

TEST(ViewerTest, TextStaysInItsPanelAndLinesBreakBetweenPairs) {
    using namespace cli::viewer;
    Framebuffer fb(200, 60);
    std::fill(fb.pixels.begin(), fb.pixels.end(), 0xff808080u);
    const Rect r = drawPanel(fb, 0, 0, {"shadows map", "Gg pq y|j"}, 1);
    EXPECT_EQ(r.w, textWidth("shadows map", 1) + 6);
    int white = 0;
    for (int y = 0; y < 60; ++y)
        for (int x = 0; x < 200; ++x) {
            const uint32_t p = fb.pixels[size_t(y * 200 + x)];
            const bool inside = x < r.w && y < r.h;
            if (!inside) {
                ASSERT_EQ(p, 0xff808080u) << x << ", " << y;
            } else if (p != 0xffffffffu) {
                ASSERT_LT(p & 0xffu, 0x80u); // darkened
            }
            white += p == 0xffffffffu;
        }
    EXPECT_GT(white, 60);
    // Pairs stay whole: "occlusion 292, total 1.21 s" (27 characters) does not fit 26.
    EXPECT_EQ(wrapWords("flatten 0.5, G-buffer 26, occlusion 292, total 1.21 s", 26),
              (std::vector<std::string>{"flatten 0.5, G-buffer 26,", "occlusion 292,", "total 1.21 s"}));
    EXPECT_EQ(wrapWords("saved view-001.png view-001.json", 20),
              (std::vector<std::string>{"saved view-001.png", "view-001.json"}));
}

// A session on the small tree, saving into `dir`.
cli::viewer::ViewSetup treeSetup(const test::TempDir& dir, std::shared_ptr<const Scene> scene) {
    cli::viewer::ViewSetup setup;
    setup.scene = scene;
    setup.name = "tree";
    setup.camera = aimAtScene(scene->cameras[0], *scene);
    setup.optionsFor = [scene](const std::string& shadows, const std::string& glass) {
        RenderOptions o = renderOptionsFor(*scene, shadows, glass);
        setRenderOption(o, "mapResolution", int64_t(512));
        setRenderOption(o, "gridResolution", int64_t(64));
        setRenderOption(o, "gridDepth", int64_t(64));
        return o;
    };
    setup.width = 80;
    setup.height = 45;
    setup.saveDir = dir.path().string();
    return setup;
}

TEST(ViewerTest, KeysCycleTheKindsAndTheSavedViewRendersTheSavedFrame) {
    using namespace cli::viewer;
    test::TempDir dir;
    const auto scene = std::make_shared<const Scene>(demo::makeTreeScene(smallTree()));
    ViewState state(treeSetup(dir, scene));
    EXPECT_EQ(state.stateText(), "shadows map, glass none, aa full, ao screen");
    state.cycleShadows(1);
    state.cycleGlass(-1); // wraps around to the last method
    state.toggleAntiAliasing();
    EXPECT_EQ(state.stateText(),
              "shadows transmittance, glass " + std::string(glassNames().back()) + ", aa off, ao screen");
    state.cycleGlass(1);
    state.camera = dollyCamera(orbitCamera(state.camera, 0.5, 0.1), 0.9);
    const RenderOptions preview = state.frameOptions(true);
    EXPECT_EQ(preview.width, 20);
    EXPECT_EQ(preview.ambientOcclusion, Occlusion::Off);
    cli::viewer::Frame f;
    f.camera = state.camera;
    f.options = state.frameOptions(false);
    FrameRenderer renderer(scene);
    f.image = renderer.render(f.camera, f.options).image;
    f.width = f.image.width;
    f.height = f.image.height;
    const std::vector<std::string> files = state.save(f);
    ASSERT_EQ(files.size(), 3u); // png, glb (a demo scene has no file), json
    EXPECT_EQ(std::filesystem::path(files[2]).filename(), "view-001.json");
    const Scene saved = loadScene(files[2]);
    const Image again = render(saved, sceneCamera(saved, 0, 1), renderOptionsFor(saved)).image;
    ASSERT_EQ(again.pixels.size(), f.image.pixels.size());
    EXPECT_TRUE(again.pixels == f.image.pixels) << "the saved view renders another image";
    EXPECT_TRUE(readPng(files[0]).pixels == readPng((dir.path() / "view-001.png").string()).pixels);
    EXPECT_EQ(std::filesystem::path(state.save(f)[0]).filename(), "view-002.png"); // the next number
    state.resetCamera();
    EXPECT_EQ(state.camera.position, aimAtScene(scene->cameras[0], *scene).position);
}

TEST(ViewerTest, AViewOfASceneFileNamesTheFileAndTheEnvironment) {
    using namespace cli::viewer;
    test::TempDir dir;
    std::filesystem::create_directories(dir.path() / "scenes");
    std::filesystem::create_directories(dir.path() / "out");
    const auto scene = std::make_shared<const Scene>(demo::makeTreeScene(smallTree()));
    writeGltf(*scene, dir.file("scenes/tree.glb"));
    ViewSetup setup = treeSetup(dir, scene);
    setup.sceneFile = dir.file("scenes/tree.glb");
    setup.saveDir = dir.file("out");
    setup.environmentRequest = "sky";
    ViewState state(std::move(setup));
    cli::viewer::Frame f;
    f.camera = state.camera;
    f.options = state.frameOptions(false);
    f.image = Image(80, 45, {0.25f, 0.5f, 1});
    const std::vector<std::string> files = state.save(f);
    ASSERT_EQ(files.size(), 2u); // no copy of the scene
    std::ifstream in(files[1]);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("\"scene\": \"../scenes/tree.glb\""), std::string::npos) << text;
    EXPECT_NE(text.find("\"environmentMap\": \"sky\""), std::string::npos) << text;
    EXPECT_EQ(loadScene(files[1]).meshes.size(), scene->meshes.size());
}

#endif // VOXFX_HAVE_VIEWER_LIBRARY

} // namespace
} // namespace voxfx
