// voxfx — a rigid mesh obstacle that moves every step of a particle simulation (GI08 §7: the
// solid is re-voxelized every frame, which the slicemap voxelizer makes cheap enough).
//
// Pose at step n: the mesh turned about the vertical (world z) axis through the centre of its
// bounds by n * spinDegreesPerStep, then shifted by n * shiftPerStep. One orthographic frame holds
// every pose of steps 0 .. steps (fitted to the box of the cylinder the spin sweeps, or to the
// bounds without a spin, stretched by the shift), so the particle collider keeps its frame and only its bits
// change:
//
//     MovingObstacle obstacle(std::move(mesh), {.spinDegreesPerStep = 2}, steps, fit, {});
//     ParticleCollider collider(obstacle.voxelizeAt(0));
//     for (int64_t n = 1; n <= steps; ++n) {
//         collider.update(obstacle.voxelizeAt(n).bits);
//         stepParticles(particles, collider, options);
//     }
//
// Thread-safety: a MovingObstacle keeps a posed copy of the mesh; use it from one thread at a
// time (voxelizeAt itself spreads over worker threads).
#pragma once

#include <cstdint>

#include "voxfx/frame.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

struct ObstacleMotion {
    double spinDegreesPerStep = 0; ///< about the vertical axis through the centre of the bounds
    Vec3d shiftPerStep{0, 0, 0};   ///< world units per step
};

class MovingObstacle {
public:
    /// Takes the mesh (validated) and fits the frame for steps 0 .. `steps` with `fit`'s
    /// resolution, voxel size or dims, margin and axis (fit.bounds, when set, replaces the swept
    /// box). `voxelize` is used for every pose, its mode forced to Solid (default fill Auto:
    /// parity for a closed mesh, flood otherwise). Throws voxfx::Error as fitFrame does, or for a
    /// negative step count or a non-finite motion.
    MovingObstacle(Mesh mesh, const ObstacleMotion& motion, int64_t steps, const FitOptions& fit,
                   const VoxelizeOptions& voxelize = autoSolid());

    const Frame& frame() const { return frame_; }
    const ObstacleMotion& motion() const { return motion_; }

    /// The obstacle's solid at step n (any n, also beyond `steps`; parts that leave the frame are
    /// cut). Step 0 is the mesh as given. Cost: one voxelization, O(triangles + cells / 64).
    VoxelGrid voxelizeAt(int64_t step);

    /// VoxelizeOptions with mode Solid and fill Auto.
    static VoxelizeOptions autoSolid();

private:
    Mesh mesh_, posed_;
    ObstacleMotion motion_;
    Vec3d centre_;
    Frame frame_;
    VoxelizeOptions voxelize_;
};

} // namespace voxfx
