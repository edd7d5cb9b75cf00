// Tests of src/io/volume_to_mesh.cpp (OpenVDB's volumeToMesh behind the module): a sphere's analytic
// field gives a closed, outward surface (voxfx::analyzeTopology; the signed volume against the
// ball's) whose vertices lie within h^2 / (2 r) of the sphere (the bound derived in
// python/tests/test_marching_cubes.py), a mesh's level set gives a closed surface, the same mesh for
// any thread count, and bad fields are clear errors.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/level_set.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/volume_to_mesh.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

struct SphereField {
    std::vector<float> values;
    ScalarFieldView view;
    double h = 0;
};

SphereField sphereField(int64_t n, double r) {
    SphereField s;
    s.h = 2.0 / double(n - 1);
    s.values.resize(std::size_t(n * n * n));
    for (int64_t k = 0; k < n; ++k)
        for (int64_t j = 0; j < n; ++j)
            for (int64_t i = 0; i < n; ++i) {
                const Vec3d p{-1 + double(i) * s.h, -1 + double(j) * s.h, -1 + double(k) * s.h};
                s.values[std::size_t(i + n * (j + n * k))] = float(length(p) - r);
            }
    s.view.values = s.values.data();
    s.view.dims = {n, n, n};
    s.view.origin = {-1, -1, -1};
    s.view.spacing = {s.h, s.h, s.h};
    return s;
}

double signedVolume(const SurfaceMesh& m) {
    double v = 0;
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
        const Vec3d a(m.positions[m.indices[t]]), b(m.positions[m.indices[t + 1]]),
            c(m.positions[m.indices[t + 2]]);
        v += dot(a, cross(b, c)) / 6;
    }
    return v;
}

TEST(VolumeToMesh, ASpheresFieldGivesAClosedOutwardSphere) {
    const double r = 0.7;
    const SphereField s = sphereField(48, r);
    const SurfaceMesh m = volumeToMesh(s.view);
    ASSERT_GT(m.triangleCount(), 1000u);
    EXPECT_TRUE(analyzeTopology(m.view()).closed());
    const double bound = s.h * s.h / (2 * r);
    for (const Vec3f& p : m.positions) ASSERT_LT(std::abs(length(Vec3d(p)) - r), bound);
    const double ball = 4.0 / 3 * std::numbers::pi * r * r * r;
    EXPECT_NEAR(signedVolume(m), ball, 4 * std::numbers::pi * r * r * bound);
    for (std::size_t i = 0; i < m.positions.size(); ++i) ASSERT_GT(dot(m.normals[i], m.positions[i]), 0.0f);
    // Inside above: the negated field, the same surface the same way round.
    std::vector<float> negated(s.values.size());
    for (std::size_t i = 0; i < negated.size(); ++i) negated[i] = -s.values[i];
    ScalarFieldView nv = s.view;
    nv.values = negated.data();
    VolumeToMeshOptions above;
    above.insideAbove = true;
    const SurfaceMesh n = volumeToMesh(nv, above);
    EXPECT_EQ(n.indices, m.indices);
    EXPECT_GT(signedVolume(n), 0);
}

TEST(VolumeToMesh, TheMeshIsTheSameForEveryThreadCount) {
    const SphereField s = sphereField(40, 0.5);
    SurfaceMesh one, all;
    withThreads(1, [&] { one = volumeToMesh(s.view); });
    all = volumeToMesh(s.view);
    EXPECT_EQ(one.indices, all.indices);
    EXPECT_EQ(one.positions, all.positions);
}

TEST(VolumeToMesh, AMeshsLevelSetGivesAClosedSurface) {
    const Mesh torus = test::makeTorus({0.1, 0, 0}, 1.0, 0.35, 48, 24);
    FitOptions fo;
    fo.resolution = 64;
    fo.marginCells = 3;
    const SignedDistanceField field =
        signedDistanceField(torus.view(), fitFrame(computeBounds(torus.view()), fo));
    const SurfaceMesh m = volumeToMesh(LevelSet::fromField(field));
    EXPECT_TRUE(analyzeTopology(m.view()).closed());
    EXPECT_GT(signedVolume(m), 0);
    const SurfaceMesh same = volumeToMesh(field);
    EXPECT_EQ(same.indices, m.indices);
}

TEST(VolumeToMesh, BadFieldsAreClearErrors) {
    SphereField s = sphereField(8, 0.5);
    s.values[5] = std::nanf("");
    try {
        volumeToMesh(s.view);
        ADD_FAILURE() << "a NaN value passed";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("(5, 0, 0)"), std::string::npos) << e.what();
    }
    s.values[5] = 1;
    VolumeToMeshOptions o;
    o.adaptivity = 1.5;
    EXPECT_THROW(volumeToMesh(s.view, o), Error);
    ScalarFieldView bad = s.view;
    bad.spacing.y = 0;
    EXPECT_THROW(volumeToMesh(bad), Error);
    bad = s.view;
    bad.dims.z = 0;
    EXPECT_THROW(volumeToMesh(bad), Error);
    EXPECT_THROW(volumeToMesh(LevelSet()), Error);
    std::vector<float> positive(64, 1.0f);
    ScalarFieldView flat;
    flat.values = positive.data();
    flat.dims = {4, 4, 4};
    EXPECT_EQ(volumeToMesh(flat).triangleCount(), 0u);
}

} // namespace
} // namespace voxfx
