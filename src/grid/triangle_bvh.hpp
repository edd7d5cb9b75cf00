// voxfx — the one closest-point query over a mesh's triangles (internal to grid/): a point-triangle
// distance kernel in double precision and a bounding-volume hierarchy over the triangles, shared by
// voxfx/distance.hpp (closest points, signed distance at points) and voxfx/sdf.hpp (signed
// distance fields).
//
// The kernel: the triangle's corners are the mesh's float coordinates, converted exactly to double;
// the query point is a double. Let n = (b - a) x (c - a). When n != 0 and the point's projection
// onto the plane lies in the closed triangle (its three edge functions, scaled barycentric
// coordinates, are >= 0), the squared distance is (n . (p - a))^2 / (n . n); otherwise the closest
// point lies on an edge whose edge function is negative (every edge when n = 0: degenerate
// triangles are their segments, a point triangle its point), and on each such edge the parameter
// t = clamp((p - a) . e / (e . e), 0, 1) gives it. Ericson's region tests are not used: they
// divide by n . n in every case, which fails on degenerate triangles.
// Why it is accurate: b - a of float corners is exact in double (for exponents within 29 of each
// other), so the products in n = (b - a) x (c - a) are exact and each component of n is rounded
// once; the distance then carries a relative error of a few ulps of double of
// max(distance, |p - a|) at most. See voxfx/distance.hpp for what is promised.
//
// The hierarchy: a binary tree over the triangles' boxes (float, exact: the corners are floats),
// split by the surface area heuristic over 16 bins of the centroids, at most 4 triangles a leaf;
// each node holds both children's boxes (one cache line per visit), the triangles are stored as
// their float corners in tree order (36 bytes each: queries are bound by memory, not arithmetic).
// Built in parallel below the top levels; the tree does not depend on the thread count.
// Queries descend the nearer child first and skip a child whose box lies farther than the best
// distance found (with a relative slack of 2^-40, so a triangle at the same computed distance is
// never skipped: ties go to the smallest face index, independent of the tree's shape).
// Thread-safety: immutable after construction; every query may run from many threads at once.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx::detail {

/// A triangle prepared for distance queries (double; 200 bytes): what triangleDistance2 computes
/// from the corners, computed once (for a triangle tested against many points).
struct DistanceTriangle {
    Vec3d a, ab, ac, bc;                 ///< corner a, and the edges b - a, c - a, c - b
    Vec3d n;                             ///< ab x ac (not normalized)
    Vec3d nab, nac;                      ///< n x ab and ac x n: (p - a) . nab = n . (ab x (p - a)), etc.
    double nn = 0;                       ///< n . n; 0 for a degenerate triangle (n = 0, or n . n not finite)
    double abab = 0, acac = 0, bcbc = 0; ///< e . e per edge
};

inline DistanceTriangle prepareTriangle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    DistanceTriangle t;
    t.a = a;
    t.ab = b - a;
    t.ac = c - a;
    t.bc = c - b;
    t.n = cross(t.ab, t.ac);
    t.nab = cross(t.n, t.ab);
    t.nac = cross(t.ac, t.n);
    t.nn = dot(t.n, t.n);
    // A triangle whose normal is zero (or underflows, or overflows) is its three segments.
    if (!(t.nn > 0 && t.nn < std::numeric_limits<double>::infinity())) t.nn = 0;
    t.abab = dot(t.ab, t.ab);
    t.acac = dot(t.ac, t.ac);
    t.bcbc = dot(t.bc, t.bc);
    return t;
}

/// Squared distance from p to the closed triangle, and the barycentric weights (u, v) of corners
/// b and c of the closest point (the weight of a is 1 - u - v). See the file comment. The same
/// bits whether `t` was prepared once or just now (prepareTriangle is the only arithmetic).
inline double triangleDistance2(const DistanceTriangle& t, const Vec3d& p, double& u, double& v) {
    const Vec3d ap = p - t.a;
    u = v = 0;
    bool outAb = true, outAc = true, outBc = true;
    if (t.nn > 0) {
        const double sb = dot(ap, t.nac); // (weight of b) * (n . n)
        const double sc = dot(ap, t.nab); // (weight of c) * (n . n)
        const double sa = t.nn - sb - sc;
        if (sa >= 0 && sb >= 0 && sc >= 0) {
            const double inv = 1.0 / t.nn;
            u = sb * inv;
            v = sc * inv;
            const double h = dot(ap, t.n);
            return h * h * inv;
        }
        outAb = sc < 0;
        outAc = sb < 0;
        outBc = sa < 0;
    }
    const auto param = [](double num, double den) { return den > 0 ? std::clamp(num / den, 0.0, 1.0) : 0.0; };
    double best = std::numeric_limits<double>::infinity();
    // Edge ab: weights (1 - s, s, 0).
    if (outAb) {
        const double s = param(dot(ap, t.ab), t.abab);
        const Vec3d d = ap - t.ab * s;
        best = dot(d, d);
        u = s;
        v = 0;
    }
    // Edge ac: weights (1 - s, 0, s).
    if (outAc) {
        const double s = param(dot(ap, t.ac), t.acac);
        const Vec3d d = ap - t.ac * s;
        const double d2 = dot(d, d);
        if (d2 < best) {
            best = d2;
            u = 0;
            v = s;
        }
    }
    // Edge bc: weights (0, 1 - s, s).
    if (outBc) {
        const Vec3d bp = ap - t.ab;
        const double s = param(dot(bp, t.bc), t.bcbc);
        const Vec3d d = bp - t.bc * s;
        const double d2 = dot(d, d);
        if (d2 < best) {
            best = d2;
            u = 1 - s;
            v = s;
        }
    }
    return best;
}

/// Squared distance from p to the box [lo, hi] (0 inside).
inline double boxDistance2(const float lo[3], const float hi[3], const Vec3d& p) {
    double s = 0;
    for (int k = 0; k < 3; ++k) {
        const double d = std::max({double(lo[k]) - p[k], 0.0, p[k] - double(hi[k])});
        s += d * d;
    }
    return s;
}

/// Squared distance between the boxes [lo, hi] and [blo, bhi] (0 when they meet).
inline double boxBoxDistance2(const float lo[3], const float hi[3], const Vec3d& blo, const Vec3d& bhi) {
    double s = 0;
    for (int k = 0; k < 3; ++k) {
        const double d = std::max({double(lo[k]) - bhi[k], 0.0, blo[k] - double(hi[k])});
        s += d * d;
    }
    return s;
}

/// An inner node: the boxes of both children, so that a visit reads one cache line.
struct BvhNode {
    float lo[2][3], hi[2][3];
    uint32_t ref[2];   ///< child node index, or (count > 0) the child leaf's first triangle
    uint32_t count[2]; ///< triangles of a leaf child; 0 for a node child
};
static_assert(sizeof(BvhNode) == 64);

/// A child as the builder returns it: its box and reference.
struct BvhRef {
    Box3d box;
    uint32_t ref = 0, count = 0;
};

/// The nearest triangle found: face (mesh index, -1 when none), squared distance, and the
/// barycentric weights (u, v) of the face's corners 1 and 2.
struct NearestHit {
    int64_t face = -1;
    uint32_t index = 0; ///< the triangle in tree order (TriangleBvh::triangle)
    double distance2 = std::numeric_limits<double>::infinity();
    double u = 0, v = 0;
};

class TriangleBvh {
public:
    TriangleBvh() = default;
    /// Builds over every triangle of `mesh` (which must be valid: voxfx::validateMesh). Copies
    /// what it needs; the mesh may go away afterwards.
    explicit TriangleBvh(const MeshView& mesh);

    std::size_t triangleCount() const { return faces_.size(); }
    /// The mesh's bounds (empty without triangles) and the length of their diagonal.
    const Box3d& bounds() const { return root_.box; }
    double diagonal() const { return diagonal_; }

    /// The nearest triangle to p with squared distance <= maxDistance2 (ties: the smallest face
    /// index). face = -1 when none is that near, or p is not finite. `hint` (a tree index, e.g. the
    /// answer for a nearby point; UINT32_MAX for none) only makes the search faster.
    NearestHit nearest(const Vec3d& p, double maxDistance2 = std::numeric_limits<double>::infinity(),
                       uint32_t hint = UINT32_MAX) const;

    /// Appends to `out` (tree order indices, in an order fixed by the tree) every triangle whose box lies
    /// within `radius` of the box [lo, hi] (squared box-to-box distance <= radius^2).
    void gather(const Vec3d& lo, const Vec3d& hi, double radius, std::vector<uint32_t>& out) const;

    /// Triangle i in tree order: its corners (exactly the mesh's floats) and its mesh face index.
    Vec3d corner(uint32_t i, int k) const {
        const float* c = &corners_[9 * std::size_t(i) + 3 * std::size_t(k)];
        return {c[0], c[1], c[2]};
    }
    DistanceTriangle triangle(uint32_t i) const {
        return prepareTriangle(corner(i, 0), corner(i, 1), corner(i, 2));
    }
    uint32_t face(uint32_t i) const { return faces_[i]; }

private:
    struct Pending {
        uint32_t begin, end;
        int depth;
    };
    struct BuildState {
        std::vector<uint32_t>& order; ///< permuted in place: disjoint ranges per subtree
        const std::vector<Vec3d>& centroid;
        const std::vector<float>& boxes;
        std::vector<Pending> pending;
        uint32_t cutoff;
    };
    static constexpr uint32_t kPendingCount = UINT32_MAX; ///< BvhRef::count of a placeholder
    void buildAll(BuildState& st, uint32_t n);
    BvhRef build(BuildState& st, std::vector<BvhNode>& nodes, uint32_t begin, uint32_t end, int depth,
                 bool top) const;
    static void setChild(BvhNode& node, int c, const BvhRef& child);
    uint32_t split(std::vector<uint32_t>& order, const std::vector<Vec3d>& centroid, uint32_t begin,
                   uint32_t end, const std::vector<float>& boxes, const Box3d& box, int depth) const;
    /// Squared distance from p to the box of triangle i (from its corners).
    double triangleBoxDistance2(uint32_t i, const Vec3d& p) const;

    std::vector<BvhNode> nodes_;
    BvhRef root_;                 ///< a leaf when the mesh has at most a leaf's triangles
    std::vector<float> corners_;  ///< tree order, 9 floats per triangle
    std::vector<uint32_t> faces_; ///< tree order -> mesh face
    double diagonal_ = 0;
};

} // namespace voxfx::detail
