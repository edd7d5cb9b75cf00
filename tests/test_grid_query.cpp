// Tests of src/grid/grid_query.cpp: column popcounts against a bit-by-bit loop, DDA traversal
// against a per-cell box clip of the segment, volumes against exact mesh volumes, analytic
// frustum volumes and hand-counted cells.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

using test::randomBits;

TEST(GridQueryTest, ColumnRangeCountMatchesBitLoopForAllDepthsAndRanges) {
    for (const int64_t D : {1, 5, 63, 64, 65, 127, 128, 129, 200}) {
        const BitGrid g = randomBits(3, 2, D, 0.5, uint64_t(D));
        for (int64_t y = 0; y < 2; ++y)
            for (int64_t x = 0; x < 3; ++x)
                for (int64_t s0 = -2; s0 <= D + 1; s0 += (D > 70 ? 7 : 1))
                    for (int64_t s1 = -1; s1 <= D + 2; s1 += (D > 70 ? 5 : 1)) {
                        int64_t expected = 0;
                        for (int64_t s = std::max<int64_t>(0, s0); s < std::min(s1, D); ++s)
                            expected += g.get(x, y, s);
                        ASSERT_EQ(countColumnRange(g, x, y, s0, s1), expected)
                            << "D " << D << " column " << x << "," << y << " range [" << s0 << ", " << s1
                            << ")";
                    }
    }
}

// Reference: the segment clipped to one cell's box [c, c+1)^3, following the documented
// half-open rule for segments lying in a plane between cells. Returns the parameter length.
double clipToCell(const Vec3d& a, const Vec3d& d, const int64_t c[3]) {
    double t0 = 0, t1 = 1;
    for (int i = 0; i < 3; ++i) {
        const double lo = double(c[i]), hi = double(c[i] + 1);
        if (d[i] == 0) {
            if (!(a[i] >= lo && a[i] < hi)) return 0;
            continue;
        }
        double ta = (lo - a[i]) / d[i], tb = (hi - a[i]) / d[i];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return std::max(0.0, t1 - t0);
}

struct NaiveTrace {
    SegmentHits hits;
    bool ambiguous = false; // some cell is touched with a length too small to classify
};

NaiveTrace naiveTrace(const BitGrid& g, const Vec3d& a, const Vec3d& b) {
    NaiveTrace r;
    const Vec3d d = b - a;
    const double L = length(d);
    r.hits.length = L;
    for (int64_t s = 0; s < g.depth(); ++s)
        for (int64_t y = 0; y < g.height(); ++y)
            for (int64_t x = 0; x < g.width(); ++x) {
                const int64_t c[3] = {x, y, s};
                const double t = clipToCell(a, d, c);
                if (t > 0 && t < 1e-9) r.ambiguous = true;
                if (!(t > 0)) continue;
                ++r.hits.cellsVisited;
                if (g.get(x, y, s)) {
                    ++r.hits.filledCells;
                    r.hits.filledLength += t * L;
                }
            }
    return r;
}

void expectSameHits(const SegmentHits& got, const SegmentHits& want, const std::string& what) {
    EXPECT_EQ(got.cellsVisited, want.cellsVisited) << what;
    EXPECT_EQ(got.filledCells, want.filledCells) << what;
    // Both sum the same per-cell parameter intervals; they differ only by rounding.
    EXPECT_NEAR(got.filledLength, want.filledLength, 1e-9 * (1 + want.length)) << what;
    EXPECT_DOUBLE_EQ(got.length, want.length) << what;
}

TEST(GridQueryTest, SegmentTraversalMatchesPerCellClipOnRandomGrids) {
    // Sizes that are not multiples of 64 in depth, and thin grids.
    const int64_t sizes[][3] = {{13, 9, 70}, {1, 1, 130}, {7, 1, 65}, {5, 6, 64}};
    std::mt19937_64 rng(7);
    int checked = 0;
    for (const auto& n : sizes) {
        const BitGrid g = randomBits(n[0], n[1], n[2], 0.4, uint64_t(n[0] * 1000 + n[2]));
        std::uniform_real_distribution<double> ux(-3.0, double(n[0]) + 3), uy(-3.0, double(n[1]) + 3),
            uz(-3.0, double(n[2]) + 3);
        for (int i = 0; i < 150; ++i) {
            Vec3d a{ux(rng), uy(rng), uz(rng)}, b{ux(rng), uy(rng), uz(rng)};
            // Every third segment is parallel to an axis, at integer (between-cell) or generic offsets.
            if (i % 3 == 1) {
                const int axis = i % 9 == 1 ? 2 : (i % 9 == 4 ? 0 : 1);
                for (int k = 0; k < 3; ++k)
                    if (k != axis) b[k] = a[k] = (i % 2) ? std::floor(a[k]) : a[k];
            }
            const NaiveTrace want = naiveTrace(g, a, b);
            if (want.ambiguous) continue;
            ++checked;
            expectSameHits(traceSegmentGrid(g, a, b), want.hits,
                           detail::concat("grid ", n[0], "x", n[1], "x", n[2], " segment ", i));
        }
    }
    EXPECT_GT(checked, 500);
}

TEST(GridQueryTest, QueriesMatchTheReferencesOnAVoxelizedMesh) {
    VOXFX_REQUIRE_DATA("meshes/knot1.off");
    const std::string path = test::dataPath("meshes/knot1.off");
    const Mesh knot = loadMesh(path);
    FitOptions fit;
    fit.resolution = 37;
    fit.axis = Axis::Y;
    const VoxelGrid g = voxelize(knot.view(), fitFrame(computeBounds(knot.view()), fit));
    const BitGrid& b = g.bits;
    for (int64_t y = 0; y < b.height(); ++y)
        for (int64_t x = 0; x < b.width(); ++x) {
            int64_t expected = 0;
            for (int64_t s = 3; s < b.depth() - 2; ++s) expected += b.get(x, y, s);
            ASSERT_EQ(countColumnRange(b, x, y, 3, b.depth() - 2), expected) << x << "," << y;
        }
    std::mt19937_64 rng(21);
    std::uniform_real_distribution<double> u(-2.0, 40.0);
    int checked = 0, hitSolid = 0;
    for (int i = 0; i < 40; ++i) {
        const Vec3d a{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
        const NaiveTrace want = naiveTrace(b, a, c);
        if (want.ambiguous) continue;
        ++checked;
        hitSolid += want.hits.filledCells > 0;
        expectSameHits(traceSegmentGrid(b, a, c), want.hits, detail::concat("segment ", i));
    }
    EXPECT_GT(checked, 30);
    EXPECT_GT(hitSolid, 5);
}

// filledCellIndices / filledCellCenters against the definition: every (i, j, k) in i, j, k order
// with atWorldIndex set, centres lo + (index + 0.5) * cell; every slicing axis, depths around a
// word, any thread count. filledAt against atWorldIndex of the floored grid coordinates.
TEST(GridQueryTest, FilledCellsAndLookupsMatchTheCellByCellDefinition) {
    const Box3d box{{-1.5, 0.25, 3}, {2.5, 1.25, 7}};
    for (const Axis axis : {Axis::X, Axis::Y, Axis::Z})
        for (const Vec3i dims : {Vec3i{5, 7, 63}, Vec3i{9, 3, 65}, Vec3i{64, 2, 1}}) {
            const VoxelGrid g = test::randomVoxelGrid(box, axis, dims, 0.3, uint64_t(dims.x * 7 + int(axis)));
            std::vector<int32_t> expected;
            std::vector<double> centres;
            const Vec3d cell = g.frame.cellSize();
            for (int64_t i = 0; i < dims.x; ++i)
                for (int64_t j = 0; j < dims.y; ++j)
                    for (int64_t k = 0; k < dims.z; ++k)
                        if (g.atWorldIndex(i, j, k)) {
                            const int64_t ijk[3] = {i, j, k};
                            for (int a = 0; a < 3; ++a) {
                                expected.push_back(int32_t(ijk[a]));
                                centres.push_back(box.lo[a] + (double(ijk[a]) + 0.5) * cell[a]);
                            }
                        }
            ASSERT_EQ(int64_t(expected.size()), 3 * g.bits.count());
            for (const int threads : {1, 3}) {
                std::vector<int32_t> got(expected.size());
                filledCellIndices(g, got, threads);
                EXPECT_EQ(got, expected) << toString(axis) << " " << threads;
                std::vector<double> c(expected.size());
                filledCellCenters(g, c, threads);
                EXPECT_EQ(c, centres) << toString(axis);
            }
            std::vector<float> cf(expected.size());
            filledCellCenters(g, cf);
            for (std::size_t n = 0; n < cf.size(); ++n) ASSERT_EQ(cf[n], float(centres[n]));
            std::vector<int32_t> small(expected.size() + 3);
            EXPECT_THROW(filledCellIndices(g, small), Error);

            std::mt19937_64 rng(5);
            std::uniform_real_distribution<double> u(-0.2, 1.2);
            std::vector<Vec3d> pts;
            for (int n = 0; n < 4000; ++n)
                pts.push_back(box.lo + Vec3d{u(rng) * box.extent().x, u(rng) * box.extent().y,
                                             u(rng) * box.extent().z});
            pts.push_back(box.lo);                 // a corner: cell (0, 0, 0)
            pts.push_back(box.hi);                 // the far corner: outside
            pts.push_back({std::nan(""), 0.5, 4}); // not finite: outside
            std::vector<uint8_t> at(pts.size());
            filledAt(g, pts, at, 2);
            for (std::size_t n = 0; n < pts.size(); ++n) {
                Vec3i idx;
                bool in = true;
                for (int a = 0; a < 3; ++a) {
                    const double q = std::floor((pts[n][a] - box.lo[a]) / cell[a]);
                    in = in && q >= 0 && q < double(dims[a]);
                    idx[a] = in ? int64_t(q) : 0;
                }
                ASSERT_EQ(bool(at[n]), in && g.atWorldIndex(idx.x, idx.y, idx.z)) << n;
            }
            EXPECT_EQ(at[pts.size() - 3], g.atWorldIndex(0, 0, 0));
            EXPECT_EQ(at[pts.size() - 2], 0);
            EXPECT_EQ(at[pts.size() - 1], 0);
        }
}

TEST(GridQueryTest, SegmentTraversalHandCases) {
    BitGrid g(4, 4, 4);
    g.set(1, 1, 1);
    // The main diagonal of cell (1,1,1): length sqrt(3), one filled cell among 1 visited.
    SegmentHits h = traceSegmentGrid(g, {1, 1, 1}, {2, 2, 2});
    EXPECT_EQ(h.filledCells, 1);
    EXPECT_NEAR(h.filledLength, std::sqrt(3.0), 1e-12);
    // Straight through along x at the cell's centre line: 4 cells visited, 1 filled, length 1.
    h = traceSegmentGrid(g, {-1, 1.5, 1.5}, {5, 1.5, 1.5});
    EXPECT_EQ(h.cellsVisited, 4);
    EXPECT_EQ(h.filledCells, 1);
    EXPECT_NEAR(h.filledLength, 1.0, 1e-12);
    EXPECT_NEAR(h.length, 6.0, 1e-12);
    // Along a column (the popcount path), half of the filled cell.
    h = traceSegmentGrid(g, {1.5, 1.5, 1.5}, {1.5, 1.5, 3.25});
    EXPECT_EQ(h.cellsVisited, 3);
    EXPECT_NEAR(h.filledLength, 0.5, 1e-12);
    // Zero length, NaN and a miss give zeros.
    EXPECT_EQ(traceSegmentGrid(g, {1.5, 1.5, 1.5}, {1.5, 1.5, 1.5}).cellsVisited, 0);
    EXPECT_EQ(traceSegmentGrid(g, {NAN, 1, 1}, {2, 2, 2}).cellsVisited, 0);
    EXPECT_EQ(traceSegmentGrid(g, {-2, -2, -2}, {-1, 9, 9}).cellsVisited, 0);
}

TEST(GridQueryTest, WorldSegmentLengthsUseWorldUnits) {
    // Non-cubic cells (2 x 0.5 x 1 world units), sliced along x.
    const Box3d box{{0, 0, 0}, {8, 2, 4}};
    VoxelGrid g{Frame::orthographic(box, Axis::X, 4, 4, 4), BitGrid(4, 4, 4)};
    // Fill every cell: the filled length equals the clipped world length.
    for (int64_t y = 0; y < 4; ++y)
        for (int64_t x = 0; x < 4; ++x)
            for (int64_t s = 0; s < 4; ++s) g.bits.set(x, y, s);
    const Vec3d a{-1, 0.7, 1.3}, b{9, 1.1, 2.9};
    const SegmentHits h = traceSegment(g, a, b);
    // Inside the box for world x in [0, 8] of [-1, 9]: 80% of the segment.
    EXPECT_NEAR(h.length, length(b - a), 1e-12);
    EXPECT_NEAR(h.filledLength, 0.8 * length(b - a), 1e-9);
    EXPECT_NEAR(h.filledFraction(), 0.8, 1e-12);
    Frame persp = Frame::perspective({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 1.0, 4, 4, 1, 10, 4);
    EXPECT_THROW(traceSegment(VoxelGrid{persp, BitGrid(4, 4, 4)}, a, b), Error);
}

TEST(GridQueryTest, VolumeOfBoxOnCellBoundariesIsExact) {
    // Faces on cell boundaries of a 16^3 grid with cell 0.25: 8^3 cells of 1/64.
    const Mesh box = test::makeBox({0.5, 0.5, 0.5}, {2.5, 2.5, 2.5});
    const Frame f = Frame::orthographic({{0, 0, 0}, {4, 4, 4}}, Axis::Y, 16, 16, 16);
    EXPECT_DOUBLE_EQ(filledVolume(voxelize(box.view(), f)), 8.0);
}

TEST(GridQueryTest, VolumeOfVoxelizedSphereConvergesToTheMeshVolume) {
    // A finely tessellated sphere; its polyhedron's exact volume is the target. A cell centre
    // is misclassified only within half a cell diagonal of the surface, so the error is bounded
    // by area * sqrt(3)/2 * h and in practice shrinks ~h^2 (errors cancel).
    const Mesh sphere = test::makeUvSphere({0.1, -0.2, 0.3}, 1.0, 64, 128);
    const double exact = test::meshVolume(sphere.view());
    ASSERT_NEAR(exact, 4.0 / 3.0 * M_PI, 0.01); // sanity: the polyhedron is close to the sphere
    double previous = 1e9;
    for (const int64_t n : {16, 32, 64, 128}) {
        FitOptions fo;
        fo.resolution = n;
        const VoxelGrid g = voxelize(sphere.view(), fitFrame(computeBounds(sphere.view()), fo));
        const double h = g.frame.cellSize().x;
        const double err = std::fabs(filledVolume(g) - exact);
        EXPECT_LT(err, 4 * M_PI * std::sqrt(3.0) / 2 * h) << "resolution " << n;
        EXPECT_LT(err, previous) << "resolution " << n;
        previous = err;
    }
    EXPECT_LT(previous / exact, 0.002);
}

TEST(GridQueryTest, VolumeOfFullPerspectiveAndLocallySlicedGridsIsAnalytic) {
    // A full perspective grid is the frustum between near and far: (A(far) far - A(near) near) / 3
    // with A(z) = (2 z tan(fovX/2)) (2 z tan(fovY/2)); tan(fovX/2) = tan(fovY/2) * W / H.
    const int64_t W = 6, H = 4, D = 70;
    const double fov = 0.8, nearZ = 2, farZ = 9;
    VoxelGrid p{Frame::perspective({1, 2, 3}, {1, 2, 10}, {0, 1, 0}, fov, W, H, nearZ, farZ, D),
                BitGrid(W, H, D)};
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x)
            for (int64_t s = 0; s < D; ++s) p.bits.set(x, y, s);
    const double ty = std::tan(fov / 2), tx = ty * double(W) / double(H);
    const double frustum = 4 * tx * ty * (farZ * farZ * farZ - nearZ * nearZ * nearZ) / 3;
    EXPECT_NEAR(filledVolume(p), frustum, 1e-9 * frustum);

    // Local slicing: column c spans [near_c, far_c] in slice units of the uniform slicing.
    VoxelGrid l{Frame::orthographic({{0, 0, 0}, {2, 3, 4}}, Axis::Z, 2, 3, 8), BitGrid(2, 3, 8)};
    std::vector<double> nearC(6), farC(6);
    double expected = 0;
    for (int c = 0; c < 6; ++c) {
        nearC[size_t(c)] = 0.5 * c;
        farC[size_t(c)] = 0.5 * c + 1 + c; // thickness 1 + c uniform slices = (1 + c) * 0.5 world
        for (int64_t s = 0; s < 8; ++s) l.bits.set(c % 2, c / 2, s);
        expected += 1.0 * (1 + c) * 0.5; // area 1 x 1, thickness (1 + c) * 0.5
    }
    l.frame.setLocalSlicing(nearC, farC);
    EXPECT_NEAR(filledVolume(l), expected, 1e-12);
}

} // namespace
} // namespace voxfx
