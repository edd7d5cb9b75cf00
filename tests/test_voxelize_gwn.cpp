// Fill::Gwn (generalized winding number >= 0.5 at cell centres): the same solid as parity on
// closed meshes away from the surface, and the closed solid back where a hole wider than a cell
// lets the flood in. Oracles: the parity fill (itself checked against CGAL in
// test_voxelize_oracle.cpp) of the closed mesh, and the conservative surface for "away from".
#include <bit>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

Frame gwnTestFrame(const Mesh& mesh, int64_t resolution) {
    FitOptions fo;
    fo.resolution = resolution;
    fo.marginCells = 2;
    return fitFrame(computeBounds(mesh.view()), fo);
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

TEST(VoxelizeGwnTest, GwnRecoversTheSolidThroughAHoleWiderThanACellWhereTheFloodLeaks) {
    // A UV sphere 32 cells across without its top cap (the triangles above z = 0.9 r): the hole's
    // rim is 0.38 r across, about 12 cells. Parity of the closed sphere is the reference.
    const Mesh closed = test::makeUvSphere({0.3, -0.1, 0.2}, 1.0, 16, 24);
    Mesh open;
    open.positions = closed.positions;
    for (std::size_t t = 0; t < closed.indices.size() / 3; ++t) {
        bool cap = true;
        for (int k = 0; k < 3; ++k)
            cap &= closed.positions[closed.indices[3 * t + std::size_t(k)]].z > 0.2f + 0.9f;
        if (!cap)
            for (int k = 0; k < 3; ++k) open.indices.push_back(closed.indices[3 * t + std::size_t(k)]);
    }
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

} // namespace
} // namespace voxfx
