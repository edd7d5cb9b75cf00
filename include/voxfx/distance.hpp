// voxfx — distances from points to a triangle mesh: the closest point (with its face and
// barycentric coordinates) and the signed distance, for millions of points.
//
// One closest-point query serves everything (this header and the signed distance fields of
// voxfx/sdf.hpp): a bounding-volume hierarchy over the triangles (binned SAH, nearest child first,
// branch and bound) and a point-triangle kernel in double precision. It was measured against
// Embree 3's rtcPointQuery and CGAL's AABB tree (bench/bench_distance.cpp, BENCHMARKS.md) and kept
// because it was the fastest of the three.
//
// What "exact" means here. The mesh is the triangles whose corners are its float coordinates
// (converted to double without rounding); a query point is a double. The distance returned is the
// Euclidean distance from the point to that closed triangle set, evaluated in double precision:
// its error is a few units in the last place of double of max(distance, distance from the point
// to the triangle's corners), about 1e-16 of the mesh's size for points near it, far below the
// rounding to float (2^-24 relative) that a float result or a float grid would add. Tests compare
// it with CGAL's exact (rational) squared distance to the nearest triangle of CGAL's AABB tree.
// The closest point and barycentric coordinates carry the same kind of error; the face is one of
// the faces at the minimal computed distance, the one with the smallest index when several tie
// exactly (a point on an edge or a vertex shared by several faces gets the smallest of them), so
// the answer does not depend on the hierarchy or the thread count.
//
// Defined answers: a point with a NaN or infinite coordinate gets distance NaN, point and
// barycentric coordinates NaN and face -1. Degenerate triangles (zero area: collinear corners,
// repeated corners) are the segments (or the point) they span, and keep barycentric coordinates
// on their corners. A mesh without triangles is an error.
//
// Cost: building O(T log T) (about 0.3 s for 1M triangles on one core), each query
// O(log T) for points near the surface (longer far from meshes with many equidistant triangles,
// e.g. the centre of a sphere), spread over worker threads.
// Thread-safety: a ClosestPointQuery is immutable after construction; its members may be called
// from many threads at once, and use worker threads themselves (`threads`). Results do not depend
// on the thread count.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace detail {
class TriangleBvh;
}

/// The point of the mesh closest to a query point.
struct ClosestPoint {
    Vec3d point{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
                std::numeric_limits<double>::quiet_NaN()};
    /// Weights of the face's corners 0, 1, 2 (each in [0, 1], sum 1): point = w0 v0 + w1 v1 + w2 v2.
    Vec3d barycentric{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
                      std::numeric_limits<double>::quiet_NaN()};
    double distance = std::numeric_limits<double>::quiet_NaN(); ///< |query - point|, world units
    int64_t face = -1;                                          ///< triangle index, -1 for a non-finite query
};

struct DistanceOptions {
    /// Worker threads, 0 = all. Results are identical for every value.
    int threads = 0;
    /// Polled between chunks of points; may cancel (voxfx::Error "cancelled"). Not owned.
    Progress* progress = nullptr;
};

/// A mesh prepared for many closest-point queries (the hierarchy, built once). The mesh is
/// validated (voxfx::Error on bad indices, non-finite vertices or no triangles) and copied.
class ClosestPointQuery {
public:
    explicit ClosestPointQuery(const MeshView& mesh);
    ~ClosestPointQuery();
    ClosestPointQuery(ClosestPointQuery&&) noexcept;
    ClosestPointQuery& operator=(ClosestPointQuery&&) noexcept;

    /// One point, on the calling thread.
    ClosestPoint closest(const Vec3d& p) const;
    /// out[i] = closest(points[i]); the sizes must match (voxfx::Error otherwise).
    void closest(std::span<const Vec3d> points, std::span<ClosestPoint> out,
                 const DistanceOptions& options = {}) const;
    /// out[i] = closest(points[i]).distance, without the point and weights.
    void distance(std::span<const Vec3d> points, std::span<double> out,
                  const DistanceOptions& options = {}) const;

    std::size_t triangleCount() const;
    /// The hierarchy itself, for the library's signed distance fields (voxfx/sdf.hpp).
    const detail::TriangleBvh& bvh() const { return *bvh_; }

private:
    std::unique_ptr<detail::TriangleBvh> bvh_;
};

/// closest() of every point, building the query once. Throws voxfx::Error.
std::vector<ClosestPoint> closestPoints(const MeshView& mesh, std::span<const Vec3d> points,
                                        const DistanceOptions& options = {});

/// How the sign of a signed distance is decided.
///   Parity   the exact inside test of voxfx/contains.hpp (ContainsMethod::Parity) with its tie
///            rule: exact for closed meshes, and the same answer as a solid voxelization gives a
///            voxel centre at that point. A point on the surface (distance 0) takes the side of
///            the point nudged by (+eps, +eps^2, -delta), as a voxel centre would.
///   Winding  the generalized winding number >= 0.5 (ContainsMethod::Winding, Barill et al.'s
///            fast approximation): for open meshes and meshes with holes, where parity has no
///            meaning; needs a consistent orientation.
///   Auto     Parity when the mesh is closed (voxfx::analyzeTopology), Winding otherwise.
enum class SignMethod : uint8_t { Auto, Parity, Winding };
inline constexpr EnumName<SignMethod> kSignMethodNames[] = {{"auto", SignMethod::Auto},
                                                            {"parity", SignMethod::Parity},
                                                            {"winding", SignMethod::Winding},
                                                            {"gwn", SignMethod::Winding, true}};
const char* toString(SignMethod m);
/// Parses "auto", "parity", "winding"; throws voxfx::Error listing them otherwise.
SignMethod parseSignMethod(const std::string& name);

struct SignedDistanceOptions {
    SignMethod sign = SignMethod::Auto;
    /// Winding: Barill et al.'s accuracy parameter (ContainsOptions::windingBeta).
    double windingBeta = 3.0;
    int threads = 0;
    Progress* progress = nullptr;
    /// Receives the method Auto chose (or the one given). Not owned; may be null.
    SignMethod* used = nullptr;
};

/// out[i] = the distance from points[i] to the mesh, negative inside (see SignMethod); -0.0 for
/// a point on the surface that the inside test puts inside. NaN for non-finite points. Sizes
/// must match. Cost: closest points plus the inside test (voxfx/contains.hpp). Throws voxfx::Error.
void signedDistance(const MeshView& mesh, std::span<const Vec3d> points, std::span<double> out,
                    const SignedDistanceOptions& options = {});
std::vector<double> signedDistance(const MeshView& mesh, std::span<const Vec3d> points,
                                   const SignedDistanceOptions& options = {});

} // namespace voxfx
