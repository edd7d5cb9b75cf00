// Tests of src/grid/density.cpp and density_io.cpp: block counts against a cell-by-cell loop on
// random grids (odd sizes, depths around multiples of 64) and on a voxelized mesh, every level,
// gradients against central differences of the naive counts, normals of a sphere against its
// radial direction, trilinear sampling, the octahedral code, and the files read back.
#include <cmath>
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include "grid/density_kernels.hpp"
#include "test_util.hpp"
#include "voxfx/density.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

using test::randomBits;

// Naive density: every fine cell adds itself to its block's count.
struct NaiveDensity {
    int64_t w, h, d;
    std::vector<uint64_t> counts;
    uint64_t at(int64_t x, int64_t y, int64_t s) const {
        if (x < 0 || y < 0 || s < 0 || x >= w || y >= h || s >= d) return 0;
        return counts[size_t((y * w + x) * d + s)];
    }
};

NaiveDensity naiveDensity(const BitGrid& g, int level) {
    const int64_t k = int64_t(1) << level;
    NaiveDensity n{(g.width() + k - 1) / k, (g.height() + k - 1) / k, (g.depth() + k - 1) / k, {}};
    n.counts.assign(size_t(n.w * n.h * n.d), 0);
    for (int64_t y = 0; y < g.height(); ++y)
        for (int64_t x = 0; x < g.width(); ++x)
            for (int64_t s = 0; s < g.depth(); ++s)
                if (g.get(x, y, s)) ++n.counts[size_t(((y / k) * n.w + x / k) * n.d + s / k)];
    return n;
}

::testing::AssertionResult sameCounts(const DensityGrid& got, const NaiveDensity& want) {
    if (got.width() != want.w || got.height() != want.h || got.depth() != want.d)
        return ::testing::AssertionFailure()
               << "size " << got.width() << "x" << got.height() << "x" << got.depth() << ", expected "
               << want.w << "x" << want.h << "x" << want.d;
    for (int64_t y = 0; y < want.h; ++y)
        for (int64_t x = 0; x < want.w; ++x) {
            for (int64_t s = 0; s < want.d; ++s)
                if (got.count(x, y, s) != want.at(x, y, s))
                    return ::testing::AssertionFailure()
                           << "cell " << x << "," << y << "," << s << ": " << got.count(x, y, s)
                           << ", expected " << want.at(x, y, s);
            // Padding lanes above D' stay zero.
            const uint64_t last = got.column(x, y)[got.wordsPerColumn() - 1];
            const int64_t used = want.d - (got.wordsPerColumn() - 1) * got.lanesPerWord();
            const int b = got.laneBits();
            if (used * b < 64 && (last >> (used * b)) != 0)
                return ::testing::AssertionFailure() << "nonzero padding in column " << x << "," << y;
        }
    return ::testing::AssertionSuccess();
}

TEST(DensityTest, Level1MatchesBlockCountsOnRandomGridsOfAwkwardSizes) {
    // Deep columns too: the vectorized path takes four input words at a time, then a tail.
    const int64_t sizes[][3] = {{1, 1, 1},    {5, 3, 1},   {7, 9, 63},  {4, 4, 64},
                                {3, 5, 65},   {2, 2, 130}, {9, 1, 129}, {6, 7, 31},
                                {11, 4, 200}, {2, 3, 512}, {3, 5, 600}, {5, 2, 1001}};
    for (const auto& n : sizes)
        for (const double fill : {0.1, 0.5, 1.0}) {
            const BitGrid g = randomBits(n[0], n[1], n[2], fill, uint64_t(n[0] * 7 + n[2]));
            const DensityGrid d = computeDensity(g);
            EXPECT_TRUE(sameCounts(d, naiveDensity(g, 1)))
                << n[0] << "x" << n[1] << "x" << n[2] << " fill " << fill;
            EXPECT_EQ(d.total(), uint64_t(g.count()));
        }
}

TEST(DensityTest, CallerOwnedOutputIsReusedAndOverwritten) {
    const BitGrid g = randomBits(9, 7, 100, 0.5, 17);
    DensityGrid out = computeDensity(randomBits(9, 7, 100, 0.9, 18)); // stale counts, right size
    const uint64_t* reused = out.words();
    computeDensity(g, out);
    EXPECT_EQ(out.words(), reused);
    EXPECT_TRUE(sameCounts(out, naiveDensity(g, 1)));
    DensityOptions o;
    o.level = 2;
    computeDensity(g, out, o); // other level: replaced
    EXPECT_TRUE(sameCounts(out, naiveDensity(g, 2)));
}

TEST(DensityTest, LargerKernelsByRepetitionMatchBlockCounts) {
    for (int level = 2; level <= 5; ++level) {
        const BitGrid g = randomBits(37, 21, 150 + level * 30, 0.6, uint64_t(level));
        DensityOptions o;
        o.level = level;
        const DensityGrid d = computeDensity(g, o);
        EXPECT_EQ(d.level(), level);
        EXPECT_EQ(d.laneBits(), 2 << level);
        EXPECT_TRUE(sameCounts(d, naiveDensity(g, level))) << "level " << level;
        // coarsenDensity goes one level up from the level below: the same block counts.
        o.level = level - 1;
        const DensityGrid coarsened = coarsenDensity(computeDensity(g, o));
        EXPECT_EQ(coarsened.level(), level);
        EXPECT_TRUE(sameCounts(coarsened, naiveDensity(g, level))) << "coarsened to level " << level;
    }
    // A full 32^3 block reaches the largest count of level 5.
    BitGrid full(32, 32, 32);
    for (int64_t c = 0; c < full.wordCount(); ++c) full.words()[c] = ~uint64_t(0) >> 32;
    DensityOptions o;
    o.level = 5;
    EXPECT_EQ(computeDensity(full, o).count(0, 0, 0), 32768u);
    o.level = 6;
    EXPECT_THROW(computeDensity(full, o), Error);
}

// The word kernels alone (density_kernels.hpp), called the way a device back end calls them: one
// (output column, input word) item at a time, in reverse order, each writing only its own words,
// with neither the AVX2 path nor the row loops of density.cpp. Every level against the naive
// counts, on depths around multiples of 64 (the odd output word of a column's last input word).
TEST(DensityTest, WordKernelsAloneGiveTheBlockCountsInAnyOrder) {
    const int64_t sizes[][3] = {{1, 1, 1}, {5, 3, 63}, {3, 5, 65}, {9, 1, 129}, {2, 3, 512}, {7, 4, 1001}};
    for (const auto& n : sizes) {
        const BitGrid g = randomBits(n[0], n[1], n[2], 0.6, uint64_t(n[0] * 13 + n[2]));
        DensityGrid cur(1, (n[0] + 1) / 2, (n[1] + 1) / 2, (n[2] + 1) / 2);
        const int64_t P = g.wordsPerColumn(), Po = cur.wordsPerColumn();
        for (int64_t item = cur.columnCount() * P - 1; item >= 0; --item) {
            const int64_t c = item / P, k = item % P;
            const detail::DensityColumnBlock blk(g.words(), g.width(), g.height(), P, c % cur.width(),
                                                 c / cur.width());
            uint64_t lo, hi;
            detail::densityLevel1Words(blk, k, lo, hi);
            uint64_t* o = cur.words() + c * Po;
            o[2 * k] = lo;
            if (2 * k + 1 < Po)
                o[2 * k + 1] = hi;
            else
                EXPECT_EQ(hi, 0u) << "past the column";
        }
        EXPECT_TRUE(sameCounts(cur, naiveDensity(g, 1))) << n[0] << "x" << n[1] << "x" << n[2];
        while (cur.level() < 5) {
            DensityGrid next(cur.level() + 1, (cur.width() + 1) / 2, (cur.height() + 1) / 2,
                             (cur.depth() + 1) / 2);
            const int64_t Pi = cur.wordsPerColumn();
            ASSERT_EQ(next.wordsPerColumn(), Pi);
            const uint64_t even = detail::densityEvenLanes(cur.laneBits());
            for (int64_t item = next.columnCount() * Pi - 1; item >= 0; --item) {
                const int64_t c = item / Pi, k = item % Pi;
                const detail::DensityColumnBlock blk(cur.words(), cur.width(), cur.height(), Pi,
                                                     c % next.width(), c / next.width());
                next.words()[c * Pi + k] = detail::densityCoarsenWord(blk, k, cur.laneBits(), even);
            }
            cur = std::move(next);
            EXPECT_TRUE(sameCounts(cur, naiveDensity(g, cur.level())))
                << n[0] << "x" << n[1] << "x" << n[2] << " level " << cur.level();
        }
    }
}

TEST(DensityTest, VoxelizedMeshDensityMatchesBlockCountsForAnyThreadCount) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const std::string path = test::dataPath("meshes/bunny00.off");
    const Mesh bunny = loadMesh(path);
    FitOptions fit;
    fit.resolution = 77; // odd, and not a multiple of 64
    const VoxelGrid g = voxelize(bunny.view(), fitFrame(computeBounds(bunny.view()), fit));
    DensityOptions o;
    o.threads = 1;
    const DensityGrid one = computeDensity(g.bits, o);
    o.threads = 2;
    EXPECT_EQ(computeDensity(g.bits, o), one);
    EXPECT_TRUE(sameCounts(one, naiveDensity(g.bits, 1)));
    o.level = 3;
    EXPECT_TRUE(sameCounts(computeDensity(g.bits, o), naiveDensity(g.bits, 3)));
}

TEST(DensityTest, GradientIsTheCentralDifferenceOfBlockCounts) {
    const BitGrid g = randomBits(13, 10, 70, 0.5, 3);
    const DensityGrid d = computeDensity(g);
    const NaiveDensity n = naiveDensity(g, 1);
    for (int64_t y = 0; y < n.h; ++y)
        for (int64_t x = 0; x < n.w; ++x)
            for (int64_t s = 0; s < n.d; ++s) {
                const Vec3f grad = densityGradient(d, x, y, s);
                const Vec3d want{0.5 * (double(n.at(x + 1, y, s)) - double(n.at(x - 1, y, s))),
                                 0.5 * (double(n.at(x, y + 1, s)) - double(n.at(x, y - 1, s))),
                                 0.5 * (double(n.at(x, y, s + 1)) - double(n.at(x, y, s - 1)))};
                ASSERT_EQ(Vec3d(grad), want) << x << "," << y << "," << s; // halves of small integers: exact
                const Vec3f nrm = densityNormal(d, x, y, s);
                if (dot(want, want) == 0) {
                    EXPECT_EQ(nrm, Vec3f{});
                } else {
                    EXPECT_NEAR(length(nrm), 1.0f, 1e-6f);
                    EXPECT_NEAR(dot(Vec3d(nrm), normalize(-want)), 1.0, 1e-6);
                }
            }
}

TEST(DensityTest, NormalsOfAVoxelizedSpherePointRadiallyOutwards) {
    // Sphere of radius 40 fine cells centred on a grid corner (20 density cells). What bounds the
    // angle to the radial direction is the estimator, not the placement: the 2 x 2 x 2 box is
    // only as wide as the central-difference step (one density cell each way), so on a surface
    // that is not axis-aligned the neighbours' counts saturate at 0 or 8 and the gradient's
    // components stop being proportional to the normal's. Investigated for a reported ~10 degree
    // error: the mean per-cell error is 10.3-10.5 degrees at R = 20, 40 and 80 (it does not
    // shrink with R, as a resolution or half-cell placement error would), it is smallest with
    // the radial direction taken exactly at the density cell centre (shifting that point by
    // +-0.5 or +-1 fine cell along the diagonal only increases it, symmetrically), and the
    // voxelized solid's centroid is the sphere's centre to 1e-12. Interpolated normals
    // (sampleNormal) at points on the sphere are better: 6.2-6.4 degrees mean, ~22 worst. So
    // the bounds below are those measurements plus a margin; a sign error gives ~180 degrees and
    // an axis swap tens of degrees. (A half-cell offset barely moves these means at R = 40, so
    // the density frame's placement is checked exactly in OccupancyFieldAndWorldFrame.)
    const double R = 40;
    const Mesh sphere = test::makeUvSphere({0, 0, 0}, R, 128, 256);
    const Frame f = Frame::orthographic({{-48, -48, -48}, {48, 48, 48}}, Axis::Z, 96, 96, 96);
    const VoxelGrid g = voxelize(sphere.view(), f);
    const DensityGrid d = computeDensity(g.bits);
    const Frame coarse = densityFrame(f, 1);
    auto degrees = [](const Vec3d& a, const Vec3d& b) {
        return std::acos(std::clamp(dot(a, b), -1.0, 1.0)) * 180 / M_PI;
    };
    double sumAngle = 0, worst = 0;
    int64_t n = 0;
    for (int64_t y = 0; y < d.height(); ++y)
        for (int64_t x = 0; x < d.width(); ++x)
            for (int64_t s = 0; s < d.depth(); ++s) {
                const uint64_t c = d.count(x, y, s);
                if (c == 0 || c == 8) continue;
                const Vec3d radial = normalize(coarse.cellCenter(x, y, s));
                const double angle =
                    degrees(radial, worldFromGridNormal(coarse, Vec3d(densityNormal(d, x, y, s))));
                sumAngle += angle;
                worst = std::max(worst, angle);
                ++n;
            }
    ASSERT_GT(n, 3000);
    EXPECT_LT(sumAngle / double(n), 12.0) << n << " cells";
    EXPECT_LT(worst, 35.0) << n << " cells";
    // Interpolated normals at points on the sphere, placed through the frame's own map.
    std::mt19937_64 rng(21);
    std::normal_distribution<double> gauss;
    double sumSampled = 0, worstSampled = 0;
    const int samples = 4000;
    for (int i = 0; i < samples; ++i) {
        const Vec3d u = normalize(Vec3d{gauss(rng), gauss(rng), gauss(rng)});
        const Vec3d nrm = worldFromGridNormal(coarse, Vec3d(sampleNormal(d, coarse.gridFromWorld(u * R))));
        const double angle = degrees(u, nrm);
        sumSampled += angle;
        worstSampled = std::max(worstSampled, angle);
    }
    EXPECT_LT(sumSampled / samples, 8.0);
    EXPECT_LT(worstSampled, 30.0);
}

TEST(DensityTest, TrilinearSamplesInterpolateBetweenCellCentres) {
    // Expected values from the naive block counts: occupancy count / 8, the normal against the
    // central difference.
    const BitGrid g = randomBits(9, 8, 40, 0.5, 11);
    const DensityGrid d = computeDensity(g);
    const NaiveDensity n = naiveDensity(g, 1);
    std::mt19937_64 rng(5);
    for (int i = 0; i < 200; ++i) {
        const int64_t x = int64_t(rng() % 4), y = int64_t(rng() % 3), s = int64_t(rng() % 19);
        // At a centre: the cell's own values.
        const Vec3d c{double(x) + 0.5, double(y) + 0.5, double(s) + 0.5};
        EXPECT_FLOAT_EQ(sampleOccupancy(d, c), float(n.at(x, y, s)) / 8.0f);
        const Vec3d grad{double(n.at(x + 1, y, s)) - double(n.at(x - 1, y, s)),
                         double(n.at(x, y + 1, s)) - double(n.at(x, y - 1, s)),
                         double(n.at(x, y, s + 1)) - double(n.at(x, y, s - 1))};
        const Vec3d want = dot(grad, grad) == 0 ? Vec3d{} : normalize(-grad);
        EXPECT_NEAR(length(Vec3d(sampleNormal(d, c)) - want), 0.0, 1e-6);
        // A quarter of the way to the next centre along each axis: hand-written trilinear weights.
        const Vec3d p = c + Vec3d{0.25, 0.5, 0.75};
        double want3 = 0;
        for (int k = 0; k < 8; ++k) {
            const double w = ((k & 1) ? 0.25 : 0.75) * ((k & 2) ? 0.5 : 0.5) * ((k & 4) ? 0.75 : 0.25);
            want3 += w * double(n.at(x + (k & 1), y + ((k >> 1) & 1), s + ((k >> 2) & 1))) / 8.0;
        }
        EXPECT_NEAR(sampleOccupancy(d, p), want3, 1e-6);
    }
    EXPECT_EQ(sampleOccupancy(d, {-5, 1, 1}), 0.0f);
    EXPECT_EQ(sampleNormal(d, {NAN, 1, 1}), Vec3f{});
}

TEST(DensityTest, OctahedralNormalCodeIsWithinOneDegree) {
    std::mt19937_64 rng(9);
    std::normal_distribution<float> gauss;
    double worst = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3f n = normalize(Vec3f{gauss(rng), gauss(rng), gauss(rng)});
        const uint16_t code = encodeNormalOct16(n);
        ASSERT_NE(code, kNoNormal);
        const Vec3f back = decodeNormalOct16(code);
        worst = std::max(worst, std::acos(std::clamp(double(dot(n, back)), -1.0, 1.0)) * 180 / M_PI);
    }
    EXPECT_LT(worst, 1.0);
    for (const Vec3f axis : {Vec3f{1, 0, 0}, Vec3f{0, -1, 0}, Vec3f{0, 0, 1}, Vec3f{0, 0, -1}})
        EXPECT_NEAR(length(decodeNormalOct16(encodeNormalOct16(axis)) - axis), 0.0f, 1e-6f);
    EXPECT_EQ(encodeNormalOct16({}), kNoNormal);
    EXPECT_EQ(decodeNormalOct16(kNoNormal), Vec3f{});
    // Per-cell codes decode to the cells' normals (within the code's precision).
    const DensityGrid d = computeDensity(randomBits(6, 5, 33, 0.5, 2));
    const std::vector<uint16_t> codes = quantizedNormals(d);
    ASSERT_EQ(int64_t(codes.size()), d.cellCount());
    for (int64_t y = 0; y < d.height(); ++y)
        for (int64_t x = 0; x < d.width(); ++x)
            for (int64_t s = 0; s < d.depth(); ++s) {
                const Vec3f want = densityNormal(d, x, y, s);
                const Vec3f got = decodeNormalOct16(codes[size_t((y * d.width() + x) * d.depth() + s)]);
                EXPECT_LT(length(got - want), 0.02f);
            }
}

TEST(DensityTest, OccupancyFieldAndWorldFrame) {
    const BitGrid g = randomBits(5, 6, 9, 0.5, 4);
    const DensityGrid d = computeDensity(g);
    const NaiveDensity want = naiveDensity(g, 1);
    const std::vector<float> occ = occupancyField(d);
    ASSERT_EQ(int64_t(occ.size()), want.w * want.h * want.d);
    for (int64_t y = 0; y < want.h; ++y)
        for (int64_t x = 0; x < want.w; ++x)
            for (int64_t s = 0; s < want.d; ++s)
                EXPECT_EQ(occ[size_t((y * want.w + x) * want.d + s)], float(want.at(x, y, s)) / 8.0f);
    std::vector<float> small(3);
    EXPECT_THROW(occupancyField(d, small), Error);
    // A density cell's centre is the centre of its 2 x 2 x 2 fine block.
    const Frame fine = Frame::orthographic({{1, 2, 3}, {6, 8, 12}}, Axis::X, 6, 9, 5);
    const Frame coarse = densityFrame(fine, 1);
    const Vec3d blockCentre = (fine.cellCenter(2, 4, 0) + fine.cellCenter(3, 5, 1)) * 0.5;
    EXPECT_NEAR(length(coarse.cellCenter(1, 2, 0) - blockCentre), 0.0, 1e-12);
}

// The raw samples of a NRRD written by writeDensity (header up to the blank line).
std::vector<uint8_t> nrrdSamples(const std::string& path) {
    const std::string all = test::readFileBytes(path);
    const size_t end = all.find("\n\n");
    if (end == std::string::npos) {
        ADD_FAILURE() << path << ": no blank line ends the header";
        return {};
    }
    return std::vector<uint8_t>(all.begin() + std::ptrdiff_t(end + 2), all.end());
}

TEST(DensityTest, FilesHoldTheCountsInWorldOrder) {
    test::TempDir dir;
    // Sliced along y, so world order differs from the column order.
    const VoxelGrid g = test::randomVoxelGrid({{0, 0, 0}, {7, 5, 9}}, Axis::Y, {7, 5, 9}, 0.4, 8);
    const DensityGrid d = computeDensity(g.bits);
    const std::string nrrd = dir.file("d.nrrd"), vdb = dir.file("d.vdb");
    writeDensity(d, g.frame, nrrd);
    writeDensity(d, g.frame, vdb);
    const Frame coarse = densityFrame(g.frame, 1);
    const Vec3i n = VoxelGrid{coarse, {}}.worldDims();
    const std::vector<uint8_t> samples = nrrdSamples(nrrd);
    ASSERT_EQ(int64_t(samples.size()), n.x * n.y * n.z);
    const NaiveDensity want = naiveDensity(g.bits, 1);
    for (int64_t k = 0; k < n.z; ++k)
        for (int64_t j = 0; j < n.y; ++j)
            for (int64_t i = 0; i < n.x; ++i) {
                // Axis Y: columns run along (z, x), slices along y.
                EXPECT_EQ(samples[size_t((k * n.y + j) * n.x + i)], want.at(k, i, j))
                    << i << "," << j << "," << k;
            }
    // The .vdb with plain OpenVDB: a float fog volume of count / 8 at world indices, its index
    // space centred on the density cells (2 x 2 x 2 fine cells of 1).
    {
        openvdb::initialize();
        openvdb::io::File file(vdb);
        file.open(/*delayLoad=*/false);
        const openvdb::GridBase::Ptr base = file.readGrid("density");
        file.close();
        const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
        ASSERT_TRUE(grid);
        auto acc = grid->getConstAccessor();
        int64_t wrong = 0, active = 0, misplaced = 0;
        for (int64_t k = 0; k < n.z; ++k)
            for (int64_t j = 0; j < n.y; ++j)
                for (int64_t i = 0; i < n.x; ++i) {
                    const openvdb::Coord ijk{int(i), int(j), int(k)};
                    wrong += acc.getValue(ijk) != float(want.at(k, i, j)) / 8.0f;
                    active += acc.isValueOn(ijk);
                    const openvdb::Vec3d w = grid->transform().indexToWorld(ijk);
                    misplaced += std::abs(w.x() - (2.0 * double(i) + 1)) > 1e-12 ||
                                 std::abs(w.y() - (2.0 * double(j) + 1)) > 1e-12 ||
                                 std::abs(w.z() - (2.0 * double(k) + 1)) > 1e-12;
                }
        EXPECT_EQ(wrong, 0);
        EXPECT_EQ(misplaced, 0);
        EXPECT_EQ(active, int64_t(grid->activeVoxelCount())) << "active voxels outside the grid";
    }
    // Both files read back as grids of the nonzero cells, placed on the density cells.
    for (const std::string& p : {nrrd, vdb}) {
        const VoxelGrid back = readGrid(p);
        ASSERT_EQ(back.worldDims(), n) << p;
        int64_t wrong = 0;
        for (int64_t k = 0; k < n.z; ++k)
            for (int64_t j = 0; j < n.y; ++j)
                for (int64_t i = 0; i < n.x; ++i)
                    wrong += back.atWorldIndex(i, j, k) != (want.at(k, i, j) > 0);
        EXPECT_EQ(wrong, 0) << p;
        EXPECT_NEAR(back.frame.cellSize().x, 2.0, 1e-9) << p;
    }
    EXPECT_THROW(writeDensity(d, g.frame, dir.file("d.binvox")), Error);
    writeDensityNormalsNrrd(d, g.frame, dir.file("n.nrrd"));
    EXPECT_EQ(int64_t(nrrdSamples(dir.file("n.nrrd")).size()), n.x * n.y * n.z * 12);
}

TEST(DensityTest, CommandLineWritesTheLibraryCounts) {
    test::TempDir dir;
    const VoxelGrid g = test::randomVoxelGrid({{0, 0, 0}, {9, 6, 11}}, Axis::Z, {9, 6, 11}, 0.5, 13);
    writeGrid(g, dir.file("g.binvox"));
    const test::CommandRun run =
        test::runVoxfx(dir, "density " + dir.file("g.binvox") + " -q -o " + dir.file("d.nrrd"));
    ASSERT_EQ(run.exitCode, 0) << run.err;
    // Sliced along z: world order is column order. Expected: the block counts, cell by cell.
    const NaiveDensity want = naiveDensity(g.bits, 1);
    const std::vector<uint8_t> samples = nrrdSamples(dir.file("d.nrrd"));
    ASSERT_EQ(int64_t(samples.size()), want.w * want.h * want.d);
    for (int64_t k = 0; k < want.d; ++k)
        for (int64_t j = 0; j < want.h; ++j)
            for (int64_t i = 0; i < want.w; ++i)
                ASSERT_EQ(samples[size_t((k * want.h + j) * want.w + i)], want.at(i, j, k))
                    << i << "," << j << "," << k;
    EXPECT_NE(
        test::runVoxfx(dir, "density " + dir.file("g.binvox") + " -l 9 -o " + dir.file("d.nrrd")).exitCode,
        0);
}

} // namespace
} // namespace voxfx
