// Tests of screen-space ambient occlusion (render/screen_space_ao.hpp, GTAO on the G-buffer).
// Oracles: the cosine-weighted unoccluded fraction beside a wall in closed form (a floor and a wall
// meeting at a right angle), properties (a plane alone is never occluded; the same output for every
// thread count and with kept buffers), and on the tree and bunny demo scenes the field method
// (voxfx/ambient_occlusion.hpp, what the renderer uses today) and counted Embree rays, with the
// bounds on the differences measured and explained.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "render/render_cache.hpp"
#include "render/screen_space_ao.hpp"
#include "render/shading.hpp"
#include "test_util.hpp"
#include "voxfx/ambient_occlusion.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"
#include "voxfx/triangle_tracer.hpp"

// Helpers in a namespace of their own: the test program is a unity build.
namespace voxfx::screen_space_ao_test {
namespace {

using detail::ScreenSpaceOcclusionOptions;

// A scene seen through its G-buffer, as the renderer hands it to the screen-space method (the
// G-buffer with its triangles' bases), and as the buffers of gatherSurfaces.
struct View {
    SceneGeometry geometry;
    Frame frame;
    GBuffer gbuffer;
    std::vector<detail::TriangleBasis> bases;
    std::vector<uint8_t> opaque; ///< per material
    detail::SurfaceBuffers surfaces;
};

View viewOf(const Scene& scene, const Camera& camera, int64_t width, int64_t height) {
    View v;
    v.geometry = flattenScene(scene);
    v.frame = cameraFrame(camera, width, height);
    v.gbuffer = renderGBuffer(v.geometry, v.frame);
    v.bases = detail::triangleBases(v.geometry);
    for (const Material& m : scene.materials) v.opaque.push_back(m.isOpaque());
    v.surfaces = detail::gatherSurfaces(v.gbuffer, v.geometry, scene.materials);
    return v;
}

// The two entries of the method: the renderer's, on the G-buffer itself, and the one on gathered
// buffers; each test of the method's accuracy runs both.
enum class Entry { GBuffer, Buffers };
const char* nameOf(Entry e) { return e == Entry::GBuffer ? "G-buffer" : "buffers"; }
constexpr Entry kEntries[] = {Entry::GBuffer, Entry::Buffers};

std::vector<float> occlusion(const View& v, const ScreenSpaceOcclusionOptions& o, Entry entry) {
    const detail::SurfaceBuffers& s = v.surfaces;
    if (entry == Entry::Buffers)
        return detail::screenSpaceOcclusion(v.frame, v.frame.width(), v.frame.height(), s.position, s.normal,
                                            s.covered, o, s.occluder);
    std::vector<float> out(s.covered.size());
    detail::ScreenSpaceOcclusionScratch scratch;
    detail::screenSpaceOcclusion(v.gbuffer, v.geometry, v.bases, v.opaque, 1, o, out, scratch);
    return out;
}

Scene sceneOf(std::initializer_list<Mesh> meshes) {
    Scene scene;
    Material grey;
    grey.baseColor = {0.7f, 0.7f, 0.7f};
    const uint32_t mat = scene.addMaterial(grey);
    for (const Mesh& m : meshes) {
        SceneMesh sm;
        sm.mesh = m;
        sm.material = mat;
        scene.meshes.push_back(sm);
    }
    return scene;
}

// The cosine-weighted fraction of the hemisphere above a point at distance d from an infinite plane
// perpendicular to its own (a floor beside a wall, or a wall above a floor) that meets the plane
// within r. Cosine-weighted directions project to a uniform distribution over the unit disk of the
// tangent plane (Malley); a direction w meets the plane within r iff its component towards the
// plane exceeds c = d / r, a circular segment of the disk of area acos(c) - c sqrt(1 - c^2), so
// the visible fraction is 1 - (acos(c) - c sqrt(1 - c^2)) / pi (1/2 at the foot of the wall, 1 from
// d = r on). Exact for a finite wall too where it reaches r beyond the point on every side.
double besideAPlane(double d, double r) {
    const double c = std::min(d / r, 1.0);
    return 1 - (std::acos(c) - c * std::sqrt(1 - c * c)) / M_PI;
}

// The floor y = 0 (x in [0, 5], z in [-5, 5]) and the wall x = 0 (y in [0, 4], z in [-5, 5]),
// seen from the front and above, occlusion radius 1.
struct Corner {
    static constexpr double kRadius = 1, kHalfWidth = 5, kWallHeight = 4;
    Scene scene;
    Camera camera;
    Corner() {
        Mesh floor, wall;
        test::appendQuad(floor, {2.5, 0, 0}, {0, 0, kHalfWidth}, {2.5, 0, 0});
        test::appendQuad(wall, {0, kWallHeight / 2, 0}, {0, kWallHeight / 2, 0}, {0, 0, kHalfWidth});
        scene = sceneOf({floor, wall});
        camera.position = {5.5, 4.2, 0.5};
        camera.target = {0.6, 0.6, 0};
        camera.fovY = 0.9;
    }
};

struct Errors {
    double mean = 0, meanWithin = 0, max = 0; ///< meanWithin: over the pixels within the radius
    int64_t count = 0, within = 0;
};

// SSAO against besideAPlane on the pixels whose radius, with a quarter to spare, lies in the image
// (screen-space methods have no data beyond its border) and which are at least the radius from the
// quads' sides (so the finite floor and wall act as infinite ones).
Errors cornerErrors(const ScreenSpaceOcclusionOptions& o, int64_t W, int64_t H, Entry entry) {
    const Corner c;
    const View v = viewOf(c.scene, c.camera, W, H);
    const std::vector<float> got = occlusion(v, o, entry);
    Errors e;
    double sum = 0, sumWithin = 0;
    const double r = Corner::kRadius;
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const auto i = std::size_t(y * W + x);
            if (!v.surfaces.covered[i]) continue;
            const Vec3d p(v.surfaces.position[i]), n(v.surfaces.normal[i]);
            const double pixels = 1.25 * r / (v.frame.viewDepth(p) * v.frame.tanHalfFovY()) * 0.5 * double(H);
            if (double(x) < pixels || double(y) < pixels || double(W - x) < pixels || double(H - y) < pixels)
                continue;
            if (std::abs(p.z) > Corner::kHalfWidth - r) continue;
            const double d = std::max(n.y > 0.99 ? p.x : p.y, 0.0); // floor: to the wall; wall: height
            const double err = std::abs(double(got[i]) - besideAPlane(d, r));
            sum += err;
            e.max = std::max(e.max, err);
            ++e.count;
            if (d < r) sumWithin += err, ++e.within;
        }
    e.mean = e.count ? sum / double(e.count) : 0;
    e.meanWithin = e.within ? sumWithin / double(e.within) : 0;
    return e;
}

TEST(ScreenSpaceOcclusionTest, CornerMatchesTheExactHemisphereIntegral) {
    // GTAO integrates each slice exactly between its horizons, and a wall over a floor is a height
    // field as the camera sees it, so what is left is sampling: 32 slice angles (2 per pixel times
    // the 16 of the pattern, averaged by the blur), the horizon between samples, the pixels'
    // positions and the bias angle; at half resolution, the samples next to the crease take the
    // occlusion of working pixels up to two samples farther from it, where the exact fraction
    // climbs by 2/pi per radius (the largest errors, 0.09, lie there). Measured (320 x 240, 27,913
    // samples in the mask, 12,582 within the radius), at the default 4 steps per side: within the
    // radius mean 0.0106, max 0.094 at half resolution, mean 0.0082, max 0.027 at full (5 steps:
    // 0.0073 and 0.090, 0.0041 and 0.026; 3 steps: 0.020 and 0.102); beyond it (exactly 1) a few
    // thousandths.
    // Without the horizon's interpolation to the radius the mean within the radius is 0.033 (half)
    // and 0.031 (full): these bounds fail then.
    for (const Entry entry : kEntries)
        for (const bool half : {true, false}) {
            ScreenSpaceOcclusionOptions o;
            o.radius = Corner::kRadius;
            o.halfResolution = half;
            const Errors e = cornerErrors(o, 320, 240, entry);
            std::printf("corner, %s, %s resolution: %lld pixels (%lld within the radius), |SSAO - exact| "
                        "mean %.4f (within the radius %.4f), max %.4f\n",
                        nameOf(entry), half ? "half" : "full", (long long)e.count, (long long)e.within,
                        e.mean, e.meanWithin, e.max);
            ASSERT_GT(e.within, 10000);
            EXPECT_LT(e.meanWithin, 0.02) << nameOf(entry) << (half ? " half" : " full");
            EXPECT_LT(e.max, half ? 0.15 : 0.05) << nameOf(entry) << (half ? " half" : " full");
        }
}

TEST(ScreenSpaceOcclusionTest, APlaneAloneIsNeverOccluded) {
    // However the camera sees it (steeply, at a grazing angle, tilted), a plane does not hide the sky
    // from its own points: every sample on it lies on its tangent plane (to rounding, which the bias
    // absorbs), so no horizon rises and each slice is the open one: exactly 1.
    Mesh plane;
    test::appendQuad(plane, {0, 0, 0}, {40, 0, 0}, {0, 0, 40});
    Mesh tilted;
    test::appendQuad(tilted, {1, 2, -1}, Vec3d{30, 9, 0}, Vec3d{0, -7, 30});
    const struct {
        const Mesh* mesh;
        Vec3d eye, target;
    } cases[] = {{&plane, {0, 8, 3}, {0, 0, 0}},
                 {&plane, {0, 0.4, 6}, {0, 0, -10}},
                 {&plane, {3, 2, 4}, {-2, 0, -3}},
                 {&tilted, {6, 9, 8}, {1, 2, -1}}};
    for (const auto& c : cases) {
        Camera cam;
        cam.position = c.eye;
        cam.target = c.target;
        const View v = viewOf(sceneOf({*c.mesh}), cam, 160, 120);
        int64_t covered = 0;
        for (const uint8_t b : v.surfaces.covered) covered += b;
        ASSERT_GT(covered, 5000);
        for (const Entry entry : kEntries)
            for (const bool half : {true, false}) {
                ScreenSpaceOcclusionOptions o;
                o.radius = 1.5;
                o.halfResolution = half;
                const std::vector<float> got = occlusion(v, o, entry);
                int64_t below = 0;
                for (const float g : got) below += g != 1.0f;
                EXPECT_EQ(below, 0) << "eye " << c.eye.x << " " << c.eye.y << " " << c.eye.z << " "
                                    << nameOf(entry) << (half ? " half" : " full");
            }
    }
}

// On the covered samples of every second row and column, the field method's visibility, built as
// the renderer builds it (fieldOcclusionSetup: the opaque triangles, the radius from the meshes'
// diagonals); on every fourth, the exact cosine-weighted fraction of directions meeting no opaque
// triangle within the radius, counted with 256 Embree rays (a 16 x 16 grid of Malley directions,
// stratified: about 0.01 from the integral).
struct Reference {
    std::vector<float> field, rays;
    std::vector<uint8_t> compared, counted; ///< where `field`, `rays` hold a value
    double radius = 0;
};

Vec3d cosineDirection(const Vec3d& n, double u1, double u2) {
    const double r = std::sqrt(u1), phi = 2 * M_PI * u2;
    const Vec3d a = std::abs(n.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
    const Vec3d t1 = normalize(cross(n, a)), t2 = cross(n, t1);
    return normalize(t1 * (r * std::cos(phi)) + t2 * (r * std::sin(phi)) +
                     n * std::sqrt(std::max(0.0, 1 - u1)));
}

Reference referenceOf(const Scene& scene, const View& v) {
    Reference ref;
    const detail::FieldOcclusionSetup setup = detail::fieldOcclusionSetup(
        v.geometry, scene.materials, scene.meshes.size(), 0, RenderOptions{}.occlusionResolution);
    ref.radius = setup.radius;
    MeshView occluders;
    occluders.positions = &v.geometry.mesh.positions[0].x;
    occluders.vertexCount = v.geometry.mesh.positions.size();
    occluders.indices = setup.indices.data();
    occluders.triangleCount = setup.indices.size() / 3;
    AmbientOcclusionOptions ao;
    ao.radius = setup.radius;
    ao.resolution = setup.resolution;
    const AmbientOcclusion field(occluders, setup.region, ao);
    const TriangleTracer tracer(occluders);
    const int64_t W = v.frame.width(), H = v.frame.height();
    ref.field.assign(std::size_t(W * H), 1.0f);
    ref.rays.assign(std::size_t(W * H), 1.0f);
    ref.compared.assign(std::size_t(W * H), 0);
    ref.counted.assign(std::size_t(W * H), 0);
    parallelFor(0, H, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto i = std::size_t(y * W + x);
                if (!v.surfaces.covered[i] || x % 2 || y % 2) continue;
                const Vec3d p(v.surfaces.position[i]), n(v.surfaces.normal[i]);
                ref.field[i] = float(field.visibility(p, n));
                ref.compared[i] = 1;
                if (x % 4 || y % 4) continue;
                int free = 0;
                for (int k = 0; k < 256; ++k) {
                    const Vec3d w = cosineDirection(n, (k % 16 + 0.5) / 16, (k / 16 + 0.5) / 16);
                    free += !tracer.intersect(p + n * tracer.epsilon(), w, 0, setup.radius).hit;
                }
                ref.rays[i] = float(free / 256.0);
                ref.counted[i] = 1;
            }
    });
    return ref;
}

struct Agreement {
    double mean = 0, meanOccluded = 0, correlation = 0;
    int64_t count = 0, occluded = 0;
};

// Mean absolute difference and Pearson correlation of a and b over the samples `mask` marks, and
// the mean difference over those of them where a or b is below 0.98 (the occluded ones: the others
// are 1 in both on open ground, and would hide the difference).
Agreement agreement(const std::vector<float>& a, const std::vector<float>& b,
                    const std::vector<uint8_t>& mask) {
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, diff = 0, diffOccluded = 0;
    Agreement g;
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (!mask[i]) continue;
        const double x = a[i], y = b[i];
        sa += x, sb += y, saa += x * x, sbb += y * y, sab += x * y, diff += std::abs(x - y);
        if (x < 0.98 || y < 0.98) diffOccluded += std::abs(x - y), ++g.occluded;
        ++g.count;
    }
    if (g.count == 0) return g;
    const double N = double(g.count);
    g.mean = diff / N;
    g.meanOccluded = g.occluded ? diffOccluded / double(g.occluded) : 0;
    const double cov = sab / N - sa / N * sb / N, va = saa / N - sa / N * sa / N,
                 vb = sbb / N - sb / N * sb / N;
    g.correlation = va > 0 && vb > 0 ? cov / std::sqrt(va * vb) : 0;
    return g;
}

// What a demo scene's screen-space occlusion must meet: against the field method, the mean
// difference over the compared samples and over the occluded ones, and the correlation; against the
// counted rays, the mean difference over the occluded samples and the correlation.
struct Bounds {
    double fieldMean, fieldMeanOccluded, fieldCorrelation, raysMeanOccluded, raysCorrelation;
};

// The demo scene at 640 x 360 from its own camera, with the radius the renderer picks for the field
// method (a tenth of the median diagonal of the non-flat opaque meshes).
void compareWithTheFieldMethod(const char* name, const Scene& scene, const Bounds& bounds) {
    const View v = viewOf(scene, scene.cameras[0], 640, 360);
    const Reference ref = referenceOf(scene, v);
    ScreenSpaceOcclusionOptions o;
    o.radius = ref.radius;
    for (const Entry entry : kEntries) {
        const std::vector<float> ssao = occlusion(v, o, entry);
        const Agreement vsField = agreement(ssao, ref.field, ref.compared);
        const Agreement ssaoVsRays = agreement(ssao, ref.rays, ref.counted);
        const Agreement fieldVsRays = agreement(ref.field, ref.rays, ref.counted);
        std::printf(
            "%s, %s (radius %.3f): SSAO - field over %lld samples: mean |diff| %.4f (%.4f over the %lld "
            "occluded), "
            "correlation %.3f\n  against %lld ray-counted samples: SSAO mean |diff| %.4f (%.4f over the %lld "
            "occluded), correlation %.3f; field %.4f (%.4f over %lld), correlation %.3f\n",
            name, nameOf(entry), ref.radius, (long long)vsField.count, vsField.mean, vsField.meanOccluded,
            (long long)vsField.occluded, vsField.correlation, (long long)ssaoVsRays.count, ssaoVsRays.mean,
            ssaoVsRays.meanOccluded, (long long)ssaoVsRays.occluded, ssaoVsRays.correlation, fieldVsRays.mean,
            fieldVsRays.meanOccluded, (long long)fieldVsRays.occluded, fieldVsRays.correlation);
        ASSERT_GT(vsField.occluded, 500) << name << ": the comparison needs occluded samples";
        EXPECT_LT(vsField.mean, bounds.fieldMean) << name << " " << nameOf(entry);
        EXPECT_LT(vsField.meanOccluded, bounds.fieldMeanOccluded) << name << " " << nameOf(entry);
        EXPECT_GT(vsField.correlation, bounds.fieldCorrelation) << name << " " << nameOf(entry);
        EXPECT_LT(ssaoVsRays.meanOccluded, bounds.raysMeanOccluded) << name << " " << nameOf(entry);
        EXPECT_GT(ssaoVsRays.correlation, bounds.raysCorrelation) << name << " " << nameOf(entry);
    }
}

// Screen-space occlusion sees only the depth buffer: it misses occluders outside the image and
// hidden behind nearer surfaces (the trunk behind the leaves, the bunny's far side), takes each
// visible surface for a solid slab behind it (thin branches darken what lies beside them on
// screen), and its blur and half resolution smooth over creases a few samples wide. So it differs
// from the field method where something is occluded by about 0.06-0.08 on average (measured at
// 640 x 360 with the default 4 steps per side: tree 0.076, bunny 0.059; correlation 0.76 and 0.90;
// with 5 steps 0.071 and 0.053), and from the counted rays by a little more than the field method
// does (tree 0.068 against 0.039, bunny 0.070 against 0.033; correlation 0.78 and 0.84 against 0.96
// and 0.98; with 5 steps 0.061 and 0.063). Open ground is 1 in all three, so over all
// samples the means are a few thousandths. The bounds leave 20-35 % to spare.
TEST(ScreenSpaceOcclusionTest, TreeDemoAgreesWithTheFieldMethod) {
    compareWithTheFieldMethod("tree", demo::makeTreeScene(), {0.01, 0.1, 0.65, 0.085, 0.7});
}

TEST(ScreenSpaceOcclusionTest, BunnyDemoAgreesWithTheFieldMethod) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    compareWithTheFieldMethod("bunny", demo::makeBunnyScene(test::dataPath("meshes")),
                              {0.01, 0.08, 0.8, 0.09, 0.75});
}

// The gathered buffers of one sample of each 2 x 2 cell of `fine`: (dx, dy) of the cell.
detail::SurfaceBuffers gatherCells(const View& fine, int64_t w, int64_t h, int dx, int dy) {
    detail::SurfaceBuffers s;
    s.position.assign(std::size_t(w * h), Vec3f{0, 0, 0});
    s.normal = s.position;
    s.covered.assign(std::size_t(w * h), 0);
    s.occluder = s.covered;
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x) {
            SurfacePoint sp;
            if (!surfaceAt(fine.gbuffer, fine.geometry, 2 * x + dx, 2 * y + dy, sp)) continue;
            const auto i = std::size_t(y * w + x);
            s.position[i] = Vec3f(sp.position);
            s.normal[i] = Vec3f(sp.normal);
            s.covered[i] = 1;
            s.occluder[i] = fine.opaque[sp.material];
        }
    return s;
}

TEST(ScreenSpaceOcclusionTest, TheRenderersCellsAgreeWithTheirGatheredSamples) {
    // The renderer's G-buffer has 2 x 2 samples per cell (adaptive anti-aliasing) and wants one
    // occlusion per cell, of the sample (1, 1) the shading pass shades: the G-buffer entry at
    // adaptive 2 against the buffers entry on those samples gathered by surfaceAt. What may differ:
    // positions from the depth in float, face normals in the downsample's one-surface test, a
    // block's normal interpolated at its mean position, face normals in the upsample's weights.
    // Measured (320 x 180 cells of the tree, radius 0.8): mean |diff| 0.0001 over the 34,357 covered
    // cells, 0.04 % of them more than 0.05 apart. The control, the same against the cells' samples
    // (0, 0) half a cell away, differs 18 times as much (mean 0.0019, 0.9 % apart).
    const Scene tree = demo::makeTreeScene();
    const int64_t w = 320, h = 180;
    const View fine = viewOf(tree, tree.cameras[0], 2 * w, 2 * h);
    ScreenSpaceOcclusionOptions o;
    o.radius = 0.8;
    std::vector<float> cells(std::size_t(w * h));
    detail::ScreenSpaceOcclusionScratch scratch;
    detail::screenSpaceOcclusion(fine.gbuffer, fine.geometry, fine.bases, fine.opaque, 2, o, cells, scratch);
    double mean[2] = {0, 0};
    for (const int d : {1, 0}) {
        const detail::SurfaceBuffers s = gatherCells(fine, w, h, d, d);
        const std::vector<float> gathered = detail::screenSpaceOcclusion(
            cameraFrame(tree.cameras[0], w, h), w, h, s.position, s.normal, s.covered, o, s.occluder);
        double sum = 0;
        int64_t covered = 0, apart = 0, occluded = 0;
        for (std::size_t i = 0; i < cells.size(); ++i) {
            if (!s.covered[i]) continue;
            const double diff = std::abs(double(cells[i]) - double(gathered[i]));
            sum += diff, ++covered, apart += diff > 0.05, occluded += gathered[i] < 0.9f;
        }
        mean[d] = sum / double(covered);
        std::printf(
            "cells against their gathered samples (%d, %d): %lld covered (%lld occluded), mean |diff| "
            "%.5f, %.3f %% more than 0.05 apart\n",
            d, d, (long long)covered, (long long)occluded, mean[d], 100.0 * double(apart) / double(covered));
        ASSERT_GT(occluded, 300);
        if (d == 1) {
            EXPECT_LT(mean[d], 0.001);
            EXPECT_LT(double(apart) / double(covered), 0.002);
            for (std::size_t i = 0; i < cells.size(); ++i)
                if (!s.covered[i]) { EXPECT_EQ(cells[i], 1.0f) << i; }
        }
    }
    EXPECT_GT(mean[0], 3 * mean[1]) << "the control must differ more";
}

TEST(ScreenSpaceOcclusionTest, TheRenderersUpsampleInTheShadingPassMatchesTheGBufferEntry) {
    // The renderer upsamples to the cells in its shading pass (CellOcclusion::at, given the position
    // and face normal the pass reconstructs in double from the depth), the G-buffer entry from its own
    // float reconstruction: the same method, so on the frame's own G-buffer (kept in the cache) the
    // two differ by rounding only. What would show a mistake: a cell's value from another cell, one
    // left unwritten (the buffer is reused between frames: a first frame of another camera fills it
    // first), background cells not 1.
    const Scene tree = demo::makeTreeScene();
    RenderOptions o; // every default: adaptive anti-aliasing (2 x 2 samples per cell), screen-space AO
    o.width = 320, o.height = 180;
    o.threads = 2;
    RenderCache cache;
    Camera other = tree.cameras[0];
    other.position = other.target + (other.position - other.target) * 0.7;
    render(tree, other, o, cache);
    render(tree, tree.cameras[0], o, cache);
    detail::RenderCacheData& c = cache.data();
    ASSERT_EQ(c.screenOcclusion.size(), std::size_t(o.width * o.height));
    const detail::FieldOcclusionSetup setup =
        detail::fieldOcclusionSetup(c.geometry, tree.materials, tree.meshes.size(), 0, 0);
    ScreenSpaceOcclusionOptions so;
    so.radius = setup.radius;
    std::vector<uint8_t> opaque;
    for (const Material& m : tree.materials) opaque.push_back(m.isOpaque());
    std::vector<float> entry(c.screenOcclusion.size());
    detail::ScreenSpaceOcclusionScratch scratch;
    detail::screenSpaceOcclusion(c.gbuffer, c.geometry, c.triangleBases, opaque, 2, so, entry, scratch);
    double sum = 0, max = 0;
    int64_t covered = 0, occluded = 0;
    for (int64_t y = 0; y < o.height; ++y)
        for (int64_t x = 0; x < o.width; ++x) {
            const auto i = std::size_t(y * o.width + x);
            const bool shows =
                c.gbuffer.triangle[std::size_t((2 * y + 1) * 2 * o.width + 2 * x + 1)] != GBuffer::kNone;
            if (!shows) {
                EXPECT_EQ(c.screenOcclusion[i], 1.0f) << x << ", " << y;
                continue;
            }
            const double d = std::abs(double(c.screenOcclusion[i]) - double(entry[i]));
            sum += d, max = std::max(max, d), ++covered, occluded += entry[i] < 0.98f;
        }
    std::printf(
        "renderer's cells against the G-buffer entry: %lld covered (%lld occluded), mean |diff| %.2e, "
        "max %.2e\n",
        (long long)covered, (long long)occluded, sum / double(covered), max);
    ASSERT_GT(occluded, 300) << "the test needs occluded cells";
    // Measured: mean 6e-10, max 3e-7 (tree at 320 x 180 cells).
    EXPECT_LT(sum / double(covered), 1e-6);
    EXPECT_LT(max, 1e-3);
}

// Two outputs of the method compared bit for bit: the values that differ, and those of `a` below 0.98
// (the comparison needs occluded samples).
struct BitCompare {
    int64_t occluded = 0, differ = 0;
};
BitCompare compareBits(const std::vector<float>& a, const std::vector<float>& b) {
    BitCompare c;
    for (std::size_t i = 0; i < a.size(); ++i) {
        c.occluded += a[i] < 0.98f;
        c.differ += std::memcmp(&a[i], &b[i], sizeof(float)) != 0;
    }
    return c;
}

// The working pixels (half resolution, after a G-buffer entry's call in `scratch`) whose horizon search
// was skipped (ScreenSpaceOcclusionOptions::flatMeshes), and the covered ones.
std::pair<int64_t, int64_t> skippedPixels(const detail::ScreenSpaceOcclusionScratch& scratch, int64_t w,
                                          int64_t h) {
    int64_t skipped = 0, covered = 0;
    const int64_t tw = (w + 7) / 8;
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x) {
            const auto i = std::size_t(y * w + x);
            if (!(scratch.samples[i].flags & 1)) continue;
            ++covered;
            const auto& t = scratch.tiles[std::size_t((y / 8) * tw + x / 8)];
            skipped += t.skipAll || (t.skipMesh >= 0 && scratch.meshes[i] == t.skipMesh);
        }
    return {skipped, covered};
}

TEST(ScreenSpaceOcclusionTest, SkippingSearchesThatCouldFindNothingGivesTheSameBits) {
    // Where no occluder within reach on screen lies within twice the radius in view depth (its own
    // flat mesh's excepted), a working pixel's horizon search cannot raise a horizon, so skipping it
    // (visibility 1) must give the search's output bit for bit; and it must skip something, most of
    // the ground and the open surfaces. The tree, the bunny, a 25-tree forest and the corner (the
    // floor beyond twice the radius from the wall skips; nearer it must search), G-buffer entry at 1
    // and 2 samples per cell.
    const Scene tree = demo::makeTreeScene();
    demo::ForestOptions fo;
    fo.trees = 25;
    const Scene forest = demo::makeForestScene(fo);
    const Corner corner;
    std::vector<std::pair<const char*, const Scene*>> scenes = {{"tree", &tree}, {"forest", &forest}};
    Scene bunny;
    if (test::missingData("meshes/bunny00.off").empty()) { // else left out (the data test above says why)
        bunny = demo::makeBunnyScene(test::dataPath("meshes"));
        scenes.emplace_back("bunny", &bunny);
    }
    scenes.emplace_back("corner", &corner.scene);
    for (const auto& [name, scene] : scenes)
        for (const int adaptive : {1, 2}) {
            const Camera& camera = scene == &corner.scene ? corner.camera : scene->cameras[0];
            const int64_t w = 320, h = 180;
            const SceneGeometry geometry = flattenScene(*scene);
            const GBuffer g = renderGBuffer(geometry, cameraFrame(camera, adaptive * w, adaptive * h));
            const std::vector<detail::TriangleBasis> bases = detail::triangleBases(geometry);
            std::vector<uint8_t> opaque;
            for (const Material& m : scene->materials) opaque.push_back(m.isOpaque());
            const detail::FieldOcclusionSetup setup =
                detail::fieldOcclusionSetup(geometry, scene->materials, scene->meshes.size(), 0, 0);
            ScreenSpaceOcclusionOptions o;
            o.radius = scene == &corner.scene ? Corner::kRadius : setup.radius;
            std::vector<float> searched(std::size_t(w * h)), skipping(searched.size());
            detail::ScreenSpaceOcclusionScratch scratch;
            detail::screenSpaceOcclusion(g, geometry, bases, opaque, adaptive, o, searched, scratch);
            o.flatMeshes = setup.flatMeshes;
            detail::screenSpaceOcclusion(g, geometry, bases, opaque, adaptive, o, skipping, scratch);
            const auto [skipped, covered] = skippedPixels(scratch, (w + 1) / 2, (h + 1) / 2);
            const BitCompare bits = compareBits(searched, skipping);
            std::printf(
                "%s, %d x %d samples per cell: %lld of %lld working pixels skip the search (%.1f %%); "
                "%lld of %lld cells occluded; %lld differ\n",
                name, adaptive, adaptive, (long long)skipped, (long long)covered,
                100.0 * double(skipped) / double(std::max<int64_t>(covered, 1)), (long long)bits.occluded,
                (long long)searched.size(), (long long)bits.differ);
            EXPECT_GT(bits.occluded, 100) << name;
            EXPECT_EQ(bits.differ, 0) << name << " " << adaptive;
            EXPECT_GT(skipped, covered / 10) << name << ": the test needs skipped pixels";
        }
}

// The compact per-triangle records (detail::TriangleTag) the downsample and the anti-aliasing's
// marking read, against the geometry itself: the face normal from the corner positions (double), the
// mesh, whether the material occludes (Material::isOpaque), and flat where each of the three vertex
// normals lies within kTagFlatCos (0.01 rad) of the face normal (either side; triangles within 1e-6
// of the threshold in cosine are left out, where float and double may disagree). On a forest of 4
// trees (2,466 triangles) 2,370 are flat (the leaves, whose vertex normals are their face's to float
// rounding), 96 not (the trunks); a flat triangle's shading normal (interpolatedNormal, what the
// downsample would otherwise compute) lies within 0.01 rad of its face normal at every point (measured
// 3.7e-4), which is what lets the downsample take the face normal there.
TEST(ScreenSpaceOcclusionTest, TriangleTagsMatchTheGeometry) {
    demo::ForestOptions fo;
    fo.trees = 4;
    fo.leavesPerTree = 200;
    const Scene forest = demo::makeForestScene(fo);
    const SceneGeometry g = flattenScene(forest);
    const std::vector<detail::TriangleBasis> bases = detail::triangleBases(g);
    std::vector<uint8_t> opaque;
    for (const Material& m : forest.materials) opaque.push_back(m.isOpaque());
    opaque.back() = 0; // one material that does not occlude, so that both answers are checked
    const std::vector<detail::TriangleTag> tags = detail::triangleTags(g, bases, opaque);
    ASSERT_EQ(tags.size(), g.mesh.triangleCount());
    int64_t flat = 0, notFlat = 0, occluding = 0, borderline = 0;
    double worst = 0;
    uint64_t seed = 12345;
    const auto uniform = [&] {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        return float(double(seed >> 11) / double(1ull << 53));
    };
    for (std::size_t t = 0; t < tags.size(); ++t) {
        const uint32_t* corner = &g.mesh.indices[3 * t];
        const Vec3d a(g.mesh.positions[corner[0]]), b(g.mesh.positions[corner[1]]),
            c(g.mesh.positions[corner[2]]);
        const Vec3d n = cross(b - a, c - a);
        ASSERT_GT(length(n), 0) << t;
        const Vec3d face = normalize(n);
        EXPECT_LT(length(Vec3d(tags[t].normal) - face), 1e-5) << t;
        EXPECT_EQ(tags[t].mesh & detail::kTagMesh, g.triangleMesh[t]) << t;
        const uint32_t m = g.triangleMaterial[t];
        const bool occludes = m < opaque.size() && opaque[m];
        EXPECT_EQ((tags[t].mesh & detail::kTagOccludes) != 0, occludes) << t;
        occluding += occludes;
        bool isFlat = true, near = false;
        for (int k = 0; k < 3; ++k) {
            const double cosine = std::abs(dot(Vec3d(g.normals[corner[k]]), face));
            isFlat = isFlat && cosine > double(detail::kTagFlatCos);
            near = near || std::abs(cosine - double(detail::kTagFlatCos)) < 1e-6;
        }
        borderline += near;
        if (!near) { ASSERT_EQ((tags[t].mesh & detail::kTagFlat) != 0, isFlat) << t; }
        isFlat = (tags[t].mesh & detail::kTagFlat) != 0;
        if (!isFlat) {
            ++notFlat;
            continue;
        }
        ++flat;
        // The shading normal at random points of the triangle against its face normal (either side).
        for (int k = 0; k < 4; ++k) {
            float u = uniform(), w = uniform();
            if (u + w > 1) u = 1 - u, w = 1 - w;
            const Vec3f p = Vec3f(a + (b - a) * double(u) + (c - a) * double(w));
            const Vec3f s = detail::interpolatedNormal(bases[t], p - bases[t].a);
            worst = std::max(worst, std::acos(std::min(1.0, std::abs(dot(Vec3d(s), face)))));
        }
    }
    std::printf("forest of %zu triangles: %lld flat, %lld not (%lld within rounding of the threshold); %lld "
                "occlude; a flat triangle's shading normal at most %.2e rad from its face normal\n",
                tags.size(), (long long)flat, (long long)notFlat, (long long)borderline, (long long)occluding,
                worst);
    EXPECT_GT(flat, 1000) << "the leaves are flat";
    EXPECT_GT(notFlat, 50) << "the trunks are not";
    EXPECT_GT(occluding, 0);
    EXPECT_LT(occluding, int64_t(tags.size()));
    EXPECT_LT(worst, 0.0101);
}

// The downsample takes a flat triangle's face normal (kTagFlat) instead of interpolating its corner
// normals: against the same G-buffer entry with every flat bit cleared (the interpolation everywhere),
// the forest's occlusion may move by no more than its normals' few 1e-4 rad do, through the slices'
// angles (measured at 640 x 360, 19,802 flat triangles: 3,846 of 230,400 samples differ, by at most
// 4.1e-6).
TEST(ScreenSpaceOcclusionTest, AFlatTrianglesFaceNormalMovesTheOcclusionByRoundingOnly) {
    demo::ForestOptions fo;
    fo.trees = 25;
    fo.leavesPerTree = 300;
    const Scene forest = demo::makeForestScene(fo);
    const View v = viewOf(forest, forest.cameras[0], 640, 360);
    const detail::FieldOcclusionSetup setup =
        detail::fieldOcclusionSetup(v.geometry, forest.materials, forest.meshes.size(), 0, 0);
    ScreenSpaceOcclusionOptions o;
    o.radius = setup.radius;
    std::vector<detail::TriangleTag> tags = detail::triangleTags(v.geometry, v.bases, v.opaque);
    int64_t flat = 0;
    std::vector<float> withFlat(std::size_t(640 * 360)), without(withFlat.size());
    detail::ScreenSpaceOcclusionScratch scratch;
    detail::screenSpaceOcclusion(v.gbuffer, v.geometry, v.bases, v.opaque, 1, o, withFlat, scratch, tags);
    for (detail::TriangleTag& t : tags) {
        flat += (t.mesh & detail::kTagFlat) != 0;
        t.mesh &= ~detail::kTagFlat;
    }
    detail::screenSpaceOcclusion(v.gbuffer, v.geometry, v.bases, v.opaque, 1, o, without, scratch, tags);
    double sum = 0, max = 0;
    int64_t occluded = 0, differ = 0;
    for (std::size_t i = 0; i < withFlat.size(); ++i) {
        const double d = std::abs(double(withFlat[i]) - double(without[i]));
        sum += d, max = std::max(max, d), occluded += without[i]<0.98f, differ += d> 0;
    }
    std::printf("forest, %lld flat triangles: %lld of %zu samples differ, mean |diff| %.2e, max %.2e (%lld "
                "occluded)\n",
                (long long)flat, (long long)differ, withFlat.size(), sum / double(withFlat.size()), max,
                (long long)occluded);
    ASSERT_GT(flat, 1000);
    ASSERT_GT(occluded, 1000) << "the test needs occluded samples";
    EXPECT_LT(sum / double(withFlat.size()), 1e-6);
    EXPECT_LT(max, 1e-4);
}

TEST(ScreenSpaceOcclusionTest, OutputIsTheSameForEveryThreadCount) {
    const Scene scene = demo::makeTreeScene();
    const View v = viewOf(scene, scene.cameras[0], 320, 180);
    for (const bool half : {true, false}) {
        ScreenSpaceOcclusionOptions o;
        o.radius = 0.8;
        o.halfResolution = half;
        for (const Entry entry : kEntries) {
            std::vector<float> one, two;
            withThreads(1, [&] { one = occlusion(v, o, entry); });
            withThreads(2, [&] { two = occlusion(v, o, entry); });
            ASSERT_EQ(one.size(), two.size());
            const BitCompare c = compareBits(one, two);
            EXPECT_GT(c.occluded, 500) << "the test needs occluded samples";
            EXPECT_EQ(c.differ, 0) << nameOf(entry) << (half ? " half" : " full");
        }
    }
}

TEST(ScreenSpaceOcclusionTest, TheVectorHorizonSearchGivesTheScalarOutputBitForBit) {
    // The horizon search walks the four sides of two slices in SIMD lanes (vectorWalk, the default)
    // with the scalar walk's arithmetic, operation for operation: the output must be the same bits,
    // on every path of the walk (samples beyond the image, on the pixel itself, not occluding,
    // within the radius, the crossing of the sphere after one within it; the slivers' GTAO at the
    // upsample). Odd slice counts leave the last pair half used; 1 to 3 slices and 1 to 7 steps.
    const Scene tree = demo::makeTreeScene();
    const View v = viewOf(tree, tree.cameras[0], 320, 180);
    const Corner c;
    const View corner = viewOf(c.scene, c.camera, 160, 120);
    const struct { int directions, steps; } counts[] = {{2, 5}, {1, 7}, {3, 3}, {2, 1}};
    for (const View* view : {&v, &corner})
        for (const auto& n : counts)
            for (const bool half : {true, false})
                for (const Entry entry : kEntries) {
                    ScreenSpaceOcclusionOptions o;
                    o.radius = view == &v ? 0.8 : 1.0;
                    o.halfResolution = half;
                    o.directions = n.directions;
                    o.steps = n.steps;
                    const std::vector<float> vector = occlusion(*view, o, entry);
                    o.vectorWalk = false;
                    const std::vector<float> scalar = occlusion(*view, o, entry);
                    ASSERT_EQ(vector.size(), scalar.size());
                    const BitCompare bits = compareBits(scalar, vector);
                    EXPECT_GT(bits.occluded, 300) << "the test needs occluded samples";
                    EXPECT_EQ(bits.differ, 0) << n.directions << " x " << n.steps << " " << nameOf(entry)
                                              << (half ? " half" : " full");
                }
}

TEST(ScreenSpaceOcclusionTest, AKeptScratchGivesTheSameOutputAsFreshBuffers) {
    // Nothing of a previous call may leak into the next through the kept buffers: a scratch used
    // first on another scene, size and resolution mode gives the fresh result (the tree's frame has
    // background and edges wherever the corner's had surface).
    const Corner c;
    const View first = viewOf(c.scene, c.camera, 320, 180);
    const Scene tree = demo::makeTreeScene();
    const View second = viewOf(tree, tree.cameras[0], 161, 97);
    for (const bool half : {true, false}) {
        ScreenSpaceOcclusionOptions o;
        o.radius = 0.8;
        o.halfResolution = half;
        detail::ScreenSpaceOcclusionScratch scratch;
        for (const bool otherHalf : {!half, half}) {
            ScreenSpaceOcclusionOptions other = o;
            other.halfResolution = otherHalf;
            const detail::SurfaceBuffers& a = first.surfaces;
            std::vector<float> out(a.covered.size());
            detail::screenSpaceOcclusion(first.frame, 320, 180, a.position, a.normal, a.covered, other,
                                         a.occluder, out, scratch);
        }
        const detail::SurfaceBuffers& b = second.surfaces;
        std::vector<float> kept(b.covered.size(), -1.0f);
        detail::screenSpaceOcclusion(second.frame, 161, 97, b.position, b.normal, b.covered, o, b.occluder,
                                     kept, scratch);
        const std::vector<float> fresh = occlusion(second, o, Entry::Buffers);
        int64_t differ = 0;
        for (std::size_t i = 0; i < fresh.size(); ++i)
            differ += std::memcmp(&fresh[i], &kept[i], sizeof(float)) != 0;
        EXPECT_EQ(differ, 0) << (half ? "half" : "full");
    }
}

TEST(ScreenSpaceOcclusionTest, BadInputIsRejected) {
    const Corner c;
    const View v = viewOf(c.scene, c.camera, 64, 48);
    const detail::SurfaceBuffers& s = v.surfaces;
    ScreenSpaceOcclusionOptions o;
    o.radius = 1;
    const auto run = [&](const ScreenSpaceOcclusionOptions& opt, int64_t W, int64_t H) {
        return detail::screenSpaceOcclusion(v.frame, W, H, s.position, s.normal, s.covered, opt, s.occluder);
    };
    EXPECT_NO_THROW(run(o, 64, 48));
    EXPECT_THROW(run(o, 48, 64), Error);
    const std::span<const Vec3f> shorter(s.position.data(), s.position.size() - 1);
    EXPECT_THROW(detail::screenSpaceOcclusion(v.frame, 64, 48, shorter, s.normal, s.covered, o), Error);
    EXPECT_THROW(detail::screenSpaceOcclusion(v.frame, 64, 48, s.position, s.normal, s.covered, o,
                                              std::span<const uint8_t>(s.occluder.data(), 3)),
                 Error);
    for (const double r : {0.0, -1.0, std::nan(""), double(INFINITY)}) {
        ScreenSpaceOcclusionOptions bad = o;
        bad.radius = r;
        EXPECT_THROW(run(bad, 64, 48), Error) << r;
    }
    ScreenSpaceOcclusionOptions bad = o;
    bad.directions = 0;
    EXPECT_THROW(run(bad, 64, 48), Error);
    bad = o;
    bad.steps = 33;
    EXPECT_THROW(run(bad, 64, 48), Error);
    bad = o;
    bad.bias = 1;
    EXPECT_THROW(run(bad, 64, 48), Error);
    const Frame ortho = Frame::orthographic(Box3d{{0, 0, 0}, {1, 1, 1}}, Axis::Z, 64, 48, 1);
    EXPECT_THROW(detail::screenSpaceOcclusion(ortho, 64, 48, s.position, s.normal, s.covered, o), Error);
}

} // namespace
} // namespace voxfx::screen_space_ao_test
