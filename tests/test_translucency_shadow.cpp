// Tests of the translucency shadows (GI08 §7; src/render/translucency_shadow.cpp) against exact
// chord lengths: the matter a light ray crosses on its way to a receiver is, for a sphere, the
// analytic chord 2 sqrt(R^2 - d^2) (the polygonal sphere's own facets bound how far its chords can
// fall short), and for a CGAL mesh (the Stanford bunny) the sum of the inside intervals between the
// segment's exact crossings (cgal_oracle.hpp: CGAL::intersection of the segment with every
// triangle, paired by parity). Receivers sit at the light grid's column centres behind the
// casters, so the light's ray to them is the column's centre ray along which the solid
// voxelization samples; the cell centres inside a chord of length c number floor or ceil of c / h
// (h: a slice's world length along the ray, derived here from the frame's definition), so the
// counted length may differ from the chord by less than h per entry into the solid. Visibility is
// checked per channel against Beer-Lambert exp(-extinction / tint_c * chord) over the same band.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "support/ground_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/translucency_shadow.hpp"

namespace voxfx {
namespace {

// `mesh` of a translucent solid without attenuation of its own: GI08's one matter, whose extinction
// and tint the shadow's options give.
Scene solidScene(const Mesh& mesh, const Light& light) {
    Scene s;
    SceneMesh m;
    m.name = "solid";
    m.mesh = mesh;
    Material matter;
    matter.diffuseTransmission = 1;
    m.material = s.addMaterial(matter);
    s.meshes.push_back(m);
    s.lights.push_back(light);
    return s;
}

TranslucencyShadowOptions exactLookup(int64_t columns, int64_t slices, double extinction, Vec3f tint) {
    TranslucencyShadowOptions o;
    o.grid.resolution = columns;
    o.grid.depth = slices;
    o.grid.skipCells = 0; // receivers lie behind the grid: every slice of the column counts
    o.grid.normalOffset = 0;
    o.extinction = extinction;
    o.tint = tint;
    return o;
}

/// A receiver behind the grid on the centre ray of column (x, y), where the light's ray to it
/// starts, and the world length h of one slice along that ray (from the frame's definition: an
/// orthographic slice is cellSize().z thick along the light's direction; a perspective frame's
/// depth is the distance along its axis, uniform over [near, far] in D slices, and the ray is
/// longer by |p - eye| / ((p - eye) . forward)).
struct Receiver {
    Vec3d from, at;
    double slice;
};

Receiver receiverBehind(const Frame& f, int64_t x, int64_t y) {
    const double gx = double(x) + 0.5, gy = double(y) + 0.5;
    Receiver r;
    if (!f.isPerspective()) {
        r.from = f.worldFromGrid({gx, gy, -0.5});
        r.at = f.worldFromGrid({gx, gy, double(f.depth()) + 0.5});
        r.slice = f.cellSize().z;
        return r;
    }
    r.from = f.eye();
    r.at = f.worldFromGrid({gx, gy, f.farDepth() * 1.05});
    const Vec3d v = r.at - r.from;
    r.slice = (f.farDepth() - f.nearDepth()) / double(f.depth()) * length(v) / dot(v, f.forward());
    return r;
}

/// Distance from c to the segment from a to b (a point light's ray runs from the light, not
/// through it: a sphere behind the light is not on the ray).
double lineDistance(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d u = normalize(b - a);
    const Vec3d w = c - a;
    const double t = std::clamp(dot(w, u), 0.0, length(b - a));
    return length(w - u * t);
}

double sphereChord(double r, double d) { return d < r ? 2 * std::sqrt(r * r - d * d) : 0.0; }

struct Counts {
    int64_t checked = 0, nonzero = 0;
    double maxError = 0; ///< largest |L - chord| / h
};

/// Checks every `stride`-th column of view frame `f` against the polygonal sphere (centre c,
/// circumradius R, inradius r) for receivers whose ray passes at most 0.8 R from the centre.
void checkSphereView(const TranslucencyShadow& shadow, const Frame& f, const Vec3d& c, double R, double r,
                     const Vec3d& sigma, int64_t stride, Counts& n) {
    for (int64_t y = 0; y < f.height(); y += stride)
        for (int64_t x = 0; x < f.width(); x += stride) {
            const Receiver rc = receiverBehind(f, x, y);
            const double d = lineDistance(rc.from, rc.at, c);
            if (d > 0.8 * R) continue;
            // The faceted sphere holds the inscribed ball and lies in the circumscribed one.
            // 1e-6: the vertices are rounded to float.
            const double hi = sphereChord(R, d) + 1e-6, lo = sphereChord(r, d) - 1e-6;
            const double L = shadow.pathLength(rc.at, {0, 0, 0});
            ++n.checked;
            n.nonzero += L > 0;
            EXPECT_GE(L, lo - rc.slice)
                << "column " << x << ", " << y << ": chord in [" << lo << ", " << hi << "]";
            EXPECT_LE(L, hi + rc.slice)
                << "column " << x << ", " << y << ": chord in [" << lo << ", " << hi << "]";
            n.maxError = std::max(n.maxError, std::max(lo - L, L - hi) / rc.slice);
            const Vec3f v = shadow.visibility(rc.at, {0, 0, 0});
            for (int ch = 0; ch < 3; ++ch) {
                EXPECT_LE(v[ch], std::exp(-sigma[ch] * (lo - rc.slice)) * (1 + 1e-5)) << "channel " << ch;
                EXPECT_GE(v[ch], std::exp(-sigma[ch] * (hi + rc.slice)) * (1 - 1e-5)) << "channel " << ch;
            }
        }
}

/// checkSphereView over every view of the shadow (a point light's six cube faces).
Counts checkSphere(const TranslucencyShadow& shadow, const Vec3d& c, double R, double r, const Vec3d& sigma,
                   int64_t stride) {
    Counts n;
    for (const TranslucencyShadowMap& map : shadow.maps())
        checkSphereView(shadow, map.view().frame, c, R, r, sigma, stride, n);
    return n;
}

/// The smallest distance from c to a face plane of `mesh` (a convex mesh holds that ball).
double inradius(const Mesh& mesh, const Vec3d& c) {
    double r = 1e300;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
        const Vec3d a(mesh.positions[mesh.indices[3 * t]]), b(mesh.positions[mesh.indices[3 * t + 1]]),
            e(mesh.positions[mesh.indices[3 * t + 2]]);
        const Vec3d nrm = normalize(cross(b - a, e - a));
        r = std::min(r, std::abs(dot(c - a, nrm)));
    }
    return r;
}

/// A UV sphere (centre c, radius R) lit by `light` through a light grid of columns x slices, checked
/// with checkSphere over every view; at least `minChecked` receivers, each behind some matter.
Counts sphereUnder(const Light& light, const Vec3d& c, double R, int64_t columns, int64_t slices,
                   double extinction, Vec3f tint, std::size_t views, int64_t minChecked) {
    const Mesh sphere = test::makeUvSphere(c, R, 96, 192);
    const TranslucencyShadow shadow = TranslucencyShadow::build(
        solidScene(sphere, light), light, exactLookup(columns, slices, extinction, tint));
    EXPECT_EQ(shadow.maps().size(), views);
    const Vec3d sigma{extinction / tint.x, extinction / tint.y, extinction / tint.z};
    const Counts n = checkSphere(shadow, c, R, inradius(sphere, c), sigma, 1);
    EXPECT_GT(n.checked, minChecked);
    EXPECT_EQ(n.nonzero, n.checked);
    EXPECT_LE(n.maxError, 1.0);
    std::printf("sphere: %lld receivers, largest error %.3f slices\n", (long long)n.checked, n.maxError);
    return n;
}

TEST(TranslucencyShadowTest, SphereChordsUnderDirectionalLight) {
    Light sun;
    sun.direction = normalize(Vec3d{0.35, -1, 0.2});
    // 500: the disc of radius 0.8 R in a view fitted to the bounding box.
    sphereUnder(sun, {0.3, 1.5, -0.2}, 1.0, 64, 96, 0.8, {0.35f, 1.0f, 0.55f}, 1, 500);
}

TEST(TranslucencyShadowTest, SphereChordsUnderSpotLight) {
    Light spot;
    spot.type = LightType::Spot;
    spot.position = {1.5, 4.5, 0.8};
    spot.direction = normalize(Vec3d{0, 1, 0} - spot.position);
    spot.outerConeAngle = 0.6;
    sphereUnder(spot, {0, 1, 0}, 0.8, 80, 128, 1.5, {1, 1, 1}, 1, 1000);
}

TEST(TranslucencyShadowTest, SphereChordsUnderPointLightAcrossCubeFaces) {
    // The sphere straddles the edge between two cube faces of the point light.
    Light lamp;
    lamp.type = LightType::Point;
    lamp.position = {0, 1.0, 0};
    sphereUnder(lamp, {1.2, 1.0, 1.2}, 0.7, 96, 128, 1.0, {1, 1, 1}, 6, 300);
}

TEST(TranslucencyShadowTest, BunnyChordsMatchCgalCrossings) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh bunny = loadMesh(test::dataPath("meshes/bunny00.off"));
    Light sun;
    sun.direction = normalize(Vec3d{-0.4, -1, 0.3});
    const Box3d box = computeBounds(bunny.view());
    const double size = length(box.hi - box.lo);
    const double sigma = 4 / size;
    const TranslucencyShadow shadow =
        TranslucencyShadow::build(solidScene(bunny, sun), sun, exactLookup(72, 160, sigma, {1, 1, 1}));
    ASSERT_EQ(shadow.maps().size(), 1u);
    const Frame& f = shadow.maps()[0].view().frame;
    std::vector<Receiver> receivers;
    std::vector<Vec3d> from, to;
    for (int64_t y = 0; y < f.height(); ++y)
        for (int64_t x = 0; x < f.width(); ++x) {
            receivers.push_back(receiverBehind(f, x, y));
            from.push_back(receivers.back().from);
            to.push_back(receivers.back().at);
        }
    const std::vector<test::OracleChord> chords = test::oracleChords(bunny.view(), from, to);
    int64_t checked = 0, crossed = 0, degenerate = 0;
    double maxError = 0;
    for (std::size_t i = 0; i < receivers.size(); ++i) {
        if (chords[i].degenerate) {
            ++degenerate;
            continue;
        }
        const Receiver& r = receivers[i];
        const double L = shadow.pathLength(r.at, {0, 0, 0});
        const double chord = chords[i].inside;
        const double tolerance = r.slice * (chords[i].crossings / 2) * (1 + 1e-9);
        ++checked;
        crossed += chords[i].crossings > 0;
        EXPECT_NEAR(L, chord, tolerance) << "receiver " << i << " (" << chords[i].crossings << " crossings)";
        if (chords[i].crossings > 0) maxError = std::max(maxError, std::abs(L - chord) / r.slice);
        const float v = shadow.visibility(r.at, {0, 0, 0}).y;
        EXPECT_LE(v, std::exp(-sigma * (chord - tolerance)) * (1 + 1e-5)) << "receiver " << i;
        EXPECT_GE(v, std::exp(-sigma * (chord + tolerance)) * (1 - 1e-5)) << "receiver " << i;
    }
    EXPECT_LT(degenerate, checked / 100);
    EXPECT_GT(crossed, checked / 4); // the bunny covers a good part of its fitted view
    std::printf("bunny: %lld receivers (%lld behind the bunny, %lld degenerate), largest error %.3f slices\n",
                (long long)checked, (long long)crossed, (long long)degenerate, maxError);
}

// GI08 §7 for the camera (viewMatterBehind): the matter behind each visible surface point along
// the pixel's centre ray, against the exact chord of that ray through the same mesh (every
// crossing with a triangle, Moller-Trumbore in double, paired in order: the mesh is closed),
// within one slice along the ray per entry into the solid. A box and a sphere in front of each
// other, so rays enter twice where they overlap on screen.
double exactMatterAlong(const Mesh& mesh, const Vec3d& o, const Vec3d& d, double from) {
    std::vector<double> ts;
    for (std::size_t t = 0; t < mesh.indices.size() / 3; ++t) {
        const Vec3d a(mesh.positions[mesh.indices[3 * t]]), b(mesh.positions[mesh.indices[3 * t + 1]]),
            c(mesh.positions[mesh.indices[3 * t + 2]]);
        const Vec3d e1 = b - a, e2 = c - a, h = cross(d, e2);
        const double det = dot(e1, h);
        if (std::abs(det) < 1e-14) continue;
        const Vec3d s = o - a;
        const double u = dot(s, h) / det;
        const Vec3d q = cross(s, e1);
        const double v = dot(d, q) / det;
        if (u < 0 || v < 0 || u + v > 1) continue;
        ts.push_back(dot(e2, q) / det);
    }
    std::sort(ts.begin(), ts.end());
    double inside = 0;
    for (std::size_t k = 0; k + 1 < ts.size(); k += 2)
        inside += std::max(0.0, ts[k + 1] - std::max(ts[k], from));
    return inside;
}

TEST(TranslucencyShadowTest, CameraViewMatterMatchesExactChords) {
    const Mesh sphere = test::makeUvSphere({0.3, 0.2, -0.4}, 0.7, 48, 64);
    Mesh solids = sphere;
    const Mesh box = test::makeBox({-1.2, -0.5, 0.3}, {-0.1, 0.6, 1.1});
    const auto base = uint32_t(solids.positions.size());
    solids.positions.insert(solids.positions.end(), box.positions.begin(), box.positions.end());
    for (const uint32_t i : box.indices) solids.indices.push_back(base + i);
    Scene s;
    SceneMesh m;
    m.name = "solids";
    m.mesh = solids;
    m.material = s.addMaterial(Material{});
    s.meshes.push_back(m);
    Camera cam;
    cam.position = {-1.5, 1.2, 4.0};
    cam.target = {0, 0, 0};
    cam.fovY = 0.7;
    const SceneGeometry geometry = flattenScene(s);
    const GBuffer g = renderGBuffer(geometry, cameraFrame(cam, 96, 72));
    const Frame& f = g.frame;
    const int64_t slices = 256;
    const std::vector<double> L = viewMatterBehind(f, solids.view(), g.depth, Fill::Auto, slices);
    // The depth range the function slices: the solids' bounds along the view axis.
    const Box3d b = computeBounds(solids.view());
    double lo = 1e300, hi = -1e300;
    for (int k = 0; k < 8; ++k) {
        const Vec3d q{(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z};
        lo = std::min(lo, dot(q - f.eye(), f.forward()));
        hi = std::max(hi, dot(q - f.eye(), f.forward()));
    }
    int64_t pixels = 0, twice = 0;
    double sumError = 0;
    for (int64_t y = 0; y < f.height(); ++y)
        for (int64_t x = 0; x < f.width(); ++x) {
            const auto i = size_t(y * f.width() + x);
            if (g.triangle[i] == GBuffer::kNone) {
                EXPECT_EQ(L[i], 0.0);
                continue;
            }
            const Vec3d d = normalize(f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - f.eye());
            const double cosAxis = dot(d, f.forward());
            const double tSurface = double(g.depth[i]) / cosAxis;
            const double exact = exactMatterAlong(solids, f.eye(), d, tSurface * (1 - 1e-6));
            const double h = (hi - lo) / double(slices) / cosAxis;
            // Entries into the solid behind the surface: the box and the sphere (convex) once each.
            const int entries = (exactMatterAlong(box, f.eye(), d, tSurface * (1 - 1e-6)) > 0) +
                                (exactMatterAlong(sphere, f.eye(), d, tSurface * (1 - 1e-6)) > 0);
            twice += entries == 2;
            ++pixels;
            sumError += std::abs(L[i] - exact);
            EXPECT_NEAR(L[i], exact, h * entries + 1e-6) << x << ", " << y;
        }
    std::printf("view matter: %lld pixels on the solids (%lld entering twice), mean |L - chord| %.4f "
                "(slice along the axis %.4f)\n",
                (long long)pixels, (long long)twice, sumError / double(pixels), (hi - lo) / double(slices));
    EXPECT_GT(pixels, 1000);
    EXPECT_GT(twice, 20);
    EXPECT_LT(sumError / double(pixels), 0.5 * (hi - lo) / double(slices));
    EXPECT_THROW(viewMatterBehind(f, solids.view(), std::vector<float>(3), Fill::Auto, 8), Error);
}

// The renderer's translucency pass (render.hpp): a translucent solid (diffuse transmission 1, so
// it reflects nothing) over a wall and the flat sky, lit by a constant ambient only. A pixel
// showing it must hold what lies behind (the wall's albedo times the ambient, or the sky) times
// exp(-sigma_c * chord), sigma_c = -ln(attenuationColor_c) / attenuationDistance and the chord the
// exact length of the pixel's centre ray inside the translucent solids in front of the wall
// (ray-triangle crossings, exactMatterAlong), within one slice along the ray per entry. A second
// translucent sphere behind the wall must not count.
struct TranslucentSetup {
    Scene scene;
    Camera camera;
    RenderOptions options;
    Mesh sphere, box, hidden; ///< the translucent solids: two in front of the wall, one behind it
    Mesh all, wall;           ///< every translucent mesh; the opaque wall
    Material jade;
    Vec3f wallColor{0.9f, 0.7f, 0.5f};
};

Mesh joined(const Mesh& a, const Mesh& b) {
    Mesh m = a;
    const auto base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
    for (const uint32_t i : b.indices) m.indices.push_back(base + i);
    return m;
}

TranslucentSetup translucentSetup() {
    TranslucentSetup t;
    t.sphere = test::makeUvSphere({0.2, 0.1, 0}, 0.7, 32, 48);
    t.box = test::makeBox({-1.1, -0.6, 0.8}, {-0.2, 0.5, 1.3});  // apart from the sphere
    t.hidden = test::makeUvSphere({-0.3, 0, -2.5}, 0.5, 16, 24); // behind the wall
    t.all = joined(joined(t.sphere, t.box), t.hidden);
    t.wall = test::makeBox({-4, -4, -1.6}, {0.4, 4, -1.4}); // the left part of the view only
    t.jade.name = "jade";
    t.jade.diffuseTransmission = 1;
    t.jade.attenuationDistance = 0.8f;
    t.jade.attenuationColor = {0.2f, 0.6f, 0.9f};
    Material wall;
    wall.name = "wall";
    wall.baseColor = t.wallColor;
    wall.specular = 0;
    const uint32_t jade = t.scene.addMaterial(t.jade), w = t.scene.addMaterial(wall);
    t.scene.meshes.push_back({"solids", t.all, {}, jade, true});
    t.scene.meshes.push_back({"wall", t.wall, {}, w, true});
    t.camera.position = {0.6, 0.5, 4.5};
    t.camera.target = {-0.2, 0, 0};
    t.camera.fovY = 0.6;
    RenderOptions& o = t.options;
    o.width = 96, o.height = 72;
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    o.exposure = 1; // fixed: the closed forms describe radiance
    o.sky = SkyKind::Flat;
    o.background = {0.8f, 0.9f, 1.0f};
    o.skyLight = 0;
    o.ambient = {1, 1, 1};
    o.defaultLights = false;
    o.ambientOcclusion = Occlusion::Off;
    o.translucencySlices = 256;
    o.translucencyBlur = 0; // the chords' closed form is of the unblurred image (the blur: below)
    return t;
}

/// The nearest crossing of the ray with the mesh's triangles (infinity: none).
double firstHit(const Mesh& mesh, const Vec3d& o, const Vec3d& d) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < mesh.indices.size() / 3; ++t) {
        const Vec3d a(mesh.positions[mesh.indices[3 * t]]), b(mesh.positions[mesh.indices[3 * t + 1]]),
            c(mesh.positions[mesh.indices[3 * t + 2]]);
        const Vec3d e1 = b - a, e2 = c - a, h = cross(d, e2);
        const double det = dot(e1, h);
        if (std::abs(det) < 1e-14) continue;
        const Vec3d s = o - a;
        const double u = dot(s, h) / det;
        const Vec3d q = cross(s, e1);
        const double v = dot(d, q) / det;
        if (u < 0 || v < 0 || u + v > 1) continue;
        const double dist = dot(e2, q) / det;
        if (dist > 0) best = std::min(best, dist);
    }
    return best;
}

TEST(TranslucencyShadowTest, RenderedTranslucentSolidAttenuatesWhatLiesBehindByExactChords) {
    const TranslucentSetup t = translucentSetup();
    const RenderResult r = render(t.scene, t.camera, t.options);
    const Frame f = cameraFrame(t.camera, t.options.width, t.options.height);
    const int64_t W = f.width(), H = f.height(), slices = t.options.translucencySlices;
    // The depth range the pass slices: every translucent mesh's bounds along the view axis.
    const Box3d b = computeBounds(t.all.view());
    double lo = 1e300, hi = -1e300;
    for (int k = 0; k < 8; ++k) {
        const Vec3d q{(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z};
        lo = std::min(lo, dot(q - f.eye(), f.forward()));
        hi = std::max(hi, dot(q - f.eye(), f.forward()));
    }
    Vec3d sigma;
    for (int c = 0; c < 3; ++c)
        sigma[c] = -std::log(double(t.jade.attenuationColor[c])) / t.jade.attenuationDistance;
    // Per pixel, independently: what the centre ray sees first (0 sky, 1 wall, 2 translucent), the
    // chord through the solids in front of the wall, the entries into them (the sphere and the box
    // are convex), whether the ray meets the wall and whether it goes on into the hidden sphere.
    struct Ray {
        int kind = 0, entries = 0;
        double chord = 0, cosAxis = 1;
        bool wall = false, hidden = false;
    };
    std::vector<Ray> rays(size_t(W * H));
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            Ray& ray = rays[size_t(y * W + x)];
            const Vec3d d = normalize(f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - f.eye());
            const double tWall = firstHit(t.wall, f.eye(), d), tSolid = firstHit(t.all, f.eye(), d);
            ray.wall = std::isfinite(tWall);
            ray.kind = tSolid < tWall ? 2 : ray.wall ? 1 : 0;
            if (ray.kind != 2) continue;
            const double inSphere = exactMatterAlong(t.sphere, f.eye(), d, 0),
                         inBox = exactMatterAlong(t.box, f.eye(), d, 0);
            ray.chord = inSphere + inBox;
            ray.entries = (inSphere > 0) + (inBox > 0);
            ray.hidden = exactMatterAlong(t.hidden, f.eye(), d, 0) > 0;
            ray.cosAxis = dot(d, f.forward());
        }
    int64_t checked = 0, overWall = 0, overSky = 0, twice = 0, hiddenBehind = 0;
    double worst = 0;
    for (int64_t y = 1; y + 1 < H; ++y)
        for (int64_t x = 1; x + 1 < W; ++x) {
            const auto i = size_t(y * W + x);
            const Ray& ray = rays[i];
            // Silhouettes: the rasterizer's tie rule and the ray test may disagree there.
            const int k = ray.kind;
            if (k != rays[i - 1].kind || k != rays[i + 1].kind || k != rays[i - size_t(W)].kind ||
                k != rays[i + size_t(W)].kind)
                continue;
            const Vec3f got = r.image.at(x, H - 1 - y);
            if (k != 2) { // the wall or the sky, untouched
                const Vec3f want = k == 1 ? t.wallColor : t.options.background;
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-5) << x << ", " << y;
                continue;
            }
            if (ray.entries == 0) continue; // grazing
            const double h = (hi - lo) / double(slices) / ray.cosAxis;
            const Vec3f behind = ray.wall ? t.wallColor : t.options.background;
            (ray.wall ? overWall : overSky) += 1;
            twice += ray.entries == 2;
            hiddenBehind += ray.wall && ray.hidden;
            ++checked;
            for (int c = 0; c < 3; ++c) {
                const double want = double(behind[c]) * std::exp(-sigma[c] * ray.chord);
                const double band =
                    double(behind[c]) * (std::exp(-sigma[c] * std::max(0.0, ray.chord - ray.entries * h)) -
                                         std::exp(-sigma[c] * ray.chord));
                worst = std::max(worst, std::abs(double(got[c]) - want) / std::max(band, 1e-9));
                EXPECT_NEAR(got[c], want, band + 1e-5) << x << ", " << y << " channel " << c;
            }
        }
    std::printf(
        "translucent pixels: %lld checked (%lld over the wall, %lld of them with the hidden sphere "
        "behind it, %lld over the sky, %lld entering twice); largest error %.2f of the one-slice band\n",
        (long long)checked, (long long)overWall, (long long)hiddenBehind, (long long)overSky,
        (long long)twice, worst);
    EXPECT_GT(overWall, 300);
    EXPECT_GT(overSky, 100);
    EXPECT_GT(twice, 30);
    EXPECT_GT(hiddenBehind, 30);
}

TEST(TranslucencyShadowTest, RenderedTranslucencyIsTheSameForEveryThreadCount) {
    TranslucentSetup t = translucentSetup();
    t.options.antiAliasing = AntiAliasing::Full; // adaptive samples too
    t.options.defaultLights = true;              // the sun lights the solids' back
    t.options.shadow = TranslucencyShadowOptions{};
    t.options.translucencyBlur = RenderOptions{}.translucencyBlur; // its taps too
    t.options.threads = 1;
    const RenderResult one = render(t.scene, t.camera, t.options);
    t.options.threads = 3;
    const RenderResult three = render(t.scene, t.camera, t.options);
    ASSERT_EQ(one.image.pixels.size(), three.image.pixels.size());
    for (std::size_t i = 0; i < one.image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(one.image.pixels[i][c], three.image.pixels[i][c]) << i;
}

// The pass changes nothing where no translucent solid shows: a scene whose only translucent mesh
// hides behind a wall (it casts no shadow, and occlusion is off) renders the image of the scene
// without it, bit for bit; the pass is timed among the others.
TEST(TranslucencyShadowTest, RenderedTranslucencyLeavesOtherPixelsAlone) {
    TranslucentSetup t = translucentSetup();
    Scene plain;
    Material wall;
    wall.baseColor = t.wallColor;
    const uint32_t w = plain.addMaterial(wall);
    plain.meshes.push_back({"wall", test::makeBox({-4, -4, -1.6}, {4, 4, -1.4}), {}, w, true});
    plain.meshes.push_back({"ball", test::makeUvSphere({1, 0, 0}, 0.5, 16, 24), {}, w, true});
    RenderOptions o;
    o.width = 64, o.height = 48;
    o.ambientOcclusion = Occlusion::Off;
    const RenderResult before = render(plain, t.camera, o);
    Scene hidden = plain;
    const uint32_t jade = hidden.addMaterial(t.jade);
    hidden.meshes.push_back({"hidden", test::makeUvSphere({0, 0, -2.5}, 0.5, 16, 24), {}, jade, false});
    const RenderResult after = render(hidden, t.camera, o);
    ASSERT_EQ(before.image.pixels.size(), after.image.pixels.size());
    for (std::size_t i = 0; i < before.image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(before.image.pixels[i][c], after.image.pixels[i][c]) << i;
    std::vector<std::string> names;
    for (const PassTime& p : after.timings.passes) names.emplace_back(p.name);
    EXPECT_EQ(names, (std::vector<std::string>{"flatten", "G-buffer", "occlusion", "shadows", "shading",
                                               "translucency", "glass", "ray casting", "resolve"}));
}

// Back-lit (GI08 §7's jade): with translucency shadows the lights' diffusely transmitted light is
// t / pi times the light times exp(-extinction * L), L the matter the light crossed: at the centre
// of a sphere lit from straight behind (a black sky, so nothing is seen through it), L = 2R.
TEST(TranslucencyShadowTest, BackLitTranslucentSolidPassesTheLightThroughTheMatterCrossed) {
    Scene s;
    Material m;
    m.diffuseTransmission = 0.8f;
    m.diffuseTransmissionColor = {1, 0.5f, 0.25f};
    m.attenuationDistance = 1;
    m.specular = 0;
    const double R = 0.6;
    s.meshes.push_back({"ball", test::makeUvSphere({0, 0, 0}, R, 48, 64), {}, s.addMaterial(m), true});
    Light sun;
    sun.direction = {0, 0, 1}; // travels towards the camera
    sun.intensity = 2;
    s.lights.push_back(sun);
    Camera cam;
    cam.position = {0, 0, 4};
    cam.target = {0, 0, 0};
    cam.fovY = 0.5;
    RenderOptions o;
    o.width = o.height = 33;
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    o.exposure = 1; // fixed: the closed forms describe radiance
    o.sky = SkyKind::Flat;
    o.background = {0, 0, 0};
    o.skyLight = 0;
    o.ambientOcclusion = Occlusion::Off;
    TranslucencyShadowOptions ts;
    ts.extinction = 1.5;
    ts.grid.resolution = 128;
    ts.grid.depth = 256;
    o.shadow = ts;
    const Vec3f got = render(s, cam, o).image.at(16, 16);
    // One slice along the light is 2R / 256 of the fitted view at most a few times that; skipped
    // cells and the normal offset shorten L by a few slices: allow 4 % of 2R.
    for (int c = 0; c < 3; ++c) {
        const double near = 0.8 * m.diffuseTransmissionColor[c] * 2 / M_PI;
        EXPECT_NEAR(got[c], near * std::exp(-1.5 * 2 * R),
                    near * (std::exp(-1.5 * 2 * R * 0.96) - std::exp(-1.5 * 2 * R)))
            << c;
        EXPECT_GT(got[c], 0.5 * near * std::exp(-1.5 * 2 * R)); // not the map shadow's black
    }
}

TEST(TranslucencyShadowTest, TranslucentMaterialsBadValuesAndFiles) {
    TranslucentSetup t = translucentSetup();
    t.scene.materials[0].attenuationDistance = -1;
    EXPECT_THROW(render(t.scene, t.camera, t.options), Error);
    t.scene.materials[0].attenuationDistance = 0;
    EXPECT_THROW(render(t.scene, t.camera, t.options), Error);
    t.scene.materials[0].attenuationDistance = 1;
    t.scene.materials[0].diffuseTransmission = 1.5f;
    EXPECT_THROW(render(t.scene, t.camera, t.options), Error);
    t.scene.materials[0].diffuseTransmission = -0.1f;
    EXPECT_THROW(render(t.scene, t.camera, t.options), Error);
    RenderOptions o;
    EXPECT_THROW(setRenderOption(o, "translucencySlices", OptionValue(int64_t(0))), Error);
    EXPECT_TRUE(setRenderOption(o, "translucency-slices", OptionValue(int64_t(64))));
    EXPECT_EQ(o.translucencySlices, 64);
    // Glass and blended materials are not translucent solids; the default material is not either.
    Material m;
    EXPECT_FALSE(m.isTranslucent());
    m.diffuseTransmission = 0.5f;
    EXPECT_TRUE(m.isTranslucent());
    m.transmission = 1;
    EXPECT_FALSE(m.isTranslucent());
    // Files: the JSON wrapper's keys, and glTF's KHR_materials_diffuse_transmission through writeGltf.
    test::TempDir dir;
    test::writeFile(dir.file("ball.off"),
                    "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    const Scene w = loadScene(test::writeFile(
        dir.file("s.json"),
        R"({"meshes": [{"file": "ball.off", "material": {"name": "jade", "diffuseTransmission": 0.7,
          "diffuseTransmissionColor": [0.5, 1, 0.5], "attenuationDistance": 0.25, "attenuationColor": [0.3, 0.9, 0.4]}}]})"));
    const Material& jw = w.materials[w.meshes[0].material];
    EXPECT_FLOAT_EQ(jw.diffuseTransmission, 0.7f);
    EXPECT_FLOAT_EQ(jw.diffuseTransmissionColor.x, 0.5f);
    EXPECT_FLOAT_EQ(jw.attenuationDistance, 0.25f);
    EXPECT_FLOAT_EQ(jw.attenuationColor.z, 0.4f);
    EXPECT_TRUE(jw.isTranslucent());
    EXPECT_THROW(
        loadScene(test::writeFile(dir.file("bad.json"),
                                  R"({"meshes": [{"file": "ball.off", "material": {"diffuseTransmission": 0.7,
          "attenuationDistance": -2}}]})")),
        Error);
    writeGltf(w, dir.file("s.gltf"));
    const Scene g = loadScene(dir.file("s.gltf"));
    ASSERT_EQ(g.meshes.size(), 1u);
    const Material& jg = g.materials[g.meshes[0].material];
    EXPECT_FLOAT_EQ(jg.diffuseTransmission, 0.7f);
    EXPECT_FLOAT_EQ(jg.diffuseTransmissionColor.x, 0.5f);
    EXPECT_FLOAT_EQ(jg.attenuationDistance, 0.25f);
    EXPECT_FLOAT_EQ(jg.attenuationColor.z, 0.4f);
}

TEST(TranslucencyShadowTest, OptionsByNameReachTheTechnique) {
    RenderOptions o;
    setRenderOption(o, "shadows", std::string("translucency"));
    ASSERT_TRUE(std::holds_alternative<TranslucencyShadowOptions>(o.shadow));
    EXPECT_TRUE(setRenderOption(o, "extinction", 2.5));
    EXPECT_TRUE(setRenderOption(o, "tint", Vec3d{0.5, 1, 0.25}));
    EXPECT_TRUE(setRenderOption(o, "fill", std::string("parity")));
    EXPECT_TRUE(setRenderOption(o, "grid-resolution", int64_t(40)));
    const auto& t = std::get<TranslucencyShadowOptions>(o.shadow);
    EXPECT_EQ(t.extinction, 2.5);
    EXPECT_EQ(t.tint, (Vec3f{0.5f, 1, 0.25f}));
    EXPECT_EQ(t.fill, Fill::Parity);
    EXPECT_EQ(t.grid.resolution, 40);
    EXPECT_THROW(setRenderOption(o, "tint", Vec3d{0, 1, 1}), Error);
    EXPECT_THROW(setRenderOption(o, "extinction", -1.0), Error);
    EXPECT_THROW(setRenderOption(o, "fill", std::string("flood")), Error); // light views cannot flood
}

// #37: every caster was GI08's one matter (the option's extinction), so an opaque trunk became
// translucent. Now each material has its own extinction: an opaque caster stays opaque (its shadow
// as dark as the exact shadow's), a translucent solid with KHR_materials_volume attenuation passes
// Beer-Lambert with its own sigma (closed form over the box's height), even when the opaque box
// lies in the light's path behind or in front of it.
TEST(TranslucencyShadowTest, EachCasterTakesItsMaterialsExtinctionAndOpaqueStaysOpaque) {
    Scene s = test::sunlitGroundScene(); // the sun straight down onto the ground at y = 0
    Material jade;
    jade.diffuseTransmission = 0.7f;
    jade.attenuationDistance = 0.5f;
    jade.attenuationColor = {0.6f, 0.4f, 0.2f};
    const double h = 0.5; // every box is h tall: the light crosses h of it
    const uint32_t opaque = s.addMaterial(Material{}), translucent = s.addMaterial(jade);
    s.meshes.push_back({"trunk", test::makeBox({-1.5, 0.5, -0.5}, {-0.5, 0.5 + h, 0.5}), {}, opaque, true});
    s.meshes.push_back({"jade", test::makeBox({0.5, 0.5, -0.5}, {1.5, 0.5 + h, 0.5}), {}, translucent, true});
    // Over z in [1, 2]: the jade box over the opaque one, both in one column of the light.
    s.meshes.push_back({"jade2", test::makeBox({-0.5, 1.5, 1}, {0.5, 1.5 + h, 2}), {}, translucent, true});
    s.meshes.push_back({"trunk2", test::makeBox({-0.5, 0.5, 1}, {0.5, 0.5 + h, 2}), {}, opaque, true});
    TranslucencyShadowOptions o;
    o.grid.resolution = 96;
    o.grid.depth = 256;
    o.extinction = 1; // the matter of translucent solids without attenuation of their own
    const LightShadow ls = buildLightShadow(s, s.lights[0], o);
    ExactShadowOptions eo;
    const LightShadow exact = buildLightShadow(s, s.lights[0], eo);
    const Vec3f sigma = attenuationCoefficient(jade);
    const Vec3f centre[3] = {shadowVisibility(ls, {-1, 0, 0}, {0, 1, 0}),
                             shadowVisibility(ls, {0, 0, 1.5}, {0, 1, 0}),
                             shadowVisibility(ls, {1, 0, 0}, {0, 1, 0})};
    std::printf("under the opaque box %.3f, jade over opaque %.3f, jade %.3f %.3f %.3f\n", centre[0].y,
                centre[1].y, centre[2].x, centre[2].y, centre[2].z);
    for (double dz = -0.3; dz <= 0.3; dz += 0.15)
        for (double dx = -0.3; dx <= 0.3; dx += 0.15) {
            const Vec3d underTrunk{-1 + dx, 0, dz}, underJade{1 + dx, 0, dz}, underBoth{dx, 0, 1.5 + dz};
            for (const Vec3d& p : {underTrunk, underBoth}) {
                EXPECT_EQ(shadowVisibility(exact, p, {0, 1, 0}), (Vec3f{0, 0, 0}));
                EXPECT_EQ(shadowVisibility(ls, p, {0, 1, 0}), (Vec3f{0, 0, 0})) << p.x << ", " << p.z;
            }
            const Vec3f got = shadowVisibility(ls, underJade, {0, 1, 0});
            for (int c = 0; c < 3; ++c) {
                // The counted length is within a slice or two of h (the fitted view's depth over
                // 256 slices): allow 4 % of h.
                const double want = std::exp(-double(sigma[c]) * h);
                EXPECT_NEAR(got[c], want, want * sigma[c] * 0.04 * h + 1e-4) << "channel " << c;
            }
        }
}

TEST(TranslucencyShadowTest, BadOptionsAndEmptyScenes) {
    Light sun;
    const Scene s = solidScene(test::makeBox({0, 0, 0}, {1, 1, 1}), sun);
    TranslucencyShadowOptions o;
    o.tint = {0, 1, 1};
    EXPECT_THROW(TranslucencyShadow::build(s, sun, o), Error);
    o = {};
    o.extinction = std::nan("");
    EXPECT_THROW(TranslucencyShadow::build(s, sun, o), Error);
    o = {};
    o.grid.depth = 0;
    EXPECT_THROW(TranslucencyShadow::build(s, sun, o), Error);
    // An open caster (a box without its top) under Auto: the gwn fill, which light views can run.
    Mesh open = test::makeBox({0, 0, 0}, {1, 1, 1});
    open.indices.resize(open.indices.size() - 6);
    Scene openScene = solidScene(open, sun);
    EXPECT_GT(TranslucencyShadow::build(openScene, sun, {}).stats().filledCells, 0);
    const TranslucencyShadow none = TranslucencyShadow::build(Scene{}, sun, {});
    EXPECT_EQ(none.visibility({0, 0, 0}, {0, 0, 0}), (Vec3f{1, 1, 1}));
    EXPECT_EQ(none.stats().grids, 0);
}

// ---- #37 item 6: jade is not glass ---------------------------------------------------------------
//
// A slab of a translucent solid (diffuse transmission 1, no reflection of its own) thickness t in
// front of a sharp black / white edge, lit by a constant ambient only: the camera sees the edge
// through it, attenuated by exp(-sigma t) and blurred by the scattering, over a disc whose 10-90 %
// width grows with t. The oracle: a uniform disc of radius r across a step rises from 10 % to 90 %
// over 2 u r, F(u) = 1/2 + (u sqrt(1 - u^2) + asin u) / pi = 0.9 (u = 0.687), r the cone of
// half-angle blur * t / attenuationDistance from the slab's front face to the edge, seen from the
// eye (the model RenderOptions::translucencyBlur states, from the scene's geometry here).
struct EdgeSlab {
    static constexpr double kEye = 5, kWall = -2, kFov = 0.4, kAttenuationDistance = 1;
    static constexpr int64_t kWidth = 200, kHeight = 100;
};

Scene edgeSlabScene(double t, bool glass) {
    Scene s;
    Material black, white, slab;
    black.baseColor = {0, 0, 0};
    white.baseColor = {1, 1, 1};
    black.specular = white.specular = slab.specular = 0;
    if (glass) {
        slab.transmission = 1;
        slab.baseColor = {1, 1, 1};
    } else {
        slab.diffuseTransmission = 1;
        slab.baseColor = {0.5f, 0.5f, 0.5f};
    }
    slab.attenuationDistance = float(EdgeSlab::kAttenuationDistance);
    slab.attenuationColor = {0.8f, 0.8f, 0.8f};
    const uint32_t b = s.addMaterial(black), w = s.addMaterial(white), j = s.addMaterial(slab);
    const double z = EdgeSlab::kWall;
    s.meshes.push_back({"black", test::makeBox({-8, -8, z - 0.2}, {0, 8, z}), {}, b, true});
    s.meshes.push_back({"white", test::makeBox({0, -8, z - 0.2}, {8, 8, z}), {}, w, true});
    if (t > 0) s.meshes.push_back({"slab", test::makeBox({-4, -4, -t / 2}, {4, 4, t / 2}), {}, j, true});
    Camera c;
    c.position = {0, 0, EdgeSlab::kEye};
    c.target = {0, 0, 0};
    c.fovY = EdgeSlab::kFov;
    s.cameras.push_back(c);
    return s;
}

RenderOptions edgeSlabOptions(double blur) {
    RenderOptions o;
    o.width = EdgeSlab::kWidth, o.height = EdgeSlab::kHeight;
    o.antiAliasing = AntiAliasing::Off;
    o.toneMap = ToneMap::Clamp;
    o.exposure = 1;
    o.sky = SkyKind::Flat;
    o.background = {0, 0, 0};
    o.skyLight = 0;
    o.ambient = {1, 1, 1};
    o.defaultLights = false;
    o.ambientOcclusion = Occlusion::Off;
    o.shadow = NoShadowOptions{};
    o.translucencyBlur = blur;
    return o;
}

// The 10-90 % width (pixels) of the edge along the image's middle row: the green channel
// normalized by its mean over the 8 rightmost pixels (the black side is 0).
double edgeWidth(const Image& image) {
    const int64_t y = image.height / 2, W = image.width;
    double white = 0;
    for (int64_t x = W - 8; x < W; ++x) white += double(image.at(x, y).y) / 8;
    auto crossing = [&](double level) {
        for (int64_t x = 1; x < W; ++x) {
            const double a = image.at(x - 1, y).y / white, b = image.at(x, y).y / white;
            if (a < level && b >= level) return double(x - 1) + (level - a) / (b - a);
        }
        return std::nan("");
    };
    return crossing(0.9) - crossing(0.1);
}

double discEdgeWidth(double r) {
    double lo = 0, hi = 1; // F(u) = 0.9 by bisection
    for (int i = 0; i < 60; ++i) {
        const double u = (lo + hi) / 2;
        (0.5 + (u * std::sqrt(1 - u * u) + std::asin(u)) / M_PI < 0.9 ? lo : hi) = u;
    }
    return 2 * lo * r;
}

TEST(TranslucencyShadowTest, ASlabOfJadeBlursTheEdgeBehindItByItsThickness) {
    const double blur = RenderOptions{}.translucencyBlur;
    ASSERT_GT(blur, 0);
    const double focal = double(EdgeSlab::kHeight) / (2 * std::tan(EdgeSlab::kFov / 2));
    const double bare = edgeWidth(
        render(edgeSlabScene(0, false), edgeSlabScene(0, false).cameras[0], edgeSlabOptions(blur)).image);
    std::printf("edge behind jade, blur %.2f: no slab %.2f px\n", blur, bare);
    EXPECT_LT(bare, 1.01);
    double previous = bare;
    for (const double t : {0.05, 0.1, 0.2, 0.4}) {
        const Scene s = edgeSlabScene(t, false);
        const double width = edgeWidth(render(s, s.cameras[0], edgeSlabOptions(blur)).image);
        const double front = EdgeSlab::kEye - t / 2, behind = EdgeSlab::kEye - EdgeSlab::kWall;
        const double r =
            focal * std::tan(blur * t / EdgeSlab::kAttenuationDistance) * (behind - front) / behind;
        std::printf("  t %.2f: width %.2f px, a disc of radius %.2f px %.2f px\n", t, width, r,
                    discEdgeWidth(r));
        EXPECT_GT(width, previous + 1) << t;
        EXPECT_NEAR(width, discEdgeWidth(r), 0.25 * discEdgeWidth(r) + 1) << t;
        previous = width;
    }
    // Blur 0: as sharp as with no slab (what the pass did before).
    const Scene thick = edgeSlabScene(0.4, false);
    const double sharp = edgeWidth(render(thick, thick.cameras[0], edgeSlabOptions(0)).image);
    std::printf("  t 0.40, blur 0: width %.2f px\n", sharp);
    EXPECT_LT(sharp, 1.01);
}

// Clear glass keeps its own path: the blur of translucent solids changes no pixel of it.
TEST(TranslucencyShadowTest, TheTranslucencyBlurLeavesClearGlassAlone) {
    const Scene s = edgeSlabScene(0.4, true);
    RenderOptions o = edgeSlabOptions(0);
    setRenderOption(o, "glass", std::string("exact"));
    const RenderResult sharp = render(s, s.cameras[0], o);
    EXPECT_THROW(setRenderOption(o, "translucency-blur", -1.0), Error);
    EXPECT_TRUE(setRenderOption(o, "translucency-blur", 5.0));
    EXPECT_EQ(o.translucencyBlur, 5);
    const RenderResult blurred = render(s, s.cameras[0], o);
    ASSERT_EQ(sharp.image.pixels.size(), blurred.image.pixels.size());
    for (std::size_t i = 0; i < sharp.image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(sharp.image.pixels[i][c], blurred.image.pixels[i][c]) << i;
    EXPECT_LT(edgeWidth(sharp.image), 1.01); // and glass shows the edge sharply
}
} // namespace
} // namespace voxfx
