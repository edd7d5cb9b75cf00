// Tests of include/voxfx/dda.hpp (and the segment queries walked with it) against a brute-force
// traversal: the segment sampled densely, each sample's cell found by flooring its coordinates.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/dda.hpp"
#include "voxfx/grid_query.hpp"

namespace voxfx {
namespace {

using test::randomBits;

constexpr int kSamples = 20000;

struct Cell {
    int64_t c[3];
    bool operator==(const Cell& o) const { return c[0] == o.c[0] && c[1] == o.c[1] && c[2] == o.c[2]; }
};

std::ostream& operator<<(std::ostream& os, const Cell& c) {
    return os << "(" << c.c[0] << ", " << c.c[1] << ", " << c.c[2] << ")";
}

// Brute force: the cells of samples t = (k + 0.5) / N in [0, 1], consecutive repeats merged;
// also the number of samples per run, so a cell the segment crosses for long is known to be hit.
struct Sampled {
    std::vector<Cell> cells;
    std::vector<int> counts;
};

Sampled sampleCells(const Vec3d& a, const Vec3d& b, const int64_t dims[3]) {
    Sampled s;
    for (int k = 0; k < kSamples; ++k) {
        const double t = (double(k) + 0.5) / kSamples;
        const Vec3d p = a + (b - a) * t;
        Cell c;
        bool in = true;
        for (int i = 0; i < 3; ++i) {
            in = in && p[i] >= 0 && p[i] < double(dims[i]);
            c.c[i] = int64_t(std::floor(p[i]));
        }
        if (!in) continue;
        if (s.cells.empty() || !(s.cells.back() == c)) {
            s.cells.push_back(c);
            s.counts.push_back(0);
        }
        ++s.counts.back();
    }
    return s;
}

struct Piece {
    Cell cell;
    double t0, t1;
};

// The walk under test: clip, start, step until t1; pieces of positive length.
std::vector<Piece> walkCells(const Vec3d& a, const Vec3d& b, const int64_t dims[3]) {
    std::vector<Piece> out;
    const Vec3d d = b - a;
    const DdaClip clip = clipToGrid(a, d, dims);
    if (clip.empty()) return out;
    Dda w = Dda::start(a, d, dims, clip.t0);
    double t = clip.t0;
    for (int guard = 0; guard < 100000; ++guard) {
        const int axis = w.nextAxis();
        const double tNext = std::min(w.tMax[axis], clip.t1);
        if (tNext > t) out.push_back({{{w.cell[0], w.cell[1], w.cell[2]}}, t, tNext});
        t = std::max(t, tNext);
        if (w.tMax[axis] >= clip.t1 || !w.advance(axis)) break;
    }
    return out;
}

void expectWalkMatchesSamples(const Vec3d& a, const Vec3d& b, const int64_t dims[3]) {
    SCOPED_TRACE(::testing::Message()
                 << "segment (" << a.x << ", " << a.y << ", " << a.z << ") -> (" << b.x << ", " << b.y << ", "
                 << b.z << ") in " << dims[0] << " x " << dims[1] << " x " << dims[2]);
    const Sampled s = sampleCells(a, b, dims);
    const std::vector<Piece> w = walkCells(a, b, dims);
    // Each piece lies in its cell: its midpoint is inside the closed cell box.
    for (const Piece& p : w) {
        const Vec3d m = a + (b - a) * (0.5 * (p.t0 + p.t1));
        for (int i = 0; i < 3; ++i) {
            EXPECT_GE(m[i], double(p.cell.c[i]) - 1e-9) << p.cell;
            EXPECT_LE(m[i], double(p.cell.c[i] + 1) + 1e-9) << p.cell;
        }
    }
    // The sampled cells appear in the walk, in the same order; a cell held by more than one
    // sample spacing of the segment must be sampled, so the walk has no cell the samples lack
    // unless that cell is crossed for less than two spacings.
    size_t j = 0;
    for (size_t i = 0; i < s.cells.size(); ++i) {
        while (j < w.size() && !(w[j].cell == s.cells[i])) {
            EXPECT_LT(w[j].t1 - w[j].t0, 2.0 / kSamples) << "walk cell " << w[j].cell << " was never sampled";
            ++j;
        }
        ASSERT_LT(j, w.size()) << "sampled cell " << s.cells[i] << " (" << s.counts[i]
                               << " samples) is missing from the walk or out of order";
        ++j;
    }
    for (; j < w.size(); ++j)
        EXPECT_LT(w[j].t1 - w[j].t0, 2.0 / kSamples) << "walk cell " << w[j].cell << " was never sampled";
    // The pieces tile the clipped parameter range without gaps or overlaps.
    for (size_t i = 1; i < w.size(); ++i) EXPECT_EQ(w[i].t0, w[i - 1].t1);
}

TEST(DdaTest, WalkVisitsTheCellsOfADenseSamplingOnRandomSegments) {
    std::mt19937_64 rng(11);
    const int64_t dims[3] = {7, 5, 9};
    std::uniform_real_distribution<double> u(-3.0, 12.0);
    for (int i = 0; i < 300; ++i)
        expectWalkMatchesSamples({u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, dims);
}

TEST(DdaTest, WalkHandlesAxesEdgesCornersOutsideStartsAndZeroComponents) {
    const int64_t dims[3] = {6, 6, 6};
    const std::vector<std::pair<Vec3d, Vec3d>> cases = {
        // Along each axis, inside cells and exactly on cell planes, both directions.
        {{2.5, 3.5, -1.0}, {2.5, 3.5, 8.0}},
        {{2.5, 3.5, 8.0}, {2.5, 3.5, -1.0}},
        {{-1.0, 2.0, 3.0}, {7.0, 2.0, 3.0}},
        {{7.0, 2.0, 3.0}, {-1.0, 2.0, 3.0}},
        {{1.0, -2.0, 4.0}, {1.0, 9.0, 4.0}},
        {{0.0, 0.0, 0.0}, {0.0, 0.0, 6.0}},
        {{6.0, 0.5, 0.5}, {6.0, 0.5, 5.5}}, // on the far face: outside (half-open)
        {{0.5, 0.5, 6.0}, {5.5, 0.5, 6.0}},
        // Through edges (two coordinates integer at the same t) and corners (all three).
        {{0.0, 0.0, 0.5}, {6.0, 6.0, 0.5}},
        {{6.0, 6.0, 2.5}, {0.0, 0.0, 2.5}},
        {{0.0, 0.0, 0.0}, {6.0, 6.0, 6.0}},
        {{6.0, 0.0, 6.0}, {0.0, 6.0, 0.0}},
        {{-1.0, -1.0, -1.0}, {7.0, 7.0, 7.0}},
        {{1.0, 5.0, 3.0}, {4.0, 2.0, 3.0}},
        // Starting outside, ending inside and the reverse; grazing a face; missing the grid.
        {{-4.0, 2.2, 3.3}, {2.7, 2.9, 3.1}},
        {{2.7, 2.9, 3.1}, {-4.0, 2.2, 3.3}},
        {{-1.0, 0.0, 1.5}, {7.0, 0.0, 4.5}},
        {{-1.0, 7.0, 1.5}, {7.0, 7.5, 4.5}},
        {{-2.0, -2.0, 3.0}, {0.0, -0.5, 3.0}},
        // One zero direction component, the other two not.
        {{-0.5, 1.25, 2.0}, {6.5, 4.75, 2.0}},
        {{5.5, 0.0, 0.25}, {5.5, 6.0, 5.75}},
    };
    for (const auto& [a, b] : cases) expectWalkMatchesSamples(a, b, dims);
}

TEST(DdaTest, ContainingStartIsTheCellOfTheStartPoint) {
    const int64_t dims[3] = {4, 4, 4};
    // On the plane z = 2 moving down: the point's (half-open) cell is z = 2, while the segment
    // occupies z = 1 right after the start.
    const Vec3d a{1.5, 1.5, 2.0}, d{0.0, 0.0, -1.0};
    EXPECT_EQ(Dda::start(a, d, dims, 0.0, DdaStart::Containing).cell[2], 2);
    EXPECT_EQ(Dda::start(a, d, dims, 0.0, DdaStart::AlongSegment).cell[2], 1);
    const Dda w = Dda::start(a, d, dims, 0.0, DdaStart::Containing);
    EXPECT_EQ(w.nextAxis(), 2);
    EXPECT_EQ(w.tMax[2], 0.0); // the first crossing is immediate
}

// traceSegmentGrid: the filled length against the share of samples in filled cells.
TEST(DdaTest, SegmentFilledLengthMatchesDenseSampling) {
    const BitGrid g = randomBits(6, 5, 70, 0.5, 3);
    const int64_t dims[3] = {6, 5, 70};
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-2.0, 8.0), uz(-2.0, 72.0);
    std::vector<std::pair<Vec3d, Vec3d>> cases = {{{2.5, 1.5, -1.0}, {2.5, 1.5, 71.0}}, // along the column
                                                  {{0.0, 0.0, 3.5}, {6.0, 5.0, 3.5}},
                                                  {{0.0, 0.0, 0.0}, {5.0, 5.0, 5.0}}};
    for (int i = 0; i < 100; ++i) cases.push_back({{u(rng), u(rng), uz(rng)}, {u(rng), u(rng), uz(rng)}});
    for (const auto& [a, b] : cases) {
        int filled = 0;
        for (int k = 0; k < kSamples; ++k) {
            const Vec3d p = a + (b - a) * ((double(k) + 0.5) / kSamples);
            bool in = true;
            for (int i = 0; i < 3; ++i) in = in && p[i] >= 0 && p[i] < double(dims[i]);
            if (in && g.get(int64_t(p.x), int64_t(p.y), int64_t(p.z))) ++filled;
        }
        const SegmentHits h = traceSegmentGrid(g, a, b);
        // Each cell boundary can move a sample across it: at most one sample per crossing.
        EXPECT_NEAR(h.filledFraction(), double(filled) / kSamples, double(h.cellsVisited + 1) / kSamples)
            << "segment (" << a.x << ", " << a.y << ", " << a.z << ") -> (" << b.x << ", " << b.y << ", "
            << b.z << ")";
    }
}

} // namespace
} // namespace voxfx
