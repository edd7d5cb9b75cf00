// Tests of the camera pass for Boolean-shaped opaque and translucent objects (render/volume_pass):
// the surfaces it finds along camera rays and the colours it composites.
//
// Oracle: every camera ray is intersected with every triangle of every leaf by brute force
// (Möller–Trumbore, written here), and the inside of each leaf between consecutive crossings is
// decided by CGAL::Side_of_triangle_mesh (exact predicates, tests/cgal_oracle.hpp); the Boolean
// shapes are evaluated on those flags (shapeInside, tests/support/volume_reference.hpp). The
// visible surfaces are where an object's shape changes from one interval to the next; the
// compositing reference is the definition of α blending front to back over those surfaces.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "render/volume_pass.hpp"
#include "support/volume_reference.hpp"
#include "voxfx/render.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {
namespace {

using test::shapeInside;

// A box rotated by `angle` about `axis` around `pivot`.
Mesh brenRotatedBox(const Box3d& box, const Vec3d& axis, double angle, const Vec3d& pivot) {
    Mesh m = boxMesh(box);
    const Vec3d k = normalize(axis);
    const double c = std::cos(angle), s = std::sin(angle);
    for (Vec3f& p : m.positions) {
        const Vec3d v = Vec3d(p) - pivot;
        const Vec3d r = v * c + cross(k, v) * s + k * (dot(k, v) * (1 - c)); // Rodrigues
        p = Vec3f(r + pivot);
    }
    return m;
}

// A notched block (difference), a translucent union of two overlapping blocks in front of part of
// it, and an opaque intersection: every Boolean kind, rotated so that no face is axis-aligned.
VolumeScene brenScene() {
    VolumeScene s;
    const Vec3d axis{0.3, 1.0, 0.2};
    const int32_t a = s.addLeaf(brenRotatedBox({{-1, -1, -1}, {1, 1, 1}}, axis, 0.5, {0, 0, 0}));
    const int32_t b = s.addLeaf(brenRotatedBox({{0.3, -0.45, 0.2}, {1.6, 0.55, 1.7}}, axis, 0.5, {0, 0, 0}));
    const int32_t c =
        s.addLeaf(brenRotatedBox({{-0.9, -0.7, 1.3}, {0.1, 0.2, 2.2}}, axis, -0.3, {0, 0, 1.7}));
    const int32_t d =
        s.addLeaf(brenRotatedBox({{-0.4, -0.2, 1.5}, {0.6, 0.9, 2.5}}, axis, -0.3, {0, 0, 1.7}));
    const int32_t e =
        s.addLeaf(brenRotatedBox({{1.5, -1.2, -0.5}, {2.7, 0.1, 0.7}}, {1, 0.2, 0.4}, 0.7, {2, 0, 0}));
    const int32_t f =
        s.addLeaf(brenRotatedBox({{1.9, -0.9, -0.2}, {3.1, 0.4, 1.0}}, {0.1, 1, 0.5}, 0.4, {2, 0, 0}));
    VolumeSceneObject o;
    o.name = "notched";
    o.color = {0.9f, 0.3f, 0.2f};
    o.shape = s.addNode(ShapeOp::Difference, a, b);
    s.addObject(o);
    o.name = "glass";
    o.kind = ObjectKind::Translucent;
    o.opacity = 0.35f;
    o.color = {0.2f, 0.5f, 0.9f};
    o.shape = s.addNode(ShapeOp::Union, c, d);
    s.addObject(o);
    o.name = "lens";
    o.kind = ObjectKind::Opaque;
    o.opacity = 1;
    o.color = {0.3f, 0.8f, 0.3f};
    o.shape = s.addNode(ShapeOp::Intersection, e, f);
    s.addObject(o);
    s.validate();
    return s;
}

Camera brenCamera() {
    Camera c;
    c.position = {0.8, 2.2, 6.5};
    c.target = {0.6, 0, 0.3};
    c.fovY = 0.75;
    return c;
}

struct BrenExpected {
    double t;
    std::size_t object;
    bool entering;
};

// Per pixel (row-major, y up): the expected surfaces up to the first opaque one, or nullopt where
// a crossing is within 1e-5 (barycentric) of an edge or a test point lies on a surface.
std::vector<std::optional<std::vector<BrenExpected>>> brenOracle(const VolumeScene& s, const Frame& f) {
    const int64_t W = f.width(), H = f.height();
    std::vector<std::vector<double>> groups(std::size_t(W * H));
    std::vector<uint8_t> ambiguous(std::size_t(W * H), 0);
    std::vector<Vec3d> points; // per pixel: a point after each crossing group
    std::vector<std::size_t> firstPoint(std::size_t(W * H) + 1, 0);
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const std::size_t px = std::size_t(y * W + x);
            const Vec3d o = f.eye(), d = f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - o;
            std::vector<double> ts;
            for (const Mesh& leaf : s.leaves) {
                const MeshView m = leaf.view();
                for (std::size_t tr = 0; tr < m.triangleCount; ++tr) {
                    const Vec3d a = m.vertex(m.index(tr, 0)), b = m.vertex(m.index(tr, 1)),
                                c = m.vertex(m.index(tr, 2));
                    const Vec3d e1 = b - a, e2 = c - a, p = cross(d, e2);
                    const double det = dot(e1, p);
                    if (std::abs(det) < 1e-300) continue;
                    const Vec3d sv = o - a, q = cross(sv, e1);
                    const double u = dot(sv, p) / det, v = dot(d, q) / det, t = dot(e2, q) / det;
                    const double edge = std::min({u, v, 1 - u - v});
                    if (std::abs(edge) < 1e-5) ambiguous[px] = 1;
                    if (edge > 0 && t > 0) ts.push_back(t);
                }
            }
            std::sort(ts.begin(), ts.end());
            for (const double t : ts)
                if (groups[px].empty() || t - groups[px].back() > 1e-9 * t) groups[px].push_back(t);
            firstPoint[px] = points.size();
            for (std::size_t g = 0; g < groups[px].size(); ++g) {
                const double next = g + 1 < groups[px].size() ? groups[px][g + 1] : groups[px][g] + 1;
                points.push_back(o + d * (0.5 * (groups[px][g] + next)));
            }
            firstPoint[px + 1] = points.size();
        }
    std::vector<std::vector<int>> side;
    for (const Mesh& leaf : s.leaves) side.push_back(test::sideOfClosedMesh(leaf.view(), points));
    std::vector<std::optional<std::vector<BrenExpected>>> out(std::size_t(W * H));
    for (std::size_t px = 0; px < out.size(); ++px) {
        if (ambiguous[px]) continue;
        std::vector<BrenExpected> surfaces;
        std::vector<uint8_t> before(s.objects.size(), 0);
        bool onSurface = false, stopped = false;
        for (std::size_t g = 0; g < groups[px].size() && !stopped; ++g) {
            std::vector<int> leafInside;
            for (const auto& sd : side) {
                onSurface = onSurface || sd[firstPoint[px] + g] == 0;
                leafInside.push_back(sd[firstPoint[px] + g]);
            }
            for (std::size_t o = 0; o < s.objects.size() && !stopped; ++o) {
                const bool after = shapeInside(s, s.objects[o].shape, leafInside);
                if (after == bool(before[o])) continue;
                before[o] = after;
                surfaces.push_back({groups[px][g], o, after});
                stopped = s.objects[o].kind == ObjectKind::Opaque;
            }
        }
        if (!onSurface) out[px] = surfaces;
    }
    return out;
}

TEST(BooleanRenderTest, VisibleSurfacesAndOutwardNormalsAgreeWithExactInsideTests) {
    const VolumeScene s = brenScene();
    const Frame f = cameraFrame(brenCamera(), 64, 48);
    const auto expected = brenOracle(s, f);
    const auto hits = detail::objectSurfaceHits(s, f);
    ASSERT_EQ(hits.size(), expected.size());
    int64_t checked = 0, perObject[3] = {0, 0, 0}, subtracted = 0, leaving = 0;
    std::vector<Vec3d> probes; // p + eps n (must be outside), p - eps n (inside)
    std::vector<std::size_t> probeObject;
    for (std::size_t px = 0; px < hits.size(); ++px) {
        if (!expected[px]) continue;
        const auto& e = *expected[px];
        ++checked;
        ASSERT_EQ(hits[px].size(), e.size()) << "pixel " << px % 64 << ", " << px / 64;
        for (std::size_t k = 0; k < e.size(); ++k) {
            const detail::ObjectSurfaceHit& h = hits[px][k];
            EXPECT_EQ(h.object, e[k].object) << px;
            EXPECT_EQ(h.entering, e[k].entering) << px;
            EXPECT_NEAR(h.depth, e[k].t, 1e-9 * e[k].t) << px;
            ++perObject[h.object];
            leaving += !h.entering;
            probes.push_back(h.position + h.outwardNormal * 1e-6);
            probes.push_back(h.position - h.outwardNormal * 1e-6);
            probeObject.push_back(h.object);
        }
    }
    EXPECT_GT(checked, 2500);
    EXPECT_GT(perObject[0], 100);
    EXPECT_GT(perObject[1], 100);
    EXPECT_GT(perObject[2], 60);
    EXPECT_GT(leaving, 50); // the translucent union's far side
    std::vector<std::vector<int>> side;
    for (const Mesh& leaf : s.leaves) side.push_back(test::sideOfClosedMesh(leaf.view(), probes));
    int64_t wrong = 0;
    for (std::size_t k = 0; k < probeObject.size(); ++k) {
        std::vector<int> out, in;
        for (const auto& sd : side) {
            out.push_back(sd[2 * k]);
            in.push_back(sd[2 * k + 1]);
        }
        const int32_t shape = s.objects[probeObject[k]].shape;
        wrong += shapeInside(s, shape, out) || !shapeInside(s, shape, in);
        // Surfaces of the notch: outside the block's leaf a just behind, inside the subtracted leaf b.
        subtracted += probeObject[k] == 0 && out[1] > 0;
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(subtracted, 10);
}

TEST(BooleanRenderTest, RenderedPixelsAreTheSurfacesAlphaCompositedInDepthOrder) {
    Scene scene;
    scene.volumeScene = std::make_shared<VolumeScene>(brenScene());
    const VolumeScene& s = *scene.volumeScene;
    RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.shadow = NoShadowOptions{};
    o.defaultLights = false;
    o.ambient = {1, 1, 1}; // no lights: a surface's radiance is its colour
    o.skyLight = 0;
    o.sky = SkyKind::Flat;
    o.background = {0.1f, 0.2f, 0.3f};
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    o.exposure = 1; // fixed: the oracle describes radiance
    const RenderResult r = render(scene, brenCamera(), o);
    const auto expected = brenOracle(s, cameraFrame(brenCamera(), 64, 48));
    int64_t checked = 0, blended = 0;
    for (int64_t y = 0; y < 48; ++y)
        for (int64_t x = 0; x < 64; ++x) {
            const auto& e = expected[std::size_t(y * 64 + x)];
            if (!e) continue;
            Vec3d c{0, 0, 0};
            double transmittance = 1;
            for (const BrenExpected& h : *e) {
                const VolumeSceneObject& obj = s.objects[h.object];
                const double a = obj.kind == ObjectKind::Opaque ? 1.0 : double(obj.opacity);
                c += Vec3d(obj.color) * (a * transmittance);
                transmittance *= 1 - a;
            }
            c += Vec3d(o.background) * transmittance;
            const Vec3f got = r.image.at(x, 47 - y);
            for (int a = 0; a < 3; ++a) EXPECT_NEAR(got[a], c[a], 1e-5) << x << ", " << y;
            ++checked;
            blended += transmittance > 0 && transmittance < 1;
        }
    EXPECT_GT(checked, 2500);
    EXPECT_GT(blended, 50);
}

} // namespace
} // namespace voxfx
