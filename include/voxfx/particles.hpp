// voxfx — particles colliding with a solid grid (GI08 §7; experimental: the API may change until
// the issue closes).
//
// Particles live in world space as structure-of-arrays (separate float arrays for positions and
// velocities). Each step is semi-implicit Euler with a fixed time step:
//     v += gravity * dt;   p' = p + v * dt
// and the path p -> p' is walked through the grid (3D DDA). When it enters a filled cell the
// particle stops at the entry point, clamped a hair inside the last free cell it crossed, and its
// velocity is reflected about the outward normal n of the density map at that point (GI08 §6;
// the crossed cell face when the density normal is degenerate or faces the wrong way):
//     v_n = (v . n) n,  v_t = v - v_n,  v <- (1 - friction) v_t - restitution v_n
// Before the reflection the speed is reduced by the potential energy the particle keeps by
// stopping short of p', so with restitution <= 1 the energy 1/2 |v|^2 - gravity . p never grows
// (semi-implicit Euler itself loses 1/2 |gravity|^2 dt^2 per step). Invariant: after every step,
// no particle is inside a filled cell (positions are checked after rounding to float, and a
// particle whose rounded position would land in a filled cell keeps its previous position).
// Particles found inside filled cells at the start of a step (a moving obstacle swept over them)
// move to the nearest free cell within 4 cells; failing that they stay and are counted as stuck.
// Each particle is independent, so results are identical for any thread count; the step
// allocates nothing per particle (the parallel loop's bookkeeping allocates a few objects per
// call).
// Thread-safety: a ParticleCollider is read-only during stepParticles, so several particle sets
// may step against one collider concurrently; update() needs exclusive access. stepParticles
// (`threads`), the collider's construction and update (density) and renderParticles use worker
// threads; emitting, sorting and writing run on the calling thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "voxfx/density.hpp"
#include "voxfx/image.hpp"
#include "voxfx/math.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx {

/// Particle state, structure-of-arrays; all six arrays have size() elements. World units.
struct Particles {
    std::vector<float> px, py, pz; ///< positions
    std::vector<float> vx, vy, vz; ///< velocities (world units per second)

    std::size_t size() const { return px.size(); }
    void resize(std::size_t n);
    void push(const Vec3f& p, const Vec3f& v = {});
    Vec3f position(std::size_t i) const { return {px[i], py[i], pz[i]}; }
    Vec3f velocity(std::size_t i) const { return {vx[i], vy[i], vz[i]}; }
};

/// The solid the particles collide with: an orthographic, uniformly sliced grid and its density
/// map (for normals).
class ParticleCollider {
public:
    ParticleCollider() = default;
    /// Takes the grid; computes its density map of `densityLevel` (1..5). Throws voxfx::Error for
    /// perspective or locally sliced frames or an empty grid.
    explicit ParticleCollider(VoxelGrid grid, int densityLevel = 1);
    /// Replaces the occupancy (same frame and size, e.g. a moving mesh re-voxelized) and updates
    /// the density map. Throws voxfx::Error on a size mismatch.
    void update(BitGrid bits);

    const VoxelGrid& grid() const { return grid_; }
    const DensityGrid& density() const { return density_; }
    /// True when the world point lies in a filled cell (points outside the grid: false).
    bool filledAt(const Vec3d& world) const;
    /// Outward unit normal of the density map at a world point (world axes); zero where the
    /// density gradient vanishes.
    Vec3d normalAt(const Vec3d& world) const;

private:
    VoxelGrid grid_;
    DensityGrid density_;
};

struct ParticleOptions {
    Vec3d gravity{0, 0, -9.81}; ///< world units per second squared
    double dt = 1.0 / 120.0;    ///< seconds, > 0
    double restitution = 0.5;   ///< normal velocity kept on a bounce, in [0, 2]; <= 1 loses energy
    double friction = 0.0;      ///< fraction of the tangential velocity lost on a bounce, in [0, 1]
    /// The faces of the grid's box are walls too (with their own normals); otherwise particles
    /// leave the grid freely and fly on.
    bool boxWalls = false;
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
};

struct StepStats {
    int64_t bounces = 0;   ///< particles that hit a filled cell (or a wall) during the step
    int64_t pushedOut = 0; ///< particles moved out of a filled cell at the start of the step
    int64_t stuck = 0;     ///< particles inside a filled cell with no free cell within 4 cells
};

/// Advances every particle by one step (see the file comment). Throws voxfx::Error for invalid
/// options or arrays of different sizes. Cost: O(particles + cells crossed), parallel, no
/// allocation.
StepStats stepParticles(Particles& particles, const ParticleCollider& collider,
                        const ParticleOptions& options);

/// `count` particles at rest, uniformly distributed over the free cells of `region` (world box,
/// clipped to the grid; empty = the top quarter of the grid's box along world z), from a fixed
/// seed, in sortParticles order. Places fewer when the region has no free space (after 64
/// attempts per particle).
Particles emitParticles(const ParticleCollider& collider, std::size_t count, const Box3d& region = {},
                        uint64_t seed = 1);

/// Reorders the particles (all six arrays alike) by the memory position of their grid cell, so
/// that a step reads the grid almost sequentially: with particles in random order each one
/// costs a cache miss, and stepping runs about twice as slow. Particles outside the grid go
/// last; ties keep their order. O(n log n), allocates; call it now and then (it changes which
/// index is which particle).
void sortParticles(Particles& particles, const ParticleCollider& collider);

/// Total mechanical energy per unit mass, sum over particles of 1/2 |v|^2 - gravity . p (double).
double particleEnergy(const Particles& particles, const Vec3d& gravity);

struct ParticleImageOptions {
    int64_t width = 800;         ///< image width in pixels; the height follows the grid's aspect ratio
    float particleRadius = 1.5f; ///< in pixels
    Vec3f particleColor{0.9f, 0.35f, 0.1f};
    Vec3f background{0.02f, 0.02f, 0.03f};
};

/// A front view of the final state: orthographic along world +y (image x = world x, image up =
/// world z), the solid shaded by its density normals, particles as discs hidden behind the solid.
Image renderParticles(const Particles& particles, const ParticleCollider& collider,
                      const ParticleImageOptions& options = {});

} // namespace voxfx
