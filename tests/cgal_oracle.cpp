// voxfx tests — the CGAL side of the exactness oracle (see cgal_oracle.hpp).
#include "cgal_oracle.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_2.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include "cgal_oracle_bits.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::test {

namespace oracle {

// The CGAL types behind the oracle.
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point2 = K::Point_2;
using Point3 = K::Point_3;
using Triangle3 = K::Triangle_3;
using SurfaceMesh = CGAL::Surface_mesh<Point3>;

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

/// The triangles' bounding boxes (for a rejection test before an exact one).
std::vector<CGAL::Bbox_3> boxes(const std::vector<Triangle3>& tris) {
    std::vector<CGAL::Bbox_3> out;
    out.reserve(tris.size());
    for (const Triangle3& t : tris) out.push_back(t.bbox());
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

/// The first w in [0, n] with above(w) >= 0, for above() non-decreasing in w (a line of centres
/// against one plane): binary search.
template <class Above> int64_t firstNotBelow(Above&& above, int64_t n) {
    int64_t lo = 0, hi = n; // the answer lies in [lo, hi]
    while (lo < hi) {
        const int64_t mid = (lo + hi) / 2;
        if (above(mid) < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/// Step 1 of the solid oracles for one triangle (coordinates already permuted so that the
/// lines run along the third): calls hit(column, p) for each column u + nu * v whose centre
/// line (p, the centre in the (au, av) plane) pierces it, the point strictly inside the
/// projected triangle; on an edge or vertex of it, or on the projection of a vertical
/// triangle, the column is marked degenerate.
template <class Hit>
void piercedColumns(const Triangle3& tri, const CellGeometry& g, int au, int av,
                    std::vector<uint8_t>& degenerate, Hit&& hit) {
    const int64_t nu = g.dims[au], nv = g.dims[av];
    const Point2 a(tri[0].x(), tri[0].y()), b(tri[1].x(), tri[1].y()), c(tri[2].x(), tri[2].y());
    const CGAL::Orientation o = CGAL::orientation(a, b, c);
    // Centre indices whose centre may lie in the projected bounding box, one spare each side
    // (the floating-point index estimate is off by far less than a cell).
    auto range = [&](int axis, double lo, double hi, int64_t n, int64_t& first, int64_t& last) {
        first =
            std::clamp<int64_t>(int64_t(std::floor((lo - g.lo[axis]) / g.cell[axis] - 0.5)) - 1, 0, n - 1);
        last = std::clamp<int64_t>(int64_t(std::ceil((hi - g.lo[axis]) / g.cell[axis] - 0.5)) + 1, 0, n - 1);
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
                hit(column, p);
            else
                degenerate[std::size_t(column)] = 1; // on an edge or a vertex
        }
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
    for (std::size_t t = 0; t < tris.size(); ++t)
        piercedColumns(tris[t], g, au, av, degenerate,
                       [&](int64_t column, const Point2&) { hits.emplace_back(column, uint32_t(t)); });
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
            const int64_t lo = firstNotBelow(above, nw);
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

namespace oracle {

// oracleSolidBits' per-triangle work: the columns whose centre line the triangle pierces get the
// bit of the first centre above the crossing flipped; edge and vertex hits, vertical triangles
// touching a line and centres on the plane mark the column degenerate.
struct BitsPass {
    const CellGeometry& g;
    SolidOracleBits& r;
    std::vector<uint8_t>& degenerate;

    Point3 centre(int64_t u, int64_t v, int64_t w) const {
        return Point3(g.center(0, u), g.center(1, v), g.center(2, w));
    }
    // The first centre of column (u, v) not below the triangle's plane (0..nw), or -1 when a
    // centre lies on it. `o` is the projected triangle's orientation.
    int64_t firstAbove(const Triangle3& tri, CGAL::Orientation o, int64_t u, int64_t v, double guess) const {
        const int64_t nw = g.dims.z;
        auto above = [&](int64_t w) {
            return int(CGAL::orientation(tri[0], tri[1], tri[2], centre(u, v, w))) * int(o);
        };
        int64_t k = std::isfinite(guess) ? std::clamp<int64_t>(int64_t(std::ceil(guess)), 0, nw) : 0;
        const int here = k < nw ? above(k) : 1, below = k > 0 ? above(k - 1) : -1;
        if (here == 0 || below == 0) return -1;
        if (here > 0 && below < 0) return k;
        const int64_t lo = firstNotBelow(above, nw); // oracleSolid's search
        return lo < nw && above(lo) == 0 ? -1 : lo;
    }
    void triangle(const Triangle3& tri) {
        const CGAL::Orientation o = CGAL::orientation(
            Point2(tri[0].x(), tri[0].y()), Point2(tri[1].x(), tri[1].y()), Point2(tri[2].x(), tri[2].y()));
        // The plane's depth at a column, in double: only a guess, checked exactly.
        const Vec3d p0(tri[0].x(), tri[0].y(), tri[0].z()), p1(tri[1].x(), tri[1].y(), tri[1].z()),
            p2(tri[2].x(), tri[2].y(), tri[2].z());
        const Vec3d n = cross(p1 - p0, p2 - p0);
        piercedColumns(tri, g, 0, 1, degenerate, [&](int64_t column, const Point2& p) {
            ++r.crossings;
            if (degenerate[std::size_t(column)]) return;
            const double z = p0.z - (n.x * (p.x() - p0.x) + n.y * (p.y() - p0.y)) / n.z;
            const int64_t k =
                firstAbove(tri, o, column % g.dims.x, column / g.dims.x, (z - g.lo.z) / g.cell.z - 0.5);
            if (k < 0)
                degenerate[std::size_t(column)] = 1;
            else if (k < g.dims.z)
                r.words[std::size_t(column * r.wordsPerColumn + (k >> 6))] ^= uint64_t(1) << (k & 63);
        });
    }
};

} // namespace oracle

SolidOracleBits oracleSolidBits(const MeshView& mesh, const CellGeometry& g) {
    using namespace oracle;
    SolidOracleBits r;
    r.dims = g.dims;
    const int64_t nu = g.dims.x, nv = g.dims.y, nw = g.dims.z;
    r.wordsPerColumn = (nw + 63) / 64;
    const int64_t wpc = r.wordsPerColumn;
    r.words.assign(std::size_t(nu * nv * wpc), 0);
    std::vector<uint8_t> degenerate(std::size_t(nu * nv), 0);
    BitsPass pass{g, r, degenerate};
    for (const Triangle3& tri : triangles(mesh)) pass.triangle(tri);
    // Parity: a prefix XOR down each column (carried across words).
    for (int64_t column = 0; column < nu * nv; ++column) {
        uint64_t parity = 0;
        for (int64_t w = 0; w < wpc; ++w) {
            uint64_t x = r.words[std::size_t(column * wpc + w)];
            for (int s = 1; s < 64; s <<= 1) x ^= x << s;
            x ^= parity;
            r.words[std::size_t(column * wpc + w)] = x;
            parity = uint64_t(0) - (x >> 63);
        }
        if (nw % 64) r.words[std::size_t(column * wpc + wpc - 1)] &= (uint64_t(1) << (nw % 64)) - 1;
    }
    // Degenerate columns: Side_of_triangle_mesh per centre (closed mesh) or left out (open).
    std::optional<SurfaceMesh> sm;
    std::optional<CGAL::Side_of_triangle_mesh<SurfaceMesh, K>> side;
    bool closed = false;
    for (int64_t column = 0; column < nu * nv; ++column) {
        if (!degenerate[std::size_t(column)]) continue;
        ++r.degenerateColumns;
        if (!sm) {
            bool manifold = false;
            sm.emplace(surfaceMesh(mesh, 2, manifold));
            closed = manifold && CGAL::is_closed(*sm);
            if (closed) side.emplace(*sm);
        }
        if (r.leftOut.empty()) r.leftOut.assign(r.words.size(), 0);
        uint64_t* in = &r.words[std::size_t(column * wpc)];
        uint64_t* left = &r.leftOut[std::size_t(column * wpc)];
        std::fill(in, in + wpc, uint64_t(0));
        for (int64_t w = 0; w < nw; ++w) {
            const uint64_t bit = uint64_t(1) << (w & 63);
            if (!closed) {
                left[w >> 6] |= bit;
                continue;
            }
            const CGAL::Bounded_side bs =
                (*side)(Point3(g.center(0, column % nu), g.center(1, column / nu), g.center(2, w)));
            if (bs == CGAL::ON_BOUNDED_SIDE) in[w >> 6] |= bit;
            if (bs == CGAL::ON_BOUNDARY) left[w >> 6] |= bit;
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
    const std::vector<CGAL::Bbox_3> boxes = oracle::boxes(tris);
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

// See cgal_oracle.hpp.
std::vector<OracleChord> oracleChords(const MeshView& mesh, const std::vector<Vec3d>& from,
                                      const std::vector<Vec3d>& to) {
    const std::vector<oracle::Triangle3> tris = oracle::triangles(mesh);
    const std::vector<CGAL::Bbox_3> boxes = oracle::boxes(tris);
    std::vector<OracleChord> out(from.size());
    for (std::size_t i = 0; i < from.size(); ++i) {
        const oracle::Point3 a(from[i].x, from[i].y, from[i].z), b(to[i].x, to[i].y, to[i].z);
        const oracle::K::Segment_3 seg(a, b);
        const CGAL::Bbox_3 sb = seg.bbox();
        const double len = std::sqrt(CGAL::to_double(seg.squared_length()));
        std::vector<double> t; // distances from `from` of the crossings
        for (std::size_t k = 0; k < tris.size(); ++k) {
            if (!CGAL::do_overlap(sb, boxes[k]) || !CGAL::do_intersect(seg, tris[k])) continue;
            const auto hit = CGAL::intersection(seg, tris[k]);
            const oracle::Point3* p = hit ? boost::get<oracle::Point3>(&*hit) : nullptr;
            if (!p) {
                out[i].degenerate = true; // the segment lies in the triangle's plane
                continue;
            }
            t.push_back(std::sqrt(CGAL::to_double(CGAL::squared_distance(a, *p))));
        }
        std::sort(t.begin(), t.end());
        for (std::size_t k = 1; k < t.size(); ++k)
            if (t[k] - t[k - 1] <= 1e-9 * len) out[i].degenerate = true;
        if (t.size() % 2) out[i].degenerate = true;
        out[i].crossings = int(t.size());
        for (std::size_t k = 1; k < t.size(); k += 2) out[i].inside += t[k] - t[k - 1];
    }
    return out;
}

// See cgal_oracle.hpp.
FrameOracle oracleFrameCells(const MeshView& mesh, const Frame& frame, double nearCells) {
    using namespace oracle;
    const int64_t W = frame.width(), H = frame.height(), D = frame.depth();
    FrameOracle e{WorldGrid({W, H, D}), WorldGrid({W, H, D}), WorldGrid({W, H, D}), WorldGrid({W, H, D}),
                  false};
    const std::vector<Triangle3> tris = triangles(mesh);
    bool manifold = false;
    const SurfaceMesh sm = surfaceMesh(mesh, 2, manifold);
    e.closed = manifold && CGAL::is_closed(sm);
    CGAL::Side_of_triangle_mesh<SurfaceMesh, K> side(sm);
    const Vec3d cell = frame.cellSize();
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const DepthToSlice m = frame.depthToSlice(y * W + x);
            for (int64_t s = 0; s < D; ++s) {
                const Vec3d a = frame.worldFromGrid({double(x), double(y), m.near + double(s) / m.scale});
                const Vec3d b =
                    frame.worldFromGrid({double(x + 1), double(y + 1), m.near + double(s + 1) / m.scale});
                const Vec3d lo = min(a, b), hi = max(a, b);
                // The near band: the box grown by nearCells of its own size along the slices
                // (local slices are thinner than uniform ones) and of a cell across.
                Vec3d grow = cell * nearCells;
                const int sa = sliceAxis(frame.axis());
                grow[sa] = (hi[sa] - lo[sa]) * nearCells;
                const K::Iso_cuboid_3 box(Point3(lo.x, lo.y, lo.z), Point3(hi.x, hi.y, hi.z));
                const K::Iso_cuboid_3 grown(Point3(lo.x - grow.x, lo.y - grow.y, lo.z - grow.z),
                                            Point3(hi.x + grow.x, hi.y + grow.y, hi.z + grow.z));
                bool touch = false, near = false;
                for (const Triangle3& t : tris) {
                    if (CGAL::do_intersect(t, box)) {
                        touch = true;
                        break;
                    }
                    near = near || CGAL::do_intersect(t, grown);
                }
                e.conservative.at(x, y, s) = touch;
                e.conservativeNear.at(x, y, s) = !touch && near;
                const Vec3d c = frame.cellCenter(x, y, s);
                const CGAL::Bounded_side bs = side(Point3(c.x, c.y, c.z));
                e.inside.at(x, y, s) = bs == CGAL::ON_BOUNDED_SIDE;
                e.onSurface.at(x, y, s) = bs == CGAL::ON_BOUNDARY;
            }
        }
    return e;
}

// See cgal_oracle.hpp.
void markNearlyDegenerateCentres(const MeshView& mesh, const Frame& frame, double nearCells,
                                 WorldGrid& onSurface, bool worldOrder) {
    using namespace oracle;
    using Point2 = K::Point_2;
    const int ax = columnXAxis(frame.axis()), ay = columnYAxis(frame.axis());
    const Vec3d cell = frame.cellSize();
    const double tol = nearCells * std::max(cell[ax], cell[ay]);
    std::vector<K::Segment_2> edges;
    for (std::size_t t = 0; t < mesh.triangleCount; ++t)
        for (int k = 0; k < 3; ++k) {
            const Vec3d a = mesh.vertex(mesh.index(t, k)), b = mesh.vertex(mesh.index(t, (k + 1) % 3));
            edges.emplace_back(Point2(a[ax], a[ay]), Point2(b[ax], b[ay]));
        }
    // Centres within nearCells of a slice of the surface along their line: local slices are
    // fitted to the geometry of their column (a face spanning a column puts the centre of its
    // middle slice on it), and faces through lattice-like points put centres on them.
    std::vector<Triangle3> tris = triangles(mesh);
    auto mark = [&](int64_t x, int64_t y, int64_t s) {
        if (!worldOrder) {
            onSurface.at(x, y, s) = 1;
            return;
        }
        Vec3i w;
        w[ax] = x;
        w[ay] = y;
        w[sliceAxis(frame.axis())] = s;
        onSurface.at(w.x, w.y, w.z) = 1;
    };
    const int sa = sliceAxis(frame.axis());
    for (int64_t y = 0; y < frame.height(); ++y)
        for (int64_t x = 0; x < frame.width(); ++x)
            for (int64_t s = 0; s < frame.depth(); ++s) {
                const Vec3d c = frame.cellCenter(x, y, s);
                const double d =
                    nearCells * (frame.cellCenter(x, y, std::min<int64_t>(s + 1, frame.depth() - 1))[sa] -
                                 frame.cellCenter(x, y, std::max<int64_t>(s - 1, 0))[sa]);
                Vec3d lo = c, hi = c;
                lo[sa] -= std::abs(d);
                hi[sa] += std::abs(d);
                const K::Segment_3 probe(Point3(lo.x, lo.y, lo.z), Point3(hi.x, hi.y, hi.z));
                for (const Triangle3& t : tris) {
                    if (t.bbox().xmax() < lo.x || t.bbox().xmin() > hi.x || t.bbox().ymax() < lo.y ||
                        t.bbox().ymin() > hi.y || t.bbox().zmax() < lo.z || t.bbox().zmin() > hi.z)
                        continue;
                    if (CGAL::do_intersect(t, probe)) {
                        mark(x, y, s);
                        break;
                    }
                }
            }
    for (int64_t y = 0; y < frame.height(); ++y)
        for (int64_t x = 0; x < frame.width(); ++x) {
            const Vec3d c = frame.cellCenter(x, y, 0);
            const Point2 p(c[ax], c[ay]);
            bool near = false;
            for (const K::Segment_2& e : edges)
                near = near || CGAL::to_double(CGAL::squared_distance(e, p)) <= tol * tol;
            if (!near) continue;
            for (int64_t s = 0; s < frame.depth(); ++s) mark(x, y, s);
        }
}

std::vector<int> sideOfClosedMeshPerturbed(const MeshView& mesh, const std::vector<Vec3d>& points) {
    using EK = CGAL::Exact_predicates_exact_constructions_kernel;
    using EKMesh = CGAL::Surface_mesh<EK::Point_3>;
    bool manifold = false;
    const oracle::SurfaceMesh sm = oracle::surfaceMesh(mesh, 2, manifold); // axis 2: no permutation
    if (!manifold) return {};
    // The same mesh with exact (rational) coordinates.
    EKMesh em;
    for (const auto v : sm.vertices()) {
        const auto& p = sm.point(v);
        em.add_vertex(EK::Point_3(p.x(), p.y(), p.z()));
    }
    for (const auto f : sm.faces()) {
        std::vector<EKMesh::Vertex_index> corners;
        for (const auto v : CGAL::vertices_around_face(sm.halfedge(f), sm))
            corners.push_back(EKMesh::Vertex_index(uint32_t(v)));
        em.add_face(corners);
    }
    CGAL::Side_of_triangle_mesh<EKMesh, EK> side(em);
    const Box3d b = computeBounds(mesh);
    const double scale = std::max({b.extent().x, b.extent().y, b.extent().z});
    // delta far below float feature sizes (2^-24 of the extent); eps1 far below delta times any
    // slope a float triangle can have; eps2 far below eps1 times any edge's dx / dy ratio.
    const EK::FT delta = EK::FT(scale) * std::ldexp(1.0, -60);
    const EK::FT eps1 = delta * EK::FT(std::ldexp(1.0, -200));
    const EK::FT eps2 = eps1 * EK::FT(std::ldexp(1.0, -200));
    std::vector<int> out;
    out.reserve(points.size());
    for (const Vec3d& p : points) {
        const CGAL::Bounded_side bs =
            side(EK::Point_3(EK::FT(p.x) + eps1, EK::FT(p.y) + eps2, EK::FT(p.z) - delta));
        out.push_back(bs == CGAL::ON_BOUNDED_SIDE ? 1 : (bs == CGAL::ON_BOUNDARY ? 0 : -1));
    }
    return out;
}

std::vector<OracleNearest> oracleNearest(const MeshView& mesh, const std::vector<Vec3d>& points, bool exact) {
    using namespace oracle;
    using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<Triangle3>::const_iterator>;
    using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
    const std::vector<Triangle3> tris = triangles(mesh);
    Tree tree(tris.begin(), tris.end());
    tree.accelerate_distance_queries();
    std::vector<OracleNearest> out(points.size());
    // The tree is read-only once built: queries run on worker threads (voxfx's parallel-for only
    // spreads the loop; nothing of voxfx's distance code is involved).
    parallelFor(0, int64_t(points.size()), 256, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i) {
            const Vec3d& p = points[std::size_t(i)];
            OracleNearest& o = out[std::size_t(i)];
            if (!isFinite(p)) {
                o.distance = std::numeric_limits<double>::quiet_NaN();
                continue;
            }
            const Point3 q(p.x, p.y, p.z);
            const auto [cp, prim] = tree.closest_point_and_primitive(q);
            o.point = {cp.x(), cp.y(), cp.z()};
            o.face = int64_t(prim - tris.begin());
            o.distance = std::sqrt(CGAL::to_double(CGAL::squared_distance(q, *prim)));
        }
    });
    if (!exact) return out;
    // Exact minimum over the triangles near the tree's answer, serially (CGAL's lazy exact
    // numbers): the triangles whose box meets the cube around the point that holds the tree's
    // distance, filtered by their inexact distance (with a margin far above its rounding), then
    // compared exactly.
    using EK = CGAL::Exact_predicates_exact_constructions_kernel;
    const Box3d bounds = computeBounds(mesh);
    const double margin = 1e-9 * length(bounds.extent());
    std::vector<Tree::Primitive_id> nearby;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3d& p = points[i];
        OracleNearest& o = out[i];
        if (!isFinite(p)) continue;
        const double r = o.distance * (1 + 1e-9) + margin;
        nearby.clear();
        tree.all_intersected_primitives(CGAL::Bbox_3(p.x - r, p.y - r, p.z - r, p.x + r, p.y + r, p.z + r),
                                        std::back_inserter(nearby));
        std::sort(nearby.begin(), nearby.end());
        const Point3 q(p.x, p.y, p.z);
        const EK::Point_3 ep(p.x, p.y, p.z);
        std::optional<EK::FT> best;
        for (const auto it : nearby) {
            if (std::sqrt(CGAL::to_double(CGAL::squared_distance(q, *it))) > r) continue;
            const auto ek = [](const Point3& v) { return EK::Point_3(v.x(), v.y(), v.z()); };
            const EK::FT d2 =
                CGAL::squared_distance(ep, EK::Triangle_3(ek((*it)[0]), ek((*it)[1]), ek((*it)[2])));
            const auto t = int64_t(it - tris.begin());
            if (!best || d2 < *best) {
                best = d2;
                o.ties.assign(1, t);
            } else if (d2 == *best) {
                o.ties.push_back(t);
            }
        }
        if (best) o.distance = std::sqrt(CGAL::to_double(CGAL::exact(*best)));
    }
    return out;
}

double oracleTriangleDistance2(const std::array<Vec3d, 3>& t, const Vec3d& p) {
    using namespace oracle;
    const auto pt = [](const Vec3d& v) { return Point3(v.x, v.y, v.z); };
    return CGAL::to_double(CGAL::squared_distance(pt(p), Triangle3(pt(t[0]), pt(t[1]), pt(t[2]))));
}

int oracleOrient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    using oracle::Point2;
    const CGAL::Orientation o = CGAL::orientation(Point2(ax, ay), Point2(bx, by), Point2(cx, cy));
    return o == CGAL::LEFT_TURN ? 1 : (o == CGAL::RIGHT_TURN ? -1 : 0);
}

int oracleOrient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    using oracle::Point3;
    const CGAL::Orientation o = CGAL::orientation(Point3(a.x, a.y, a.z), Point3(b.x, b.y, b.z),
                                                  Point3(c.x, c.y, c.z), Point3(d.x, d.y, d.z));
    return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

std::vector<Point2d> oracleConvexHull2(const std::vector<Point2d>& points) {
    using oracle::Point2;
    std::vector<Point2> in, hull;
    for (const Point2d& p : points) in.emplace_back(p[0], p[1]);
    CGAL::convex_hull_2(in.begin(), in.end(), std::back_inserter(hull));
    std::vector<Point2d> out;
    for (const Point2& p : hull) out.push_back({p.x(), p.y()});
    return out;
}

double oracleDistanceToSegment2(const Point2d& a, const Point2d& b, const Point2d& p) {
    using oracle::K;
    using oracle::Point2;
    const K::Segment_2 e(Point2(a[0], a[1]), Point2(b[0], b[1]));
    return std::sqrt(CGAL::to_double(CGAL::squared_distance(e, Point2(p[0], p[1]))));
}

bool oracleTriangleMeetsBox(const std::array<Vec3d, 3>& t, const Box3d& box) {
    using oracle::K;
    using oracle::Point3;
    const K::Triangle_3 tri(Point3(t[0].x, t[0].y, t[0].z), Point3(t[1].x, t[1].y, t[1].z),
                            Point3(t[2].x, t[2].y, t[2].z));
    const K::Iso_cuboid_3 b(Point3(box.lo.x, box.lo.y, box.lo.z), Point3(box.hi.x, box.hi.y, box.hi.z));
    return CGAL::do_intersect(tri, b);
}

} // namespace voxfx::test
