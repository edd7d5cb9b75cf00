// voxfx — a rigid mesh obstacle re-voxelized every step (GI08 §7's moving obstacles).
#include "voxfx/moving_obstacle.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "voxfx/error.hpp"

namespace voxfx {

VoxelizeOptions MovingObstacle::autoSolid() {
    VoxelizeOptions o;
    o.mode = VoxelizeMode::Solid;
    o.fill = Fill::Auto;
    return o;
}

MovingObstacle::MovingObstacle(Mesh mesh, const ObstacleMotion& motion, int64_t steps, const FitOptions& fit,
                               const VoxelizeOptions& voxelize)
    : mesh_(std::move(mesh)), motion_(motion), voxelize_(voxelize) {
    validateMesh(mesh_.view(), "moving obstacle");
    if (steps < 0) fail("moving obstacle: the step count must be >= 0, got ", steps);
    if (!std::isfinite(motion.spinDegreesPerStep) || !isFinite(motion.shiftPerStep))
        fail("moving obstacle: the motion must be finite");
    voxelize_.mode = VoxelizeMode::Solid;
    posed_ = mesh_;
    // The spin sweeps a vertical cylinder about the centre of the bounds: its box holds every
    // angle (without a spin the bounds do). The shift moves it along: the box of the first and
    // the last pose holds them all.
    const Box3d b = computeBounds(mesh_.view());
    centre_ = b.center();
    Box3d swept = b;
    if (motion.spinDegreesPerStep != 0) {
        double r = 0;
        for (const Vec3f& p : mesh_.positions)
            r = std::max(r, std::hypot(double(p.x) - centre_.x, double(p.y) - centre_.y));
        swept = Box3d{{centre_.x - r, centre_.y - r, b.lo.z}, {centre_.x + r, centre_.y + r, b.hi.z}};
    }
    if (motion.shiftPerStep != Vec3d{0, 0, 0}) {
        const Vec3d last = motion.shiftPerStep * double(steps);
        swept.extend(Box3d{swept.lo + last, swept.hi + last});
    }
    frame_ = fitFrame(swept, fit);
}

VoxelGrid MovingObstacle::voxelizeAt(int64_t step) {
    if (step == 0) return voxfx::voxelize(mesh_.view(), frame_, voxelize_);
    const double angle = double(step) * motion_.spinDegreesPerStep * std::numbers::pi / 180.0;
    const double c = std::cos(angle), s = std::sin(angle);
    const Vec3d shift = motion_.shiftPerStep * double(step);
    for (size_t i = 0; i < mesh_.positions.size(); ++i) {
        const Vec3d p = Vec3d(mesh_.positions[i]) - centre_;
        posed_.positions[i] = Vec3f(centre_ + Vec3d{c * p.x - s * p.y, s * p.x + c * p.y, p.z} + shift);
    }
    return voxfx::voxelize(posed_.view(), frame_, voxelize_);
}

} // namespace voxfx
