// voxfx — ambient occlusion from a distance field: how much of the sky a surface point sees past the
// geometry near it, for the renderer's ambient light (RenderOptions::ambientOcclusion).
//
// Field: the distance from the centres of a grid of cells to the occluding triangles, clamped to the
// occlusion radius plus two cells, trilinear between centres. Exact (the closest-point hierarchy of
// voxfx/distance.hpp) at the cells a conservative voxelization of the occluders touches and their
// neighbours; beyond them the closest points are carried outwards by two raster sweeps (a vector
// distance transform), so each value is the distance to a point of the surface: never below the
// exact distance, and above it by a small part of a cell (tested against CGAL's AABB tree). The cost
// is one query per surface cell plus a few operations per cell, not the triangles within the
// radius of every cell (what an exact band as wide as the radius cost: seconds on a dense mesh).
//
// Occlusion: cone tracing the distance field (the distance-field ambient occlusion of Wright, "Dynamic
// occlusion with signed distance fields", SIGGRAPH 2015 course; Evans 2006). Seven cones of
// half-angle 30 degrees cover the hemisphere around the normal: one along it and six at 50 degrees
// from it, each traced to the radius times cos 30deg (so a ray along its side ends at the radius).
// The axis is traced exactly first (an Embree ray: an unsigned field cannot tell a sheet the axis
// crossed from one it passed by). A cone's visibility is then the smallest, over steps t, of
// 1/2 + d(p + t w) / (2 t tan 30deg) before the axis meets an occluder and 1/2 - d / (2 t tan 30deg)
// behind it, clamped to [0, 1]: an occluder at distance d from the axis at depth t covers about
// that part of the cone (half where it grazes the axis). The seven are weighted by the cosine of
// their axis to the normal. The axes make at most 50 degrees with the normal and
// cos 50deg > tan 30deg, so an unbounded plane never occludes its own points: a flat open floor has
// visibility 1 everywhere (tested).
// What it approximates: the cosine-weighted fraction of directions around the normal along which
// nothing lies within the radius: within 0.1 of it at every point and 0.03 on average beside a wall
// and around a box on the ground (tested against the fraction integrated in closed form and
// counted with Embree rays).
//
// Thread-safety: an AmbientOcclusion is read-only after construction; visibility() may be called
// from any number of threads. Results do not depend on the thread count.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {

struct AmbientOcclusionOptions {
    /// Occluders farther than this from a point do not occlude it (world units, > 0).
    double radius = 1;
    /// Cells along the longest side of the region (8..2048): the field's resolution.
    int64_t resolution = 128;
    int threads = 0;              ///< 0 = all; results are identical for every value
    Progress* progress = nullptr; ///< polled while the field is built; may cancel
};

class AmbientOcclusion {
public:
    AmbientOcclusion() = default;
    /// The field of the triangles of `occluders` over `region` (world box, grown by the radius on
    /// every side, clipped to the occluders' bounds grown by the radius: beyond that nothing is
    /// within reach). Points outside the field see no occluder. Throws voxfx::Error for a radius
    /// that is not positive and finite, a resolution out of range, an invalid mesh, or an empty or
    /// non-finite region.
    AmbientOcclusion(const MeshView& occluders, const Box3d& region, const AmbientOcclusionOptions& options);

    /// Fraction of the cosine-weighted hemisphere around the unit normal `n` at `p` that sees no
    /// occluder within the radius, in [0, 1] (1 without occluders).
    double visibility(const Vec3d& p, const Vec3d& n) const;
    /// Distance from p to the nearest occluder, trilinear between cell centres (the outermost
    /// centres' values in the field's outer half cell); the band's width (at least the radius)
    /// where farther or outside the field.
    double distance(const Vec3d& p) const;

    double radius() const { return radius_; }
    double cellSize() const { return cell_; }
    Vec3i dims() const { return dims_; }
    /// The corner of cell (0, 0, 0): cell (i, j, k) is centred at origin() + (i + 1/2, j + 1/2, k + 1/2) *
    /// cellSize().
    Vec3d origin() const { return lo_; }

private:
    void buildField(const MeshView& occluders, const AmbientOcclusionOptions& options);
    Vec3d lo_;        ///< corner of cell (0, 0, 0)
    double cell_ = 1; ///< cubic cells
    Vec3i dims_{0, 0, 0};
    double radius_ = 0, band_ = 0;
    std::vector<float> distance_; ///< per cell centre, x fastest; empty: no occluder in reach
    std::shared_ptr<const TriangleTracer> tracer_; ///< the cones' axes (Embree)
};

} // namespace voxfx
