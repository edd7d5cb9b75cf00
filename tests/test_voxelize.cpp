// Tests of src/voxelize/: hand-derived counts on boxes (including faces exactly on cell
// boundaries and exactly through cell centres), a brute-force ray-parity reference on curved
// meshes, perspective and local slicing, fills, determinism and bad input. Real meshes against
// CGAL are in test_voxelize_oracle.cpp.
#include <cmath>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

using test::makeBox;

// Grid over [0, 16]^3 with 16 cells per axis: grid coordinates equal world coordinates exactly.
Frame unitFrame(Axis axis = Axis::Z, int64_t n = 16) {
    return Frame::orthographic({{0, 0, 0}, {double(n), double(n), double(n)}}, axis, n, n, n);
}

int64_t countMode(const Mesh& mesh, const Frame& frame, VoxelizeMode mode, Fill fill = Fill::Parity) {
    VoxelizeOptions o;
    o.mode = mode;
    o.fill = fill;
    return voxelize(mesh.view(), frame, o).bits.count();
}

// Cells whose bit differs from brute-force ray parity of `mesh` at the cell's centre, and cells
// inside by that parity. WorldIndex: a frame of unit cells from the world origin, cell (i, j, k)
// centred at (i + 0.5, j + 0.5, k + 0.5) and read through atWorldIndex (so the frame's own axis
// mapping is checked too); Frame: cell (x, y, s) centred where the frame says (perspective and
// local slicing), read from the bits.
enum class Centres { WorldIndex, Frame };
struct ParityCheck {
    int64_t mismatches = 0, inside = 0;
};

ParityCheck againstRayParity(const Mesh& mesh, const VoxelGrid& g, Centres centres) {
    const bool byFrame = centres == Centres::Frame;
    const Vec3i n = byFrame ? Vec3i{g.bits.width(), g.bits.height(), g.bits.depth()} : g.worldDims();
    ParityCheck r;
    for (int64_t a = 0; a < n.x; ++a)
        for (int64_t b = 0; b < n.y; ++b)
            for (int64_t c = 0; c < n.z; ++c) {
                const Vec3d p = byFrame ? g.frame.cellCenter(a, b, c) : Vec3d{a + 0.5, b + 0.5, c + 0.5};
                const bool expected = test::insideByRay(mesh.view(), p);
                r.inside += expected;
                r.mismatches += expected != (byFrame ? g.bits.get(a, b, c) : g.atWorldIndex(a, b, c));
            }
    return r;
}

TEST(VoxelizeTest, CubeFitGivesAnNCubedGridOfCubicCellsCentredOnTheBounds) {
    const Box3d bounds{{1, -2, 0.5}, {4, -1.5, 1.5}}; // extents 3, 0.5, 1
    FitOptions fo;
    fo.resolution = 12;
    fo.cube = true;
    for (const int64_t margin : {0, 2}) {
        fo.marginCells = margin;
        const Frame f = fitFrame(bounds, fo);
        const int64_t n = 12 + 2 * margin;
        EXPECT_EQ(f.width(), n);
        EXPECT_EQ(f.height(), n);
        EXPECT_EQ(f.depth(), n);
        const Vec3d cell = f.cellSize();
        for (int a = 0; a < 3; ++a) {
            EXPECT_DOUBLE_EQ(cell[a], 3.0 / 12);
            EXPECT_DOUBLE_EQ(f.box().lo[a] + f.box().hi[a], bounds.lo[a] + bounds.hi[a]); // centred
        }
        // The longest axis is filled exactly, less the margins.
        EXPECT_DOUBLE_EQ(f.box().lo.x + double(margin) * cell.x, 1.0);
    }
    fo.resolution = 0;
    fo.voxelSize = 0.5;
    EXPECT_THROW(fitFrame(bounds, fo), Error);
}

TEST(VoxelizeTest, BoxInsideCellsGivesHandCountedVoxels) {
    // Faces at 1.3 and 8.7: centres 1.5 .. 8.5 inside (8 per axis); the surface touches cells
    // 1 .. 8 along each axis, so the conservative shell is 8^3 - 6^3.
    const Mesh box = makeBox({1.3, 1.3, 1.3}, {8.7, 8.7, 8.7});
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        const Frame f = unitFrame(axis);
        EXPECT_EQ(countMode(box, f, VoxelizeMode::Solid), 512) << toString(axis);
        EXPECT_EQ(countMode(box, f, VoxelizeMode::Conservative), 512 - 216) << toString(axis);
        EXPECT_EQ(countMode(box, f, VoxelizeMode::SolidConservative), 512) << toString(axis);
        EXPECT_EQ(countMode(box, f, VoxelizeMode::Interior), 216) << toString(axis);
    }
}

TEST(VoxelizeTest, FacesOnCellBoundariesTouchBothNeighboursButNeverDoubleCountInside) {
    // Faces exactly on cell boundaries 4 and 12. Closed boxes that touch count as overlapping,
    // so the conservative surface covers cells 3..12 minus the open interior 5..10.
    const Mesh box = makeBox({4, 4, 4}, {12, 12, 12});
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        const Frame f = unitFrame(axis);
        EXPECT_EQ(countMode(box, f, VoxelizeMode::Solid), 8 * 8 * 8) << toString(axis);
        EXPECT_EQ(countMode(box, f, VoxelizeMode::Conservative), 10 * 10 * 10 - 6 * 6 * 6) << toString(axis);
    }
}

TEST(VoxelizeTest, FacesThroughCellCentresBelongToExactlyOneSide) {
    // Faces through centres 4.5 and 11.5: the tie rule makes each axis half-open, 7 cells of 8.
    const Mesh box = makeBox({4.5, 4.5, 4.5}, {11.5, 11.5, 11.5});
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z})
        EXPECT_EQ(countMode(box, unitFrame(axis), VoxelizeMode::Solid), 343);
}

TEST(VoxelizeTest, TouchingBoxesPartitionTheirUnionOnEveryAxis) {
    // Two boxes sharing a face that passes through cell centres, along each world axis in turn.
    for (int shared = 0; shared < 3; ++shared) {
        Vec3d aLo{2.5, 3.5, 4.5}, aHi{12.5, 11.5, 10.5};
        Vec3d bLo = aLo, bHi = aHi;
        aHi[shared] = 7.5;
        bLo[shared] = 7.5;
        const Mesh a = makeBox(aLo, aHi), b = makeBox(bLo, bHi);
        Mesh both = a;
        test::appendBox(both, bLo, bHi);
        for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
            const Frame f = unitFrame(axis);
            const VoxelGrid ga = voxelize(a.view(), f), gb = voxelize(b.view(), f),
                            gu = voxelize(both.view(), f);
            int64_t overlap = 0, unionMismatch = 0;
            for (int64_t c = 0; c < f.columnCount(); ++c)
                for (int64_t w = 0; w < ga.bits.wordsPerColumn(); ++w) {
                    const uint64_t x = ga.bits.column(c)[w], y = gb.bits.column(c)[w],
                                   u = gu.bits.column(c)[w];
                    overlap += std::popcount(x & y);
                    unionMismatch += std::popcount((x | y) ^ u);
                }
            EXPECT_EQ(overlap, 0) << "shared face normal " << shared << ", axis " << toString(axis);
            EXPECT_EQ(unionMismatch, 0) << "shared face normal " << shared << ", axis " << toString(axis);
            EXPECT_GT(ga.bits.count(), 0);
        }
    }
}

TEST(VoxelizeTest, SolidMatchesBruteForceRayParityOnTorus) {
    // A coarse torus has many triangles meeting at shared edges and vertices inside columns.
    const Mesh torus = test::makeTorus({8.1, 7.9, 8.05}, 5.0, 2.2, 24, 12);
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        const ParityCheck r =
            againstRayParity(torus, voxelize(torus.view(), unitFrame(axis)), Centres::WorldIndex);
        EXPECT_EQ(r.mismatches, 0) << toString(axis);
        EXPECT_GT(r.inside, 100);
    }
}

TEST(VoxelizeTest, SolidIsIndependentOfTriangleOrderAndWinding) {
    Mesh torus = test::makeTorus({8, 8, 8}, 5.3, 2.1, 20, 10);
    const VoxelGrid reference = voxelize(torus.view(), unitFrame());
    Mesh shuffled = torus;
    const size_t T = shuffled.triangleCount();
    for (size_t t = 0; t < T; ++t) {
        const size_t u = (t * 7919) % T; // a fixed permutation (7919 is prime, coprime with T)
        for (int k = 0; k < 3; ++k) std::swap(shuffled.indices[3 * t + k], shuffled.indices[3 * u + k]);
        if (t % 2) std::swap(shuffled.indices[3 * t], shuffled.indices[3 * t + 1]); // flip winding
    }
    EXPECT_EQ(voxelize(shuffled.view(), unitFrame()).bits, reference.bits);
}

TEST(VoxelizeTest, ResultsAreIdenticalForAnyThreadCountAndRasterPath) {
    // The binned path (tiles own their rows) and the direct path (atomic writes from any thread,
    // in an order that varies from run to run) must give the same bits.
    const Mesh torus = test::makeTorus({31.7, 32.2, 32.1}, 20, 8, 64, 32);
    const Frame f = unitFrame(Axis::Z, 64);
    for (VoxelizeMode mode :
         {VoxelizeMode::Surface, VoxelizeMode::Conservative, VoxelizeMode::Solid, VoxelizeMode::Interior}) {
        VoxelizeOptions o;
        o.mode = mode;
        o.threads = 1;
        o.rasterPath = RasterPath::Binned;
        const VoxelGrid one = voxelize(torus.view(), f, o);
        EXPECT_GT(one.bits.count(), 0);
        for (RasterPath path : {RasterPath::Binned, RasterPath::Direct})
            for (int threads : {1, 2, 3, 8}) {
                o.threads = threads;
                o.rasterPath = path;
                EXPECT_EQ(voxelize(torus.view(), f, o).bits, one.bits)
                    << toString(mode) << " threads " << threads << " path " << int(path);
            }
    }
    // The flood fill works on bands of rows in parallel and settles the seams between them.
    VoxelizeOptions o;
    o.fill = Fill::Flood;
    o.threads = 1;
    const VoxelGrid one = voxelize(torus.view(), f, o);
    for (int threads : {2, 3, 8}) {
        o.threads = threads;
        EXPECT_EQ(voxelize(torus.view(), f, o).bits, one.bits) << "flood, threads " << threads;
    }
}

TEST(VoxelizeTest, SurfaceIsFaithfulToEd06AndLeavesHolesOnSteepTriangles) {
    // A box seen along z: its side faces are parallel to the view and produce no fragment, so
    // the surface mode marks only the top and bottom caps (ED06's known flaw, kept on purpose).
    const Mesh box = makeBox({1.3, 1.3, 1.3}, {8.7, 8.7, 8.7});
    const VoxelGrid g = voxelize(box.view(), unitFrame(Axis::Z), {VoxelizeMode::Surface});
    EXPECT_EQ(g.bits.count(), 2 * 8 * 8);
    for (int64_t x = 1; x <= 8; ++x)
        for (int64_t y = 1; y <= 8; ++y) {
            EXPECT_TRUE(g.bits.get(x, y, 1));
            EXPECT_TRUE(g.bits.get(x, y, 8));
        }
}

TEST(VoxelizeTest, SurfaceIsContainedInConservative) {
    const Mesh torus = test::makeTorus({31.7, 32.2, 32.1}, 20, 8, 64, 32);
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        const Frame f = unitFrame(axis, 64);
        const VoxelGrid s = voxelize(torus.view(), f, {VoxelizeMode::Surface});
        const VoxelGrid c = voxelize(torus.view(), f, {VoxelizeMode::Conservative});
        int64_t outside = 0;
        for (int64_t i = 0; i < s.bits.wordCount(); ++i)
            outside += std::popcount(s.bits.words()[i] & ~c.bits.words()[i]);
        EXPECT_EQ(outside, 0) << toString(axis);
        EXPECT_GT(s.bits.count(), 1000);
    }
}

TEST(VoxelizeTest, ConservativeMatchesBruteForceBoxOverlapOnTiltedTriangle) {
    // One tilted triangle; reference: a cell overlaps it iff the triangle clipped to the cell's
    // closed box is non-empty. Computed here by dense sampling of the triangle (barycentric grid)
    // for cells that must be in, and a separating-axis test for cells that must be out.
    Mesh tri;
    tri.positions = {Vec3f{1.2f, 2.7f, 3.1f}, Vec3f{13.9f, 5.3f, 9.6f}, Vec3f{4.4f, 14.1f, 12.2f}};
    tri.indices = {0, 1, 2};
    const VoxelGrid g = voxelize(tri.view(), unitFrame(), {VoxelizeMode::Conservative});
    // Every sampled point of the triangle lies in a marked cell (no holes).
    const Vec3d a = tri.view().vertex(0), b = tri.view().vertex(1), c = tri.view().vertex(2);
    const int n = 400;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; i + j <= n; ++j) {
            const Vec3d p = a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n);
            const auto x = int64_t(p.x), y = int64_t(p.y), z = int64_t(p.z);
            ASSERT_TRUE(g.bits.get(x, y, z)) << p.x << " " << p.y << " " << p.z;
        }
    // No marked cell is farther from the triangle's plane than half its diagonal (no extras).
    const Vec3d nrm = normalize(cross(b - a, c - a));
    for (int64_t x = 0; x < 16; ++x)
        for (int64_t y = 0; y < 16; ++y)
            for (int64_t z = 0; z < 16; ++z)
                if (g.bits.get(x, y, z)) {
                    const double d = std::abs(dot(Vec3d{x + 0.5, y + 0.5, z + 0.5} - a, nrm));
                    const double reach = 0.5 * (std::abs(nrm.x) + std::abs(nrm.y) + std::abs(nrm.z));
                    EXPECT_LE(d, reach + 1e-12) << x << " " << y << " " << z;
                }
}

TEST(VoxelizeTest, FitFrameGivesResolutionCellsAlongTheLongestSide) {
    const Box3d bounds{{-1, 0, 2}, {3, 1, 2.5}};
    FitOptions o;
    o.resolution = 64;
    const Frame f = fitFrame(bounds, o);
    const VoxelGrid probe{f, {}};
    const Vec3i d = probe.worldDims();
    EXPECT_EQ(d.x, 64);
    EXPECT_EQ(d.y, 16);
    EXPECT_EQ(d.z, 8);
    EXPECT_DOUBLE_EQ(f.box().lo.x, -1);
    EXPECT_DOUBLE_EQ(f.box().hi.x, 3);
    EXPECT_NEAR(f.cellSize().y, 4.0 / 64, 1e-15);
    EXPECT_NEAR(f.box().center().y, 0.5, 1e-12);
    o.marginCells = 2;
    const VoxelGrid withMargin{fitFrame(bounds, o), {}};
    EXPECT_EQ(withMargin.worldDims().x, 68);
    EXPECT_NEAR(withMargin.frame.box().lo.x, -1 - 2 * 4.0 / 64, 1e-12);
}

TEST(VoxelizeTest, PerspectiveSolidMatchesBruteForceAtCellCentres) {
    const Mesh torus = test::makeTorus({0.1, -0.2, 0.05}, 1.0, 0.4, 32, 16);
    // A light looking at the torus from above and to the side.
    const Frame f = Frame::perspective({0.5, -3.0, 2.5}, {0, 0, 0}, {0, 0, 1}, 0.9, 32, 28, 1.5, 6.0, 64);
    const ParityCheck r = againstRayParity(torus, voxelize(torus.view(), f), Centres::Frame);
    EXPECT_EQ(r.mismatches, 0);
    EXPECT_GT(r.inside, 1000);
}

TEST(VoxelizeTest, LocalSlicingSpendsAllSlicesOnEachColumnsGeometry) {
    const Mesh torus = test::makeTorus({8.1, 7.9, 8.05}, 5.0, 2.2, 48, 24);
    VoxelizeOptions o;
    o.mode = VoxelizeMode::Surface;
    o.slicing = Slicing::Local;
    const VoxelGrid g = voxelize(torus.view(), unitFrame(Axis::Z, 32), o);
    ASSERT_EQ(g.frame.slicing(), Slicing::Local);
    int64_t columns = 0;
    for (int64_t c = 0; c < g.frame.columnCount(); ++c) {
        const uint64_t* col = g.bits.column(c);
        int64_t bits = 0;
        for (int64_t w = 0; w < g.bits.wordsPerColumn(); ++w) bits += std::popcount(col[w]);
        if (bits < 2) continue; // no geometry, or one fragment (no depth range to spread)
        ++columns;
        // The nearest fragment defines slice 0, the farthest the last slice.
        EXPECT_TRUE(col[0] & 1u) << c;
        EXPECT_TRUE((col[(g.frame.depth() - 1) >> 6] >> ((g.frame.depth() - 1) & 63)) & 1u) << c;
    }
    EXPECT_GT(columns, 100);
    // Solid with local slicing is parity at the centres of its own (local) cells: brute-force ray
    // parity at each cell's world centre under the frame's local slicing.
    o.mode = VoxelizeMode::Solid;
    const VoxelGrid local = voxelize(torus.view(), unitFrame(Axis::Z, 32), o);
    ASSERT_EQ(local.frame.slicing(), Slicing::Local);
    const ParityCheck r = againstRayParity(torus, local, Centres::Frame);
    EXPECT_EQ(r.mismatches, 0);
    EXPECT_GT(r.inside, 1000);
}

// A finely tessellated torus (triangles ~0.3 cells), the same with one triangle removed (a hole
// narrower than a cell), and CGAL's solid-conservative cells of the closed one (centres inside,
// or closed box touching it) with the cells too close to call.
struct HoleyTorus {
    Mesh closed, holey;
    test::WorldGrid solidCons, ignore;
    bool oracleClosed = false;
};

HoleyTorus holeyTorus() {
    HoleyTorus t;
    t.closed = test::makeTorus({8.1, 7.9, 8.05}, 5.0, 2.2, 96, 48);
    t.holey = t.closed;
    t.holey.indices.erase(t.holey.indices.begin() + 3 * 1000, t.holey.indices.begin() + 3 * 1001);
    const VoxelGrid probe{unitFrame(), {}};
    const test::CellGeometry g = test::CellGeometry::of(probe);
    const test::SolidOracle inside = test::oracleSolid(t.closed.view(), g);
    t.oracleClosed = inside.closed;
    const test::ConservativeOracle touching = test::oracleConservative(t.closed.view(), g, 2e-9);
    t.solidCons = inside.inside;
    t.ignore = touching.near;
    for (size_t c = 0; c < t.solidCons.cells.size(); ++c) {
        t.solidCons.cells[c] |= touching.cells.cells[c];
        t.ignore.cells[c] |= inside.leftOut.cells[c] && !touching.cells.cells[c];
    }
    return t;
}

TEST(VoxelizeTest, RobustFillsRecoverTheSolidOfAMeshWithASmallHole) {
    // The hole of holeyTorus() is narrower than a cell, so the conservative surface still seals
    // it and flood fill recovers the closed torus's solid-conservative cells; the vote outvotes
    // the one bad column per axis and recovers its solid (brute-force ray parity at the centres).
    const HoleyTorus t = holeyTorus();
    ASSERT_TRUE(t.oracleClosed);
    const Mesh &closed = t.closed, &holey = t.holey;
    const test::WorldGrid &solidCons = t.solidCons, &ignore = t.ignore;
    VoxelizeOptions o;
    o.mode = VoxelizeMode::SolidConservative;
    o.fill = Fill::Flood;
    const Mesh* const meshes[] = {&holey, &closed};
    for (const Mesh* m : meshes) {
        const test::GridDiff d =
            test::compareGrids(test::toWorldGrid(voxelize(m->view(), unitFrame(), o)), solidCons, &ignore);
        EXPECT_TRUE(d.equal()) << (m == &holey ? "holey" : "closed") << " flood: " << d;
    }
    o.mode = VoxelizeMode::Solid;
    o.fill = Fill::Vote;
    const ParityCheck r =
        againstRayParity(closed, voxelize(holey.view(), unitFrame(), o), Centres::WorldIndex);
    EXPECT_EQ(r.mismatches, 0) << "vote";
    EXPECT_GT(r.inside, 100);
}

TEST(VoxelizeTest, AutoFillIsParityForAClosedMeshAndFloodForAnOpenOneAndSaysWhy) {
    // holeyTorus(): removing one triangle leaves its three edges used once each (3 boundary
    // edges). Auto must give CGAL's solid-conservative cells of the closed torus for both (parity
    // on the closed one, flood on the holey one), and report so.
    const HoleyTorus torus = holeyTorus();
    ASSERT_TRUE(torus.oracleClosed);
    VoxelizeReport report;
    VoxelizeOptions o{.mode = VoxelizeMode::SolidConservative, .fill = Fill::Auto, .report = &report};
    test::GridDiff d = test::compareGrids(test::toWorldGrid(voxelize(torus.holey.view(), unitFrame(), o)),
                                          torus.solidCons, &torus.ignore);
    EXPECT_TRUE(d.equal()) << "holey: " << d;
    EXPECT_EQ(report.fill, Fill::Flood);
    EXPECT_TRUE(report.topologyAnalyzed);
    EXPECT_EQ(report.topology.boundaryEdges, 3u);
    EXPECT_EQ(report.fillNote.rfind(
                  "not closed (3 boundary, 0 non-manifold, 0 misoriented edges): filled by flood", 0),
              0u)
        << report.fillNote;

    d = test::compareGrids(test::toWorldGrid(voxelize(torus.closed.view(), unitFrame(), o)), torus.solidCons,
                           &torus.ignore);
    EXPECT_TRUE(d.equal()) << "closed: " << d;
    EXPECT_EQ(report.fill, Fill::Parity);
    EXPECT_TRUE(report.fillNote.empty()) << report.fillNote;

    // A surface mode needs no fill: nothing is analyzed.
    o.mode = VoxelizeMode::Surface;
    voxelize(torus.holey.view(), unitFrame(), o);
    EXPECT_EQ(report.fill, Fill::Parity);
    EXPECT_FALSE(report.topologyAnalyzed);
}

TEST(VoxelizeTest, AutoFillOfAnOpenMeshIsGwnWhereFloodCannotRun) {
    // Flood walks an axis-aligned grid; in a perspective frame (a spot light's view) or with local
    // slicing, Auto on an open mesh must pick the generalized winding number instead of a fill
    // that then fails. The cells must be those of the closed torus's parity fill but near the hole.
    const HoleyTorus torus = holeyTorus();
    const Frame persp = Frame::perspective({8, -20, 30}, {8, 8, 8}, {0, 0, 1}, 0.9, 48, 48, 15, 50, 64);
    VoxelizeReport report;
    VoxelizeOptions o{.mode = VoxelizeMode::Solid, .fill = Fill::Auto, .report = &report};
    const VoxelGrid autoGrid = voxelize(torus.holey.view(), persp, o);
    EXPECT_EQ(report.fill, Fill::Gwn);
    EXPECT_NE(report.fillNote.find("filled by gwn"), std::string::npos) << report.fillNote;
    VoxelizeOptions parity{.mode = VoxelizeMode::Solid, .fill = Fill::Parity};
    const VoxelGrid closed = voxelize(torus.closed.view(), persp, parity);
    const int64_t inside = int64_t(closed.bits.count());
    ASSERT_GT(inside, 500);
    int64_t differ = 0;
    for (int64_t y = 0; y < persp.height(); ++y)
        for (int64_t x = 0; x < persp.width(); ++x)
            for (int64_t z = 0; z < persp.depth(); ++z)
                differ += autoGrid.bits.get(x, y, z) != closed.bits.get(x, y, z);
    EXPECT_LT(differ, inside / 50) << "of " << inside;

    o.slicing = Slicing::Local;
    (void)voxelize(torus.holey.view(), unitFrame(), o);
    EXPECT_EQ(report.fill, Fill::Gwn);
    o.slicing = Slicing::Uniform;
    (void)voxelize(torus.holey.view(), unitFrame(), o);
    EXPECT_EQ(report.fill, Fill::Flood);
}

TEST(VoxelizeTest, WindingGivesTheUnionAndParityTheSymmetricDifferenceOfOverlaps) {
    Mesh overlap = makeBox({1.3, 1.3, 1.3}, {8.7, 8.7, 8.7});
    test::appendBox(overlap, {4.3, 4.3, 4.3}, {12.7, 12.7, 12.7});
    const int64_t a = 8 * 8 * 8, b = 9 * 9 * 9, both = 5 * 5 * 5; // centres 4.5..8.5 are shared
    VoxelizeOptions o;
    o.fill = Fill::Winding;
    EXPECT_EQ(voxelize(overlap.view(), unitFrame(), o).bits.count(), a + b - both);
    o.fill = Fill::Parity;
    EXPECT_EQ(voxelize(overlap.view(), unitFrame(), o).bits.count(), a + b - 2 * both);
}

TEST(VoxelizeTest, BadInputRaisesClearErrors) {
    Mesh nan = makeBox({1, 1, 1}, {2, 2, 2});
    nan.positions[3].y = std::nanf("");
    EXPECT_THROW(voxelize(nan.view(), unitFrame()), Error);
    Mesh bad = makeBox({1, 1, 1}, {2, 2, 2});
    bad.indices[5] = 99;
    EXPECT_THROW(voxelize(bad.view(), unitFrame()), Error);
    FitOptions huge;
    huge.resolution = 1 << 20;
    try {
        fitFrame({{0, 0, 0}, {1, 1, 1}}, huge);
        FAIL() << "a 2^60-cell grid must not fit";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("needs"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parseVoxelizeMode("solidd"), Error);
    FitOptions eight;
    eight.resolution = 8;
    EXPECT_THROW(fitFrame(Box3d{}, eight), Error);
}

TEST(VoxelizeTest, WideGridsUse64BitIndices) {
    // 2048 columns along x and 2048 slices: index arithmetic past 2^31 bits. Centres c + 0.5
    // inside (100.25, 1900.75) are c = 100..1900.
    const Mesh box = makeBox({100.25, 0.25, 200.25}, {1900.75, 3.75, 1800.75});
    const Frame f = Frame::orthographic({{0, 0, 0}, {2048, 4, 2048}}, Axis::Z, 2048, 4, 2048);
    EXPECT_EQ(voxelize(box.view(), f).bits.count(), int64_t(1801) * 4 * 1601);
}

} // namespace
} // namespace voxfx
