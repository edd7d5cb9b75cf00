// voxfx — nearest-hit ray queries on triangles: Embree 3 in the loadable voxfx_embree module (loaded
// on first use, src/render/modules/embree_module.cpp). The exact reference of the glass methods
// (voxfx/exact_glass.hpp) and of the shadows (voxfx/exact_shadow.hpp).
//
// Thread-safety: a TriangleTracer is read-only after construction and may be queried from any
// number of threads.
#pragma once

#include <cstdint>
#include <memory>

#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx {

/// Nearest-hit ray queries on triangles (Embree 3 in the voxfx_embree module, loaded on first use).
class TriangleTracer {
public:
    struct Hit {
        bool hit = false;
        double t = 0;          ///< distance along the (unit) direction
        uint32_t triangle = 0; ///< index into the mesh given to the constructor
        double u = 0, v = 0;   ///< barycentrics of corners 1 and 2
    };
    /// Builds the acceleration structure over a copy of `mesh` (world space). Throws voxfx::Error
    /// for an invalid mesh, when the module is missing or when Embree fails.
    explicit TriangleTracer(const MeshView& mesh);
    ~TriangleTracer();
    TriangleTracer(const TriangleTracer&) = delete;
    TriangleTracer& operator=(const TriangleTracer&) = delete;
    /// Nearest hit of origin + t * dir (dir unit) with t in (tNear, tFar).
    Hit intersect(const Vec3d& origin, const Vec3d& dir, double tNear, double tFar) const;
    /// The triangles traced (the copy made at construction; Hit::triangle indexes them).
    const Mesh& mesh() const { return mesh_; }
    /// The step that leaves a triangle just crossed behind, for a ray continued from the hit: 1e-5
    /// of the mesh's diagonal (at least 1e-9; 1e-6 for an empty mesh).
    double epsilon() const { return epsilon_; }

private:
    struct Impl;
    Mesh mesh_;
    double epsilon_ = 1e-6;
    std::unique_ptr<Impl> impl_;
};

} // namespace voxfx
