// voxfx — distances from points to meshes (voxfx/distance.hpp) against CGAL.
//
// Oracles:
//   - CGAL's exact squared distance (Epeck, rational) to the triangles near the answer of CGAL's
//     AABB tree: the distance to within a few ulps of double, and which faces tie exactly;
//   - CGAL's AABB tree closest point (Epick) for the point itself, and CGAL's point-triangle
//     distance for "the returned point lies on the returned face";
//   - brute force over every triangle with the same kernel: the hierarchy must change nothing,
//     bit for bit (its pruning and its tie rule);
//   - CGAL::Side_of_triangle_mesh for the sign off the surface, the perturbed exact test for
//     points on it, the exact winding number sum for open meshes.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "grid/triangle_bvh.hpp"
#include "test_util.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/distance.hpp"
#include "voxfx/mesh_io.hpp"

namespace voxfx {
namespace {

constexpr double kDoubleEps = 0x1p-52;

/// Query points around a mesh: uniform in the bounds grown by 20%, points near the surface (a
/// vertex moved by a small random offset), the vertices themselves, edge midpoints and face
/// centroids (on the surface), and a few far away.
std::vector<Vec3d> distanceQueryPoints(const MeshView& mesh, std::size_t n, uint64_t seed) {
    const Box3d b = computeBounds(mesh);
    const Vec3d e = b.extent();
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Vec3d> pts;
    for (std::size_t i = 0; i < n; ++i) {
        Vec3d p;
        for (int k = 0; k < 3; ++k) p[k] = b.lo[k] - 0.2 * e[k] + u(rng) * 1.4 * e[k];
        pts.push_back(p);
    }
    const double scale = std::max({e.x, e.y, e.z});
    for (std::size_t i = 0; i < n / 2; ++i) {
        const auto t = std::size_t(u(rng) * double(mesh.triangleCount)) % mesh.triangleCount;
        const Vec3d v = mesh.vertex(mesh.index(t, int(i % 3)));
        pts.push_back(v + Vec3d{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5} * (scale * 0.02));
    }
    for (std::size_t i = 0; i < n / 8; ++i) {
        const auto t = std::size_t(u(rng) * double(mesh.triangleCount)) % mesh.triangleCount;
        const Vec3d a = mesh.vertex(mesh.index(t, 0)), bb = mesh.vertex(mesh.index(t, 1)),
                    c = mesh.vertex(mesh.index(t, 2));
        pts.push_back(a);
        pts.push_back((a + bb) * 0.5);
        pts.push_back((a + bb + c) / 3.0);
    }
    for (const double far : {1e3, -1e5, 3e7}) pts.push_back(b.center() + Vec3d{far, far * 0.5, -far} * scale);
    return pts;
}

std::array<Vec3d, 3> distanceFace(const MeshView& mesh, int64_t f) {
    return {mesh.vertex(mesh.index(std::size_t(f), 0)), mesh.vertex(mesh.index(std::size_t(f), 1)),
            mesh.vertex(mesh.index(std::size_t(f), 2))};
}

/// The scale of a query's rounding: the distance plus the farthest corner of the face.
double distanceScale(const MeshView& mesh, const Vec3d& p, int64_t face) {
    double s = 0;
    for (const Vec3d& v : distanceFace(mesh, face)) s = std::max(s, length(p - v));
    return s;
}

// Checks every answer against CGAL (see the file comment). Returns the largest distance error
// in units of the scale's double ulp.
double checkAgainstCgal(const MeshView& mesh, const std::vector<Vec3d>& pts, const std::string& name) {
    const std::vector<ClosestPoint> got = closestPoints(mesh, pts);
    const std::vector<test::OracleNearest> cgal = test::oracleNearest(mesh, pts, true);
    double worst = 0;
    int shown = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const ClosestPoint& c = got[i];
        const test::OracleNearest& o = cgal[i];
        if (c.face < 0) {
            ADD_FAILURE() << name << " point " << i << ": no face";
            continue;
        }
        const double scale = distanceScale(mesh, pts[i], c.face);
        const double err = std::abs(c.distance - o.distance);
        worst = std::max(worst, err / (scale * kDoubleEps));
        // Distance: within 4 ulps of the scale (the kernel rounds about a dozen times, mostly
        // cancelling; the largest error measured on these meshes is under 2).
        if (!(err <= 4 * kDoubleEps * scale) && shown++ < 5)
            ADD_FAILURE() << name << " point " << i << " (" << pts[i].x << ", " << pts[i].y << ", "
                          << pts[i].z << "): distance " << c.distance << ", CGAL exact " << o.distance;
        // The face attains the minimum: exactly one of the exact ties, or within the rounding.
        const bool tie = std::find(o.ties.begin(), o.ties.end(), c.face) != o.ties.end();
        const double faceD = std::sqrt(test::oracleTriangleDistance2(distanceFace(mesh, c.face), pts[i]));
        EXPECT_TRUE(tie || std::abs(faceD - o.distance) <= 4 * kDoubleEps * scale)
            << name << " point " << i << ": face " << c.face << " at " << faceD << ", nearest " << o.distance;
        // When the minimum is attained by one face only, the face is that one.
        if (o.ties.size() == 1 && std::abs(faceD - o.distance) > 1e-9 * scale) {
            EXPECT_EQ(c.face, o.ties[0]) << name << " point " << i;
        }
        // The point lies on the face, at the distance, and is the weighted sum of the corners: a
        // constructed point rounds with its coordinates' magnitude.
        const std::array<Vec3d, 3> f = distanceFace(mesh, c.face);
        const double pointScale = scale + std::max(length(pts[i]), length(f[0]));
        EXPECT_LE(std::sqrt(test::oracleTriangleDistance2(f, c.point)), 16 * kDoubleEps * pointScale)
            << name << " " << i;
        EXPECT_NEAR(length(c.point - pts[i]), c.distance, 16 * kDoubleEps * pointScale) << name << " " << i;
        const Vec3d w = c.barycentric;
        EXPECT_TRUE(w.x >= -kDoubleEps && w.y >= 0 && w.z >= 0 &&
                    std::abs(w.x + w.y + w.z - 1) <= 4 * kDoubleEps)
            << name << " point " << i << ": weights " << w.x << " " << w.y << " " << w.z;
        EXPECT_LE(length(f[0] * w.x + f[1] * w.y + f[2] * w.z - c.point), 16 * kDoubleEps * pointScale)
            << name << " " << i;
        // CGAL's own closest point, when the nearest face is unique.
        if (o.ties.size() == 1 && o.face == c.face) {
            EXPECT_LE(length(c.point - o.point), 1e-12 * pointScale) << name << " point " << i;
        }
    }
    return worst;
}

const char* const kDistanceMeshes[] = {"meshes/elephant.off", "meshes/knot.off", "meshes/cube-meshed.off",
                                       "meshes/fandisk.off", "meshes/bunny00.off"};

TEST(Distance, ClosestPointsMatchCgalExactDistanceOnRealMeshes) {
    for (const char* name : kDistanceMeshes) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const std::size_t n = mesh.triangleCount() > 20000 ? 600 : 2000;
        const std::vector<Vec3d> pts = distanceQueryPoints(mesh.view(), n, 11);
        const double worst = checkAgainstCgal(mesh.view(), pts, name);
        std::cout << name << ": " << pts.size() << " points, largest distance error " << worst
                  << " ulps of the scale\n";
    }
}

TEST(Distance, HierarchyChangesNothingAgainstBruteForce) {
    // The same kernel over every triangle, in face order: the tree's pruning and tie rule must give
    // the same face and the same bits.
    for (const char* name : {"meshes/elephant.off", "meshes/cube-meshed.off", "meshes/knot.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const MeshView v = mesh.view();
        std::vector<detail::DistanceTriangle> tris;
        for (std::size_t t = 0; t < v.triangleCount; ++t)
            tris.push_back(detail::prepareTriangle(v.vertex(v.index(t, 0)), v.vertex(v.index(t, 1)),
                                                   v.vertex(v.index(t, 2))));
        const std::vector<Vec3d> pts = distanceQueryPoints(v, 3000, 5);
        const std::vector<ClosestPoint> got = closestPoints(v, pts);
        for (std::size_t i = 0; i < pts.size(); ++i) {
            double best = std::numeric_limits<double>::infinity();
            int64_t face = -1;
            for (std::size_t t = 0; t < tris.size(); ++t) {
                double u, w;
                const double d2 = detail::triangleDistance2(tris[t], pts[i], u, w);
                if (d2 < best) {
                    best = d2;
                    face = int64_t(t);
                }
            }
            ASSERT_EQ(got[i].face, face) << name << " point " << i;
            ASSERT_EQ(got[i].distance, std::sqrt(best)) << name << " point " << i;
        }
    }
}

TEST(Distance, SameAnswersForEveryThreadCount) {
    VOXFX_REQUIRE_DATA("meshes/bunny00.off");
    const Mesh mesh = loadMesh(test::dataPath("meshes/bunny00.off"));
    const std::vector<Vec3d> pts = distanceQueryPoints(mesh.view(), 16000, 3);
    const ClosestPointQuery query(mesh.view());
    std::vector<ClosestPoint> one(pts.size()), all(pts.size());
    DistanceOptions o;
    o.threads = 1;
    query.closest(pts, one, o);
    o.threads = 0;
    query.closest(pts, all, o);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        ASSERT_EQ(one[i].face, all[i].face);
        ASSERT_EQ(one[i].distance, all[i].distance);
        ASSERT_EQ(one[i].point, all[i].point);
    }
    std::vector<double> d(pts.size());
    query.distance(pts, d);
    for (std::size_t i = 0; i < pts.size(); ++i) ASSERT_EQ(d[i], one[i].distance);
}

TEST(Distance, DegenerateTrianglesAreTheirSegments) {
    // A proper triangle, a sliver with collinear corners, a triangle with a repeated corner and a
    // point triangle, far apart so each query's nearest face is clear.
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},  // proper
                   {5, 0, 0}, {6, 1, 1}, {7, 2, 2},  // collinear (b is the midpoint)
                   {0, 5, 0}, {0, 5, 0}, {0, 6, 1},  // repeated corner: the segment
                   {9, 9, 9}, {9, 9, 9}, {9, 9, 9}}; // a point
    m.indices = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    std::vector<Vec3d> pts = {{0.2, 0.2, 1}, {6, 1.5, 0.5}, {8, 3, 3},   {4, -1, -1}, {0.5, 5.5, 0.5},
                              {1, 4, -1},    {9, 9, 10},    {9.5, 9, 9}, {6, 1, 1},   {7, 2, 2}};
    const std::vector<ClosestPoint> got = closestPoints(m.view(), pts);
    const std::vector<test::OracleNearest> cgal = test::oracleNearest(m.view(), pts, true);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        EXPECT_NEAR(got[i].distance, cgal[i].distance, 1e-14) << "point " << i;
        const std::array<Vec3d, 3> f = distanceFace(m.view(), got[i].face);
        EXPECT_LE(test::oracleTriangleDistance2(f, got[i].point), 1e-28) << "point " << i;
        const Vec3d w = got[i].barycentric;
        EXPECT_NEAR(w.x + w.y + w.z, 1.0, 1e-15);
        EXPECT_LE(length(f[0] * w.x + f[1] * w.y + f[2] * w.z - got[i].point), 1e-14) << "point " << i;
    }
    // On the collinear triangle's corners and on the point triangle: distance exactly 0.
    EXPECT_EQ(got[8].distance, 0.0);
    EXPECT_EQ(got[9].distance, 0.0);
    EXPECT_EQ(closestPoints(m.view(), std::vector<Vec3d>{{9, 9, 9}})[0].distance, 0.0);
}

TEST(Distance, PointsOnVerticesAndEdgesAreAtZeroOnTheSmallestFace) {
    const Mesh m = test::makeOctahedron({0.25, -0.5, 0.125}, 0.75);
    const MeshView v = m.view();
    std::vector<Vec3d> pts;
    for (std::size_t i = 0; i < v.vertexCount; ++i) pts.push_back(v.vertex(i));
    for (std::size_t t = 0; t < v.triangleCount; ++t)
        pts.push_back((v.vertex(v.index(t, 0)) + v.vertex(v.index(t, 1))) * 0.5); // exact: dyadic
    const std::vector<ClosestPoint> got = closestPoints(v, pts);
    const std::vector<test::OracleNearest> cgal = test::oracleNearest(v, pts, true);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        EXPECT_EQ(cgal[i].distance, 0.0) << i;
        EXPECT_LE(got[i].distance, 1e-16) << i;
        ASSERT_FALSE(cgal[i].ties.empty());
        // Every incident face is at exact distance 0; the answer is one of them.
        EXPECT_NE(std::find(cgal[i].ties.begin(), cgal[i].ties.end(), got[i].face), cgal[i].ties.end()) << i;
    }
}

TEST(Distance, NonFinitePointsGetNaNAndNoFace) {
    const Mesh m = test::makeBox({0, 0, 0}, {1, 1, 1});
    const double nan = std::numeric_limits<double>::quiet_NaN(),
                 inf = std::numeric_limits<double>::infinity();
    const std::vector<Vec3d> pts = {{nan, 0, 0}, {0, inf, 0}, {0, 0, -inf}, {0.5, 0.5, 2}};
    const std::vector<ClosestPoint> got = closestPoints(m.view(), pts);
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(got[std::size_t(i)].face, -1);
        EXPECT_TRUE(std::isnan(got[std::size_t(i)].distance));
        EXPECT_TRUE(std::isnan(got[std::size_t(i)].point.x) && std::isnan(got[std::size_t(i)].barycentric.y));
    }
    EXPECT_EQ(got[3].distance, 1.0);
    const std::vector<double> sd = signedDistance(m.view(), pts);
    EXPECT_TRUE(std::isnan(sd[0]) && std::isnan(sd[1]) && std::isnan(sd[2]));
    EXPECT_EQ(sd[3], 1.0);
}

TEST(Distance, BadMeshesAreErrors) {
    Mesh empty;
    EXPECT_THROW(ClosestPointQuery{empty.view()}, Error);
    Mesh bad = test::makeBox({0, 0, 0}, {1, 1, 1});
    bad.indices[4] = 99;
    EXPECT_THROW(ClosestPointQuery{bad.view()}, Error);
    const Mesh box = test::makeBox({0, 0, 0}, {1, 1, 1});
    const ClosestPointQuery q(box.view());
    std::vector<Vec3d> pts(3);
    std::vector<ClosestPoint> out(2);
    EXPECT_THROW(q.closest(pts, out), Error);
    EXPECT_THROW(parseSignMethod("inside"), Error);
    EXPECT_EQ(parseSignMethod("Winding"), SignMethod::Winding);
}

TEST(Distance, SignedDistanceSignMatchesCgalSideOfMesh) {
    for (const char* name : {"meshes/elephant.off", "meshes/knot.off", "meshes/cross.off"}) {
        VOXFX_REQUIRE_DATA(name);
        const Mesh mesh = loadMesh(test::dataPath(name));
        const std::vector<Vec3d> pts = distanceQueryPoints(mesh.view(), 4000, 17);
        SignMethod used = SignMethod::Auto;
        SignedDistanceOptions o;
        o.used = &used;
        const std::vector<double> sd = signedDistance(mesh.view(), pts, o);
        EXPECT_EQ(used, SignMethod::Parity) << name;
        const std::vector<ClosestPoint> cp = closestPoints(mesh.view(), pts);
        const std::vector<int> side = test::sideOfClosedMesh(mesh.view(), pts);
        const std::vector<int> onSurface = test::sideOfClosedMeshPerturbed(mesh.view(), pts);
        ASSERT_EQ(side.size(), pts.size()) << name;
        for (std::size_t i = 0; i < pts.size(); ++i) {
            ASSERT_EQ(std::abs(sd[i]), cp[i].distance) << name << " " << i;
            // Off the surface: CGAL's side; on it: the side of the perturbed point.
            const int expected = side[i] != 0 ? side[i] : onSurface[i];
            ASSERT_NE(expected, 0) << name << " " << i;
            EXPECT_EQ(std::signbit(sd[i]), expected > 0) << name << " point " << i << " at " << sd[i];
        }
    }
}

TEST(Distance, SignedDistanceOfOpenMeshesUsesTheWindingNumber) {
    // A box without its top: parity means nothing, the winding number is 1 deep inside, about 0.5
    // near the hole, 0 outside.
    Mesh m = test::makeBox({0, 0, 0}, {1, 1, 1});
    std::vector<uint32_t> kept;
    for (std::size_t t = 0; t < m.triangleCount(); ++t) {
        bool top = true;
        for (int c = 0; c < 3; ++c) top = top && m.positions[m.indices[3 * t + std::size_t(c)]].z == 1.0f;
        if (!top)
            for (int c = 0; c < 3; ++c) kept.push_back(m.indices[3 * t + std::size_t(c)]);
    }
    m.indices = kept;
    std::mt19937_64 rng(23);
    std::uniform_real_distribution<double> u(-0.3, 1.3);
    std::vector<Vec3d> pts(3000);
    for (Vec3d& p : pts) p = {u(rng), u(rng), u(rng)};
    SignMethod used = SignMethod::Auto;
    SignedDistanceOptions o;
    o.used = &used;
    const std::vector<double> sd = signedDistance(m.view(), pts, o);
    EXPECT_EQ(used, SignMethod::Winding);
    int checked = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const double w = windingNumber(m.view(), pts[i]); // exact sum over the triangles
        if (std::abs(w - 0.5) < 0.05) continue;           // the approximation's margin
        EXPECT_EQ(std::signbit(sd[i]), w > 0.5) << i;
        ++checked;
    }
    EXPECT_GT(checked, 2500);
}

} // namespace
} // namespace voxfx
