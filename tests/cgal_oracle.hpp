// voxfx tests — an independent exactness oracle for voxelization, built on CGAL.
//
// Nothing here shares code with voxfx's rasterizer: the oracle sees only the mesh and the world
// geometry of the grid's cells, and decides everything with CGAL's exact predicates
// (Exact_predicates_inexact_constructions_kernel, whose predicates are filtered and exact on the
// double inputs). No intersection point is ever constructed.
//
// Cell geometry (orthographic frames, world-axis indices i, j, k along x, y, z), in double and
// exactly as written:
//   lower corner  lo + (i, j, k) * cell        upper corner  lo + (i + 1, j + 1, k + 1) * cell
//   centre        lo + (i + 0.5, j + 0.5, k + 0.5) * cell
// where lo = frame.box().lo and cell = frame.cellSize().
//
//   oracleSolid         centres inside a closed mesh: one line of centres at a time along an
//                       axis; orientation_2 decides which triangles the line pierces (a hit on an
//                       edge, a vertex or a triangle parallel to the line marks the column
//                       degenerate), orientation_3 places every centre below or above each
//                       crossing (binary search, the line meets a plane once). Degenerate columns
//                       and centres lying on a triangle's plane fall back to
//                       CGAL::Side_of_triangle_mesh per centre; its ON_BOUNDARY answers are
//                       reported as "on the surface" and must be left out of comparisons. For
//                       meshes that are not closed it is the parity along the chosen axis.
//   oracleConservative  cells whose closed box some triangle meets: do_intersect(Triangle_3,
//                       Iso_cuboid_3) for the cells around each triangle's bounding box; and,
//                       optionally, the cells that miss the mesh by less than a tolerance (their
//                       box grown by it meets a triangle), which a comparison may tolerate.
//   readWithCgal        a mesh file read by CGAL's own readers (OFF, OBJ, PLY, STL), as a polygon
//                       soup; meshOfSoup fan-triangulates it into a voxfx::Mesh for the oracles.
//   floodFromBorder     cells not reachable from the grid border through non-wall cells by
//                       6-connected steps: a plain voxel-by-voxel breadth-first search.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include "voxfx/mesh.hpp"
#include "voxfx/voxel_grid.hpp"

namespace voxfx::test {

/// World-space cell geometry of an orthographic, uniformly sliced grid (see the file comment).
struct CellGeometry {
    Vec3d lo;
    Vec3d cell;
    Vec3i dims; ///< cells along x, y, z

    static CellGeometry of(const VoxelGrid& grid) {
        return {grid.frame.box().lo, grid.frame.cellSize(), grid.worldDims()};
    }
    double lower(int axis, int64_t i) const { return lo[axis] + double(i) * cell[axis]; }
    double upper(int axis, int64_t i) const { return lo[axis] + double(i + 1) * cell[axis]; }
    double center(int axis, int64_t i) const { return lo[axis] + (double(i) + 0.5) * cell[axis]; }
};

/// A dense boolean grid in world-axis index order (i along x fastest, then j, then k).
struct WorldGrid {
    Vec3i dims{0, 0, 0};
    std::vector<uint8_t> cells;

    WorldGrid() = default;
    explicit WorldGrid(const Vec3i& d) : dims(d), cells(std::size_t(d.x * d.y * d.z), 0) {}
    std::size_t index(int64_t i, int64_t j, int64_t k) const {
        return std::size_t((k * dims.y + j) * dims.x + i);
    }
    uint8_t& at(int64_t i, int64_t j, int64_t k) { return cells[index(i, j, k)]; }
    uint8_t at(int64_t i, int64_t j, int64_t k) const { return cells[index(i, j, k)]; }
    int64_t count() const { return std::count(cells.begin(), cells.end(), uint8_t(1)); }
};

/// The occupancy of a voxfx grid, read cell by cell through atWorldIndex.
inline WorldGrid toWorldGrid(const VoxelGrid& grid) {
    WorldGrid out(grid.worldDims());
    for (int64_t k = 0; k < out.dims.z; ++k)
        for (int64_t j = 0; j < out.dims.y; ++j)
            for (int64_t i = 0; i < out.dims.x; ++i) out.at(i, j, k) = grid.atWorldIndex(i, j, k) ? 1 : 0;
    return out;
}

/// Cells where `actual` and `expected` differ, leaving out cells set in `ignore` (if given).
struct GridDiff {
    int64_t missing = 0;  ///< expected but not set
    int64_t extra = 0;    ///< set but not expected
    int64_t ignored = 0;  ///< cells skipped because `ignore` marks them
    std::string examples; ///< the first few differing cells, "(i, j, k) missing|extra"
    bool equal() const { return missing == 0 && extra == 0; }
};

inline GridDiff compareGrids(const WorldGrid& actual, const WorldGrid& expected,
                             const WorldGrid* ignore = nullptr) {
    GridDiff d;
    if (!(actual.dims == expected.dims)) {
        d.missing = expected.count();
        d.extra = actual.count();
        d.examples = "grids differ in size";
        return d;
    }
    std::ostringstream ex;
    int shown = 0;
    for (int64_t k = 0; k < actual.dims.z; ++k)
        for (int64_t j = 0; j < actual.dims.y; ++j)
            for (int64_t i = 0; i < actual.dims.x; ++i) {
                const std::size_t c = actual.index(i, j, k);
                if (ignore && ignore->cells[c]) {
                    ++d.ignored;
                    continue;
                }
                if (actual.cells[c] == expected.cells[c]) continue;
                (expected.cells[c] ? d.missing : d.extra)++;
                if (shown++ < 8)
                    ex << " (" << i << ", " << j << ", " << k << ") "
                       << (expected.cells[c] ? "missing" : "extra");
            }
    d.examples = ex.str();
    return d;
}

inline std::ostream& operator<<(std::ostream& os, const GridDiff& d) {
    return os << d.missing << " missing, " << d.extra << " extra (" << d.ignored
              << " ignored):" << d.examples;
}

namespace oracle {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point2 = K::Point_2;
using Point3 = K::Point_3;
using Triangle3 = K::Triangle_3;
using SurfaceMesh = CGAL::Surface_mesh<Point3>;

/// The mesh's triangles in world space (float coordinates widen to double exactly).
inline std::vector<Triangle3> triangles(const MeshView& mesh) {
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
inline SurfaceMesh surfaceMesh(const MeshView& mesh, int lineAxis, bool& valid) {
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

/// A mesh file as CGAL reads it: points and polygons (corner indices), nothing voxfx computed.
struct CgalSoup {
    std::vector<oracle::Point3> points;
    std::vector<std::vector<std::size_t>> polygons;
};

/// Reads `path` with CGAL::IO::read_polygon_soup (failure is a test failure and an empty soup).
inline CgalSoup readWithCgal(const std::string& path) {
    CgalSoup soup;
    EXPECT_TRUE(CGAL::IO::read_polygon_soup(path, soup.points, soup.polygons)) << path;
    return soup;
}

/// The soup as a voxfx::Mesh: positions rounded to float, each polygon fan-triangulated from its
/// first corner.
inline Mesh meshOfSoup(const CgalSoup& soup) {
    Mesh m;
    for (const oracle::Point3& p : soup.points) m.positions.push_back(Vec3f(Vec3d{p.x(), p.y(), p.z()}));
    for (const auto& polygon : soup.polygons)
        for (std::size_t k = 2; k < polygon.size(); ++k)
            for (const std::size_t c : {polygon[0], polygon[k - 1], polygon[k]})
                m.indices.push_back(uint32_t(c));
    return m;
}

/// Result of oracleSolid, in world-axis index order.
struct SolidOracle {
    WorldGrid inside;              ///< odd number of crossings below the centre along the line axis
    WorldGrid leftOut;             ///< centres the oracle cannot classify; comparisons must skip them
    int64_t onSurfaceCount = 0;    ///< closed mesh: centres on the surface (ON_BOUNDARY), left out
    int64_t degenerateColumns = 0; ///< closed mesh: columns decided centre by centre
    int64_t undecidedColumns = 0;  ///< open mesh: degenerate columns, all their centres left out
    int64_t crossings = 0;         ///< line-triangle crossings found
    bool closed = false;           ///< the mesh is a closed Surface_mesh (CGAL::is_closed)
};

/// Voxel centres inside `mesh` by parity of crossings along lines of centres parallel to world
/// axis `lineAxis` (0, 1, 2), decided exactly (see the file comment). For a closed mesh this is
/// the inside of the mesh, whatever the axis (degenerate columns and centres on a triangle are
/// decided by CGAL::Side_of_triangle_mesh; centres on the surface are left out). For a mesh that
/// is not closed (holes, non-manifold edges) it is the parity along that axis, with degenerate
/// columns left out. Cost ~ T * (cells per triangle footprint) + crossings * log D +
/// (degenerate columns) * D * (Side_of_triangle_mesh query).
inline SolidOracle oracleSolid(const MeshView& mesh, const CellGeometry& g, int lineAxis = 2) {
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

/// Checks `oracle` (from oracleSolid) against CGAL::Side_of_triangle_mesh at every `stride`-th
/// cell centre of a closed mesh; returns how many of them disagree (ON_BOUNDARY must match
/// leftOut), or -1 when the mesh is not closed.
inline int64_t sideOfMeshDisagreements(const MeshView& mesh, const CellGeometry& g, const SolidOracle& oracle,
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

/// Result of oracleConservative, in world-axis index order.
struct ConservativeOracle {
    WorldGrid cells; ///< the closed box meets a triangle
    WorldGrid near;  ///< the box misses every triangle, but meets one once grown by the tolerance
    int64_t nearCount = 0;
};

/// Cells whose closed box meets at least one triangle of `mesh` (exact do_intersect), and the
/// cells that miss the mesh by less than `nearCells` cell sizes (each box grown by
/// nearCells * cell per side; 0 leaves `near` empty).
inline ConservativeOracle oracleConservative(const MeshView& mesh, const CellGeometry& g,
                                             double nearCells = 0) {
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

/// The walls plus every cell that no 6-connected path of non-wall cells joins to the grid border
/// (breadth-first search from all non-wall border cells).
inline WorldGrid floodFromBorder(const WorldGrid& walls) {
    const Vec3i d = walls.dims;
    WorldGrid reached(d);
    std::vector<std::size_t> queue;
    auto push = [&](int64_t i, int64_t j, int64_t k) {
        const std::size_t c = walls.index(i, j, k);
        if (walls.cells[c] || reached.cells[c]) return;
        reached.cells[c] = 1;
        queue.push_back(c);
    };
    for (int64_t k = 0; k < d.z; ++k)
        for (int64_t j = 0; j < d.y; ++j)
            for (int64_t i = 0; i < d.x; ++i)
                if (i == 0 || j == 0 || k == 0 || i == d.x - 1 || j == d.y - 1 || k == d.z - 1) push(i, j, k);
    for (std::size_t q = 0; q < queue.size(); ++q) {
        const auto c = int64_t(queue[q]);
        const int64_t i = c % d.x, j = (c / d.x) % d.y, k = c / (d.x * d.y);
        if (i > 0) push(i - 1, j, k);
        if (i + 1 < d.x) push(i + 1, j, k);
        if (j > 0) push(i, j - 1, k);
        if (j + 1 < d.y) push(i, j + 1, k);
        if (k > 0) push(i, j, k - 1);
        if (k + 1 < d.z) push(i, j, k + 1);
    }
    WorldGrid inside(d);
    for (std::size_t c = 0; c < inside.cells.size(); ++c) inside.cells[c] = reached.cells[c] ? 0 : 1;
    return inside;
}

} // namespace voxfx::test
