// Fill::Gwn (generalized winding number |w| >= 0.5 at cell centres): the same solid as parity on
// closed meshes away from the surface, oriented outward or inward, and the closed solid back
// where a hole wider than a cell lets the flood in. Oracles: the parity fill (itself checked against CGAL in
// test_voxelize_oracle.cpp) of the closed mesh, the conservative surface for "away from", and
// the exact winding number summed over every triangle (voxfx::windingNumber).
#include <bit>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

Frame gwnTestFrame(const Mesh& mesh, int64_t resolution) {
    FitOptions fo;
    fo.resolution = resolution;
    fo.marginCells = 2;
    return fitFrame(computeBounds(mesh.view()), fo);
}

// The mesh without its triangles whose three corners lie above height z: a cap cut off, a hole.
Mesh gwnTestWithoutCap(const Mesh& closed, float z) {
    Mesh open;
    open.positions = closed.positions;
    for (std::size_t t = 0; t < closed.indices.size() / 3; ++t) {
        bool cap = true;
        for (int k = 0; k < 3; ++k) cap &= closed.positions[closed.indices[3 * t + std::size_t(k)]].z > z;
        if (!cap)
            for (int k = 0; k < 3; ++k) open.indices.push_back(closed.indices[3 * t + std::size_t(k)]);
    }
    return open;
}

VoxelGrid gwnTestRun(const Mesh& mesh, const Frame& frame, VoxelizeMode mode, Fill fill, int threads = 0) {
    VoxelizeOptions o;
    o.mode = mode;
    o.fill = fill;
    o.threads = threads;
    return voxelize(mesh.view(), frame, o);
}

TEST(VoxelizeGwnTest, OnAClosedMeshGwnEqualsParityAwayFromTheSurface) {
    EXPECT_EQ(parseFill("gwn"), Fill::Gwn);
    EXPECT_STREQ(toString(Fill::Gwn), "gwn");
    // A torus (a hole through it, concave all around the ring) and an octahedron (faces oblique
    // to every axis).
    const Mesh meshes[] = {test::makeTorus({0.1, -0.2, 0.05}, 3, 1.1, 24, 12),
                           test::makeOctahedron({0.3, 0.2, -0.1}, 2.0)};
    for (const Mesh& mesh : meshes) {
        const Frame frame = gwnTestFrame(mesh, 28);
        const VoxelGrid parity = gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Parity);
        const VoxelGrid gwn = gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Gwn, 1);
        const VoxelGrid surface = gwnTestRun(mesh, frame, VoxelizeMode::Conservative, Fill::Parity);
        int64_t compared = 0, differ = 0, insideCount = 0;
        for (int64_t y = 0; y < frame.height(); ++y)
            for (int64_t x = 0; x < frame.width(); ++x)
                for (int64_t z = 0; z < frame.depth(); ++z) {
                    if (surface.bits.get(x, y, z)) continue;
                    ++compared;
                    insideCount += parity.bits.get(x, y, z);
                    differ += parity.bits.get(x, y, z) != gwn.bits.get(x, y, z);
                }
        EXPECT_GT(insideCount, 500);
        EXPECT_GT(compared, insideCount);
        EXPECT_EQ(differ, 0);
        EXPECT_TRUE(test::paddingIsZero(gwn.bits));
        // The same cells for every thread count, and solid-conservative = solid | surface.
        EXPECT_EQ(gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Gwn, 3).bits, gwn.bits);
        BitGrid expected = gwn.bits;
        for (int64_t i = 0; i < expected.wordCount(); ++i) expected.words()[i] |= surface.bits.words()[i];
        EXPECT_EQ(gwnTestRun(mesh, frame, VoxelizeMode::SolidConservative, Fill::Gwn).bits, expected);
    }
}

// CGAL's beam, tetrahedron and ellipe0.003 are oriented inward throughout, as is a flipped bunny
// and a flipped torus: w = -1 inside, and the fill must still be parity's (which ignores
// orientation) away from the surface. Before |w| it was empty.
TEST(VoxelizeGwnTest, OnMeshesOrientedInwardGwnEqualsParityAwayFromTheSurface) {
    std::vector<std::pair<std::string, Mesh>> meshes;
    for (const char* name :
         {"meshes/beam.off", "meshes/tetrahedron.off", "meshes/ellipe0.003.off", "meshes/bunny00.off"}) {
        VOXFX_REQUIRE_DATA(name);
        meshes.emplace_back(name, loadMesh(test::dataPath(name)));
    }
    meshes.emplace_back("torus", test::makeTorus({0.1, -0.2, 0.05}, 3, 1.1, 24, 12));
    for (auto& [name, mesh] : meshes) {
        if (test::meshVolume(mesh.view()) > 0) mesh = test::flippedMesh(mesh);
        ASSERT_LT(test::meshVolume(mesh.view()), 0) << name;
        const Frame frame = gwnTestFrame(mesh, 32);
        const VoxelGrid parity = gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Parity);
        const VoxelGrid gwn = gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Gwn);
        const VoxelGrid surface = gwnTestRun(mesh, frame, VoxelizeMode::Conservative, Fill::Parity);
        int64_t insideCount = 0, differ = 0;
        for (int64_t y = 0; y < frame.height(); ++y)
            for (int64_t x = 0; x < frame.width(); ++x)
                for (int64_t z = 0; z < frame.depth(); ++z) {
                    if (surface.bits.get(x, y, z)) continue;
                    insideCount += parity.bits.get(x, y, z);
                    differ += parity.bits.get(x, y, z) != gwn.bits.get(x, y, z);
                }
        EXPECT_GT(insideCount, 100) << name;
        EXPECT_EQ(differ, 0) << name;
        // The winding fill (nonzero crossing count) agrees on every cell, as on outward meshes.
        EXPECT_EQ(gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Winding).bits, gwn.bits) << name;
    }
}

TEST(VoxelizeGwnTest, GwnRecoversTheSolidThroughAHoleWiderThanACellWhereTheFloodLeaks) {
    // A UV sphere 32 cells across without its top cap (the triangles above z = 0.9 r): the hole's
    // rim is 0.38 r across, about 12 cells. Parity of the closed sphere is the reference.
    const Mesh closed = test::makeUvSphere({0.3, -0.1, 0.2}, 1.0, 16, 24);
    const Mesh open = gwnTestWithoutCap(closed, 0.2f + 0.9f);
    ASSERT_LT(open.indices.size(), closed.indices.size());
    const Frame frame = gwnTestFrame(closed, 32);
    const VoxelGrid reference = gwnTestRun(closed, frame, VoxelizeMode::Solid, Fill::Parity);
    const VoxelGrid gwn = gwnTestRun(open, frame, VoxelizeMode::Solid, Fill::Gwn);
    const VoxelGrid flood = gwnTestRun(open, frame, VoxelizeMode::Solid, Fill::Flood);
    const int64_t solid = reference.bits.count();
    ASSERT_GT(solid, 10000);
    int64_t gwnDiffer = 0;
    for (int64_t i = 0; i < reference.bits.wordCount(); ++i)
        gwnDiffer += std::popcount(reference.bits.words()[i] ^ gwn.bits.words()[i]);
    // The level set 0.5 spans the hole a little below the missing cap (its volume is 0.4 % of
    // the sphere's): at most 2 % of the solid's cells differ.
    EXPECT_LT(double(gwnDiffer), 0.02 * double(solid)) << gwnDiffer << " of " << solid;
    // The flood comes in through the hole: what is left is about the surface shell.
    EXPECT_LT(double(flood.bits.count()), 0.5 * double(solid)) << flood.bits.count() << " of " << solid;
}

// Inside surface blocks Fill::Gwn counts the columns' crossings (the winding number jumps by
// exactly one across a triangle) and evaluates only where that cannot decide: on a closed mesh
// that is nowhere, so every cell, on the surface too, is the winding fill's.
TEST(VoxelizeGwnTest, OnAClosedMeshGwnEqualsTheWindingFillOnEveryCell) {
    const Mesh meshes[] = {test::makeTorus({0.1, -0.2, 0.05}, 3, 1.1, 24, 12),
                           test::makeOctahedron({0.3, 0.2, -0.1}, 2.0)};
    for (const Mesh& mesh : meshes)
        for (const Axis axis : {Axis::X, Axis::Z}) {
            FitOptions fo;
            fo.resolution = 24;
            fo.marginCells = 2;
            fo.axis = axis;
            const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
            const VoxelGrid winding = gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Winding);
            ASSERT_GT(winding.bits.count(), 500);
            EXPECT_EQ(gwnTestRun(mesh, frame, VoxelizeMode::Solid, Fill::Gwn).bits, winding.bits);
        }
}

// Where the surface is open the count changes also behind (or in front of) the boundary edges,
// and near them the winding number turns fast: there the fill must evaluate. A sphere with a
// wide hole, sliced along each axis (the hole faces the slices, or lies along the columns),
// against the exact winding number at every centre not within 0.1 of the threshold (the fast
// evaluator's approximation is far smaller than that).
TEST(VoxelizeGwnTest, OnAnOpenMeshGwnFollowsTheExactWindingNumberAlongEveryAxis) {
    const Mesh closed = test::makeUvSphere({0.3, -0.1, 0.2}, 1.0, 6, 10);
    const Mesh open = gwnTestWithoutCap(closed, 0.2f + 0.4f);
    ASSERT_LT(open.indices.size(), closed.indices.size());
    for (const Axis axis : {Axis::X, Axis::Y, Axis::Z}) {
        FitOptions fo;
        fo.resolution = 14;
        fo.marginCells = 2;
        fo.axis = axis;
        const Frame frame = fitFrame(computeBounds(open.view()), fo);
        const VoxelGrid gwn = gwnTestRun(open, frame, VoxelizeMode::Solid, Fill::Gwn, 1);
        EXPECT_EQ(gwnTestRun(open, frame, VoxelizeMode::Solid, Fill::Gwn, 2).bits, gwn.bits);
        int64_t compared = 0, inside = 0, differ = 0;
        for (int64_t y = 0; y < frame.height(); ++y)
            for (int64_t x = 0; x < frame.width(); ++x)
                for (int64_t z = 0; z < frame.depth(); ++z) {
                    const double w = std::abs(windingNumber(open.view(), frame.cellCenter(x, y, z)));
                    if (std::abs(w - 0.5) < 0.1) continue;
                    ++compared;
                    inside += w >= 0.5;
                    differ += gwn.bits.get(x, y, z) != (w >= 0.5);
                }
        EXPECT_GT(inside, 300) << toString(axis);
        EXPECT_GT(compared, 2 * inside) << toString(axis);
        EXPECT_EQ(differ, 0) << toString(axis);
    }
}

// A lone square sheet in the middle of one 16-cell block: the winding number stays within
// (-0.5, 0.5) everywhere, but the columns through the sheet count one crossing more behind it
// (or, counted from the far end, in front of it) while the block's corners see none. Only the
// curtains of the sheet's boundary edges keep those cells from being taken as inside; both
// orientations, since the count from the far end serves the other one.
TEST(VoxelizeGwnTest, AnOpenSheetInsideOneBlockFillsNothing) {
    for (const bool flip : {false, true}) {
        Mesh sheet;
        for (const Vec3f p : {Vec3f{-0.4f, -0.4f, 0.05f}, Vec3f{0.4f, -0.4f, 0.05f}, Vec3f{0.4f, 0.4f, 0.05f},
                              Vec3f{-0.4f, 0.4f, 0.05f}})
            sheet.positions.push_back(p);
        sheet.indices =
            flip ? std::vector<uint32_t>{0, 2, 1, 0, 3, 2} : std::vector<uint32_t>{0, 1, 2, 0, 2, 3};
        FitOptions fo;
        fo.bounds.lo = {-1, -1, -1};
        fo.bounds.hi = {1, 1, 1};
        fo.dims = {16, 16, 16};
        const Frame frame = fitFrame(computeBounds(sheet.view()), fo);
        const VoxelGrid gwn = gwnTestRun(sheet, frame, VoxelizeMode::Solid, Fill::Gwn);
        int64_t compared = 0, differ = 0;
        for (int64_t y = 0; y < frame.height(); ++y)
            for (int64_t x = 0; x < frame.width(); ++x)
                for (int64_t z = 0; z < frame.depth(); ++z) {
                    const double w = std::abs(windingNumber(sheet.view(), frame.cellCenter(x, y, z)));
                    if (std::abs(w - 0.5) < 0.1) continue;
                    ++compared;
                    differ += gwn.bits.get(x, y, z) != (w >= 0.5);
                }
        EXPECT_GT(compared, 3500) << flip;
        EXPECT_EQ(differ, 0) << flip;
        EXPECT_EQ(gwn.bits.count(), 0) << flip;
    }
}

} // namespace
} // namespace voxfx
