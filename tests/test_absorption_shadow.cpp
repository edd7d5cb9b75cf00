// Tests of the absorption shadow map's lookups (CHANG §3: voxfx/absorption_shadow.hpp) against the
// optical depth summed write by write from each group's own attribute voxelization: several grids
// (coloured foliage: a grid per colour) read as one, with and without the receiver's plane.
// Against exact light transport and the other techniques: test_light_grid.cpp,
// test_shadow_cross_technique.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/shadow_reference.hpp"
#include "voxfx/absorption_shadow.hpp"
#include "voxfx/attribute_grid.hpp"
#include "voxfx/light_view.hpp"

namespace voxfx {
namespace {

// exp(-optical depth) of column `column` in front of `depth`, less p's `skip` cells: over the
// groups, depthPerUnit times the absorption of every entry of the group's voxelization whose slice
// lies in front, summed in double.
Vec3f columnByDefinition(const std::vector<AttributeColumns>& columns,
                         const std::vector<AbsorptionShadowMap::Group>& groups, int64_t column, double depth,
                         int64_t skip) {
    double optical[3] = {0, 0, 0};
    for (std::size_t g = 0; g < groups.size(); ++g) {
        const AttributeColumns& c = columns[g];
        const int64_t D = c.frame.depth();
        const double z = c.frame.depthToSlice(column)(depth);
        const int64_t end =
            z >= 0 ? std::clamp<int64_t>((z >= double(D) ? D : int64_t(z)) - skip + 1, 0, D) : 0;
        double sum = 0;
        for (int64_t i = c.offsets[size_t(column)]; i < c.offsets[size_t(column) + 1]; ++i)
            if (int64_t(c.slice[size_t(i)]) < end) sum += double(c.absorption[size_t(i)]);
        for (int k = 0; k < 3; ++k) optical[k] += double(groups[g].depthPerUnit[k]) * sum;
    }
    return {float(std::exp(-optical[0])), float(std::exp(-optical[1])), float(std::exp(-optical[2]))};
}

// Three groups of foliage (600 leaves), each its own colour and depth per unit, and the sun's 64 x
// 48 view of them.
struct ColouredLeafGroups {
    Scene scene = test::leafScene(600, 3, 11);
    std::vector<std::vector<float>> absorption;
    std::vector<AbsorptionShadowMap::Group> groups;
    LightView view;
    ColouredLeafGroups() {
        Box3d bounds;
        for (std::size_t g = 1; g <= 3; ++g) {
            absorption.emplace_back(scene.meshes[g].mesh.triangleCount(), 0.2f + 0.15f * float(g));
            bounds.extend(computeBounds(scene.meshes[g].mesh.view()));
        }
        for (std::size_t g = 1; g <= 3; ++g)
            groups.push_back({scene.meshes[g].mesh.view(), absorption[g - 1],
                              Vec3f{0.3f * float(g), 1.0f, 1.6f - 0.4f * float(g)}, Vec3f{0, 0, 0}});
        view = makeLightViews(test::sun(), bounds, 64, 48)[0];
    }
};

TEST(ShadowTest, AbsorptionOfColouredGridsIsExpOfEveryGridsWritesInFront) {
    // Three colour groups of foliage, each its own grid with its own RGB depth per unit, centre and
    // conservative writes, uniform slicing (the grids share a frame and are read as one) and local
    // (each grid fits its own): at random points the lookup must be exp(-the summed depth of every
    // write in front of p's skipped cells), and the bilinear lookup with no normal the weighted sum
    // of that over the four columns around p.
    const ColouredLeafGroups leaves;
    const std::vector<AbsorptionShadowMap::Group>& groups = leaves.groups;
    const std::vector<std::vector<float>>& absorption = leaves.absorption;
    const LightView& view = leaves.view;
    const int64_t W = view.frame.width(), H = view.frame.height();
    for (const Coverage coverage : {Coverage::Center, Coverage::Conservative})
        for (const Slicing slicing : {Slicing::Uniform, Slicing::Local}) {
            const std::string what = std::string(toString(coverage)) + " " + toString(slicing);
            const AbsorptionShadowMap map = AbsorptionShadowMap::build(view, groups, coverage, slicing);
            AttributeOptions ao;
            ao.coverage = coverage;
            ao.channels = AttributeChannels::shadows();
            ao.slicing = slicing;
            std::vector<AttributeColumns> columns;
            for (std::size_t g = 0; g < groups.size(); ++g)
                columns.push_back(voxelizeAttributeColumns(groups[g].mesh, view.frame, absorption[g], ao));
            int shaded = 0;
            test::forEachCoveredPoint(view, [&](int i, const Vec3d& p, const Vec3d& g, int64_t column,
                                                int64_t skip) {
                const Vec3f want = columnByDefinition(columns, groups, column, g.z, skip);
                const Vec3f blend = test::bilinearByDefinition(
                    W, H, g, [&](int64_t c) { return columnByDefinition(columns, groups, c, g.z, skip); });
                const Vec3f got = map.transmittance(p, skip), gotBlend = map.transmittanceBilinear(p, skip);
                for (int c = 0; c < 3; ++c) {
                    ASSERT_NEAR(got[c], want[c], 1e-5f) << what << " point " << i;
                    ASSERT_NEAR(gotBlend[c], blend[c], 1e-5f) << what << " point " << i;
                }
                shaded += want.x < 0.99f;
            });
            EXPECT_GT(shaded, 500) << what;
        }
}

TEST(ShadowTest, TheSunsAbsorptionLookupWithANormalReadsEachColumnWhereTheReceiverPlaneCrossesIt) {
    // As the transmittance test of the same name: the sun's bilinear lookups with a normal (the fast
    // path for an oriented orthographic view with uniform slices) against the blend, by definition,
    // of the four columns around p, each at the depth where the plane through p with normal n
    // crosses the column's centre line (solved in world space, within two column footprints of p's
    // depth); points with a crossing within 1e-9 slices of a slice boundary left out (few).
    const ColouredLeafGroups leaves;
    const std::vector<AbsorptionShadowMap::Group>& groups = leaves.groups;
    const std::vector<std::vector<float>>& absorption = leaves.absorption;
    const LightView& view = leaves.view;
    ASSERT_TRUE(view.frame.isOriented());
    const Frame& f = view.frame;
    const int64_t W = f.width(), H = f.height();
    std::mt19937_64 rng(17);
    for (const Coverage coverage : {Coverage::Center, Coverage::Conservative}) {
        const AbsorptionShadowMap map = AbsorptionShadowMap::build(view, groups, coverage, Slicing::Uniform);
        AttributeOptions ao;
        ao.coverage = coverage;
        ao.channels = AttributeChannels::shadows();
        ao.slicing = Slicing::Uniform;
        std::vector<AttributeColumns> columns;
        for (std::size_t g = 0; g < groups.size(); ++g)
            columns.push_back(voxelizeAttributeColumns(groups[g].mesh, view.frame, absorption[g], ao));
        int compared = 0, shaded = 0, onBoundary = 0, tilted = 0;
        test::forEachCoveredPoint(view, [&](int i, const Vec3d& p, const Vec3d& g, int64_t, int64_t skip) {
            const Vec3d n = test::randomReceiverNormal(rng, f, i);
            bool boundary = false;
            const Vec3f want = test::bilinearByDefinition(W, H, g, [&](int64_t c) {
                return columnByDefinition(columns, groups, c,
                                          test::receiverPlaneDepth(f, p, g, n, c, boundary, tilted), skip);
            });
            if (boundary) {
                ++onBoundary;
                return;
            }
            const Vec3f got = map.transmittanceBilinear(p, skip, n);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(got[c], want[c], 1e-5f) << toString(coverage) << " point " << i;
            ++compared;
            shaded += want.x < 0.99f;
        });
        std::printf(
            "%s: %d lookups with a normal compared (%d shadowed, %d columns read more than half a slice "
            "off p's depth), %d left out on a slice boundary\n",
            toString(coverage), compared, shaded, tilted, onBoundary);
        EXPECT_GT(shaded, 500) << toString(coverage);
        EXPECT_GT(tilted, 1000) << toString(coverage);
        EXPECT_LT(onBoundary, compared / 100) << toString(coverage);
    }
}

} // namespace
} // namespace voxfx
