// Tests of src/voxelize/threshold.cpp (GI08 §7, volumes as bit grids): the grid of the CGAL CT
// images against a brute-force threshold of their samples, cell for cell and voxel centre for
// voxel centre, along every slicing axis; ties, turned volumes, bad input, threads. The command
// (`voxfx voxelize VOLUME --threshold T`) is tested in test_volume_cli.cpp.
#include <cmath>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/threshold.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx {
namespace {

// The message of the voxfx::Error that f throws ("" when it throws none).
template <class F> std::string thresholdErrorOf(F&& f) {
    try {
        f();
    } catch (const Error& e) { return e.what(); }
    return "";
}

// Cells of `g` (read by world index) that differ from "sample >= t" over every voxel of `v`.
int64_t thresholdMismatches(const Volume& v, double t, const VoxelGrid& g, int64_t* inside = nullptr) {
    const Vec3i n = v.dims();
    EXPECT_EQ(g.worldDims(), n);
    int64_t wrong = 0, in = 0;
    for (int64_t k = 0; k < n.z; ++k)
        for (int64_t j = 0; j < n.y; ++j)
            for (int64_t i = 0; i < n.x; ++i) {
                const bool want = double(v.values()[std::size_t(i + n.x * (j + n.y * k))]) >= t;
                in += want;
                wrong += want != g.atWorldIndex(i, j, k);
            }
    if (inside) *inside = in;
    return wrong;
}

TEST(ThresholdTest, CtImagesEqualABruteForceThresholdOnEveryAxis) {
    for (const char* file : {"images/skull_2.9.inr", "images/liver.inr.gz"}) {
        VOXFX_REQUIRE_DATA(file);
        const Volume v = loadVolume(test::dataPath(file));
        const double lo = v.minValue(), hi = v.maxValue();
        // Three levels across the range, and a level equal to a sample (ties are inside).
        const Vec3i n = v.dims();
        const double tie = v.at(n.x / 2, n.y / 2, n.z / 2);
        for (const double t : {lo + 0.1 * (hi - lo), lo + 0.35 * (hi - lo), lo + 0.6 * (hi - lo), tie})
            for (const Axis axis : {Axis::Z, Axis::X, Axis::Y}) {
                SCOPED_TRACE(std::string(file) + " at " + std::to_string(t) + " along " + toString(axis));
                ThresholdOptions o;
                o.axis = axis;
                const VoxelGrid g = thresholdVolume(v, t, o);
                int64_t inside = 0;
                EXPECT_EQ(thresholdMismatches(v, t, g, &inside), 0);
                EXPECT_GT(inside, 0);
                EXPECT_LT(inside, v.voxelCount());
                EXPECT_EQ(g.bits.count(), inside);
                EXPECT_TRUE(test::paddingIsZero(g.bits));
            }
        // The tie's own voxel is inside; a threshold a hair above it (in double, between two
        // floats) leaves it out.
        EXPECT_TRUE(thresholdVolume(v, tie).atWorldIndex(n.x / 2, n.y / 2, n.z / 2));
        EXPECT_FALSE(
            thresholdVolume(v, std::nextafter(tie, INFINITY)).atWorldIndex(n.x / 2, n.y / 2, n.z / 2));
    }
}

TEST(ThresholdTest, GridCellsAreTheVolumesVoxelsWhereTheVolumeIs) {
    // Cell (i, j, k) of the grid covers voxel (i, j, k): its centre (from the grid's box and cell
    // size, in world-index order) is lo + (i + 0.5) * spacing, from the image's own header.
    VOXFX_REQUIRE_DATA("images/skull_2.9.inr");
    const Volume v = loadVolume(test::dataPath("images/skull_2.9.inr"));
    for (const Axis axis : {Axis::Z, Axis::X}) {
        ThresholdOptions o;
        o.axis = axis;
        const VoxelGrid g = thresholdVolume(v, 100, o);
        const Box3d box = g.frame.box();
        const Vec3d cell = g.frame.cellSize();
        const Vec3i n = v.dims();
        for (int a = 0; a < 3; ++a) {
            EXPECT_NEAR(cell[a], v.spacing()[a], 1e-12 * v.spacing()[a]);
            EXPECT_NEAR(box.lo[a], v.lo()[a], 1e-9);
            EXPECT_NEAR(box.hi[a], v.lo()[a] + double(n[a]) * v.spacing()[a], 1e-9);
        }
        for (const Vec3i& ijk : {Vec3i{0, 0, 0}, Vec3i{n.x - 1, 3, 17}, Vec3i{21, n.y - 1, n.z - 1}}) {
            const Vec3d centre =
                box.lo + Vec3d{double(ijk.x) + 0.5, double(ijk.y) + 0.5, double(ijk.z) + 0.5} * cell;
            const Vec3d want =
                v.lo() + Vec3d{double(ijk.x) + 0.5, double(ijk.y) + 0.5, double(ijk.z) + 0.5} * v.spacing();
            for (int a = 0; a < 3; ++a) EXPECT_NEAR(centre[a], want[a], 1e-9);
        }
    }
}

TEST(ThresholdTest, TurnedVolumeKeepsItsVoxelsWhereTheyAreAndIsNotWrittenAsAnAxisAlignedGrid) {
    // A 3 x 4 x 5 ramp turned 30 degrees about z: each filled cell's centre, from the oriented
    // frame, is the centre of a voxel at or above the threshold.
    Volume v({3, 4, 5}, {10, 0, 7}, {2, 1, 0.5});
    for (std::size_t i = 0; i < v.values().size(); ++i) v.values()[i] = float(i);
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
    v.setAxes({c, s, 0}, {-s, c, 0}, {0, 0, 1});
    const VoxelGrid g = thresholdVolume(v, 29.5);
    EXPECT_TRUE(g.frame.isOriented());
    EXPECT_EQ(g.bits.count(), 60 - 30);
    for (int64_t k = 0; k < 5; ++k)
        for (int64_t j = 0; j < 4; ++j)
            for (int64_t i = 0; i < 3; ++i) {
                EXPECT_EQ(g.bits.get(i, j, k), v.at(i, j, k) >= 29.5f);
                const Vec3d want = Vec3d{10, 0, 7} + Vec3d{c, s, 0} * ((double(i) + 0.5) * 2) +
                                   Vec3d{-s, c, 0} * ((double(j) + 0.5) * 1) +
                                   Vec3d{0, 0, 1} * ((double(k) + 0.5) * 0.5);
                const Vec3d got = g.frame.cellCenter(i, j, k);
                for (int a = 0; a < 3; ++a) EXPECT_NEAR(got[a], want[a], 1e-9);
            }
    test::TempDir dir;
    const std::string error = thresholdErrorOf([&] { writeGrid(g, dir.file("turned.nrrd")); });
    EXPECT_NE(error.find("turned.nrrd"), std::string::npos) << error;
    EXPECT_NE(error.find("oriented"), std::string::npos) << error;
}

class ThresholdCancelAtHalf : public Progress {
public:
    bool update(double fraction) override { return fraction < 0.5; }
};

TEST(ThresholdTest, BadInputCancellationAndThreads) {
    Volume v({40, 30, 20}, {0, 0, 0}, {1, 1, 1});
    for (std::size_t i = 0; i < v.values().size(); ++i) v.values()[i] = float((i * 7919) % 1000);
    EXPECT_THROW(thresholdVolume(v, std::nan("")), Error);
    EXPECT_THROW(thresholdVolume(v, INFINITY), Error);
    EXPECT_THROW(thresholdVolume(Volume(), 1.0), Error);
    ThresholdCancelAtHalf cancel;
    ThresholdOptions o;
    o.progress = &cancel;
    EXPECT_NE(thresholdErrorOf([&] { thresholdVolume(v, 500, o); }).find("cancelled"), std::string::npos);
    o.progress = nullptr;
    o.threads = 1;
    const VoxelGrid one = thresholdVolume(v, 500, o);
    o.threads = 2;
    const VoxelGrid two = thresholdVolume(v, 500, o);
    EXPECT_EQ(thresholdMismatches(v, 500, one), 0);
    EXPECT_EQ(thresholdMismatches(v, 500, two), 0);
    EXPECT_EQ(one.bits.count(), two.bits.count());
}

} // namespace
} // namespace voxfx
