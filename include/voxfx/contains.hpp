// voxfx — exact point occupancy: is each of millions of points inside a triangle mesh?
//
// What learning pipelines sample (occupancy networks take ~100K points per mesh). Three methods:
//
//   Parity   exact for closed meshes, with the voxel centres' tie rule. A point is inside when
//            an odd number of triangles lie strictly below it along world z (the voxelizer's
//            slicing direction for axis Z), where "the vertical line through the point meets
//            the triangle" uses the rasterizer's strict tie rule: the point is perturbed by
//            (+eps, +eps^2) in (x, y) and every edge is evaluated on its lexicographically
//            ordered endpoints, so a point above a shared edge or vertex counts exactly one
//            triangle of a closed mesh and triangles parallel to z count none; and a triangle
//            through the point itself does not count (the voxelizer's "slice centre strictly
//            behind the fragment"). In other words: the answer for p is the exact answer for
//            p + (eps, eps^2, -delta) with 0 < eps << delta infinitesimal, so points on the
//            surface get a definite, consistent answer. Decided with exact predicates (floating
//            point filters, exact expansion arithmetic when the filter cannot decide).
//            How: the mesh is voxelized as a solid (parity) and as a conservative surface in
//            a grid one cell wider than its bounds; a point whose cell the surface does not
//            touch takes the cell's answer (the cell centre is at least half a cell from the
//            surface, so it lies on the same side), the others are decided exactly against
//            the triangles binned to their column. Cost ~ voxelization + points +
//            (points in surface cells) * (triangles per column).
//   Winding  the generalized winding number (Jacobson et al. 2013): the sum of the signed solid
//            angles of the triangles seen from the point (Van Oosterom-Strackee), / 4 pi,
//            inside when |w| >= 0.5. Robust to holes and self-intersections; needs orientation
//            consistent within each closed part, either way: a mesh oriented inward has w = -1
//            inside (three of CGAL's closed meshes are), and a hollow part's inner shell, oriented
//            against its outer one, still leaves the cavity at w = 0. (Orienting each connected
//            part by its signed volume instead would fill such cavities.) Fast approximation after Barill et
//            al. 2018: a bounding-volume hierarchy over the triangles, far clusters replaced by their dipole
//            (area-weighted normal at the area-weighted centroid), near ones summed exactly (windingBeta; 0
//            sums every triangle, cost points * triangles).
//   Flood    cells the flood from the grid border cannot reach through the conservative
//            surface (Fill::Flood), at the grid resolution: robust to holes narrower than a
//            cell; points in surface cells count as inside (as Fill::Flood includes them).
//
// Points outside the grid (NaN included) are outside. Results do not depend on the thread count.
// Thread-safety: a PointClassifier is immutable after construction; classify() may be called
// from many threads at once and uses worker threads itself (`threads`).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

enum class ContainsMethod : uint8_t { Parity, Winding, Flood };
inline constexpr EnumName<ContainsMethod> kContainsMethodNames[] = {{"parity", ContainsMethod::Parity},
                                                                    {"winding", ContainsMethod::Winding},
                                                                    {"flood", ContainsMethod::Flood}};
const char* toString(ContainsMethod m);
/// Parses "parity", "winding", "flood"; throws voxfx::Error listing them otherwise.
ContainsMethod parseContainsMethod(const std::string& name);

struct ContainsOptions {
    ContainsMethod method = ContainsMethod::Parity;
    /// Cells along the longest side of the acceleration grid; 0 picks one from the triangle
    /// count (and, in contains(), the point count). Flood answers at this resolution.
    int64_t resolution = 0;
    /// Winding: Barill et al.'s accuracy parameter beta. Triangle clusters whose bounding sphere
    /// (radius r) is farther than beta * r from the point contribute their dipole term; nearer
    /// ones are summed exactly. 0 sums every triangle exactly (cost points * triangles). With
    /// dipoles only (first order) the error is about 0.22 / beta^2 at worst (measured on CGAL
    /// meshes): 3 keeps it under 0.025.
    double windingBeta = 3.0;
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
    /// Polled between the tiles of the voxelizations that build a PointClassifier and, in
    /// contains(), between chunks of points (see classify()); returning false cancels (voxfx::Error).
    /// Not owned, and not kept by the PointClassifier (classify() takes its own).
    Progress* progress = nullptr;
};

/// Counters of the last classify() call, for tests and benchmarks.
struct ContainsStats {
    int64_t points = 0;
    int64_t fromCells = 0;  ///< decided by their cell
    int64_t exact = 0;      ///< decided against the triangles (parity) or summed (winding)
    int64_t filterMiss = 0; ///< exact predicates that needed exact arithmetic
};

/// A mesh prepared for many point queries (grids and per-column triangle lists). The mesh is
/// copied; it is validated (voxfx::Error on bad indices or non-finite vertices).
class PointClassifier {
public:
    PointClassifier(const MeshView& mesh, const ContainsOptions& options = {});
    ~PointClassifier();
    PointClassifier(PointClassifier&&) noexcept;
    PointClassifier& operator=(PointClassifier&&) noexcept;

    /// out[i] = 1 when points[i] is inside, else 0. Sizes must match (voxfx::Error otherwise).
    /// `progress`, when given, is polled between chunks of about a million points (65,536 for the
    /// winding method; fraction: the share of points done); returning false cancels with
    /// voxfx::Error, `out` then partly written.
    void classify(std::span<const Vec3d> points, std::span<uint8_t> out, ContainsStats* stats = nullptr,
                  Progress* progress = nullptr) const;
    /// One point (no worker threads).
    bool inside(const Vec3d& p) const;
    /// The acceleration grid's resolution (cells along the longest side).
    int64_t resolution() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// The resolution contains() picks for `triangles` triangles and `points` points (about
/// max(1.3 cbrt(points), 0.25 sqrt(triangles)), in 16..512).
int64_t defaultContainsResolution(std::size_t triangles, std::size_t points);

/// out[i] = 1 when points[i] lies inside `mesh` (see the file comment). Throws voxfx::Error.
void contains(const MeshView& mesh, std::span<const Vec3d> points, std::span<uint8_t> out,
              const ContainsOptions& options = {});
std::vector<uint8_t> contains(const MeshView& mesh, std::span<const Vec3d> points,
                              const ContainsOptions& options = {});

/// The generalized winding number of `mesh` at `p`: sum of signed solid angles / (4 pi)
/// (1 inside a closed, outward-oriented mesh, 0 outside). O(triangles).
double windingNumber(const MeshView& mesh, const Vec3d& p);

/// The same, approximated as in Barill et al. 2018 (see ContainsOptions::windingBeta), for many
/// points: out[i] = winding number at points[i]. Builds the hierarchy once per call.
void windingNumbers(const MeshView& mesh, std::span<const Vec3d> points, std::span<double> out,
                    double beta = 3.0, int threads = 0);

namespace exact {
// Shewchuk's floating point filters, then exact expansion arithmetic on inputs scaled by a power
// of two. Exact for finite inputs unless nonzero coordinate differences span more than about
// 2^800 between the largest and the smallest (then tiny products underflow); real meshes are far
// from that, and subnormal coordinates next to ordinary ones are handled.
/// Sign (-1, 0, +1) of (b - a) x (c - a) in the xy plane, exactly (positive: counter-clockwise).
int orient2d(double ax, double ay, double bx, double by, double cx, double cy);
/// Sign of det[b - a; c - a; d - a] (rows), exactly: positive when d lies on the side of the
/// plane (a, b, c) that its normal (b - a) x (c - a) points to.
int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d);
} // namespace exact

} // namespace voxfx
