// voxfx tests — the CGAL side of the exactness oracle (see cgal_oracle.hpp).
#include "cgal_oracle.hpp"

#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <gtest/gtest.h>

#include "cgal_oracle_kernel.hpp"

namespace voxfx::test {

namespace oracle {

/// The mesh's triangles in world space (float coordinates widen to double exactly).
std::vector<Triangle3> triangles(const MeshView& mesh) {
    std::vector<Triangle3> out;
    out.reserve(mesh.triangleCount);
    for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
        Point3 p[3];
        for (int c = 0; c < 3; ++c) {
            const Vec3d v = mesh.vertex(mesh.index(t, c));
            p[c] = Point3(v.x, v.y, v.z);
        }
        out.emplace_back(p[0], p[1], p[2]);
    }
    return out;
}

/// The mesh as a CGAL::Surface_mesh with world axis `lineAxis` last (cyclic permutation), vertices
/// with bit-identical positions merged (as analyzeTopology does). A vertex where separate fans
/// of triangles meet cannot be represented; orient_polygon_soup duplicates it (and may flip
/// faces, which no inside test here cares about). `valid` is false when even that fails.
SurfaceMesh surfaceMesh(const MeshView& mesh, int lineAxis, bool& valid) {
    namespace PMP = CGAL::Polygon_mesh_processing;
    const int au = (lineAxis + 1) % 3, av = (lineAxis + 2) % 3, aw = lineAxis;
    std::vector<Point3> points;
    std::map<std::array<double, 3>, std::size_t> merged;
    std::vector<std::size_t> pointOf(mesh.vertexCount);
    for (std::size_t i = 0; i < mesh.vertexCount; ++i) {
        const Vec3d p = mesh.vertex(i);
        auto [it, added] = merged.try_emplace({p[au], p[av], p[aw]}, points.size());
        if (added) points.emplace_back(p[au], p[av], p[aw]);
        pointOf[i] = it->second;
    }
    std::vector<std::array<std::size_t, 3>> faces(mesh.triangleCount);
    for (std::size_t t = 0; t < mesh.triangleCount; ++t)
        for (int c = 0; c < 3; ++c) faces[t][std::size_t(c)] = pointOf[mesh.index(t, c)];
    // Fast path: add the faces directly; add_face refuses a non-manifold vertex or edge.
    SurfaceMesh sm;
    for (const Point3& p : points) sm.add_vertex(p);
    valid = true;
    for (const auto& f : faces)
        if (sm.add_face(SurfaceMesh::Vertex_index(uint32_t(f[0])), SurfaceMesh::Vertex_index(uint32_t(f[1])),
                        SurfaceMesh::Vertex_index(uint32_t(f[2]))) == SurfaceMesh::null_face()) {
            valid = false;
            break;
        }
    if (valid) return sm;
    sm.clear();
    PMP::orient_polygon_soup(points, faces);
    valid = PMP::is_polygon_soup_a_polygon_mesh(faces);
    if (valid) PMP::polygon_soup_to_polygon_mesh(points, faces, sm);
    return sm;
}

} // namespace oracle

SolidOracle oracleSolid(const MeshView& mesh, const CellGeometry& g, int lineAxis) {
    using namespace oracle;
    // Permute world axes cyclically so that the lines run along the third coordinate:
    // (u, v, w) = (axis + 1, axis + 2, axis); a cyclic permutation keeps orientations.
    const int au = (lineAxis + 1) % 3, av = (lineAxis + 2) % 3, aw = lineAxis;
    const int64_t nu = g.dims[au], nv = g.dims[av], nw = g.dims[aw];
    auto permuted = [&](const Vec3d& p) { return Point3(p[au], p[av], p[aw]); };

    SolidOracle r;
    r.inside = WorldGrid(g.dims);
    r.leftOut = WorldGrid(g.dims);
    auto worldIndex = [&](int64_t u, int64_t v, int64_t w) {
        Vec3i q;
        q[au] = u;
        q[av] = v;
        q[aw] = w;
        return r.inside.index(q.x, q.y, q.z);
    };

    std::vector<Triangle3> tris;
    tris.reserve(mesh.triangleCount);
    for (std::size_t t = 0; t < mesh.triangleCount; ++t)
        tris.emplace_back(permuted(mesh.vertex(mesh.index(t, 0))), permuted(mesh.vertex(mesh.index(t, 1))),
                          permuted(mesh.vertex(mesh.index(t, 2))));
    // The same triangles as a Surface_mesh, for Side_of_triangle_mesh on degenerate columns
    // (it needs a closed mesh).
    bool manifold = false;
    const SurfaceMesh sm = surfaceMesh(mesh, lineAxis, manifold);
    r.closed = manifold && CGAL::is_closed(sm);

    // Step 1: per triangle, the columns whose centre line it pierces. A column's centre line
    // (cu, cv) pierces a non-vertical triangle when the point lies strictly inside the projected
    // triangle; on an edge or vertex of it, or on the projection of a vertical triangle, the
    // column is degenerate.
    std::vector<std::pair<int64_t, uint32_t>> hits; // (column u + nu * v, triangle)
    std::vector<uint8_t> degenerate(std::size_t(nu * nv), 0);
    for (std::size_t t = 0; t < tris.size(); ++t) {
        const Triangle3& tri = tris[t];
        const Point2 a(tri[0].x(), tri[0].y()), b(tri[1].x(), tri[1].y()), c(tri[2].x(), tri[2].y());
        const CGAL::Orientation o = CGAL::orientation(a, b, c);
        // Centre indices whose centre may lie in the projected bounding box, one spare each side
        // (the floating-point index estimate is off by far less than a cell).
        auto range = [&](int axis, double lo, double hi, int64_t n, int64_t& first, int64_t& last) {
            first = std::clamp<int64_t>(int64_t(std::floor((lo - g.lo[axis]) / g.cell[axis] - 0.5)) - 1, 0,
                                        n - 1);
            last =
                std::clamp<int64_t>(int64_t(std::ceil((hi - g.lo[axis]) / g.cell[axis] - 0.5)) + 1, 0, n - 1);
        };
        int64_t u0, u1, v0, v1;
        range(au, std::min({a.x(), b.x(), c.x()}), std::max({a.x(), b.x(), c.x()}), nu, u0, u1);
        range(av, std::min({a.y(), b.y(), c.y()}), std::max({a.y(), b.y(), c.y()}), nv, v0, v1);
        for (int64_t v = v0; v <= v1; ++v)
            for (int64_t u = u0; u <= u1; ++u) {
                const Point2 p(g.center(au, u), g.center(av, v));
                const int64_t column = u + nu * v;
                if (o == CGAL::COLLINEAR) {
                    // A triangle parallel to the line: degenerate when the line touches it.
                    if (K::Segment_2(a, b).has_on(p) || K::Segment_2(b, c).has_on(p) ||
                        K::Segment_2(c, a).has_on(p))
                        degenerate[std::size_t(column)] = 1;
                    continue;
                }
                const CGAL::Orientation s0 = CGAL::orientation(a, b, p), s1 = CGAL::orientation(b, c, p),
                                        s2 = CGAL::orientation(c, a, p);
                if (s0 == -o || s1 == -o || s2 == -o) continue; // outside
                if (s0 == o && s1 == o && s2 == o)
                    hits.emplace_back(column, uint32_t(t));
                else
                    degenerate[std::size_t(column)] = 1; // on an edge or a vertex
            }
    }
    std::sort(hits.begin(), hits.end());
    r.crossings = int64_t(hits.size());

    // Step 2: parity along each column. flip[s] toggles at the first centre above a crossing;
    // a prefix XOR gives "odd number of crossings below the centre".
    std::optional<CGAL::Side_of_triangle_mesh<SurfaceMesh, K>> side;
    std::vector<uint8_t> flip(std::size_t(nw) + 1);
    auto centre = [&](int64_t u, int64_t v, int64_t w) {
        return Point3(g.center(au, u), g.center(av, v), g.center(aw, w));
    };
    auto sideOfMesh = [&](int64_t u, int64_t v) {
        if (!r.closed) {
            ++r.undecidedColumns;
            for (int64_t w = 0; w < nw; ++w) r.leftOut.cells[worldIndex(u, v, w)] = 1;
            return;
        }
        if (!side) side.emplace(sm);
        ++r.degenerateColumns;
        for (int64_t w = 0; w < nw; ++w) {
            const CGAL::Bounded_side bs = (*side)(centre(u, v, w));
            const std::size_t c = worldIndex(u, v, w);
            r.inside.cells[c] = bs == CGAL::ON_BOUNDED_SIDE;
            r.leftOut.cells[c] = bs == CGAL::ON_BOUNDARY;
            r.onSurfaceCount += bs == CGAL::ON_BOUNDARY;
        }
    };
    std::size_t h = 0;
    for (int64_t column = 0; column < nu * nv; ++column) {
        const int64_t u = column % nu, v = column / nu;
        const std::size_t hb = h;
        while (h < hits.size() && hits[h].first == column) ++h;
        if (degenerate[std::size_t(column)]) {
            sideOfMesh(u, v);
            continue;
        }
        std::fill(flip.begin(), flip.end(), 0);
        bool onPlane = false;
        for (std::size_t i = hb; i < h && !onPlane; ++i) {
            const Triangle3& tri = tris[hits[i].second];
            const CGAL::Orientation o =
                CGAL::orientation(Point2(tri[0].x(), tri[0].y()), Point2(tri[1].x(), tri[1].y()),
                                  Point2(tri[2].x(), tri[2].y()));
            // Sign of the centre relative to the crossing along +w: orientation_3 times the sign
            // of the normal's w component (o). Monotone in w: binary search the first centre
            // that is not below.
            auto above = [&](int64_t w) {
                return int(CGAL::orientation(tri[0], tri[1], tri[2], centre(u, v, w))) * int(o);
            };
            int64_t lo = 0, hi = nw; // first w with above(w) >= 0 lies in [lo, hi]
            while (lo < hi) {
                const int64_t mid = (lo + hi) / 2;
                if (above(mid) < 0)
                    lo = mid + 1;
                else
                    hi = mid;
            }
            if (lo < nw && above(lo) == 0) {
                onPlane = true; // a centre on the triangle: let Side_of_triangle_mesh say ON_BOUNDARY
                break;
            }
            flip[std::size_t(lo)] ^= 1;
        }
        if (onPlane) {
            sideOfMesh(u, v);
            continue;
        }
        uint8_t parity = 0;
        for (int64_t w = 0; w < nw; ++w) {
            parity ^= flip[std::size_t(w)];
            r.inside.cells[worldIndex(u, v, w)] = parity;
        }
    }
    return r;
}

int64_t sideOfMeshDisagreements(const MeshView& mesh, const CellGeometry& g, const SolidOracle& oracle,
                                int64_t stride) {
    using namespace oracle;
    bool manifold = false;
    const SurfaceMesh sm = surfaceMesh(mesh, 2, manifold);
    if (!manifold || !CGAL::is_closed(sm)) return -1;
    CGAL::Side_of_triangle_mesh<SurfaceMesh, K> side(sm);
    int64_t wrong = 0;
    for (std::size_t c = 0; c < oracle.inside.cells.size(); c += std::size_t(stride)) {
        const auto n = int64_t(c);
        const int64_t i = n % g.dims.x, j = (n / g.dims.x) % g.dims.y, k = n / (g.dims.x * g.dims.y);
        const CGAL::Bounded_side bs = side(Point3(g.center(0, i), g.center(1, j), g.center(2, k)));
        wrong += (bs == CGAL::ON_BOUNDED_SIDE) != bool(oracle.inside.cells[c]) ||
                 (bs == CGAL::ON_BOUNDARY) != bool(oracle.leftOut.cells[c]);
    }
    return wrong;
}

std::vector<int> sideOfClosedMesh(const MeshView& mesh, const std::vector<Vec3d>& points) {
    using namespace oracle;
    bool manifold = false;
    const SurfaceMesh sm = surfaceMesh(mesh, 2, manifold);
    if (!manifold || !CGAL::is_closed(sm)) return {};
    CGAL::Side_of_triangle_mesh<SurfaceMesh, K> side(sm);
    std::vector<int> out;
    out.reserve(points.size());
    for (const Vec3d& p : points) {
        const CGAL::Bounded_side bs = side(Point3(p.x, p.y, p.z));
        out.push_back(bs == CGAL::ON_BOUNDED_SIDE ? 1 : (bs == CGAL::ON_BOUNDARY ? 0 : -1));
    }
    return out;
}

ConservativeOracle oracleConservative(const MeshView& mesh, const CellGeometry& g, double nearCells) {
    using namespace oracle;
    ConservativeOracle r{WorldGrid(g.dims), WorldGrid(g.dims)};
    const Vec3d grow = g.cell * nearCells;
    for (const Triangle3& tri : triangles(mesh)) {
        int64_t first[3], last[3];
        for (int a = 0; a < 3; ++a) {
            const double lo = std::min({tri[0][a], tri[1][a], tri[2][a]});
            const double hi = std::max({tri[0][a], tri[1][a], tri[2][a]});
            // Cells whose box may meet [lo, hi], one spare each side for the index estimate.
            first[a] =
                std::clamp<int64_t>(int64_t(std::floor((lo - g.lo[a]) / g.cell[a])) - 1, 0, g.dims[a] - 1);
            last[a] =
                std::clamp<int64_t>(int64_t(std::floor((hi - g.lo[a]) / g.cell[a])) + 1, 0, g.dims[a] - 1);
        }
        for (int64_t k = first[2]; k <= last[2]; ++k)
            for (int64_t j = first[1]; j <= last[1]; ++j)
                for (int64_t i = first[0]; i <= last[0]; ++i) {
                    const std::size_t c = r.cells.index(i, j, k);
                    if (r.cells.cells[c]) continue;
                    const Point3 lo(g.lower(0, i), g.lower(1, j), g.lower(2, k));
                    const Point3 hi(g.upper(0, i), g.upper(1, j), g.upper(2, k));
                    if (CGAL::do_intersect(tri, K::Iso_cuboid_3(lo, hi))) {
                        r.cells.cells[c] = 1;
                        r.near.cells[c] = 0;
                    } else if (nearCells > 0 && !r.near.cells[c]) {
                        const K::Iso_cuboid_3 grown(
                            Point3(lo.x() - grow.x, lo.y() - grow.y, lo.z() - grow.z),
                            Point3(hi.x() + grow.x, hi.y() + grow.y, hi.z() + grow.z));
                        r.near.cells[c] = CGAL::do_intersect(tri, grown) ? 1 : 0;
                    }
                }
    }
    r.nearCount = r.near.count();
    return r;
}

CgalSoup readWithCgal(const std::string& path) {
    std::vector<oracle::Point3> points;
    CgalSoup soup;
    EXPECT_TRUE(CGAL::IO::read_polygon_soup(path, points, soup.polygons)) << path;
    for (const oracle::Point3& p : points) soup.points.push_back({p.x(), p.y(), p.z()});
    return soup;
}

bool writeWithCgal(const std::string& path, const CgalSoup& soup, bool binary) {
    std::vector<oracle::Point3> points;
    for (const Vec3d& p : soup.points) points.emplace_back(p.x, p.y, p.z);
    return CGAL::IO::write_polygon_soup(path, points, soup.polygons,
                                        CGAL::parameters::stream_precision(9).use_binary_mode(binary));
}

std::vector<uint8_t> oracleSegmentsHitMesh(const MeshView& mesh, const std::vector<Vec3d>& from,
                                           const std::vector<Vec3d>& to) {
    const std::vector<oracle::Triangle3> tris = oracle::triangles(mesh);
    std::vector<CGAL::Bbox_3> boxes;
    boxes.reserve(tris.size());
    for (const oracle::Triangle3& t : tris) boxes.push_back(t.bbox());
    std::vector<uint8_t> out(from.size(), 0);
    for (std::size_t i = 0; i < from.size(); ++i) {
        const oracle::K::Segment_3 seg(oracle::Point3(from[i].x, from[i].y, from[i].z),
                                       oracle::Point3(to[i].x, to[i].y, to[i].z));
        const CGAL::Bbox_3 sb = seg.bbox();
        for (std::size_t t = 0; t < tris.size() && !out[i]; ++t)
            if (CGAL::do_overlap(sb, boxes[t]) && CGAL::do_intersect(seg, tris[t])) out[i] = 1;
    }
    return out;
}

} // namespace voxfx::test
