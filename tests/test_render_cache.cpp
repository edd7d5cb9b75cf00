// Tests of RenderCache (voxfx/render.hpp): a frame that reuses what earlier frames built is the
// image a frame without a cache renders, pixel for pixel, whatever was rendered before it (other
// shadow kinds, other cameras, another scene); a change to the meshes, a material, a light, the
// options or (for techniques fitted to the view) the camera rebuilds the part it touches; the
// timings say which passes reused a build.
#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/render.hpp"

namespace voxfx {
namespace {

using namespace voxfx::demo;

Scene smallTree() {
    TreeOptions t;
    t.leaves = 400;
    t.trunkSides = 8;
    return makeTreeScene(t);
}

RenderOptions smallDefaults(std::string_view kind, Occlusion occlusion = RenderOptions{}.ambientOcclusion) {
    RenderOptions o; // every default (anti-aliasing, ambient occlusion, sky) at a small size
    o.ambientOcclusion = occlusion;
    o.width = 96;
    o.height = 64;
    o.shadow = shadowOptionsNamed(kind);
    setRenderOption(o, "gridResolution", int64_t(64));
    setRenderOption(o, "gridDepth", int64_t(64));
    setRenderOption(o, "mapResolution", int64_t(256));
    setRenderOption(o, "dsmResolution", int64_t(128));
    return o;
}

void expectSameImage(const Image& a, const Image& b, const std::string& what) {
    ASSERT_EQ(a.width, b.width) << what;
    ASSERT_EQ(a.height, b.height) << what;
    int64_t differ = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) differ += !(a.pixels[i] == b.pixels[i]);
    EXPECT_EQ(differ, 0) << what << ": pixels differ from the frame rendered without a cache";
}

bool cached(const RenderResult& r, std::string_view pass) {
    for (const PassTime& p : r.timings.passes)
        if (p.name == pass) return p.cached;
    ADD_FAILURE() << "no pass " << pass;
    return false;
}

Camera movedCamera(const Camera& c) {
    Camera m = c;
    m.position = c.target + (c.position - c.target) * 0.8 + Vec3d{0.7, 0.2, -0.4};
    return m;
}

// Both ambient occlusion methods: the field is built once and kept (the pass says "cached" from
// the second frame on); the screen-space method (the default) is made anew for every view.
class CachedFrames : public ::testing::TestWithParam<Occlusion> {};

TEST_P(CachedFrames, AreTheUncachedImagesWhateverCameBefore) {
    const Occlusion occlusion = GetParam();
    const Scene scene = smallTree();
    const Camera cam0 = scene.cameras.at(0), cam1 = movedCamera(cam0);
    const std::vector<std::string> kinds = {"map", "transmittance", "absorption", "deep", "exact"};
    std::vector<Image> reference0, reference1;
    for (const std::string& k : kinds) {
        reference0.push_back(render(scene, cam0, smallDefaults(k, occlusion)).image);
        reference1.push_back(render(scene, cam1, smallDefaults(k, occlusion)).image);
    }
    RenderCache cache;
    const bool fieldKept = occlusion == Occlusion::Field;
    // Every kind, then every kind again from the other camera, then back in reverse order.
    for (std::size_t i = 0; i < kinds.size(); ++i) {
        const RenderResult r = render(scene, cam0, smallDefaults(kinds[i], occlusion), cache);
        expectSameImage(r.image, reference0[i], kinds[i] + " first");
        EXPECT_FALSE(cached(r, "shadows")) << kinds[i];
        EXPECT_EQ(cached(r, "flatten"), i > 0) << kinds[i];
        EXPECT_EQ(cached(r, "occlusion"), fieldKept && i > 0) << kinds[i];
    }
    for (std::size_t i = 0; i < kinds.size(); ++i) {
        const RenderResult r = render(scene, cam1, smallDefaults(kinds[i], occlusion), cache);
        expectSameImage(r.image, reference1[i], kinds[i] + " moved camera");
        // The cache keeps two techniques per light (at least eight shadows): the last ones used.
        EXPECT_EQ(cached(r, "shadows"), i + 8 >= kinds.size()) << kinds[i];
        EXPECT_EQ(cached(r, "occlusion"), fieldKept) << kinds[i];
    }
    for (std::size_t j = kinds.size(); j-- > 0;) {
        const RenderResult r = render(scene, cam0, smallDefaults(kinds[j], occlusion), cache);
        expectSameImage(r.image, reference0[j], kinds[j] + " again");
        EXPECT_TRUE(cached(r, "shadows")) << kinds[j];
        EXPECT_TRUE(cached(r, "flatten")) << kinds[j];
    }
}
INSTANTIATE_TEST_SUITE_P(RenderCacheTest, CachedFrames,
                         ::testing::Values(Occlusion::Screen, Occlusion::Field),
                         [](const auto& p) { return std::string(toString(p.param)); });

TEST(RenderCacheTest, AChangedMaterialLightMeshOrOptionRebuildsWhatItTouches) {
    Scene scene = smallTree();
    const Camera cam = scene.cameras.at(0);
    RenderCache cache;
    // The field method of ambient occlusion: the build a changed mesh or radius must redo.
    const RenderOptions o = smallDefaults("transmittance", Occlusion::Field);
    render(scene, cam, o, cache);

    // A leaf colour: the transmittance grid's channels change (and the flattening's key with the
    // materials); the image is the uncached one of the changed scene.
    for (Material& m : scene.materials)
        if (m.opacity < 1) m.baseColor = {0.9f, 0.2f, 0.1f};
    RenderResult r = render(scene, cam, o, cache);
    EXPECT_FALSE(cached(r, "shadows"));
    expectSameImage(r.image, render(scene, cam, o).image, "changed leaf colour");

    // The sun: the shadows again, not the flattened scene.
    scene.lights.at(0).direction = normalize(scene.lights.at(0).direction + Vec3d{0.3, 0, 0.2});
    r = render(scene, cam, o, cache);
    EXPECT_FALSE(cached(r, "shadows"));
    EXPECT_TRUE(cached(r, "flatten"));
    expectSameImage(r.image, render(scene, cam, o).image, "moved sun");

    // One vertex of the trunk: everything.
    scene.meshes.at(0).mesh.positions.at(0).y += 0.05f;
    r = render(scene, cam, o, cache);
    EXPECT_FALSE(cached(r, "flatten"));
    EXPECT_FALSE(cached(r, "shadows"));
    EXPECT_FALSE(cached(r, "occlusion"));
    expectSameImage(r.image, render(scene, cam, o).image, "moved vertex");

    // An option of the technique: its shadows.
    RenderOptions finer = o;
    setRenderOption(finer, "gridResolution", int64_t(96));
    r = render(scene, cam, finer, cache);
    EXPECT_FALSE(cached(r, "shadows"));
    EXPECT_TRUE(cached(r, "occlusion"));
    expectSameImage(r.image, render(scene, cam, finer).image, "finer grid");

    // The occlusion radius: the occlusion field, not the shadows.
    RenderOptions wider = finer;
    wider.ambientOcclusion = Occlusion::Field;
    wider.occlusionRadius = 0.5;
    r = render(scene, cam, wider, cache);
    EXPECT_TRUE(cached(r, "shadows"));
    EXPECT_FALSE(cached(r, "occlusion"));
    expectSameImage(r.image, render(scene, cam, wider).image, "occlusion radius");
}

// A glass box on a ground under the default sun: frosted glass is fitted to the view (its
// slicemaps are the camera's), so a moved camera rebuilds it; exact glass's tracer is kept.
TEST(RenderCacheTest, GlassFittedToTheViewFollowsTheCameraAndTheRestIsKept) {
    Scene scene;
    Material ground;
    ground.baseColor = {0.6f, 0.55f, 0.5f};
    SceneMesh g;
    test::appendQuad(g.mesh, {0, 0, 0}, {0, 0, 3}, {3, 0, 0}); // counter-clockwise from above
    g.material = scene.addMaterial(ground);
    scene.meshes.push_back(g);
    Material glass;
    glass.transmission = 1;
    glass.ior = 1.5f;
    glass.attenuationColor = {0.6f, 0.8f, 0.95f};
    glass.attenuationDistance = 1;
    SceneMesh box;
    appendBox(box.mesh, {-0.5, 0.01, -0.5}, {0.5, 1.01, 0.5});
    box.material = scene.addMaterial(glass);
    scene.meshes.push_back(box);
    Camera c;
    c.position = {2.5, 2, 3};
    c.target = {0, 0.5, 0};
    scene.cameras.push_back(c);
    const Camera moved = movedCamera(c);
    for (const char* method : {"frosted", "exact", "multi"}) {
        RenderOptions o = smallDefaults("map");
        o.glass = glassOptionsNamed(method);
        setRenderOption(o, "glassGrid", int64_t(32));
        RenderCache cache;
        render(scene, c, o, cache);
        const RenderResult r = render(scene, moved, o, cache);
        EXPECT_EQ(cached(r, "glass"), std::string_view(method) != "frosted") << method;
        EXPECT_TRUE(cached(r, "shadows")) << method;
        expectSameImage(r.image, render(scene, moved, o).image, std::string(method) + " moved camera");
    }
}

} // namespace
} // namespace voxfx
