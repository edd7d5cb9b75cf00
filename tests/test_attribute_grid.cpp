// Tests of src/voxelize/attribute.cpp (CHANG §2 attribute voxelization): hand-counted writes on
// axis-aligned quads, a brute-force point-in-triangle count per column, occupancy against a
// brute-force centre coverage and CGAL's exact triangle/box overlap, determinism across thread
// counts, local slicing and bad input.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/attribute_grid.hpp"

namespace voxfx {
namespace {

// Grid over [0, 16]^3 with 16 cells per axis: grid coordinates equal world coordinates.
Frame unitFrame(int64_t n = 16) {
    return Frame::orthographic({{0, 0, 0}, {double(n), double(n), double(n)}}, Axis::Z, n, n, n);
}

// Quad in the plane z = const, [x0, x1] x [y0, y1], counter-clockwise seen from +z.
void appendQuadZ(Mesh& m, double x0, double y0, double x1, double y1, double z) {
    const auto b = uint32_t(m.positions.size());
    m.positions.push_back(Vec3f(Vec3d{x0, y0, z}));
    m.positions.push_back(Vec3f(Vec3d{x1, y0, z}));
    m.positions.push_back(Vec3f(Vec3d{x1, y1, z}));
    m.positions.push_back(Vec3f(Vec3d{x0, y1, z}));
    m.indices.insert(m.indices.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
}

TEST(AttributeGridTest, QuadWritesEachCoveredColumnOnceInItsSlice) {
    // Quad over [2, 10]^2 at z = 4.3: column centres 2.5 .. 9.5 are inside (8 x 8 columns), each
    // written once (the tie rule gives a centre on the diagonal to one triangle) into slice 4.
    Mesh quad;
    appendQuadZ(quad, 2, 2, 10, 10, 4.3);
    const std::vector<float> absorption(quad.triangleCount(), 0.25f);
    const AttributeGrid g = voxelizeAttributes(quad.view(), unitFrame(), absorption);
    EXPECT_EQ(g.writeCount(), 64);
    for (int64_t y = 0; y < 16; ++y)
        for (int64_t x = 0; x < 16; ++x) {
            const bool inside = x >= 2 && x < 10 && y >= 2 && y < 10;
            EXPECT_EQ(g.count[size_t(g.index(x, y, 4))], inside ? 1 : 0) << x << " " << y;
            if (!inside) continue;
            EXPECT_FLOAT_EQ(g.absorption[size_t(g.index(x, y, 4))], 0.25f);
            const Vec3f n = g.normal(g.index(x, y, 4));
            EXPECT_NEAR(n.z, 1.0f, 1e-6f); // counter-clockwise seen from +z
        }
}

TEST(AttributeGridTest, TwoLeavesInOneVoxelAbsorbTwice) {
    // CHANG: dense foliage writes a voxel several times and so absorbs more.
    Mesh leaves;
    appendQuadZ(leaves, 2, 2, 6, 6, 4.3);
    appendQuadZ(leaves, 2, 2, 6, 6, 4.7);
    std::vector<float> absorption(leaves.triangleCount(), 0.5f);
    absorption[2] = absorption[3] = 1.5f; // the second quad is darker
    const AttributeGrid g = voxelizeAttributes(leaves.view(), unitFrame(), absorption);
    for (int64_t y = 2; y < 6; ++y)
        for (int64_t x = 2; x < 6; ++x) {
            EXPECT_EQ(g.count[size_t(g.index(x, y, 4))], 2);
            EXPECT_FLOAT_EQ(g.absorption[size_t(g.index(x, y, 4))], 2.0f);
        }
    EXPECT_EQ(g.writeCount(), 2 * 16);
}

TEST(AttributeGridTest, ConservativeCoverageWritesBothCellsOfABoundary) {
    // A quad exactly on the cell boundary z = 4 over [2, 10]^2 touches slices 3 and 4 of the closed
    // footprints of columns 1 .. 10 per axis: 10 x 10 columns x 2 slices.
    Mesh quad;
    appendQuadZ(quad, 2, 2, 10, 10, 4.0);
    AttributeOptions o;
    o.coverage = Coverage::Conservative;
    const AttributeGrid g = voxelizeAttributes(quad.view(), unitFrame(), {}, o);
    int64_t written = 0;
    for (int64_t i = 0; i < g.voxelCount(); ++i) written += g.count[size_t(i)] > 0;
    EXPECT_EQ(written, 200);
    for (int64_t y = 1; y <= 10; ++y)
        for (int64_t x = 1; x <= 10; ++x) {
            EXPECT_GE(g.count[size_t(g.index(x, y, 3))], 1);
            EXPECT_GE(g.count[size_t(g.index(x, y, 4))], 1);
        }
    for (const float a : g.absorption) EXPECT_EQ(a, 0.0f); // no absorption given
}

// Independent reference: number of triangles whose xy projection strictly contains the point.
int coveringTriangles(const Mesh& m, double px, double py) {
    int n = 0;
    for (size_t t = 0; t < m.triangleCount(); ++t) {
        double x[3], y[3];
        for (int k = 0; k < 3; ++k) {
            x[k] = m.positions[m.indices[3 * t + size_t(k)]].x;
            y[k] = m.positions[m.indices[3 * t + size_t(k)]].y;
        }
        double s[3];
        for (int k = 0; k < 3; ++k) {
            const int j = (k + 1) % 3;
            s[k] = (x[j] - x[k]) * (py - y[k]) - (y[j] - y[k]) * (px - x[k]);
        }
        if ((s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0)) ++n;
    }
    return n;
}

Mesh randomLeaves(int count, uint64_t seed, double lo = 1, double hi = 15) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(lo, hi), d(-1.5, 1.5);
    Mesh m;
    for (int i = 0; i < count; ++i) {
        const Vec3d c{u(rng), u(rng), u(rng)};
        const auto b = uint32_t(m.positions.size());
        for (int k = 0; k < 3; ++k) m.positions.push_back(Vec3f(c + Vec3d{d(rng), d(rng), 0.3 * d(rng)}));
        m.indices.insert(m.indices.end(), {b, b + 1, b + 2});
    }
    return m;
}

TEST(AttributeGridTest, WritesPerColumnEqualTrianglesCoveringItsCentre) {
    const Mesh leaves = randomLeaves(300, 7);
    const AttributeGrid g = voxelizeAttributes(leaves.view(), unitFrame(), {});
    int64_t mismatches = 0;
    for (int64_t y = 0; y < 16; ++y)
        for (int64_t x = 0; x < 16; ++x) {
            int64_t writes = 0;
            for (int64_t s = 0; s < 16; ++s) writes += g.count[size_t(g.index(x, y, s))];
            mismatches += writes != coveringTriangles(leaves, double(x) + 0.5, double(y) + 0.5);
        }
    // Random float vertices put no centre exactly on an edge: the counts agree everywhere.
    EXPECT_EQ(mismatches, 0);
}

// Brute-force centre coverage on a unit frame along z: for every column centre strictly inside a
// triangle's xy projection, the slice floor(z) of the triangle's plane there. Cells whose depth
// lies within 1e-9 of a slice boundary go to `ambiguous` instead (rounding may put them on either
// side).
void bruteForceCentreCells(const Mesh& m, int64_t n, std::vector<uint8_t>& cells,
                           std::vector<uint8_t>& ambiguous) {
    cells.assign(size_t(n * n * n), 0);
    ambiguous.assign(cells.size(), 0);
    for (int64_t y = 0; y < n; ++y)
        for (int64_t x = 0; x < n; ++x) {
            const double px = double(x) + 0.5, py = double(y) + 0.5;
            for (size_t t = 0; t < m.triangleCount(); ++t) {
                Vec3d v[3];
                for (int k = 0; k < 3; ++k) v[k] = Vec3d(m.positions[m.indices[3 * t + size_t(k)]]);
                // Barycentric weights of (px, py) in the projected triangle.
                const double det =
                    (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[2].x - v[0].x) * (v[1].y - v[0].y);
                if (det == 0) continue;
                const double b1 =
                    ((px - v[0].x) * (v[2].y - v[0].y) - (v[2].x - v[0].x) * (py - v[0].y)) / det;
                const double b2 =
                    ((v[1].x - v[0].x) * (py - v[0].y) - (px - v[0].x) * (v[1].y - v[0].y)) / det;
                const double b0 = 1 - b1 - b2;
                if (!(b0 > 0 && b1 > 0 && b2 > 0)) continue;
                const double z = b0 * v[0].z + b1 * v[1].z + b2 * v[2].z;
                const auto s = int64_t(std::floor(z));
                if (s < 0 || s >= n) continue;
                const size_t c = size_t((y * n + x) * n + s);
                if (z - double(s) < 1e-9 || double(s + 1) - z < 1e-9) {
                    ambiguous[c] = 1;
                    if (s + 1 < n) ambiguous[c + 1] = 1;
                    if (s > 0) ambiguous[c - 1] = 1;
                } else {
                    cells[c] = 1;
                }
            }
        }
}

TEST(AttributeGridTest, OccupancyMatchesIndependentCoverage) {
    // Centre coverage: the cell of every crossing of a column's centre line (brute force above).
    // Conservative coverage: every cell whose closed box meets a triangle (CGAL's exact
    // triangle/box test, cells within 2e-9 cells of the mesh tolerated: the rasterizer's slack).
    const Mesh torus = test::makeTorus({8.1, 7.9, 8.05}, 5, 2, 40, 20);
    const Frame f = unitFrame();
    AttributeOptions o;
    o.coverage = Coverage::Center;
    const BitGrid centre = voxelizeAttributes(torus.view(), f, {}, o).occupancy();
    std::vector<uint8_t> want, ambiguous;
    bruteForceCentreCells(torus, 16, want, ambiguous);
    int64_t wrong = 0, set = 0, skipped = 0;
    for (int64_t y = 0; y < 16; ++y)
        for (int64_t x = 0; x < 16; ++x)
            for (int64_t s = 0; s < 16; ++s) {
                const size_t c = size_t((y * 16 + x) * 16 + s);
                if (ambiguous[c] && !want[c]) {
                    ++skipped;
                    continue;
                }
                wrong += centre.get(x, y, s) != bool(want[c]);
                set += want[c];
            }
    EXPECT_EQ(wrong, 0) << skipped << " ambiguous cells left out";
    EXPECT_GT(set, 200);
    EXPECT_LT(skipped, 20);

    o.coverage = Coverage::Conservative;
    const VoxelGrid cons{f, voxelizeAttributes(torus.view(), f, {}, o).occupancy()};
    const test::ConservativeOracle oracle =
        test::oracleConservative(torus.view(), test::CellGeometry::of(cons), 2e-9);
    const test::GridDiff d = test::compareGrids(test::toWorldGrid(cons), oracle.cells, &oracle.near);
    EXPECT_TRUE(d.equal()) << d;
    EXPECT_GT(oracle.cells.count(), set);
}

TEST(AttributeGridTest, ResultDoesNotDependOnThreadCount) {
    const Mesh leaves = randomLeaves(2000, 3);
    std::vector<float> absorption(leaves.triangleCount());
    for (size_t i = 0; i < absorption.size(); ++i) absorption[i] = 0.1f + 0.001f * float(i % 97);
    AttributeOptions one, many;
    one.threads = 1;
    many.threads = 2;
    const Frame f = unitFrame(32);
    const AttributeGrid a = voxelizeAttributes(leaves.view(), f, absorption, one);
    const AttributeGrid b = voxelizeAttributes(leaves.view(), f, absorption, many);
    EXPECT_EQ(a.count, b.count);
    EXPECT_EQ(a.absorption, b.absorption); // bit-identical float sums: one owner per tile, fixed order
    ASSERT_EQ(a.normalSum.size(), b.normalSum.size());
    for (size_t i = 0; i < a.normalSum.size(); ++i) ASSERT_TRUE(a.normalSum[i] == b.normalSum[i]) << i;
}

TEST(AttributeGridTest, LocalSlicingSpreadsSlicesOverEachColumnsRange) {
    // Two quads at z = 4.3 and 12.7 with D = 2 local slices: the first in slice 0, the second at
    // the far end of the range (slice coordinate D, clamped into slice 1).
    Mesh quads;
    appendQuadZ(quads, 2, 2, 10, 10, 4.3);
    appendQuadZ(quads, 2, 2, 10, 10, 12.7);
    const Frame f = Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 16, 2);
    AttributeOptions o;
    o.slicing = Slicing::Local;
    const AttributeGrid g = voxelizeAttributes(quads.view(), f, {}, o);
    EXPECT_EQ(g.frame.slicing(), Slicing::Local);
    for (int64_t y = 2; y < 10; ++y)
        for (int64_t x = 2; x < 10; ++x) {
            EXPECT_EQ(g.count[size_t(g.index(x, y, 0))], 1);
            EXPECT_EQ(g.count[size_t(g.index(x, y, 1))], 1);
        }
}

TEST(AttributeGridTest, PerspectiveLightFrameWritesTheSliceOfTheViewDistance) {
    // A quad facing a light 10 units away; D = 10 slices over view distances [5, 15] (1 per unit):
    // the quad's centre region lies at view distance 10, slice 5.
    Mesh quad;
    appendQuadZ(quad, -1, -1, 1, 1, 0);
    const Frame f = Frame::perspective({0, 0, 10}, {0, 0, 0}, {0, 1, 0}, 0.5, 32, 32, 5, 15, 10);
    const AttributeGrid g = voxelizeAttributes(quad.view(), f, {});
    ASSERT_GT(g.writeCount(), 0);
    for (int64_t i = 0; i < g.voxelCount(); ++i)
        if (g.count[size_t(i)]) { EXPECT_EQ(i % 10, 5); }
}

TEST(AttributeGridTest, SparseColumnsHoldExactlyTheDenseWrites) {
    // Every written voxel of the dense grid appears once in the sparse form with the same count and
    // the bit-identical absorption sum (same triangle order); nothing else appears.
    const Mesh leaves = randomLeaves(1500, 9);
    std::vector<float> absorption(leaves.triangleCount());
    for (size_t i = 0; i < absorption.size(); ++i) absorption[i] = 0.05f + 0.01f * float(i % 13);
    for (const Coverage coverage : {Coverage::Center, Coverage::Conservative})
        for (const Slicing slicing : {Slicing::Uniform, Slicing::Local}) {
            AttributeOptions o;
            o.coverage = coverage;
            o.slicing = slicing;
            const Frame f = unitFrame(24);
            const AttributeGrid dense = voxelizeAttributes(leaves.view(), f, absorption, o);
            const AttributeColumns sparse = voxelizeAttributeColumns(leaves.view(), f, absorption, o);
            ASSERT_TRUE(dense.frame.sameGrid(sparse.frame));
            int64_t denseWritten = 0;
            for (const uint16_t n : dense.count) denseWritten += n > 0;
            EXPECT_EQ(sparse.entryCount(), denseWritten);
            for (int64_t c = 0; c < f.columnCount(); ++c)
                for (int64_t i = sparse.offsets[size_t(c)]; i < sparse.offsets[size_t(c) + 1]; ++i) {
                    const auto d = size_t(c * f.depth() + sparse.slice[size_t(i)]);
                    ASSERT_EQ(sparse.count[size_t(i)], dense.count[d]);
                    ASSERT_EQ(sparse.absorption[size_t(i)], dense.absorption[d]);
                    if (i > sparse.offsets[size_t(c)]) {
                        ASSERT_LT(sparse.slice[size_t(i) - 1], sparse.slice[size_t(i)]);
                    }
                }
        }
}

TEST(AttributeGridTest, RejectsBadInput) {
    Mesh quad;
    appendQuadZ(quad, 2, 2, 10, 10, 4.3);
    const std::vector<float> wrong(5, 1.0f);
    EXPECT_THROW(voxelizeAttributes(quad.view(), unitFrame(), wrong), Error);
    EXPECT_THROW(voxelizeAttributeColumns(quad.view(), unitFrame(), wrong), Error);
    Mesh bad = quad;
    bad.indices[0] = 99;
    EXPECT_THROW(voxelizeAttributes(bad.view(), unitFrame(), {}), Error);
    Mesh nan = quad;
    nan.positions[0].x = NAN;
    EXPECT_THROW(voxelizeAttributes(nan.view(), unitFrame(), {}), Error);
}

TEST(AttributeGridTest, EmptyMeshGivesAnEmptyGrid) {
    const Mesh empty;
    const AttributeGrid g = voxelizeAttributes(empty.view(), unitFrame(), {});
    EXPECT_EQ(g.writeCount(), 0);
    EXPECT_EQ(g.occupancy().count(), 0);
}

} // namespace
} // namespace voxfx
