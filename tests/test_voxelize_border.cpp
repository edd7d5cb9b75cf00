// voxfx — voxelization of geometry that touches the grid's outer boundary, against CGAL.
//
// The README's rule: conservative = every cell whose CLOSED box the surface touches, and a face
// lying exactly on a cell boundary touches the closed cells on both sides. On the grid's six
// sides only the inner cell exists, and it must be set whether the surface touches the side by
// a face, along an edge only or at a vertex only. Here small closed polyhedra (tetrahedra, a
// rhombic prism, an extruded star with vertical tooth tips) touch each side in each of those
// ways, in explicit frames (bounds given) and in frames from the resolution fit with margin 0
// (box = mesh bounds), for every mode, both raster paths and both slicings. Oracles: CGAL's exact
// triangle/box overlap and inside test (tests/cgal_oracle.hpp); for local slicing, the same
// predicates per cell of the frame's own per-column slicing.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

using test::CellGeometry;
using test::compareGrids;
using test::toWorldGrid;
using test::WorldGrid;

// Round-off allowance of the rasterizer (raster_impl.hpp kConservativeSlack = 1e-9 cell, and
// the rounded world cell bounds): cells missing the mesh by less than this may be set.
constexpr double kLeaveOutCells = 2e-9;

// --- Meshes ------------------------------------------------------------------------------------

// Appends the tetrahedron p0..p3 with outward counter-clockwise faces.
void appendTetrahedron(Mesh& m, std::array<Vec3d, 4> p) {
    const Vec3d n = cross(p[1] - p[0], p[2] - p[0]);
    if (dot(n, p[3] - p[0]) > 0) std::swap(p[1], p[2]); // p3 must lie behind face 012
    const auto base = uint32_t(m.positions.size());
    for (const Vec3d& q : p) m.positions.push_back(Vec3f(q));
    const uint32_t faces[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {0, 2, 3}};
    for (const auto& f : faces)
        for (uint32_t v : f) m.indices.push_back(base + v);
}

// Appends a closed prism: the convex polygon `ring` (counter-clockwise seen from +axis, in the
// plane coordinates (axis + 1, axis + 2)) extruded along `axis` over [lo, hi].
void appendPrism(Mesh& m, const std::vector<std::array<double, 2>>& ring, int axis, double lo, double hi,
                 bool fanFromCentre = false) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const auto base = uint32_t(m.positions.size());
    const auto n = uint32_t(ring.size());
    auto point = [&](const std::array<double, 2>& q, double h) {
        Vec3d p;
        p[a1] = q[0];
        p[a2] = q[1];
        p[axis] = h;
        return Vec3f(p);
    };
    for (const auto& q : ring) m.positions.push_back(point(q, lo));
    for (const auto& q : ring) m.positions.push_back(point(q, hi));
    for (uint32_t k = 0; k < n; ++k) { // sides: quad (k, k+1) bottom -> top
        const uint32_t j = (k + 1) % n;
        for (uint32_t v : {k, j, n + j, k, n + j, n + k}) m.indices.push_back(base + v);
    }
    if (!fanFromCentre) { // caps as fans from corner 0 (convex ring)
        for (uint32_t k = 1; k + 1 < n; ++k) {
            for (uint32_t v : {0u, k + 1, k}) m.indices.push_back(base + v);
            for (uint32_t v : {n, n + k, n + k + 1}) m.indices.push_back(base + v);
        }
        return;
    }
    // Star-shaped ring: caps as fans from the centre of the ring's box.
    double c0 = 0, c1 = 0;
    for (const auto& q : ring) {
        c0 += q[0] / double(n);
        c1 += q[1] / double(n);
    }
    m.positions.push_back(point({c0, c1}, lo));
    m.positions.push_back(point({c0, c1}, hi));
    const uint32_t cb = 2 * n, ct = 2 * n + 1;
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t j = (k + 1) % n;
        for (uint32_t v : {cb, j, k}) m.indices.push_back(base + v);
        for (uint32_t v : {ct, n + k, n + j}) m.indices.push_back(base + v);
    }
}

enum class Contact { Face, Edge, Vertex };
const char* toString(Contact c) {
    return c == Contact::Face ? "face" : c == Contact::Edge ? "edge" : "vertex";
}

// A tetrahedron inside `box` touching the side (axis, upper) by a face, along an edge only or at
// a vertex only. `at` gives the contact's position within the side as fractions of the box
// (along axis + 1 and axis + 2); `size` the tetrahedron's extent as a fraction of the box.
void appendContact(Mesh& m, const Box3d& box, int axis, bool upper, Contact contact, std::array<double, 2> at,
                   double size) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const Vec3d ext = box.extent();
    const double side = upper ? box.hi[axis] : box.lo[axis];
    const double inward = upper ? -1.0 : 1.0;
    auto p = [&](double u, double v, double depth) {
        Vec3d q;
        q[a1] = box.lo[a1] + (at[0] + u * size) * ext[a1];
        q[a2] = box.lo[a2] + (at[1] + v * size) * ext[a2];
        q[axis] = depth == 0 ? side : side + inward * depth * size * ext[axis];
        return q;
    };
    switch (contact) {
    case Contact::Face:
        appendTetrahedron(m, {p(0, 0, 0), p(1, 0, 0), p(0, 1, 0), p(0.3, 0.3, 1)});
        break;
    case Contact::Edge:
        appendTetrahedron(m, {p(0, 0, 0), p(1, 0.6, 0), p(0.2, 1, 0.8), p(0.9, 0.1, 1)});
        break;
    case Contact::Vertex:
        appendTetrahedron(m, {p(0, 0, 0), p(1, 0.4, 0.7), p(0.3, 1, 0.5), p(-0.5, 0.2, 1)});
        break;
    }
}

// Six tetrahedra, one per side of `box`, each touching its side in the same way; contacts at
// varied positions within the side (cell corners, cell edges, general points when the box has
// a lattice of 16 cells per axis).
Mesh sixContacts(const Box3d& box, Contact contact) {
    Mesh m;
    const std::array<double, 2> at[6] = {{0.25, 0.5},    {0.5, 0.3125}, {0.6, 0.21},
                                         {0.125, 0.625}, {0.375, 0.4},  {0.5625, 0.53}};
    int k = 0;
    for (int axis = 0; axis < 3; ++axis)
        for (bool upper : {false, true}) appendContact(m, box, axis, upper, contact, at[k++], 0.3);
    return m;
}

// Tetrahedra in the corners of `box`: one touching each corner at a vertex only, and one lying
// along each of the box's twelve edges (an edge of the tetrahedron on the box edge).
Mesh cornerContacts(const Box3d& box) {
    Mesh m;
    const Vec3d ext = box.extent();
    for (int k = 0; k < 8; ++k) {
        const Vec3d s{(k & 1) ? -1.0 : 1.0, (k & 2) ? -1.0 : 1.0, (k & 4) ? -1.0 : 1.0}; // inward
        const Vec3d c{(k & 1) ? box.hi.x : box.lo.x, (k & 2) ? box.hi.y : box.lo.y,
                      (k & 4) ? box.hi.z : box.lo.z};
        auto p = [&](double u, double v, double w) { return c + s * Vec3d{u, v, w} * ext * 0.2; };
        appendTetrahedron(m, {p(0, 0, 0), p(1, 0.3, 0.2), p(0.2, 1, 0.4), p(0.3, 0.2, 1)});
    }
    for (int axis = 0; axis < 3; ++axis)
        for (int k = 0; k < 4; ++k) {
            const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            Vec3d c, s;
            c[a1] = (k & 1) ? box.hi[a1] : box.lo[a1];
            c[a2] = (k & 2) ? box.hi[a2] : box.lo[a2];
            s[a1] = (k & 1) ? -1.0 : 1.0;
            s[a2] = (k & 2) ? -1.0 : 1.0;
            c[axis] = box.lo[axis];
            s[axis] = 1;
            auto p = [&](double t, double u, double v) {
                Vec3d d;
                d[axis] = t;
                d[a1] = u;
                d[a2] = v;
                return c + s * d * ext;
            };
            // The edge along the box edge from 0.55 to 0.8 of its length; the rest inside.
            appendTetrahedron(m, {p(0.55, 0, 0), p(0.8, 0, 0), p(0.6, 0.15, 0.05), p(0.7, 0.04, 0.17)});
        }
    return m;
}

// A rhombic prism along `axis`, its rhombus' corners on the box's sides: it touches the four
// sides around the axis along edges only, and the two others by a face.
Mesh rhombicPrism(const Box3d& box, int axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const double u0 = box.lo[a1], u1 = box.hi[a1], v0 = box.lo[a2], v1 = box.hi[a2];
    const double um = u0 + 0.4375 * (u1 - u0), vm = v0 + 0.5625 * (v1 - v0);
    Mesh m;
    appendPrism(m, {{um, v0}, {u1, vm}, {um, v1}, {u0, vm}}, axis, box.lo[axis], box.hi[axis]);
    return m;
}

// A gear-like CAD part: a star of `teeth` tips (radius r, valleys 0.8 r) around the origin,
// extruded along z over [-h, h]. The tips are vertical edges; four of them lie exactly on the
// bounds' sides x = +-r and y = +-r.
Mesh gear(int teeth, double r, double h) {
    std::vector<std::array<double, 2>> ring;
    for (int k = 0; k < 2 * teeth; ++k) {
        const double angle = M_PI * double(k) / double(teeth);
        const double radius = k % 2 == 0 ? r : 0.8 * r;
        double c = std::cos(angle), s = std::sin(angle);
        if (k % (teeth / 2) == 0) { // tips on the axes: exact
            c = std::round(c);
            s = std::round(s);
        }
        ring.push_back({radius * c, radius * s});
    }
    Mesh m;
    appendPrism(m, ring, 2, -h, h, true);
    return m;
}

// --- Oracles -----------------------------------------------------------------------------------

struct Expected {
    WorldGrid conservative, conservativeNear; // touching cells; cells within kLeaveOutCells
    WorldGrid inside, onSurface;              // centres inside; centres on the surface (left out)
};

// Uniform slicing: the oracles of cgal_oracle.hpp on the frame's cells.
Expected uniformOracle(const MeshView& mesh, const CellGeometry& g) {
    Expected e;
    test::ConservativeOracle c = test::oracleConservative(mesh, g, kLeaveOutCells);
    e.conservative = std::move(c.cells);
    e.conservativeNear = std::move(c.near);
    test::SolidOracle s = test::oracleSolid(mesh, g);
    EXPECT_TRUE(s.closed);
    e.inside = std::move(s.inside);
    e.onSurface = std::move(s.leftOut);
    return e;
}

// Local slicing (or any frame): the oracle of cgal_oracle.hpp on the frame's own cells.
Expected frameOracle(const MeshView& mesh, const Frame& frame) {
    test::FrameOracle f = test::oracleFrameCells(mesh, frame, kLeaveOutCells);
    EXPECT_TRUE(f.closed);
    return Expected{std::move(f.conservative), std::move(f.conservativeNear), std::move(f.inside),
                    std::move(f.onSurface)};
}

// The grid in frame index order (x, y, s), as a WorldGrid of dims (W, H, D).
WorldGrid frameCells(const VoxelGrid& g) {
    WorldGrid out({g.bits.width(), g.bits.height(), g.bits.depth()});
    for (int64_t s = 0; s < g.bits.depth(); ++s)
        for (int64_t y = 0; y < g.bits.height(); ++y)
            for (int64_t x = 0; x < g.bits.width(); ++x) out.at(x, y, s) = g.bits.get(x, y, s);
    return out;
}

::testing::AssertionResult same(const WorldGrid& actual, const WorldGrid& expected, const WorldGrid* ignore) {
    const test::GridDiff d = compareGrids(actual, expected, ignore);
    if (d.equal()) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << d;
}

WorldGrid unite(const WorldGrid& a, const WorldGrid& b) {
    WorldGrid r = a;
    for (std::size_t c = 0; c < r.cells.size(); ++c) r.cells[c] |= b.cells[c];
    return r;
}
WorldGrid minus(const WorldGrid& a, const WorldGrid& b) {
    WorldGrid r = a;
    for (std::size_t c = 0; c < r.cells.size(); ++c) r.cells[c] &= !b.cells[c];
    return r;
}

constexpr VoxelizeMode kModes[] = {VoxelizeMode::Surface, VoxelizeMode::Conservative, VoxelizeMode::Solid,
                                   VoxelizeMode::SolidConservative, VoxelizeMode::Interior};
constexpr RasterPath kBothPaths[] = {RasterPath::Binned, RasterPath::Direct};

VoxelGrid run(const Mesh& mesh, const Frame& frame, VoxelizeMode mode, RasterPath path, Slicing slicing) {
    VoxelizeOptions o;
    o.mode = mode;
    o.rasterPath = path;
    o.slicing = slicing;
    return voxelize(mesh.view(), frame, o);
}

// Every mode, both raster paths and both slicings of `mesh` in `frame` against the oracles.
// Returns the number of conservative cells that touch the mesh (for the callers' sanity checks).
int64_t expectEveryModeMatchesCgal(const Mesh& mesh, const Frame& frame) {
    int64_t touching = 0;
    for (Slicing slicing : {Slicing::Uniform, Slicing::Local}) {
        SCOPED_TRACE(toString(slicing));
        Expected e;
        bool haveOracle = false;
        for (RasterPath path : kBothPaths) {
            SCOPED_TRACE(path == RasterPath::Binned ? "binned" : "direct");
            for (VoxelizeMode mode : kModes) {
                SCOPED_TRACE(toString(mode));
                const VoxelGrid g = run(mesh, frame, mode, path, slicing);
                if (!haveOracle) {
                    // Local slicing depends on the mode (surface ranges by centres, the others by
                    // spans): the oracle follows the grid's own frame, rebuilt when it changes.
                    e = slicing == Slicing::Uniform ? uniformOracle(mesh.view(), CellGeometry::of(g))
                                                    : frameOracle(mesh.view(), g.frame);
                    test::markNearlyDegenerateCentres(mesh.view(), g.frame, kLeaveOutCells, e.onSurface,
                                                      slicing == Slicing::Uniform);
                    haveOracle = slicing == Slicing::Uniform;
                }
                const WorldGrid actual = slicing == Slicing::Uniform ? toWorldGrid(g) : frameCells(g);
                switch (mode) {
                case VoxelizeMode::Surface:
                    // Centre sampling has no closed-box oracle: it must lie within the conservative
                    // cells, and set some.
                    EXPECT_TRUE(same(unite(actual, e.conservative), e.conservative, &e.conservativeNear))
                        << "surface cells outside the conservative surface";
                    EXPECT_GT(actual.count(), 0);
                    break;
                case VoxelizeMode::Conservative:
                    EXPECT_TRUE(same(actual, e.conservative, &e.conservativeNear));
                    touching = e.conservative.count();
                    break;
                case VoxelizeMode::Solid:
                    EXPECT_TRUE(same(actual, e.inside, &e.onSurface));
                    break;
                case VoxelizeMode::SolidConservative: {
                    const WorldGrid ignore = unite(e.conservativeNear, minus(e.onSurface, e.conservative));
                    EXPECT_TRUE(same(actual, unite(e.inside, e.conservative), &ignore));
                    break;
                }
                case VoxelizeMode::Interior: {
                    const WorldGrid ignore = unite(e.conservativeNear, e.onSurface);
                    EXPECT_TRUE(same(actual, minus(e.inside, e.conservative), &ignore));
                    break;
                }
                }
            }
        }
    }
    return touching;
}

Frame resolutionFit(const Mesh& mesh, int64_t resolution, Axis axis) {
    FitOptions fit;
    fit.resolution = resolution;
    fit.axis = axis;
    fit.marginCells = 0;
    return fitFrame(computeBounds(mesh.view()), fit);
}

// --- Tests -------------------------------------------------------------------------------------

// Boxes given explicitly (as --bounds does): a lattice box where world and grid coordinates
// coincide, and a box whose cells are not representable, so that the sides map to W, H, D only
// up to rounding.
const Box3d kLatticeBox{{0, 0, 0}, {16, 16, 16}};
const Box3d kOddBox{{double(-0.7f), double(0.3f), double(1.1f)}, {double(2.9f), double(5.2f), double(3.7f)}};

TEST(VoxelizeBorderTest, ContactsWithEverySideOfAnExplicitBoxMatchCgal) {
    for (const Box3d& box : {kLatticeBox, kOddBox})
        for (Contact contact : {Contact::Face, Contact::Edge, Contact::Vertex}) {
            const Mesh mesh = sixContacts(box, contact);
            ASSERT_TRUE(analyzeTopology(mesh.view()).closed());
            for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
                SCOPED_TRACE(::testing::Message() << toString(contact) << " contacts, box (" << box.lo.x
                                                  << ", ...) along " << toString(axis));
                const Frame frame = Frame::orthographic(box, axis, 16, 13, 11);
                EXPECT_GT(expectEveryModeMatchesCgal(mesh, frame), 0);
            }
        }
}

// The cases below run fully in the *Slow tests; the fast ones take the box whose cell bounds
// are not representable, slicing along z.
void expectResolutionFitContactsMatch(const std::vector<Box3d>& boxes, const std::vector<Axis>& axes) {
    // The mesh bounds are the contacts' box; the fit makes the box the bounds on every axis
    // whose extent is a whole number of cells (the longest one always), the others centred.
    for (const Box3d& box : boxes)
        for (Contact contact : {Contact::Face, Contact::Edge, Contact::Vertex}) {
            const Mesh mesh = sixContacts(box, contact);
            for (Axis axis : axes) {
                SCOPED_TRACE(::testing::Message() << toString(contact) << " contacts, box (" << box.lo.x
                                                  << ", ...) at 23 along " << toString(axis));
                EXPECT_GT(expectEveryModeMatchesCgal(mesh, resolutionFit(mesh, 23, axis)), 0);
            }
        }
}

void expectCornerContactsMatch(const std::vector<Box3d>& boxes, const std::vector<Axis>& axes) {
    for (const Box3d& box : boxes) {
        const Mesh mesh = cornerContacts(box);
        ASSERT_TRUE(analyzeTopology(mesh.view()).closed());
        for (Axis axis : axes) {
            SCOPED_TRACE(::testing::Message() << "box (" << box.lo.x << ", ...) along " << toString(axis));
            EXPECT_GT(expectEveryModeMatchesCgal(mesh, Frame::orthographic(box, axis, 12, 14, 13)), 0);
            EXPECT_GT(expectEveryModeMatchesCgal(mesh, resolutionFit(mesh, 17, axis)), 0);
        }
    }
}

void expectRhombicPrismsMatch(const std::vector<Box3d>& boxes, const std::vector<int>& prismAxes,
                              const std::vector<Axis>& axes) {
    for (const Box3d& box : boxes)
        for (int prismAxis : prismAxes) {
            const Mesh mesh = rhombicPrism(box, prismAxis);
            ASSERT_TRUE(analyzeTopology(mesh.view()).closed());
            for (Axis axis : axes) {
                SCOPED_TRACE(::testing::Message() << "prism along " << prismAxis << ", box (" << box.lo.x
                                                  << ", ...) along " << toString(axis));
                EXPECT_GT(expectEveryModeMatchesCgal(mesh, Frame::orthographic(box, axis, 16, 16, 16)), 0);
                EXPECT_GT(expectEveryModeMatchesCgal(mesh, resolutionFit(mesh, 19, axis)), 0);
            }
        }
}

TEST(VoxelizeBorderTest, ContactsWithEverySideOfAResolutionFitWithoutMarginMatchCgal) {
    expectResolutionFitContactsMatch({kOddBox}, {Axis::Z});
}

TEST(VoxelizeBorderTest, ContactsWithEverySideOfAResolutionFitMatchCgalForEveryBoxAndAxisSlow) {
    expectResolutionFitContactsMatch({kLatticeBox, kOddBox}, {Axis::X, Axis::Y, Axis::Z});
}

TEST(VoxelizeBorderTest, VerticesInTheCornersAndEdgesAlongTheEdgesOfTheBoxMatchCgal) {
    expectCornerContactsMatch({kOddBox}, {Axis::Z});
}

TEST(VoxelizeBorderTest, CornerAndBoxEdgeContactsMatchCgalForEveryBoxAndAxisSlow) {
    expectCornerContactsMatch({kLatticeBox, kOddBox}, {Axis::X, Axis::Y, Axis::Z});
}

TEST(VoxelizeBorderTest, RhombicPrismsTouchingFourSidesAlongEdgesMatchCgal) {
    expectRhombicPrismsMatch({kOddBox}, {2}, {Axis::Z, Axis::X});
}

TEST(VoxelizeBorderTest, RhombicPrismsMatchCgalForEveryBoxPrismAxisAndSlicingAxisSlow) {
    expectRhombicPrismsMatch({kLatticeBox, kOddBox}, {0, 1, 2}, {Axis::X, Axis::Y, Axis::Z});
}

TEST(VoxelizeBorderTest, GearTipsOnTheSidesOfTheResolutionFitAt200AreConservative) {
    // The issue's example: a 16-tooth gear whose tooth tips (vertical edges) lie on the grid's
    // x and y sides. Conservative voxelization at 200 along the longest axis against CGAL.
    const Mesh mesh = gear(16, 1.0, 0.15);
    ASSERT_TRUE(analyzeTopology(mesh.view()).closed());
    for (Axis axis : {Axis::Z, Axis::X}) {
        SCOPED_TRACE(toString(axis));
        const Frame frame = resolutionFit(mesh, 200, axis);
        for (RasterPath path : kBothPaths) {
            const VoxelGrid g = run(mesh, frame, VoxelizeMode::Conservative, path, Slicing::Uniform);
            const test::ConservativeOracle o =
                test::oracleConservative(mesh.view(), CellGeometry::of(g), kLeaveOutCells);
            EXPECT_TRUE(same(toWorldGrid(g), o.cells, &o.near))
                << (path == RasterPath::Binned ? "binned" : "direct");
        }
    }
}

// --- Sides at coordinates no float holds (#23) -------------------------------------------------
// A mesh file and a --bounds box written in decimal: vertices that the file puts on the box's
// side share the side's decimal value, but mesh vertices are floats and the box is doubles, so
// the vertex can lie up to half a float step outside the box; and the far side maps to
// (hi - lo) * (n / (hi - lo)), which can round past n. A point on the grid's side is on it:
// the oracle is CGAL on the coordinates as written (doubles), where those vertices lie on the
// sides exactly. Every other coordinate is a float, so voxfx and the oracle see the same mesh
// except on the sides.

// A mesh with the coordinates as the file states them, and as voxfx holds them (floats).
struct WrittenMesh {
    std::vector<Vec3d> points;
    std::vector<uint32_t> indices;

    Mesh asFloat() const {
        Mesh m;
        for (const Vec3d& p : points) m.positions.push_back(Vec3f(p));
        m.indices = indices;
        return m;
    }
    std::array<Vec3d, 3> triangle(std::size_t t) const {
        return {points[indices[3 * t]], points[indices[3 * t + 1]], points[indices[3 * t + 2]]};
    }
    // The tetrahedron p0..p3 with outward counter-clockwise faces; returns the index of face 012.
    std::size_t addTetrahedron(std::array<Vec3d, 4> p) {
        if (dot(cross(p[1] - p[0], p[2] - p[0]), p[3] - p[0]) > 0) std::swap(p[1], p[2]);
        const auto base = uint32_t(points.size());
        points.insert(points.end(), p.begin(), p.end());
        const std::size_t first = indices.size() / 3;
        const uint32_t faces[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {0, 2, 3}};
        for (const auto& f : faces)
            for (uint32_t v : f) indices.push_back(base + v);
        return first;
    }
};

// Decimal boxes that no float holds: the issue's (its prism's bounds) and a flatter one.
const Box3d kDecimalBox{{-20.8600788, -20.8600788, -16.8600788}, {20.8600788, 20.8600788, 24.8600788}};
const Box3d kFlatDecimalBox{{-3.14159265, 0.1, -7.77777777}, {2.71828183, 1.3, 9.99999999}};

// A float near `lo + f * (hi - lo)`: what voxfx and the oracle both hold exactly.
double floatAt(double lo, double hi, double f) { return double(float(lo + f * (hi - lo))); }

// Six tetrahedra, each with a face on one side of `box` (the side's coordinate as written, the
// face's other coordinates floats at uneven fractions of the box) and its apex inside.
// `onSide[k]` receives the index of the triangle lying on side k = 2 * axis + upper.
WrittenMesh facesOnEverySide(const Box3d& box, std::array<std::size_t, 6>& onSide) {
    WrittenMesh m;
    const double at[6][2] = {{0.21, 0.43}, {0.57, 0.19}, {0.33, 0.61},
                             {0.12, 0.27}, {0.47, 0.52}, {0.64, 0.08}};
    for (int axis = 0; axis < 3; ++axis)
        for (int upper = 0; upper < 2; ++upper) {
            const int k = 2 * axis + upper, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            auto point = [&](double u, double v, double depth) {
                Vec3d q;
                q[a1] = floatAt(box.lo[a1], box.hi[a1], at[k][0] + u);
                q[a2] = floatAt(box.lo[a2], box.hi[a2], at[k][1] + v);
                q[axis] = depth == 0 ? (upper ? box.hi[axis] : box.lo[axis])
                                     : floatAt(box.lo[axis], box.hi[axis], upper ? 1 - depth : depth);
                return q;
            };
            onSide[size_t(k)] = m.addTetrahedron(
                {point(0, 0, 0), point(0.29, 0.03, 0), point(0.06, 0.31, 0), point(0.1, 0.11, 0.23)});
        }
    return m;
}

// The issue's prism: a triangle in the plane z = 0 extruded to z = 8, its face y = -20.8600788
// on the grid's lower y side (parallel to the slicing axis z).
WrittenMesh issuePrism() {
    WrittenMesh m;
    m.points = {{0.377839416, -20.8600788, 0},   {-0.377839416, -20.8600788, 0},
                {-0.0358124524, -5.99989319, 0}, {0.377839416, -20.8600788, 8},
                {-0.377839416, -20.8600788, 8},  {-0.0358124524, -5.99989319, 8}};
    m.indices = {0, 2, 1, 3, 4, 5, 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 2, 0, 3, 2, 3, 5};
    return m;
}

// Cells whose closed box meets a triangle as written (CGAL's exact triangle/box test), and those
// that meet one only once grown by kLeaveOutCells of a cell (left out of comparisons).
test::ConservativeOracle writtenConservative(const WrittenMesh& mesh, const CellGeometry& g) {
    test::ConservativeOracle o{WorldGrid(g.dims), WorldGrid(g.dims), 0};
    for (std::size_t t = 0; t < mesh.indices.size() / 3; ++t) {
        const std::array<Vec3d, 3> tri = mesh.triangle(t);
        int64_t lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const double tlo = std::min({tri[0][a], tri[1][a], tri[2][a]}),
                         thi = std::max({tri[0][a], tri[1][a], tri[2][a]});
            lo[a] = std::max<int64_t>(0, int64_t(std::floor((tlo - g.lo[a]) / g.cell[a])) - 1);
            hi[a] = std::min<int64_t>(g.dims[a] - 1, int64_t(std::floor((thi - g.lo[a]) / g.cell[a])) + 1);
        }
        for (int64_t k = lo[2]; k <= hi[2]; ++k)
            for (int64_t j = lo[1]; j <= hi[1]; ++j)
                for (int64_t i = lo[0]; i <= hi[0]; ++i) {
                    if (o.cells.at(i, j, k)) continue;
                    const int64_t idx[3] = {i, j, k};
                    Box3d cell, grown;
                    for (int a = 0; a < 3; ++a) {
                        cell.lo[a] = g.lower(a, idx[a]);
                        cell.hi[a] = g.upper(a, idx[a]);
                        grown.lo[a] = cell.lo[a] - kLeaveOutCells * g.cell[a];
                        grown.hi[a] = cell.hi[a] + kLeaveOutCells * g.cell[a];
                    }
                    if (test::oracleTriangleMeetsBox(tri, cell)) {
                        o.cells.at(i, j, k) = 1;
                        o.near.at(i, j, k) = 0;
                    } else if (test::oracleTriangleMeetsBox(tri, grown)) {
                        o.near.at(i, j, k) = 1;
                    }
                }
    }
    o.nearCount = o.near.count();
    return o;
}

// Centre sampling of a face on a depth side (the side across the slicing axis): every column
// whose centre lies inside the face's projection, a millionth of a cell or more from its edges
// (exact orientation tests on the coordinates as written), has the face in its first (lower
// side) or last (upper side) slice. Returns how many such columns there were.
int64_t expectDepthSideFaceSampled(const VoxelGrid& g, const std::array<Vec3d, 3>& tri, bool upper) {
    const Frame& f = g.frame;
    const int ax = columnXAxis(f.axis()), ay = columnYAxis(f.axis());
    const Vec3d cell = f.cellSize();
    const int turn =
        test::oracleOrient2d(tri[0][ax], tri[0][ay], tri[1][ax], tri[1][ay], tri[2][ax], tri[2][ay]);
    int64_t columns = 0;
    for (int64_t y = 0; y < f.height(); ++y)
        for (int64_t x = 0; x < f.width(); ++x) {
            const double cx = f.box().lo[ax] + (double(x) + 0.5) * cell[ax];
            const double cy = f.box().lo[ay] + (double(y) + 0.5) * cell[ay];
            bool inside = turn != 0;
            for (int e = 0; e < 3 && inside; ++e) {
                const Vec3d& a = tri[size_t(e)];
                const Vec3d& b = tri[size_t((e + 1) % 3)];
                inside = test::oracleOrient2d(a[ax], a[ay], b[ax], b[ay], cx, cy) == turn;
                // Distance of the centre from the edge's line, in cells (of the smaller side).
                const double dx = b[ax] - a[ax], dy = b[ay] - a[ay];
                const double dist = std::abs(dx * (cy - a[ay]) - dy * (cx - a[ax])) / std::hypot(dx, dy);
                inside = inside && dist > 1e-6 * std::min(cell[ax], cell[ay]);
            }
            if (!inside) continue;
            ++columns;
            const int64_t s = upper ? f.depth() - 1 : 0;
            EXPECT_TRUE(g.bits.get(x, y, s)) << "column (" << x << ", " << y << ") lost the face on the "
                                             << (upper ? "far" : "near") << " side";
        }
    return columns;
}

// Every mode and both raster paths of `written` (as floats) in `frame` against CGAL on the
// coordinates as written; `depthFaces` lists (triangle, upper) of faces on the sides across axis
// `axis`, for the surface mode's centre samples.
void expectWrittenMeshMatchesCgal(const WrittenMesh& written, const Frame& frame,
                                  const std::vector<std::pair<std::size_t, bool>>& depthFaces) {
    const Mesh mesh = written.asFloat();
    ASSERT_TRUE(analyzeTopology(mesh.view()).closed());
    for (RasterPath path : kBothPaths) {
        SCOPED_TRACE(path == RasterPath::Binned ? "binned" : "direct");
        const VoxelGrid conservative = run(mesh, frame, VoxelizeMode::Conservative, path, Slicing::Uniform);
        const CellGeometry geometry = CellGeometry::of(conservative);
        const test::ConservativeOracle c = writtenConservative(written, geometry);
        EXPECT_TRUE(same(toWorldGrid(conservative), c.cells, &c.near)) << "conservative";
        // Centres: the floats and the coordinates as written differ by less than a float step
        // (a ten-thousandth of a cell here), so centres farther than that from the surface are
        // classified alike; nearer ones are left out.
        test::SolidOracle solid = test::oracleSolid(mesh.view(), geometry);
        test::markNearlyDegenerateCentres(mesh.view(), frame, 1e-4, solid.leftOut, true);
        const VoxelGrid inside = run(mesh, frame, VoxelizeMode::Solid, path, Slicing::Uniform);
        EXPECT_TRUE(same(toWorldGrid(inside), solid.inside, &solid.leftOut)) << "solid";
        const WorldGrid leftOut = unite(c.near, solid.leftOut);
        EXPECT_TRUE(
            same(toWorldGrid(run(mesh, frame, VoxelizeMode::SolidConservative, path, Slicing::Uniform)),
                 unite(solid.inside, c.cells), &leftOut))
            << "solid-conservative";
        EXPECT_TRUE(same(toWorldGrid(run(mesh, frame, VoxelizeMode::Interior, path, Slicing::Uniform)),
                         minus(solid.inside, c.cells), &leftOut))
            << "interior";
        const VoxelGrid surface = run(mesh, frame, VoxelizeMode::Surface, path, Slicing::Uniform);
        EXPECT_TRUE(same(unite(toWorldGrid(surface), c.cells), c.cells, &c.near))
            << "surface outside conservative";
        int64_t sampled = 0;
        for (const auto& [t, upper] : depthFaces)
            sampled += expectDepthSideFaceSampled(surface, written.triangle(t), upper);
        // The faces span about a third of the box: seven columns across catch centres in them.
        if (!depthFaces.empty() && frame.width() >= 7 && frame.height() >= 7) {
            EXPECT_GT(sampled, 0) << "surface";
        }
    }
}

TEST(VoxelizeBorderTest, TheIssuesPrismOnADecimalSideMatchesCgalOnItsWrittenCoordinates) {
    // --bounds -20.8600788 ... --dims 200 200 200 --mode conservative: CGAL on the file's
    // coordinates finds the face on the lower y side in columns x = 99, 100 of row 0.
    const WrittenMesh prism = issuePrism();
    FitOptions fit;
    fit.dims = {200, 200, 200};
    fit.bounds = kDecimalBox;
    const Frame frame = fitFrame(computeBounds(prism.asFloat().view()), fit);
    for (RasterPath path : kBothPaths) {
        const VoxelGrid g = run(prism.asFloat(), frame, VoxelizeMode::Conservative, path, Slicing::Uniform);
        const test::ConservativeOracle c = writtenConservative(prism, CellGeometry::of(g));
        EXPECT_TRUE(same(toWorldGrid(g), c.cells, &c.near));
        for (int64_t k = 81; k <= 118; ++k)
            EXPECT_TRUE(g.atWorldIndex(99, 0, k) && g.atWorldIndex(100, 0, k)) << k;
    }
    // Every mode on a smaller grid of the same box (the centres' oracle costs per cell).
    fit.dims = {40, 40, 40};
    expectWrittenMeshMatchesCgal(prism, fitFrame(computeBounds(prism.asFloat().view()), fit), {});
}

// Faces on all six sides of decimal boxes, sliced along every axis (so each side is once across
// the slicing axis and twice along it), at several grid sizes.
void expectFacesOnDecimalSidesMatch(const std::vector<Vec3i>& sizes) {
    for (const Box3d& box : {kDecimalBox, kFlatDecimalBox}) {
        std::array<std::size_t, 6> onSide{};
        const WrittenMesh mesh = facesOnEverySide(box, onSide);
        for (Axis axis : {Axis::X, Axis::Y, Axis::Z})
            for (const Vec3i& n : sizes) {
                SCOPED_TRACE(::testing::Message() << "box (" << box.lo.x << ", ...), " << n.x << " x " << n.y
                                                  << " x " << n.z << " along " << toString(axis));
                const int a = int(axis);
                const Frame frame =
                    Frame::orthographic(box, axis, n[columnXAxis(axis)], n[columnYAxis(axis)], n[a]);
                expectWrittenMeshMatchesCgal(
                    mesh, frame, {{onSide[size_t(2 * a)], false}, {onSide[size_t(2 * a + 1)], true}});
            }
    }
}

TEST(VoxelizeBorderTest, FacesOnEverySideOfADecimalBoxMatchCgalOnTheirWrittenCoordinates) {
    expectFacesOnDecimalSidesMatch({{7, 9, 11}, {31, 26, 43}});
}

TEST(VoxelizeBorderTest, FacesOnEverySideOfADecimalBoxMatchCgalAtManyGridSizesSlow) {
    expectFacesOnDecimalSidesMatch({{1, 2, 3}, {16, 13, 11}, {61, 47, 53}, {100, 100, 100}, {127, 64, 200}});
}

TEST(VoxelizeBorderTest, FarSidesOfResolutionFitsKeepTheirFacesInEveryMode) {
    // The resolution fit makes the mesh's (float) bounds the box along the longest axis, whose far
    // side maps to N only up to rounding; the fit's other axes are centred. Sizes where
    // (hi - lo) * (N / (hi - lo)) rounds past N and where it does not.
    std::array<std::size_t, 6> onSide{};
    const WrittenMesh mesh = facesOnEverySide(kFlatDecimalBox, onSide);
    const Mesh floats = mesh.asFloat();
    const Box3d bounds = computeBounds(floats.view());
    int past = 0;
    for (int64_t n : {23, 37, 64, 97, 150}) {
        const double ext = bounds.extent().z, scale = double(n) / ext;
        past += ext * scale > double(n);
        SCOPED_TRACE(::testing::Message() << "resolution " << n);
        WrittenMesh asFitted = mesh; // the fit's box is the float bounds: the floats are as written
        for (Vec3d& p : asFitted.points) p = Vec3d(Vec3f(p));
        expectWrittenMeshMatchesCgal(asFitted, resolutionFit(floats, n, Axis::Z), {{onSide[5], true}});
    }
    EXPECT_GT(past, 0) << "no size rounds the far side past N: the test would not see the bug";
}

} // namespace
} // namespace voxfx
