// The shadow techniques against each other and against exact light transport, reached by name
// through the closed set's dispatch (voxfx/shadow.hpp) as the renderer reaches them: on foliage
// (the brute-force crossing counter of tests/support/shadow_reference.hpp: more leaves never
// brighten a point, results independent of the thread count, error that shrinks with resolution,
// the full error-versus-resolution table as the Slow case); through glass (the crossing-counting
// techniques, transmittance, absorption and deep shadows, against exact shadows: Fresnel, the tint
// and Beer–Lambert over the chord); and through volumes (deep shadows converging to exact shadows
// as epsilon shrinks).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "demo/demo_scenes.hpp"
#include "support/shadow_reference.hpp"
#include "test_util.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {
namespace {

using namespace voxfx::demo;
using test::ErrorStats;
using test::exactCrossings;
using test::exactReference;
using test::gridOptions;
using test::leafScene;
using test::Reference;
using test::setShadowOption;
using test::shadowError;
using test::sun;
using test::visibilityOf;

// ---- Foliage, against exact light transport ---------------------------------------------------

TEST(ShadowTest, MoreLeafLayersNeverMakeAPointBrighter) {
    // Extra leaves inside the same bounds (so the light frames do not move) can only add filled cells
    // (transmittance, map) or writes (absorption). Uniform slicing: local slicing moves cell boundaries
    // when a column's range changes.
    const Scene base = leafScene(300, 2, 11);
    Scene more = base;
    const Scene extra = leafScene(300, 2, 12);
    for (size_t k = 1; k < extra.meshes.size(); ++k) {
        Mesh& to = more.meshes[k].mesh;
        const auto b = uint32_t(to.positions.size());
        for (const Vec3f& p : extra.meshes[k].mesh.positions)
            to.positions.push_back(Vec3f(std::clamp(p.x, -1.8f, 1.8f), std::clamp(p.y, 1.7f, 2.8f),
                                         std::clamp(p.z, -1.8f, 1.8f)));
        for (const uint32_t i : extra.meshes[k].mesh.indices) to.indices.push_back(b + i);
    }
    ASSERT_TRUE(base.bounds(true) == more.bounds(true));
    const Light light = sun();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-3, 3), uy(0, 3.2);
    for (const std::string_view kind : {"map", "transmittance", "absorption"}) {
        const LightShadow a = buildLightShadow(base, light, gridOptions(kind, 96));
        const LightShadow b = buildLightShadow(more, light, gridOptions(kind, 96));
        int darker = 0;
        for (int i = 0; i < 3000; ++i) {
            const Vec3d p{u(rng), uy(rng), u(rng)};
            const Vec3f va = visibilityOf(a, p, {0, 0, 0}), vb = visibilityOf(b, p, {0, 0, 0});
            for (int c = 0; c < 3; ++c) ASSERT_LE(vb[c], va[c] + 1e-6f) << kind << " at " << i;
            darker += vb.y < va.y;
        }
        EXPECT_GT(darker, 100) << kind; // the extra leaves do shadow something
    }
}

TEST(ShadowTest, ResultDoesNotDependOnThreadCount) {
    const Scene s = leafScene(500, 3, 41);
    for (const std::string_view kind : {"map", "transmittance", "absorption"}) {
        LightShadow one, two;
        withThreads(1, [&] { one = buildLightShadow(s, sun(), gridOptions(kind, 128)); });
        withThreads(2, [&] { two = buildLightShadow(s, sun(), gridOptions(kind, 128)); });
        std::mt19937_64 rng(4);
        std::uniform_real_distribution<double> u(-3, 3), uy(0, 3.2);
        for (int i = 0; i < 1000; ++i) {
            const Vec3d p{u(rng), uy(rng), u(rng)};
            ASSERT_TRUE(visibilityOf(one, p, {0, 1, 0}) == visibilityOf(two, p, {0, 1, 0}));
        }
    }
}

TEST(ShadowTest, ErrorAgainstExactTransportShrinksWithResolution) {
    const Scene s = leafScene(500, 2, 51);
    const Light light = sun();
    const Reference pts = exactReference(s, light, 1500, 6);
    const ErrorStats t64 = shadowError(s, light, pts, gridOptions("transmittance", 64));
    const ErrorStats t256 = shadowError(s, light, pts, gridOptions("transmittance", 256));
    const ErrorStats a64 = shadowError(s, light, pts, gridOptions("absorption", 64));
    const ErrorStats a256 = shadowError(s, light, pts, gridOptions("absorption", 256));
    const ErrorStats m256 = shadowError(s, light, pts, gridOptions("map", 256));
    EXPECT_LT(t256.mean, 0.75 * t64.mean);
    EXPECT_LT(a256.mean, 0.75 * a64.mean);
    EXPECT_LT(t256.mean, 0.05);
    EXPECT_LT(a256.mean, 0.05);
    // The binary map cannot represent partial light: several times worse on foliage.
    EXPECT_GT(m256.mean, 3 * t256.mean);
    EXPECT_GT(m256.mean, 3 * a256.mean);
}

void errorTable(int leaves);

TEST(ShadowTest, ErrorTableAgainstExactTransportSlow) {
    // The table reported in BENCHMARKS.md: mean and 95th percentile of |visibility - exact| over
    // ground points that at least one leaf shadows.
    // Two canopies: dense (1,500 leaves, most shadowed points behind several) and sparse (300).
    for (const int leaves : {1500, 300}) errorTable(leaves);
}

void errorTable(int leaves) {
    const Scene s = leafScene(leaves, 3, 61);
    const Light light = sun();
    const Reference pts = exactReference(s, light, 4000, 7);
    double crossings = 0;
    for (const Vec3d& p : pts.points) crossings += exactCrossings(s, light, p);
    std::printf("%d leaves, %zu shadowed ground points, %.2f crossings on average\n", leaves,
                pts.points.size(), crossings / double(pts.points.size()));
    std::printf("%-40s %6s %9s %9s\n", "kind", "N", "mean", "p95");
    struct Row {
        const char* name;
        std::string_view kind;
        Slicing slicing;
        VoxelizeMode mode;
    };
    const Row rows[] = {
        {"transmittance surface uniform", "transmittance", Slicing::Uniform, VoxelizeMode::Surface},
        {"transmittance surface local", "transmittance", Slicing::Local, VoxelizeMode::Surface},
        {"transmittance conservative uniform", "transmittance", Slicing::Uniform, VoxelizeMode::Conservative},
        {"absorption uniform", "absorption", Slicing::Uniform, VoxelizeMode::Surface},
        {"absorption local", "absorption", Slicing::Local, VoxelizeMode::Surface},
        {"shadow map (PCF 3x3)", "map", Slicing::Uniform, VoxelizeMode::Surface},
        {"transmittance surface uniform bilinear", "transmittance", Slicing::Uniform, VoxelizeMode::Surface},
        {"absorption uniform bilinear", "absorption", Slicing::Uniform, VoxelizeMode::Surface}};
    for (const Row& row : rows) {
        double previous = 1e9;
        for (const int64_t n : {32, 64, 128, 256, 512}) {
            ShadowOptions o = gridOptions(row.kind, n, row.slicing, row.mode);
            setShadowOption(o, "bilinear", std::string(row.name).find("bilinear") != std::string::npos);
            const ErrorStats e = shadowError(s, light, pts, o);
            std::printf("%-40s %6lld %9.4f %9.4f\n", row.name, (long long)n, e.mean, e.p95);
            if (row.kind != "map" && n >= 64 && row.mode == VoxelizeMode::Surface) {
                EXPECT_LT(e.mean, previous) << row.name << " " << n;
            }
            previous = e.mean;
        }
    }
}

} // namespace
} // namespace voxfx
