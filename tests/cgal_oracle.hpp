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
//   oracleNearest       the nearest point of a mesh: CGAL's AABB tree (closest point, face,
//                       squared distance in double) and, exactly, the minimum of the rational
//                       squared distances (Epeck) to the triangles near it, with the faces tying.
//   floodFromBorder     cells not reachable from the grid border through non-wall cells by
//                       6-connected steps: a plain voxel-by-voxel breadth-first search.
// The CGAL work is compiled once, in cgal_oracle.cpp (CGAL headers cost a minute per translation unit).
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

/// A mesh file as CGAL reads it: points and polygons (corner indices), nothing voxfx computed.
struct CgalSoup {
    std::vector<Vec3d> points;
    std::vector<std::vector<std::size_t>> polygons;
};

/// Reads `path` with CGAL::IO::read_polygon_soup (failure is a test failure and an empty soup).
CgalSoup readWithCgal(const std::string& path);
/// Writes `soup` with CGAL::IO::write_polygon_soup (format from the extension, 9 digits);
/// false when CGAL fails.
bool writeWithCgal(const std::string& path, const CgalSoup& soup, bool binary);

/// The soup as a voxfx::Mesh: positions rounded to float, each polygon fan-triangulated from its
/// first corner.
inline Mesh meshOfSoup(const CgalSoup& soup) {
    Mesh m;
    for (const Vec3d& p : soup.points) m.positions.push_back(Vec3f(p));
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
SolidOracle oracleSolid(const MeshView& mesh, const CellGeometry& g, int lineAxis = 2);

/// Checks `oracle` (from oracleSolid) against CGAL::Side_of_triangle_mesh at every `stride`-th
/// cell centre of a closed mesh; returns how many of them disagree (ON_BOUNDARY must match
/// leftOut), or -1 when the mesh is not closed.
int64_t sideOfMeshDisagreements(const MeshView& mesh, const CellGeometry& g, const SolidOracle& oracle,
                                int64_t stride);

/// CGAL::Side_of_triangle_mesh at each point of a closed mesh: 1 inside, -1 outside, 0 on the
/// boundary; empty when the mesh is not a closed manifold.
std::vector<int> sideOfClosedMesh(const MeshView& mesh, const std::vector<Vec3d>& points);

/// Result of oracleConservative, in world-axis index order.
struct ConservativeOracle {
    WorldGrid cells; ///< the closed box meets a triangle
    WorldGrid near;  ///< the box misses every triangle, but meets one once grown by the tolerance
    int64_t nearCount = 0;
};
/// Cells whose closed box meets at least one triangle of `mesh` (exact do_intersect), and the
/// cells that miss the mesh by less than `nearCells` cell sizes (each box grown by
/// nearCells * cell per side; 0 leaves `near` empty).
ConservativeOracle oracleConservative(const MeshView& mesh, const CellGeometry& g, double nearCells = 0);

/// For each segment (from[i], to[i]): whether it meets any triangle of `mesh`, closed segment
/// against closed triangle, decided by CGAL's exact do_intersect(Segment_3, Triangle_3) on the
/// double inputs (after an axis-aligned bounding box rejection). Brute force over the triangles.
std::vector<uint8_t> oracleSegmentsHitMesh(const MeshView& mesh, const std::vector<Vec3d>& from,
                                           const std::vector<Vec3d>& to);

/// What a segment crosses of a closed mesh (oracleChords).
struct OracleChord {
    double inside = 0;       ///< length of the segment inside the mesh (world units)
    int crossings = 0;       ///< points where the segment crosses the surface
    bool degenerate = false; ///< an edge or vertex hit, a segment in a triangle's plane, or an odd count
};
/// For each segment (from[i], to[i]), both ends outside a closed mesh: the crossings with the
/// triangles (CGAL::intersection(Segment_3, Triangle_3), the points constructed in double, after an
/// axis-aligned bounding box rejection; brute force over the triangles), sorted along the segment
/// and paired by parity (entry, exit); the inside length is the sum of the pairs' distances.
/// Segments that meet an edge or vertex (two hits within 1e-9 of the length), lie in a triangle's
/// plane or cross an odd number of times are marked degenerate.
std::vector<OracleChord> oracleChords(const MeshView& mesh, const std::vector<Vec3d>& from,
                                      const std::vector<Vec3d>& to);

/// Result of oracleFrameCells, in the frame's index order (x, y, s) as WorldGrids of dims (W, H, D).
struct FrameOracle {
    WorldGrid conservative;     ///< the cell's closed box meets a triangle
    WorldGrid conservativeNear; ///< misses every triangle, but meets one once grown by the tolerance
    WorldGrid inside;           ///< the centre is inside (Side_of_triangle_mesh ON_BOUNDED_SIDE)
    WorldGrid onSurface;        ///< the centre is on the surface (ON_BOUNDARY): left out of comparisons
    bool closed = false;        ///< the mesh is a closed Surface_mesh; `inside` means nothing otherwise
};
/// Any frame (local slicing, non-cubic cells): every cell of `frame`, with its world box from the
/// frame's own per-column slicing, against every triangle (exact do_intersect; brute force, for
/// small meshes and grids); centres by CGAL::Side_of_triangle_mesh. The near band grows each box
/// by `nearCells` of its own size along the slices and of a cell across.
FrameOracle oracleFrameCells(const MeshView& mesh, const Frame& frame, double nearCells);

/// Marks in `onSurface` the centres whose line along the slicing axis passes within `nearCells`
/// of a mesh edge, or within `nearCells` slices of the surface along that line: in frames whose
/// cells are not representable, exact contacts at "nice" fractions of the box can put the
/// oracle's rounded world centres and the rasterizer's rounded grid coordinates on different
/// sides. `onSurface` is in world-axis order when `worldOrder`, else in frame order (x, y, s).
void markNearlyDegenerateCentres(const MeshView& mesh, const Frame& frame, double nearCells,
                                 WorldGrid& onSurface, bool worldOrder);

/// CGAL::Side_of_triangle_mesh, with exact (rational) coordinates, at each point p moved to
/// p + (eps1, eps2, -delta) where delta = 2^-60 * scale, eps1 = 2^-200 * delta and
/// eps2 = 2^-200 * eps1 (scale: the largest extent of the mesh): 1 inside, -1 outside, 0 when
/// still on the boundary (the perturbation was too small). Empty when the mesh is not a
/// manifold. Decides points lying exactly on the surface by the tie rule of voxfx/contains.hpp.
std::vector<int> sideOfClosedMeshPerturbed(const MeshView& mesh, const std::vector<Vec3d>& points);

/// The exact volume of the intersection of the solids of two closed meshes (each a closed,
/// consistently oriented, self-intersection-free surface that bounds a volume, positions as
/// stored): CGAL::Polygon_mesh_processing::corefine_and_compute_intersection with exact
/// constructions (Exact_predicates_exact_constructions_kernel), then PMP::volume of the result,
/// rounded to double only at the end. NaN when an input fails those conditions or CGAL refuses.
double oracleIntersectionVolume(const MeshView& a, const MeshView& b);

/// What CGAL says about the point of a mesh nearest to a query point.
struct OracleNearest {
    double distance = 0;       ///< see oracleNearest
    Vec3d point;               ///< the AABB tree's closest point (an inexact construction)
    int64_t face = -1;         ///< the AABB tree's closest triangle
    std::vector<int64_t> ties; ///< exact mode: every face at the exact minimal distance, ascending
};
/// For each point, CGAL's AABB tree over the triangles (Epick, accelerated distance queries):
/// closest_point_and_primitive, and `distance` = sqrt(squared_distance) in double. With `exact`,
/// the distance is instead the square root of the exact minimum (Epeck, rational arithmetic) of
/// the squared distances to every triangle whose box comes within the tree's distance (plus a
/// relative 1e-6) of the point, rounded to double, and `ties` lists the faces attaining that
/// minimum. Non-finite points are skipped (distance NaN). The Epick part runs on worker threads.
std::vector<OracleNearest> oracleNearest(const MeshView& mesh, const std::vector<Vec3d>& points, bool exact);

/// CGAL's squared distance (Epick) from `p` to the triangle (a, b, c), in double.
double oracleTriangleDistance2(const std::array<Vec3d, 3>& triangle, const Vec3d& p);

/// CGAL::orientation on the double inputs: 1 left turn (counter-clockwise), -1 right turn, 0
/// collinear.
int oracleOrient2d(double ax, double ay, double bx, double by, double cx, double cy);
/// CGAL::orientation(a, b, c, d): 1 when d lies on the positive side of (a, b, c), i.e.
/// det[b - a, c - a, d - a] > 0; -1 on the negative side; 0 coplanar.
int oracleOrient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d);

using Point2d = std::array<double, 2>;
/// The convex hull of `points` (CGAL::convex_hull_2), counter-clockwise, without collinear points.
std::vector<Point2d> oracleConvexHull2(const std::vector<Point2d>& points);
/// The distance from `p` to the closed segment [a, b] (CGAL::squared_distance, then a square root).
double oracleDistanceToSegment2(const Point2d& a, const Point2d& b, const Point2d& p);
/// Whether the closed triangle meets the closed box (CGAL::do_intersect(Triangle_3, Iso_cuboid_3),
/// exact on the double inputs).
bool oracleTriangleMeetsBox(const std::array<Vec3d, 3>& triangle, const Box3d& box);

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
