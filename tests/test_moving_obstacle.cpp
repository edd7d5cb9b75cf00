// A moving obstacle (src/sim/moving_obstacle.cpp) against closed forms: a wall sliding at a
// constant speed pushes a resting particle ahead of it, so the particle's position follows the
// wall's front, x(n) = x0 + n * shift, within a cell; a quarter turn of a box is the box with its
// extents swapped about the centre; and the frame holds every pose.
#include <cmath>
#include <cstdint>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/moving_obstacle.hpp"
#include "voxfx/particles.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

TEST(MovingObstacleTest, ASlidingWallPushesAParticleAlongItsFront) {
    // A wall 1 thick in x sliding +x by 0.02 per step (half a cell of 0.04), no gravity: a particle
    // at rest ahead of it is reached at step 15 and then kept just ahead of the front, which is at
    // 1 + 0.02 n. The collider drops velocity that points back into the solid and adds none, so
    // the particle stays at rest between pushes.
    FitOptions fit;
    fit.resolution = 100; // the swept box is 4 along y and z: cells of 0.04
    fit.marginCells = 4;
    MovingObstacle wall(test::makeBox({0, -2, -2}, {1, 2, 2}), {.shiftPerStep = {0.02, 0, 0}}, 50, fit);
    const double cell = wall.frame().cellSize().x;
    ASSERT_NEAR(cell, 0.04, 1e-12);
    ParticleCollider collider(wall.voxelizeAt(0));
    Particles ps;
    ps.push({1.3f, 0.1f, -0.3f});
    ParticleOptions po;
    po.gravity = {0, 0, 0};
    for (int64_t n = 1; n <= 40; ++n) {
        collider.update(wall.voxelizeAt(n).bits);
        stepParticles(ps, collider, po);
        const double front = 1 + 0.02 * double(n);
        const Vec3f p = ps.position(0);
        if (front < 1.3 - cell) {
            EXPECT_FLOAT_EQ(p.x, 1.3f) << "step " << n << ": moved before the wall reached it";
        } else {
            EXPECT_NEAR(p.x, std::max(front, 1.3), cell) << "step " << n;
        }
        EXPECT_FALSE(collider.filledAt(Vec3d(p))) << "step " << n << ": inside the wall";
        EXPECT_FLOAT_EQ(p.y, 0.1f);
        EXPECT_FLOAT_EQ(p.z, -0.3f);
        EXPECT_EQ(ps.velocity(0), (Vec3f{0, 0, 0})) << "step " << n;
    }
    EXPECT_GT(ps.position(0).x, 1.75f); // it was pushed: the front is at 1.8
}

TEST(MovingObstacleTest, AQuarterTurnIsTheBoxWithItsExtentsSwapped) {
    // A box turned by 90 degrees about the vertical axis through its centre (1.2, 0.55) is the box
    // with its x and y half extents (1.1 and 0.35) swapped; voxelized in the same frame it must
    // give the same cells. Four quarter turns give the first pose back.
    const Mesh box = test::makeBox({0.1, 0.2, 0.05}, {2.3, 0.9, 0.95});
    FitOptions fit;
    fit.resolution = 64;
    MovingObstacle spinning(box, {.spinDegreesPerStep = 90}, 4, fit);
    const VoxelGrid turned = spinning.voxelizeAt(1);
    VoxelizeOptions parity;
    const VoxelGrid expected =
        voxelize(test::makeBox({1.2 - 0.35, 0.55 - 1.1, 0.05}, {1.2 + 0.35, 0.55 + 1.1, 0.95}).view(),
                 spinning.frame(), parity);
    EXPECT_GT(expected.bits.count(), 1000);
    EXPECT_EQ(turned.bits, expected.bits);
    EXPECT_EQ(spinning.voxelizeAt(4).bits, spinning.voxelizeAt(0).bits);
    EXPECT_NE(spinning.voxelizeAt(1).bits, spinning.voxelizeAt(0).bits);
}

TEST(MovingObstacleTest, TheFrameHoldsEveryPoseAndBadMotionsAreRefused) {
    // The box's corners reach sqrt(1.1^2 + 0.35^2) from the axis (to float rounding of the
    // vertices, hence 1e-6): every angle fits in the frame,
    // so every pose keeps the whole volume (the cell count varies only with the sampling).
    const Mesh box = test::makeBox({0.1, 0.2, 0.05}, {2.3, 0.9, 0.95});
    FitOptions fit;
    fit.resolution = 64;
    MovingObstacle spinning(box, {.spinDegreesPerStep = 7}, 60, fit);
    const Box3d frameBox = spinning.frame().box();
    const double r = std::hypot(1.1, 0.35);
    EXPECT_LE(frameBox.lo.x, 1.2 - r + 1e-6);
    EXPECT_GE(frameBox.hi.x, 1.2 + r - 1e-6);
    EXPECT_LE(frameBox.lo.y, 0.55 - r + 1e-6);
    EXPECT_GE(frameBox.hi.y, 0.55 + r - 1e-6);
    const Vec3d cell = spinning.frame().cellSize();
    const double volume = 2.2 * 0.7 * 0.9, cellVolume = cell.x * cell.y * cell.z;
    for (int64_t n = 0; n <= 60; n += 5)
        EXPECT_NEAR(double(spinning.voxelizeAt(n).bits.count()) * cellVolume, volume, 0.08 * volume) << n;
    EXPECT_THROW(MovingObstacle(box, {}, -1, fit), Error);
    EXPECT_THROW(MovingObstacle(box, {.spinDegreesPerStep = NAN}, 1, fit), Error);
}

} // namespace
} // namespace voxfx
