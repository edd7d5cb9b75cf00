// Tests of src/voxelize/attribute.cpp (CHANG §2 attribute voxelization): hand-counted writes on
// axis-aligned quads, a brute-force point-in-triangle count per column, occupancy against a
// brute-force centre coverage and CGAL's exact triangle/box overlap, determinism across thread
// counts, local slicing and bad input.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <random>
#include <string>

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
            o.slabOverlap = slicing == Slicing::Local ? 0.3 : 0; // widened slabs write alike too
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
    AttributeOptions short_;
    const std::vector<Vec3f> threeNormals(3, Vec3f{0, 0, 1}); // the quad has 4 vertices
    short_.vertexNormals = threeNormals;
    EXPECT_THROW(voxelizeAttributes(quad.view(), unitFrame(), {}, short_), Error);
}

// With vertex normals the normal channel follows the smooth surface a renderer shades, not the
// facets: on a coarse sphere (15-degree facets) each written voxel's normal against the sphere's
// normal at the voxel's centre, with the UV sphere's exact vertex normals and without.
TEST(AttributeGridTest, VertexNormalsMakeTheNormalChannelFollowTheSmoothSurface) {
    const Vec3d c{8, 8, 8};
    const double r = 6;
    const Mesh sphere = test::makeUvSphere(c, r, 12, 24);
    std::vector<Vec3f> normals;
    for (const Vec3f& p : sphere.positions) normals.push_back(Vec3f(normalize(Vec3d(p) - c)));
    AttributeOptions o;
    o.coverage = Coverage::Conservative;
    o.channels = {true, false, true, false, false, false};
    const Frame frame = Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 64, 64, 64);
    const AttributeGrid faces = voxelizeAttributes(sphere.view(), frame, {}, o);
    o.vertexNormals = normals;
    const AttributeGrid smooth = voxelizeAttributes(sphere.view(), frame, {}, o);
    ASSERT_EQ(faces.count, smooth.count); // the same writes
    auto errors = [&](const AttributeGrid& g, double& mean, double& worst) {
        double sum = 0;
        int64_t n = 0;
        worst = 0;
        for (int64_t y = 0; y < 64; ++y)
            for (int64_t x = 0; x < 64; ++x)
                for (int64_t s = 0; s < 64; ++s) {
                    const int64_t i = g.index(x, y, s);
                    if (!g.written(i)) continue;
                    const Vec3d p = frame.cellCenter(x, y, s);
                    if (length(p - c) < 1e-9) continue;
                    const double a =
                        std::acos(std::clamp(dot(Vec3d(g.normal(i)), normalize(p - c)), -1.0, 1.0)) * 180 /
                        M_PI;
                    sum += a;
                    worst = std::max(worst, a);
                    ++n;
                }
        ASSERT_GT(n, 1000);
        mean = sum / double(n);
    };
    double faceMean = 0, faceWorst = 0, smoothMean = 0, smoothWorst = 0;
    errors(faces, faceMean, faceWorst);
    errors(smooth, smoothMean, smoothWorst);
    std::printf("normal channel against the sphere's: faces mean %.2f, max %.2f degrees; smooth mean %.2f, "
                "max %.2f degrees\n",
                faceMean, faceWorst, smoothMean, smoothWorst);
    EXPECT_GT(faceMean, 3.0); // the facets are this far off: the test can tell
    EXPECT_LT(smoothMean, 1.0);
    EXPECT_LT(smoothWorst, 4.0);
}

TEST(AttributeGridTest, EmptyMeshGivesAnEmptyGrid) {
    const Mesh empty;
    const AttributeGrid g = voxelizeAttributes(empty.view(), unitFrame(), {});
    EXPECT_EQ(g.writeCount(), 0);
    EXPECT_EQ(g.occupancy().count(), 0);
}

// A triangle through `centre` at angle `theta` (radians) to the projection axis z, its horizontal
// edge along azimuth `phi`: 12 cells tall along its tilted direction, 10 cells wide.
Mesh steepTriangle(const Vec3d& centre, double theta, double phi) {
    const Vec3d u{std::cos(phi), std::sin(phi), 0};
    const Vec3d v{-std::sin(phi) * std::sin(theta), std::cos(phi) * std::sin(theta), std::cos(theta)};
    Mesh m;
    m.positions = {Vec3f(centre + v * 6.0), Vec3f(centre - v * 6.0 + u * 5.0),
                   Vec3f(centre - v * 6.0 - u * 5.0)};
    m.indices = {0, 1, 2};
    return m;
}

// Written cells of an attribute grid in world-axis order (unit frame along z: i = x, j = y, k = s).
test::WorldGrid writtenCells(const AttributeGrid& g) {
    const VoxelGrid v{g.frame, g.occupancy()};
    return test::toWorldGrid(v);
}

TEST(AttributeGridTest, WiderSlabsTradeMissedVoxelsForDoubledOnes) {
    // CHANG §2: widening each slice's clipping slab writes a steep triangle's centre fragments into
    // neighbouring slices too: fewer missed voxels, more doubled ones. Reference: CGAL's exact
    // triangle/box overlap (the cells the triangle passes through). Missed = reference cells not
    // written; doubled = written cells the triangle does not pass through. In a column whose centre
    // the triangle covers, its depth over the column's footprint stays within h = (|dz/dx| +
    // |dz/dy|) / 2 slices of the centre's depth, so an overlap above h misses nothing there.
    const double overlaps[] = {0, 0.25, 0.5, 1, 2, 4, 8};
    int cases = 0;
    for (const double thetaDeg : {12.0, 25.0, 40.0})
        for (const double phiDeg : {0.0, 33.0, 71.0}) {
            const Mesh tri = steepTriangle({8.03, 7.97, 8.01}, thetaDeg * M_PI / 180, phiDeg * M_PI / 180);
            Vec3d p[3];
            for (int k = 0; k < 3; ++k) p[k] = Vec3d(tri.positions[size_t(k)]);
            const Vec3d n = cross(p[1] - p[0], p[2] - p[0]);
            const double h = 0.5 * (std::abs(n.x / n.z) + std::abs(n.y / n.z));
            const Frame f = unitFrame();
            const test::ConservativeOracle oracle = test::oracleConservative(
                tri.view(), test::CellGeometry::of(VoxelGrid{f, BitGrid(16, 16, 16)}));
            int64_t lastMissed = std::numeric_limits<int64_t>::max(), lastDoubled = -1, missed0 = 0;
            for (const double w : overlaps) {
                AttributeOptions o;
                o.slabOverlap = w;
                const test::WorldGrid got = writtenCells(voxelizeAttributes(tri.view(), f, {}, o));
                int64_t missed = 0, doubled = 0, missedCovered = 0;
                for (int64_t k = 0; k < 16; ++k)
                    for (int64_t j = 0; j < 16; ++j)
                        for (int64_t i = 0; i < 16; ++i) {
                            const bool want = oracle.cells.at(i, j, k), have = got.at(i, j, k);
                            missed += want && !have;
                            doubled += have && !want;
                            if (want && !have && coveringTriangles(tri, double(i) + 0.5, double(j) + 0.5) > 0)
                                ++missedCovered;
                        }
                const std::string at = "theta " + std::to_string(thetaDeg) + " phi " +
                                       std::to_string(phiDeg) + " overlap " + std::to_string(w);
                EXPECT_LE(missed, lastMissed) << at;
                EXPECT_GE(doubled, lastDoubled) << at;
                if (w == 0) {
                    EXPECT_EQ(doubled, 0) << at;       // centre fragments lie on the triangle
                    EXPECT_GT(missedCovered, 0) << at; // steep: the depth jumps slices between centres
                    missed0 = missed;
                }
                if (w > h + 1e-6) { EXPECT_EQ(missedCovered, 0) << at << " h " << h; }
                if (w == overlaps[std::size(overlaps) - 1]) {
                    EXPECT_LT(missed, missed0) << at;
                    EXPECT_GT(doubled, 0) << at;
                }
                lastMissed = missed;
                lastDoubled = doubled;
            }
            ++cases;
        }
    EXPECT_EQ(cases, 9);
}

TEST(AttributeGridTest, ConservativeCoverageLeavesNoHolesOnSteepTriangles) {
    // Triangles at 0 (parallel to the projection axis) to 10 degrees from it, at several azimuths:
    // every cell the triangle passes through (CGAL's exact triangle/box overlap) is written, with
    // and without widened slabs, and nothing else is (up to the rasterizer's 1e-9 cell slack).
    const Frame f = unitFrame();
    const test::CellGeometry geometry = test::CellGeometry::of(VoxelGrid{f, BitGrid(16, 16, 16)});
    for (const double thetaDeg : {0.0, 0.05, 0.5, 2.0, 10.0})
        for (const double phiDeg : {0.0, 17.0, 45.0, 90.0}) {
            const Mesh tri = steepTriangle({8.03, 7.97, 8.01}, thetaDeg * M_PI / 180, phiDeg * M_PI / 180);
            const test::ConservativeOracle oracle = test::oracleConservative(tri.view(), geometry, 2e-9);
            AttributeOptions o;
            o.coverage = Coverage::Conservative;
            const test::WorldGrid got = writtenCells(voxelizeAttributes(tri.view(), f, {}, o));
            const test::GridDiff d = test::compareGrids(got, oracle.cells, &oracle.near);
            EXPECT_TRUE(d.equal()) << "theta " << thetaDeg << " phi " << phiDeg << ": " << d;
            EXPECT_GT(oracle.cells.count(), 11);
            o.slabOverlap = 0.5; // widened: still a superset
            const test::WorldGrid wide = writtenCells(voxelizeAttributes(tri.view(), f, {}, o));
            EXPECT_EQ(test::compareGrids(wide, oracle.cells, &oracle.near).missing, 0);
        }
}

TEST(AttributeGridTest, ChannelsAreStoredOnlyWhenAskedFor) {
    // Two boxes two voxels apart with materials 0 and 1: a voxel's x says whose it is, so the
    // material, ior and attenuation channels must hold that material's values where written (0
    // elsewhere). Each use's channel set holds only its arrays, at the bytes per voxel of the
    // element types (2 count, 4 absorption, 12 normals, 4 id, 4 ior, 12 attenuation).
    Mesh m = test::makeBox({0.1, 0.1, 0.1}, {0.45, 0.9, 0.9});
    test::appendBox(m, {0.55, 0.1, 0.1}, {0.9, 0.9, 0.9});
    std::vector<uint32_t> mat(m.triangleCount(), 0);
    for (size_t t = 12; t < mat.size(); ++t) mat[t] = 1;
    const std::vector<float> absorption(m.triangleCount(), 0.5f);
    const std::vector<AttributeMaterial> table{{1.33f, {0.1f, 0.2f, 0.3f}}, {1.9f, {2.0f, 0.0f, 0.5f}}};
    const Frame f = Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 20, 20, 20);
    AttributeOptions o;
    o.coverage = Coverage::Conservative;
    o.triangleMaterial = mat;
    o.materials = table;
    o.channels = AttributeChannels::all();
    const AttributeGrid all = voxelizeAttributes(m.view(), f, absorption, o);
    const int64_t voxels = 20 * 20 * 20;
    EXPECT_EQ(all.bytes(), uint64_t(voxels) * (2 + 4 + 12 + 4 + 4 + 12));
    int64_t written = 0;
    for (int64_t y = 0; y < 20; ++y)
        for (int64_t x = 0; x < 20; ++x)
            for (int64_t s = 0; s < 20; ++s) {
                const auto i = size_t(all.index(x, y, s));
                if (all.count[i] == 0) {
                    EXPECT_EQ(all.material[i], AttributeGrid::kNoMaterial);
                    EXPECT_EQ(all.ior[i], 0.0f);
                    EXPECT_EQ(all.attenuation[i].y, 0.0f);
                    continue;
                }
                ++written;
                const AttributeMaterial& want = table[x < 10 ? 0 : 1];
                EXPECT_EQ(all.ior[i], want.ior);
                EXPECT_EQ(all.attenuation[i].x, want.attenuation.x);
                EXPECT_EQ(all.attenuation[i].z, want.attenuation.z);
            }
    EXPECT_GT(written, 100);

    o.channels = AttributeChannels::shadows();
    const AttributeGrid shadows = voxelizeAttributes(m.view(), f, absorption, o);
    EXPECT_EQ(shadows.bytes(), uint64_t(voxels) * (2 + 4));
    EXPECT_TRUE(shadows.normalSum.empty() && shadows.material.empty() && shadows.attenuation.empty());
    EXPECT_EQ(shadows.absorption, all.absorption);

    o.channels = AttributeChannels::glass();
    const AttributeGrid glass = voxelizeAttributes(m.view(), f, {}, o);
    EXPECT_EQ(glass.bytes(), uint64_t(voxels) * (12 + 4));
    EXPECT_TRUE(glass.count.empty() && glass.absorption.empty() && glass.ior.empty());
    EXPECT_EQ(glass.occupancy().count(), written); // occupancy from the material id
    EXPECT_EQ(glass.material, all.material);

    AttributeOptions only = o; // the attenuation channel alone still knows first writes
    only.channels = {false, false, false, false, false, true};
    const AttributeGrid att = voxelizeAttributes(m.view(), f, {}, only);
    EXPECT_EQ(att.bytes(), uint64_t(voxels) * 12);
    for (int64_t i = 0; i < voxels; ++i) {
        EXPECT_EQ(att.attenuation[size_t(i)].x, all.attenuation[size_t(i)].x);
        EXPECT_EQ(att.attenuation[size_t(i)].z, all.attenuation[size_t(i)].z);
    }
    EXPECT_THROW(att.occupancy(), Error);

    const std::vector<AttributeMaterial> shortTable{table[0]}; // id 1 is outside it
    only.materials = shortTable;
    EXPECT_THROW(voxelizeAttributes(m.view(), f, {}, only), Error);
    o.slabOverlap = -1;
    EXPECT_THROW(voxelizeAttributes(m.view(), f, {}, o), Error);
    o.slabOverlap = INFINITY;
    EXPECT_THROW(voxelizeAttributeColumns(m.view(), f, absorption, o), Error);
}

} // namespace
} // namespace voxfx
