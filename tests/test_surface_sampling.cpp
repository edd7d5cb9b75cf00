// Tests of src/grid/surface_sampling.cpp: the same samples for every thread count and as prefixes
// of longer runs, triangles picked in proportion to their area (a binomial z-test on two triangles
// of known areas), points on their faces, near-surface signs against the exact inside test, and
// bad input. The statistical tests of uniformity and the brute-force distances are in
// python/tests/test_sampling.py.
#include <cmath>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/surface_sampling.hpp"

namespace voxfx {
namespace {

TEST(SurfaceSampling, SamplesAreTheSameForEveryThreadCountAndPrefixesOfLongerRuns) {
    const Mesh m = test::makeTorus({0.1, 0.2, 0.3}, 1.0, 0.3, 24, 12);
    SurfaceSampleOptions one, all;
    one.threads = 1;
    const SurfaceSamples a = sampleSurface(m.view(), 100000, 42, one);
    const SurfaceSamples b = sampleSurface(m.view(), 100000, 42, all);
    const SurfaceSamples c = sampleSurface(m.view(), 30000, 42, all);
    ASSERT_EQ(a.points.size(), 100000u);
    EXPECT_EQ(a.points, b.points);
    EXPECT_EQ(a.faces, b.faces);
    EXPECT_TRUE(std::equal(c.points.begin(), c.points.end(), a.points.begin()));
    const SurfaceSamples d = sampleSurface(m.view(), 1000, 43, all);
    EXPECT_NE(std::vector<Vec3d>(a.points.begin(), a.points.begin() + 1000), d.points);
}

TEST(SurfaceSampling, TrianglesArePickedInProportionToTheirArea) {
    // Two disjoint right triangles of areas 0.5 and 1.5: face 1 with probability 3/4.
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0}, {8, 0, 0}, {5, 1, 0}};
    m.indices = {0, 1, 2, 3, 4, 5};
    const int64_t n = 200000;
    const SurfaceSamples s = sampleSurface(m.view(), n, 9);
    int64_t second = 0;
    for (const uint32_t f : s.faces) second += f == 1;
    // z-test: the count of a binomial(n, 3/4) lies within 5 standard deviations (p < 6e-7).
    const double mean = 0.75 * double(n), sd = std::sqrt(double(n) * 0.75 * 0.25);
    EXPECT_LT(std::abs(double(second) - mean), 5 * sd);
    // Every point on its face: z = 0 and inside the triangle's x, y range.
    for (std::size_t i = 0; i < s.points.size(); ++i) {
        const Vec3d& p = s.points[i];
        const double x0 = s.faces[i] == 0 ? 0 : 5, w = s.faces[i] == 0 ? 1 : 3;
        ASSERT_EQ(p.z, 0.0);
        ASSERT_GE(p.x, x0 - 1e-12);
        ASSERT_GE(p.y, -1e-12);
        ASSERT_LE((p.x - x0) / w + p.y, 1 + 1e-12);
        ASSERT_EQ(s.normals[i], (Vec3f{0, 0, 1}));
    }
}

TEST(SurfaceSampling, NearSurfaceSignsAreTheExactInsideTest) {
    const Mesh m = test::makeTorus({0, 0, 0}, 1.0, 0.4, 32, 16);
    NearSurfaceOptions o;
    o.sigmas = {0.05, 0.01};
    o.uniformFraction = 0.25;
    const NearSurfaceSamples s = sampleNearSurface(m.view(), 20000, 3, o);
    std::vector<uint8_t> inside(s.points.size());
    contains(m.view(), s.points, inside);
    EXPECT_EQ(s.inside, inside);
    for (std::size_t i = 0; i < s.points.size(); ++i)
        ASSERT_EQ(std::signbit(s.distances[i]), s.inside[i] != 0);
    // The uniform quarter lies in the box grown by 10% of the longest side (2.8).
    const double grow = 0.1 * 2.8 + 1e-12;
    for (std::size_t i = 15000; i < s.points.size(); ++i) {
        ASSERT_LE(std::abs(s.points[i].x), 1.4 + grow);
        ASSERT_LE(std::abs(s.points[i].z), 0.4 + grow);
    }
}

TEST(SurfaceSampling, BadInputIsAClearError) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    m.indices = {0, 1, 2};
    EXPECT_THROW(
        {
            try {
                sampleSurface(m.view(), 10, 0);
            } catch (const Error& e) {
                EXPECT_NE(std::string(e.what()).find("zero area"), std::string::npos) << e.what();
                throw;
            }
        },
        Error);
    m.positions[2] = {0, 1, 0};
    EXPECT_THROW(sampleSurface(m.view(), -1, 0), Error);
    NearSurfaceOptions o;
    o.sigmas = {};
    EXPECT_THROW(sampleNearSurface(m.view(), 10, 0, o), Error);
    o.sigmas = {std::nan("")};
    EXPECT_THROW(sampleNearSurface(m.view(), 10, 0, o), Error);
    o.sigmas = {0.1};
    o.uniformFraction = 2;
    EXPECT_THROW(sampleNearSurface(m.view(), 10, 0, o), Error);
    m.indices = {0, 1, 5};
    EXPECT_THROW(sampleSurface(m.view(), 10, 0), Error);
    m.indices = {0, 1, 2};
    EXPECT_TRUE(sampleSurface(m.view(), 0, 0).points.empty());
}

} // namespace
} // namespace voxfx
