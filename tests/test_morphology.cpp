// Tests of src/grid/morphology.cpp: erosion and dilation against a cell-by-cell box scan on
// random grids (odd sizes, depths around multiples of 64, radii beyond a word), every border
// rule, opening/closing identities on voxelized meshes, world-axis radii and thread counts.
#include <random>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

using test::randomBits;

// The definition, cell by cell: scan the box around every cell.
BitGrid naiveMorph(const BitGrid& g, bool erode, const MorphologyOptions& o) {
    BitGrid out(g.width(), g.height(), g.depth());
    for (int64_t y = 0; y < g.height(); ++y)
        for (int64_t x = 0; x < g.width(); ++x)
            for (int64_t s = 0; s < g.depth(); ++s) {
                bool any = false, all = true;
                for (int64_t dy = -o.ry; dy <= o.ry; ++dy)
                    for (int64_t dx = -o.rx; dx <= o.rx; ++dx)
                        for (int64_t ds = -o.rz; ds <= o.rz; ++ds) {
                            const int64_t X = x + dx, Y = y + dy, S = s + ds;
                            const bool inside = X >= 0 && Y >= 0 && S >= 0 && X < g.width() &&
                                                Y < g.height() && S < g.depth();
                            bool v;
                            if (inside)
                                v = g.get(X, Y, S);
                            else if (o.border == MorphBorder::Neutral)
                                continue;
                            else
                                v = o.border == MorphBorder::Filled;
                            any = any || v;
                            all = all && v;
                        }
                if (erode ? all : any) out.set(x, y, s);
            }
    return out;
}

// Every cell flipped, cell by cell (padding stays zero).
BitGrid complement(const BitGrid& g) {
    BitGrid out(g.width(), g.height(), g.depth());
    for (int64_t y = 0; y < g.height(); ++y)
        for (int64_t x = 0; x < g.width(); ++x)
            for (int64_t s = 0; s < g.depth(); ++s)
                if (!g.get(x, y, s)) out.set(x, y, s);
    return out;
}

// The options whose dilation of the complement is the complement of the erosion: the outside is
// complemented too (neutral stays neutral).
MorphologyOptions dualOf(MorphologyOptions o) {
    if (o.border != MorphBorder::Neutral)
        o.border = o.border == MorphBorder::Empty ? MorphBorder::Filled : MorphBorder::Empty;
    return o;
}

bool contains(const BitGrid& big, const BitGrid& small) {
    for (int64_t i = 0; i < big.wordCount(); ++i)
        if (small.words()[i] & ~big.words()[i]) return false;
    return true;
}

TEST(MorphologyTest, ErosionAndDilationMatchTheBoxScanOnRandomGrids) {
    const int64_t sizes[][3] = {{7, 5, 63}, {4, 6, 64}, {5, 3, 65}, {3, 4, 130}, {1, 1, 200}, {9, 2, 1}};
    // Depth radii on both sides of the word size and of every doubling-step count; an x radius
    // wider than the grid.
    const int64_t radii[][3] = {{1, 1, 1},  {0, 0, 1},   {2, 1, 0}, {0, 2, 3},  {1, 0, 64},
                                {0, 0, 70}, {3, 3, 5},   {0, 0, 8}, {0, 0, 31}, {0, 0, 63},
                                {2, 0, 40}, {0, 0, 127}, {12, 0, 2}};
    int cases = 0;
    for (const auto& n : sizes)
        for (const auto& r : radii)
            for (const MorphBorder border : {MorphBorder::Neutral, MorphBorder::Empty, MorphBorder::Filled}) {
                // Sparse grids keep dilations non-trivial, dense ones erosions.
                const double fill = (n[2] + r[2]) % 2 ? 0.15 : 0.9;
                const BitGrid g = randomBits(n[0], n[1], n[2], fill, uint64_t(n[0] * 31 + n[2] + r[2]));
                MorphologyOptions o;
                o.rx = r[0];
                o.ry = r[1];
                o.rz = r[2];
                o.border = border;
                const std::string what = detail::concat(n[0], "x", n[1], "x", n[2], " r ", r[0], ",", r[1],
                                                        ",", r[2], " border ", toString(border));
                const BitGrid e = erode(g, o), d = dilate(g, o);
                ASSERT_EQ(e, naiveMorph(g, true, o)) << "erode " << what;
                ASSERT_EQ(d, naiveMorph(g, false, o)) << "dilate " << what;
                EXPECT_TRUE(test::paddingIsZero(e) && test::paddingIsZero(d)) << what;
                EXPECT_EQ(e, complement(dilate(complement(g), dualOf(o)))) << "duality " << what;
                // Opening and closing are compositions of the two.
                EXPECT_EQ(opening(g, o), naiveMorph(naiveMorph(g, true, o), false, o)) << what;
                EXPECT_EQ(closing(g, o), naiveMorph(naiveMorph(g, false, o), true, o)) << what;
                ++cases;
            }
    EXPECT_EQ(cases, 6 * 13 * 3);
}

TEST(MorphologyTest, RadiiBeyondTheGridActLikeTheGridSizeInTimeAndMemory) {
    // A radius of the grid's size reaches every cell of the line and one beyond each end, so any
    // larger one gives the box scan's result for that size. Along depth the radius was not
    // clamped: 2^50 slices asked for petabytes of scratch (std::bad_alloc) and 10^8 took seconds.
    const BitGrid g = randomBits(5, 4, 70, 0.1, 17);
    for (const MorphBorder border : {MorphBorder::Neutral, MorphBorder::Empty, MorphBorder::Filled})
        for (const int64_t huge : {int64_t(1) << 50, int64_t(100000000)}) {
            MorphologyOptions o;
            o.border = border;
            o.rx = 1;
            o.ry = 0;
            o.rz = huge;
            MorphologyOptions atSize = o;
            atSize.rz = g.depth();
            ASSERT_EQ(dilate(g, o), naiveMorph(g, false, atSize)) << toString(border) << " rz " << huge;
            ASSERT_EQ(erode(g, o), naiveMorph(g, true, atSize)) << toString(border) << " rz " << huge;
            o.rz = 2;
            o.rx = o.ry = huge;
            atSize = o;
            atSize.rx = g.width();
            atSize.ry = g.height();
            ASSERT_EQ(dilate(g, o), naiveMorph(g, false, atSize)) << toString(border) << " rx ry " << huge;
        }
}

TEST(MorphologyTest, ClosingContainsAndOpeningIsContainedInVoxelizedMeshes) {
    for (const char* name : {"bunny00", "knot1"}) {
        VOXFX_REQUIRE_DATA(std::string("meshes/") + name + ".off");
        const std::string path = test::dataPath(std::string("meshes/") + name + ".off");
        const Mesh mesh = loadMesh(path);
        FitOptions fit;
        fit.resolution = 70;
        const VoxelGrid g = voxelize(mesh.view(), fitFrame(computeBounds(mesh.view()), fit));
        for (const int64_t r : {1, 2, 4}) {
            MorphologyOptions o;
            o.rx = r;
            o.ry = r + 1;
            o.rz = r;
            const BitGrid c = closing(g.bits, o), op = opening(g.bits, o);
            EXPECT_TRUE(contains(c, g.bits)) << name << " r " << r;
            EXPECT_TRUE(contains(g.bits, op)) << name << " r " << r;
            // Idempotence: opening and closing are projections.
            EXPECT_EQ(closing(c, o), c) << name << " r " << r;
            EXPECT_EQ(opening(op, o), op) << name << " r " << r;
            // Erosion shrinks, dilation grows, and they are duals under complement (the border
            // rule turns into its complement: empty outside <-> filled outside).
            const BitGrid e = erode(g.bits, o);
            EXPECT_TRUE(contains(g.bits, e));
            EXPECT_TRUE(contains(dilate(g.bits, o), g.bits));
            EXPECT_EQ(e, complement(dilate(complement(g.bits), dualOf(o)))) << name << " r " << r;
        }
        MorphologyOptions small;
        small.rx = 1;
        small.ry = 2;
        small.rz = 3;
        EXPECT_EQ(erode(g.bits, small), naiveMorph(g.bits, true, small)) << name;
        EXPECT_EQ(dilate(g.bits, small), naiveMorph(g.bits, false, small)) << name;
    }
}

TEST(MorphologyTest, WorldRadiiFollowTheSlicingAxis) {
    // Grid sliced along x: world x is the slice axis. A single voxel dilated by world radii
    // (2, 0, 1) becomes a 5 x 1 x 3 box in world indices.
    VoxelGrid g{Frame::orthographic({{0, 0, 0}, {9, 7, 8}}, Axis::X, 7, 8, 9), BitGrid(7, 8, 9)};
    // World (i, j, k) = (4, 3, 4): axis X -> column x = j, column y = k, slice = i.
    g.bits.set(3, 4, 4);
    const VoxelGrid d = morphology(g, MorphOp::Dilate, {2, 0, 1});
    for (int64_t k = 0; k < 8; ++k)
        for (int64_t j = 0; j < 7; ++j)
            for (int64_t i = 0; i < 9; ++i)
                EXPECT_EQ(d.atWorldIndex(i, j, k), i >= 2 && i <= 6 && j == 3 && k >= 3 && k <= 5)
                    << i << j << k;
    EXPECT_THROW(morphology(g, MorphOp::Erode, {-1, 0, 0}), Error);
}

TEST(MorphologyTest, CallerOwnedOutputsAreReusedAndOverwritten) {
    const BitGrid g = randomBits(21, 13, 90, 0.6, 31);
    const MorphologyOptions o{1, 2, 3};
    // Outputs holding stale bits of the right size, and of a wrong size.
    BitGrid out = randomBits(21, 13, 90, 0.5, 1), scratch(3, 3, 3);
    // Expected: the cell-by-cell definition (opening and closing as its compositions).
    const BitGrid e = naiveMorph(g, true, o), d = naiveMorph(g, false, o);
    const std::pair<MorphOp, BitGrid> cases[] = {{MorphOp::Erode, e},
                                                 {MorphOp::Dilate, d},
                                                 {MorphOp::Open, naiveMorph(e, false, o)},
                                                 {MorphOp::Close, naiveMorph(d, true, o)}};
    for (const auto& [op, want] : cases) {
        morphology(g, op, o, out, scratch);
        EXPECT_EQ(out, want) << toString(op);
    }
    const uint64_t* reused = out.words();
    morphology(g, MorphOp::Close, o, out, scratch);
    EXPECT_EQ(out.words(), reused); // same size: no new allocation
    EXPECT_THROW(morphology(out, MorphOp::Erode, o, out, scratch), Error);
}

TEST(MorphologyTest, ResultsAreIdenticalForAnyThreadCount) {
    const BitGrid g = randomBits(61, 47, 200, 0.7, 12);
    MorphologyOptions o{2, 3, 5};
    o.threads = 1;
    const BitGrid one = closing(g, o);
    o.threads = 2;
    EXPECT_EQ(closing(g, o), one);
    o.threads = 0;
    EXPECT_EQ(closing(g, o), one);
    EXPECT_EQ(morphology(g, MorphOp::Dilate, MorphologyOptions{0, 0, 0, MorphBorder::Neutral, 0}), g);
}

TEST(MorphologyTest, CommandLineMatchesTheLibrary) {
    test::TempDir dir;
    const VoxelGrid g = test::randomVoxelGrid({{0, 0, 0}, {12, 10, 70}}, Axis::Z, {12, 10, 70}, 0.6, 14);
    writeGrid(g, dir.file("g.binvox"));
    const test::CommandRun run =
        test::runVoxfx(dir, "morph " + dir.file("g.binvox") +
                                " --op open --radii 1 0 2 --border empty -q -o " + dir.file("o.binvox"));
    ASSERT_EQ(run.exitCode, 0) << run.err;
    // The written file (decoded from the format's description) against the definition: sliced
    // along z, world radii (1, 0, 2) are the column x, column y and slice radii.
    MorphologyOptions o;
    o.rx = 1;
    o.ry = 0;
    o.rz = 2;
    o.border = MorphBorder::Empty;
    const BitGrid want = naiveMorph(naiveMorph(g.bits, true, o), false, o);
    const test::BinvoxFile f = test::readBinvoxBySpec(dir.file("o.binvox"));
    ASSERT_EQ(f.dims, Vec3i(12, 10, 70));
    int64_t wrong = 0;
    for (int64_t k = 0; k < 70; ++k)
        for (int64_t j = 0; j < 10; ++j)
            for (int64_t i = 0; i < 12; ++i) wrong += f.at(i, j, k) != want.get(i, j, k);
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(want.count(), 0);
    EXPECT_NE(test::runVoxfx(dir, "morph " + dir.file("g.binvox") + " --op grow -o " + dir.file("o.binvox"))
                  .exitCode,
              0);
}

} // namespace
} // namespace voxfx
