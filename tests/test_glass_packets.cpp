// Tests of the glass pass's packets (issue #34): TriangleTracer's batch query (8 rays to an Embree
// packet, rtcIntersect8) against its single-ray query (rtcIntersect1, Embree's other traversal
// kernel), and the exact glass tracer's paths traced eight side by side (ExactGlass::traceMany)
// against the same paths traced one at a time: the same hits and the same paths, bit for bit, so
// that the image does not depend on which pixels share a packet.
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/exact_glass.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {
namespace {

// A bumpy ball (a UV sphere, its radius varied with latitude and longitude: faces of many
// orientations, as a scanned mesh has) and a box beside it, one mesh.
Mesh bumpyBallAndBox() {
    Mesh m = test::makeUvSphere({0, 0, 0}, 1.0, 40, 80);
    for (Vec3f& p : m.positions) {
        const double r = length(Vec3d(p));
        if (!(r > 0)) continue;
        const Vec3d u = Vec3d(p) / r;
        const double bump = 1 + 0.08 * std::sin(7 * std::atan2(u.y, u.x)) * std::cos(5 * u.z);
        p = Vec3f(u * bump);
    }
    const Mesh box = test::makeBox({1.3, -0.6, -0.5}, {2.2, 0.4, 0.6});
    const auto base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), box.positions.begin(), box.positions.end());
    for (const uint32_t i : box.indices) m.indices.push_back(base + i);
    return m;
}

void expectSameHit(const TriangleTracer::Hit& a, const TriangleTracer::Hit& b, size_t k) {
    ASSERT_EQ(a.hit, b.hit) << "ray " << k;
    if (!a.hit) return;
    EXPECT_EQ(a.triangle, b.triangle) << "ray " << k;
    EXPECT_EQ(a.t, b.t) << "ray " << k;
    EXPECT_EQ(a.u, b.u) << "ray " << k;
    EXPECT_EQ(a.v, b.v) << "ray " << k;
}

TEST(TriangleTracerTest, PacketsFindTheSingleRaysHits) {
    const Mesh mesh = bumpyBallAndBox();
    const TriangleTracer tracer(mesh.view());
    std::vector<TriangleTracer::Ray> rays;
    // Coherent: a camera's rays over the ball's silhouette and the box (hits and misses side by side).
    const Vec3d eye{0.3, 0.2, 5};
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 40; ++x) {
            const Vec3d target{-1.4 + 3.8 * (x + 0.5) / 40, -1.3 + 2.6 * (y + 0.5) / 24, 0};
            rays.push_back({eye, normalize(target - eye)});
        }
    // Incoherent: from inside the ball in every direction, and from points near its surface with
    // the intervals the glass tracer asks for (a start past the surface, a short far end).
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> uni(-1, 1);
    for (int k = 0; k < 600; ++k) {
        Vec3d d{uni(rng), uni(rng), uni(rng)};
        if (!(length(d) > 1e-3)) continue;
        d = normalize(d);
        const Vec3d o{0.2 * uni(rng), 0.2 * uni(rng), 0.2 * uni(rng)};
        const double tNear = k % 3 == 0 ? 0 : k % 3 == 1 ? 1e-7 : 0.5;
        const double tFar = k % 4 == 0 ? 0.9 : std::numeric_limits<double>::infinity();
        rays.push_back({o, d, tNear, tFar});
        const Vec3d surface(mesh.positions[mesh.indices[size_t(3 * (k * 37 % int(mesh.triangleCount())))]]);
        rays.push_back({surface, d, 1e-7, std::numeric_limits<double>::infinity()});
    }
    std::vector<TriangleTracer::Hit> one(rays.size());
    for (size_t k = 0; k < rays.size(); ++k)
        one[k] = tracer.intersect(rays[k].origin, rays[k].dir, rays[k].tNear, rays[k].tFar);
    int hits = 0;
    for (const TriangleTracer::Hit& h : one) hits += h.hit;
    ASSERT_GT(hits, int(rays.size()) / 2);
    ASSERT_LT(hits, int(rays.size())); // some miss: packets of hits and misses
    // Batches of every size up to 8 (partial packets) and 13 (two packets, the second partial).
    for (const size_t batch : {size_t(1), size_t(3), size_t(7), size_t(8), size_t(13)}) {
        std::vector<TriangleTracer::Hit> many(rays.size());
        for (size_t k0 = 0; k0 < rays.size(); k0 += batch) {
            const size_t n = std::min(batch, rays.size() - k0);
            tracer.intersect(std::span(rays).subspan(k0, n), std::span(many).subspan(k0, n));
        }
        for (size_t k = 0; k < rays.size(); ++k) {
            expectSameHit(many[k], one[k], k);
            if (HasFailure()) return;
        }
    }
}

// Several media, nested and touching, with vertex normals: the bumpy ball of clear glass holding a
// ruby core, and two blocks touching face to face (a crossing straight from one into the other).
struct GlassOfSeveralMedia {
    Mesh mesh;
    std::vector<Vec3f> normals;
    std::vector<uint32_t> medium;
    std::vector<GlassMedium> media;
};
GlassOfSeveralMedia severalMedia() {
    GlassOfSeveralMedia g;
    const auto add = [&](const Mesh& m, uint32_t medium, bool smooth) {
        const auto base = uint32_t(g.mesh.positions.size());
        g.mesh.positions.insert(g.mesh.positions.end(), m.positions.begin(), m.positions.end());
        for (const uint32_t i : m.indices) g.mesh.indices.push_back(base + i);
        g.medium.resize(g.mesh.triangleCount(), medium);
        for (const Vec3f& p : m.positions)
            g.normals.push_back(smooth ? Vec3f(normalize(Vec3d(p))) : Vec3f{0, 0, 1});
    };
    add(test::makeUvSphere({0, 0, 0}, 1.0, 40, 80), 0, true);
    add(test::makeUvSphere({0.1, 0, 0}, 0.45, 20, 40), 1, true);
    add(test::makeBox({1.3, -0.6, -0.5}, {2.2, 0.0, 0.6}), 2, false);
    add(test::makeBox({1.3, 0.0, -0.5}, {2.2, 0.6, 0.6}), 3, false);
    const auto medium = [](double ior, double sigma, float tint) {
        GlassMedium m;
        m.ior = float(ior);
        m.sigma = {float(sigma), float(sigma), float(sigma)};
        m.tint = {tint, tint, tint};
        return m;
    };
    g.media = {medium(1.5, 0.2, 1), medium(1.76, 1.5, 0.9f), medium(1.5, 0.8, 0.95f), medium(1.9, 0.4, 0.8f)};
    return g;
}

void expectSamePath(const GlassPath& a, const GlassPath& b, size_t k) {
    ASSERT_EQ(a.hit, b.hit) << "path " << k;
    EXPECT_EQ(a.events, b.events) << "path " << k;
    EXPECT_EQ(a.truncated, b.truncated) << "path " << k;
    EXPECT_EQ(a.reflectance, b.reflectance) << "path " << k;
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(a.reflectDir[c], b.reflectDir[c]) << "path " << k;
        EXPECT_EQ(a.exitPoint[c], b.exitPoint[c]) << "path " << k;
        EXPECT_EQ(a.exitDir[c], b.exitDir[c]) << "path " << k;
        EXPECT_EQ(a.throughput[c], b.throughput[c]) << "path " << k;
    }
}

TEST(GlassTest, ExactTracerTracesPathsSideBySideAsOneAtATime) {
    const GlassOfSeveralMedia g = severalMedia();
    const BuiltGlass built = ExactGlass(g.mesh.view(), g.normals, g.medium, g.media);
    const ExactGlass& glass = std::get<ExactGlass>(built);
    // A camera's rays over the ball, its core and the blocks (misses among them), and a few at a
    // grazing angle whose paths run long (total internal reflection).
    std::vector<GlassHit> hits;
    const Vec3d eye{0.4, 0.3, 5};
    for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 36; ++x) {
            const Vec3d target{-1.3 + 3.7 * (x + 0.5) / 36, -1.2 + 2.4 * (y + 0.5) / 20, 0};
            hits.push_back(GlassHit{eye, normalize(target - eye), target, {0, 0, 1}, 0});
        }
    std::vector<GlassPath> one(hits.size());
    int hitCount = 0, longPaths = 0;
    for (size_t k = 0; k < hits.size(); ++k) {
        one[k] = glass.trace(hits[k]);
        hitCount += one[k].hit;
        longPaths += one[k].events > 4;
    }
    ASSERT_GT(hitCount, int(hits.size()) / 2);
    ASSERT_LT(hitCount, int(hits.size()));
    ASSERT_GT(longPaths, 0); // through the core: 4 events and more
    for (const size_t batch : {size_t(1), size_t(5), size_t(8), size_t(20)}) {
        std::vector<GlassPath> many(hits.size());
        for (size_t k0 = 0; k0 < hits.size(); k0 += batch) {
            const size_t n = std::min(batch, hits.size() - k0);
            traceGlass(built, std::span<const GlassHit>(hits).subspan(k0, n), std::span(many).subspan(k0, n));
        }
        for (size_t k = 0; k < hits.size(); ++k) {
            expectSamePath(many[k], one[k], k);
            if (HasFailure()) return;
        }
    }
}

} // namespace
} // namespace voxfx
