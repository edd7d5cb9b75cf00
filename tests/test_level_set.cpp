// voxfx — operations on level sets (voxfx/level_set.hpp) and the commands over them (`voxfx csg`
// of level-set .vdb files and meshes, `voxfx sdf --offset`, `voxfx morph --offset`).
//
// Oracles: closed forms. Boxes have an analytic signed distance (the distance to a box's surface,
// which is also the distance to its triangles), so the CSG of two boxes' fields is compared, at
// every voxel, with min / max / max(a, -b) of the analytic distances, each clamped to the band
// as a level set holds it, and its sign with the analytic inside test of the combined solid; the
// offset cube with the rounded box's distance (grown) and the smaller box's (shrunk); OpenVDB's
// approximate offset of a sphere with the sphere of the offset radius. A mesh on a level set's
// lattice (levelSetOfMesh) is checked the same way with boxes (at indices beyond the lattice's own
// grid too), and on real meshes against CGAL's distances and inside tests at sampled voxels.
// Files are read back with plain OpenVDB (class, background, voxel size, transform).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/level_set.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/sdf_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace level_set_test {

// An axis-aligned box with float corners (the mesh's own coordinates).
struct AnalyticBox {
    Vec3d lo, hi;
    // Signed distance to the box's surface: negative inside.
    double distance(const Vec3d& p) const {
        double q[3], outside = 0, inside = -1e300;
        for (int a = 0; a < 3; ++a) {
            const double c = 0.5 * (lo[a] + hi[a]), h = 0.5 * (hi[a] - lo[a]);
            q[a] = std::abs(p[a] - c) - h;
            outside += std::max(q[a], 0.0) * std::max(q[a], 0.0);
            inside = std::max(inside, q[a]);
        }
        return std::sqrt(outside) + std::min(inside, 0.0);
    }
    bool inside(const Vec3d& p) const {
        return p.x > lo.x && p.x < hi.x && p.y > lo.y && p.y < hi.y && p.z > lo.z && p.z < hi.z;
    }
    Mesh mesh() const { return test::makeBox(lo, hi); }
};

AnalyticBox box(const Vec3d& lo, const Vec3d& hi) {
    // Corners chosen as multiples of 1/32: exact in float, and never on a voxel centre below.
    return {{double(float(lo.x)), double(float(lo.y)), double(float(lo.z))},
            {double(float(hi.x)), double(float(hi.y)), double(float(hi.z))}};
}

// The value a level set of half-width w holds for distance d.
double clampBand(double d, double w) { return std::abs(d) < w ? d : std::copysign(w, d); }

// [-2, 2]^3 in 40^3 cells of 0.1: centres at -1.95 + 0.1 i, never on a box face below.
Frame cubeFrame(double half, int64_t n, const Vec3d& shift = {0, 0, 0}) {
    const Box3d b{Vec3d{-half, -half, -half} + shift, Vec3d{half, half, half} + shift};
    return Frame::orthographic(b, Axis::Z, n, n, n);
}

Vec3d centreOf(const Frame& f, int64_t i, int64_t j, int64_t k) {
    const Vec3d c = f.cellSize();
    return f.box().lo + Vec3d{(double(i) + 0.5) * c.x, (double(j) + 0.5) * c.y, (double(k) + 0.5) * c.z};
}

const AnalyticBox kBoxA = box({-1.03125, -0.8125, -0.6875}, {0.71875, 0.65625, 0.875});
const AnalyticBox kBoxB = box({-0.21875, -0.53125, -1.09375}, {1.3125, 1.15625, 0.40625});

double combine(CsgOp op, double a, double b) {
    switch (op) {
    case CsgOp::Union:
        return std::min(a, b);
    case CsgOp::Intersection:
        return std::max(a, b);
    case CsgOp::Difference:
        return std::max(a, -b);
    case CsgOp::Xor:
        return std::max(std::min(a, b), -std::max(a, b));
    }
    return 0;
}

std::string writeOff(const test::TempDir& dir, const Mesh& m, const std::string& name) {
    std::string s =
        "OFF\n" + std::to_string(m.positions.size()) + " " + std::to_string(m.triangleCount()) + " 0\n";
    for (const Vec3f& p : m.positions) s += detail::concat(p.x, " ", p.y, " ", p.z, "\n");
    for (size_t t = 0; t < m.triangleCount(); ++t)
        s += detail::concat("3 ", m.indices[3 * t], " ", m.indices[3 * t + 1], " ", m.indices[3 * t + 2],
                            "\n");
    return test::writeFile(dir.file(name), s);
}

openvdb::FloatGrid::Ptr readByOpenVdb(const std::string& path) {
    openvdb::initialize();
    openvdb::io::File f(path);
    f.open();
    const openvdb::GridPtrVecPtr grids = f.getGrids();
    f.close();
    EXPECT_FALSE(grids->empty());
    return openvdb::GridBase::grid<openvdb::FloatGrid>(grids->front());
}

} // namespace level_set_test

namespace {
using namespace level_set_test;

TEST(LevelSetCsg, ValuesAreMinMaxOfTheBoxesDistancesAndSignsTheCombinedSolids) {
    const Frame frame = cubeFrame(2, 40);
    const LevelSet a = LevelSet::fromField(signedDistanceField(kBoxA.mesh().view(), frame));
    const LevelSet b = LevelSet::fromField(signedDistanceField(kBoxB.mesh().view(), frame));
    const double w = 3 * 0.1;
    ASSERT_NEAR(a.background(), w, 1e-6);
    for (CsgOp op : {CsgOp::Union, CsgOp::Intersection, CsgOp::Difference, CsgOp::Xor}) {
        bool resampled = true;
        const LevelSet r = levelSetCsg(a, b, op, &resampled);
        EXPECT_FALSE(resampled) << toString(op);
        EXPECT_NEAR(r.background(), w, 1e-6);
        int64_t checked = 0, wrongValue = 0, wrongSign = 0, inside = 0;
        for (int64_t k = 0; k < 40; ++k)
            for (int64_t j = 0; j < 40; ++j)
                for (int64_t i = 0; i < 40; ++i) {
                    const Vec3d p = centreOf(frame, i, j, k);
                    const double da = kBoxA.distance(p), db = kBoxB.distance(p);
                    const float v = r.value(i, j, k);
                    const bool in = test::csgInside(op, kBoxA.inside(p), kBoxB.inside(p));
                    inside += in;
                    wrongSign += (v < 0) != in;
                    // The band's edge decides active or not within a float ulp: skip it there.
                    if (std::abs(std::abs(da) - w) < 1e-5 || std::abs(std::abs(db) - w) < 1e-5) continue;
                    ++checked;
                    const double expected = combine(op, clampBand(da, w), clampBand(db, w));
                    if (std::abs(double(v) - expected) > 2e-6) {
                        if (wrongValue++ < 5)
                            ADD_FAILURE() << toString(op) << " voxel (" << i << ", " << j << ", " << k
                                          << "): " << v << ", expected " << expected;
                    }
                }
        EXPECT_EQ(wrongValue, 0) << toString(op);
        EXPECT_EQ(wrongSign, 0) << toString(op);
        EXPECT_GT(checked, 60000) << toString(op);
        EXPECT_GT(inside, 100) << toString(op); // the solids are not empty
    }
}

TEST(LevelSetCsg, WrittenFileIsALevelSetWithTheBandAndVoxelSize) {
    test::TempDir dir;
    const Frame frame = cubeFrame(2, 40);
    const LevelSet a = LevelSet::fromField(signedDistanceField(kBoxA.mesh().view(), frame));
    const LevelSet b = LevelSet::fromField(signedDistanceField(kBoxB.mesh().view(), frame));
    const LevelSet u = levelSetCsg(a, b, CsgOp::Union);
    const std::string path = dir.file("u.vdb");
    writeLevelSet(u, path);
    const openvdb::FloatGrid::Ptr g = readByOpenVdb(path);
    ASSERT_TRUE(g);
    EXPECT_EQ(g->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_NEAR(g->background(), 0.3, 1e-6);
    EXPECT_NEAR(g->voxelSize()[0], 0.1, 1e-12);
    // Index (i, j, k) is the centre of voxel (i, j, k).
    const openvdb::Vec3d c = g->indexToWorld(openvdb::Vec3d(3, 4, 5));
    const Vec3d expected = centreOf(frame, 3, 4, 5);
    EXPECT_NEAR(c.x(), expected.x, 1e-12);
    EXPECT_NEAR(c.z(), expected.z, 1e-12);
    // Read back by voxfx: the same values.
    const LevelSet back = readLevelSet(path);
    std::vector<std::array<int32_t, 3>> idx;
    std::vector<float> values;
    u.activeVoxels(idx, values);
    ASSERT_GT(values.size(), 1000u);
    EXPECT_EQ(back.activeCount(), int64_t(values.size()));
    for (size_t n = 0; n < values.size(); n += 7)
        ASSERT_EQ(back.value(idx[n][0], idx[n][1], idx[n][2]), values[n]);
}

TEST(LevelSetCsg, CopiesKeepTheTransformSoLatticesFarFromTheOriginCombineWithoutResampling) {
    // OpenVDB's Grid::deepCopy rebuilds the transform's map (simplify), which moved the voxel size
    // of a lattice 2000 units away by 1e-12 relative and made it non-uniform: the copy that CSG
    // works on no longer equalled the other operand's transform, and identical lattices were
    // resampled.
    const Vec3d far{1000.3, -2000.1, 500.7};
    const Frame frame = cubeFrame(2, 40, far);
    Mesh ma = kBoxA.mesh(), mb = kBoxB.mesh();
    for (Mesh* m : {&ma, &mb})
        for (Vec3f& p : m->positions) p = Vec3f(Vec3d(p) + far);
    const LevelSet a = LevelSet::fromField(signedDistanceField(ma.view(), frame));
    const LevelSet b = LevelSet::fromField(signedDistanceField(mb.view(), frame));
    const LevelSet copy = a;
    EXPECT_EQ(copy.voxelSize().x, a.voxelSize().x);
    EXPECT_EQ(copy.voxelSize().z, a.voxelSize().z);
    EXPECT_EQ(copy.indexOrigin().y, a.indexOrigin().y);
    bool resampled = true;
    const LevelSet u = levelSetCsg(a, b, CsgOp::Union, &resampled);
    EXPECT_FALSE(resampled);
    EXPECT_EQ(u.voxelSize().y, a.voxelSize().y);
    resampled = true;
    levelSetCsg(copy, b, CsgOp::Difference, &resampled);
    EXPECT_FALSE(resampled);
    // A copy's offset still sees cubic voxels.
    EXPECT_NO_THROW(offsetLevelSet(copy, 0.05));
}

TEST(LevelSetCsg, OperandOnAnotherLatticeIsResampledWithinAVoxel) {
    const Frame frame = cubeFrame(2, 40);
    const Frame shifted = cubeFrame(2, 40, {0.037, -0.021, 0.05});
    const LevelSet a = LevelSet::fromField(signedDistanceField(kBoxA.mesh().view(), frame));
    const LevelSet b = LevelSet::fromField(signedDistanceField(kBoxB.mesh().view(), shifted));
    bool resampled = false;
    const LevelSet r = levelSetCsg(a, b, CsgOp::Union, &resampled);
    EXPECT_TRUE(resampled);
    const double w = 0.3, h = 0.1;
    double maxError = 0;
    int64_t wrongSign = 0, checked = 0;
    for (int64_t k = 0; k < 40; ++k)
        for (int64_t j = 0; j < 40; ++j)
            for (int64_t i = 0; i < 40; ++i) {
                const Vec3d p = centreOf(frame, i, j, k);
                const double expected = std::min(kBoxA.distance(p), kBoxB.distance(p));
                if (std::abs(expected) > w - h) continue; // well inside the band
                ++checked;
                const float v = r.value(i, j, k);
                maxError = std::max(maxError, std::abs(double(v) - expected));
                if (std::abs(expected) > h) wrongSign += (v < 0) != (expected < 0);
            }
    EXPECT_GT(checked, 5000);
    EXPECT_EQ(wrongSign, 0);
    // A level-set rebuild: the resampled box's edges and corners are rounded by up to about a voxel
    // (0.87 voxel measured here).
    EXPECT_LT(maxError, h) << "max error " << maxError;
}

// A box overlapping kBoxA and partly outside the lattice's frame (x > 2, y < -2: negative indices
// and indices past the frame's 40), corners multiples of 1/32 that no centre of the lattices below
// meets.
const AnalyticBox kBoxOut = box({0.40625, -2.59375, -0.28125}, {2.71875, 0.40625, 1.09375});

TEST(LevelSetOfMesh, CsgWithABoxIsMinMaxOfTheAnalyticDistancesWithoutResampling) {
    // The lattice: a level set on a frame whose centres are not multiples of anything simple.
    const Frame frame = cubeFrame(2, 40, {0.037, -0.021, 0.05});
    const LevelSet a = LevelSet::fromField(signedDistanceField(kBoxA.mesh().view(), frame), "a");
    const LevelSet b = levelSetOfMesh(kBoxOut.mesh().view(), a);
    const double w = 0.3;
    EXPECT_EQ(b.background(), a.background());
    EXPECT_EQ(b.name(), "a");
    EXPECT_TRUE(b.axisAligned());
    EXPECT_EQ(b.indexOrigin().x, a.indexOrigin().x);
    EXPECT_EQ(b.voxelSize().z, a.voxelSize().z);

    // The mesh's level set alone: active exactly where the box's distance is below the band.
    std::vector<std::array<int32_t, 3>> idx;
    std::vector<float> vals;
    b.activeVoxels(idx, vals);
    Vec3i lo, hi;
    b.activeBounds(lo, hi);
    EXPECT_LT(lo.y, 0);  // the band below y = -2 lies at negative indices
    EXPECT_GT(hi.x, 40); // and past the frame along x
    int64_t wrongActive = 0;
    for (std::size_t n = 0; n < idx.size(); ++n) {
        const double d = kBoxOut.distance(centreOf(frame, idx[n][0], idx[n][1], idx[n][2]));
        wrongActive += !(std::abs(d) < w + 1e-6) || std::abs(double(vals[n]) - d) > 2e-6;
    }
    EXPECT_EQ(wrongActive, 0);
    EXPECT_GT(idx.size(), 10000u);

    // Every index of a box around both solids and their bands, each operand first.
    std::vector<std::array<int32_t, 3>> all;
    for (int32_t k = -6; k < 46; ++k)
        for (int32_t j = -12; j < 46; ++j)
            for (int32_t i = -6; i < 56; ++i) all.push_back({i, j, k});
    std::vector<float> got(all.size());
    for (CsgOp op : {CsgOp::Union, CsgOp::Intersection, CsgOp::Difference, CsgOp::Xor})
        for (bool meshFirst : {false, true}) {
            bool resampled = true;
            const LevelSet r =
                meshFirst ? levelSetCsg(b, a, op, &resampled) : levelSetCsg(a, b, op, &resampled);
            EXPECT_FALSE(resampled) << toString(op);
            r.values(all, got);
            int64_t checked = 0, wrongValue = 0, wrongSign = 0, inside = 0;
            for (std::size_t n = 0; n < all.size(); ++n) {
                const Vec3d p = centreOf(frame, all[n][0], all[n][1], all[n][2]);
                double da = kBoxA.distance(p), db = kBoxOut.distance(p);
                bool inA = kBoxA.inside(p), inB = kBoxOut.inside(p);
                if (meshFirst) {
                    std::swap(da, db);
                    std::swap(inA, inB);
                }
                const float v = got[n];
                const bool in = test::csgInside(op, inA, inB);
                inside += in;
                wrongSign += (v < 0) != in;
                if (std::abs(std::abs(da) - w) < 1e-5 || std::abs(std::abs(db) - w) < 1e-5) continue;
                ++checked;
                const double expected = combine(op, clampBand(da, w), clampBand(db, w));
                if (std::abs(double(v) - expected) > 2e-6 && wrongValue++ < 5)
                    ADD_FAILURE() << toString(op) << (meshFirst ? " (mesh first)" : "") << " index ("
                                  << all[n][0] << ", " << all[n][1] << ", " << all[n][2] << "): " << v
                                  << ", expected " << expected;
            }
            EXPECT_EQ(wrongValue, 0) << toString(op);
            EXPECT_EQ(wrongSign, 0) << toString(op);
            EXPECT_GT(checked, 150000) << toString(op);
            EXPECT_GT(inside, 100) << toString(op);
        }
}

TEST(LevelSetOfMesh, CsgOfRealMeshesMatchesCgalDistancesAndSides) {
    const char* names[] = {"meshes/bunny00.off", "meshes/armadillo.off"};
    for (const char* name : names) VOXFX_REQUIRE_DATA(name);
    const Mesh bunny = loadMesh(test::dataPath(names[0]));
    Mesh armadillo = loadMesh(test::dataPath(names[1]));
    // The armadillo scaled to 0.8 of the bunny's size and moved so that it sticks out of the
    // bunny's grid (+x, -z): the mesh's level set reaches indices the lattice's field never had.
    const Box3d bb = computeBounds(bunny.view()), ba = computeBounds(armadillo.view());
    const double scale = 0.8 * std::max({bb.extent().x, bb.extent().y, bb.extent().z}) /
                         std::max({ba.extent().x, ba.extent().y, ba.extent().z});
    for (Vec3f& q : armadillo.positions)
        q = Vec3f((Vec3d(q) - ba.center()) * scale + bb.center() + Vec3d{0.35, 0.05, -0.2});
    FitOptions fo;
    fo.resolution = 96;
    fo.marginCells = 4;
    const Frame frame = fitFrame(bb, fo);
    const LevelSet a = LevelSet::fromField(signedDistanceField(bunny.view(), frame));
    const LevelSet b = levelSetOfMesh(armadillo.view(), a);
    bool resampled = true;
    const LevelSet r = levelSetCsg(a, b, CsgOp::Difference, &resampled);
    EXPECT_FALSE(resampled);
    // A few hundred voxels of the result's band and of the armadillo's, spread evenly.
    std::vector<std::array<int32_t, 3>> ir, ib, sample;
    std::vector<float> vr, vb;
    r.activeVoxels(ir, vr);
    b.activeVoxels(ib, vb);
    ASSERT_GT(ir.size(), 1000u);
    for (std::size_t n = 0; n < ir.size(); n += ir.size() / 300) sample.push_back(ir[n]);
    for (std::size_t n = 0; n < ib.size(); n += ib.size() / 300) sample.push_back(ib[n]);
    std::vector<Vec3d> points;
    int64_t outsideFrame = 0;
    for (const auto& c : sample) {
        points.push_back(centreOf(frame, c[0], c[1], c[2]));
        outsideFrame += c[0] >= frame.width() || c[2] < 0;
    }
    EXPECT_GT(outsideFrame, 10);
    const auto nearA = test::oracleNearest(bunny.view(), points, false);
    const auto nearB = test::oracleNearest(armadillo.view(), points, false);
    const std::vector<int> sideA = test::sideOfClosedMeshPerturbed(bunny.view(), points);
    const std::vector<int> sideB = test::sideOfClosedMeshPerturbed(armadillo.view(), points);
    ASSERT_EQ(sideA.size(), points.size());
    ASSERT_EQ(sideB.size(), points.size());
    std::vector<float> got(sample.size());
    r.values(sample, got);
    const double w = r.background();
    int64_t wrong = 0, checked = 0;
    for (std::size_t n = 0; n < sample.size(); ++n) {
        ASSERT_EQ(got[n], r.value(sample[n][0], sample[n][1], sample[n][2]));
        // sideOf...: 1 inside, -1 outside.
        const double da = -sideA[n] * nearA[n].distance, db = -sideB[n] * nearB[n].distance;
        // The band's edge decides active or not within a float ulp: skipped.
        if (std::abs(std::abs(da) - w) < 1e-6 * w || std::abs(std::abs(db) - w) < 1e-6 * w) continue;
        ++checked;
        const double expected = combine(CsgOp::Difference, clampBand(da, w), clampBand(db, w));
        // One float rounding of the exact distance (plus CGAL's double).
        if (!(std::abs(double(got[n]) - expected) <= 2 * std::abs(expected) * 0x1p-24 + 1e-12) && wrong++ < 5)
            ADD_FAILURE() << "index (" << sample[n][0] << ", " << sample[n][1] << ", " << sample[n][2]
                          << "): " << got[n] << ", expected " << expected;
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(checked, 500);
}

TEST(LevelSetOfMesh, LatticesItCannotUseAreClearErrors) {
    test::TempDir dir;
    const Mesh mesh = kBoxA.mesh();
    const auto message = [&](const LevelSet& lattice, const SdfOptions& o = {}) -> std::string {
        try {
            levelSetOfMesh(mesh.view(), lattice, o);
        } catch (const Error& e) { return e.what(); }
        return "no error";
    };
    EXPECT_NE(message(LevelSet()).find("empty"), std::string::npos);
    // Non-cubic voxels (voxfx's own field), a rotated and a mirrored transform (OpenVDB files).
    const Frame flat = Frame::orthographic({{-2, -2, -2}, {2, 2, 2}}, Axis::Z, 40, 40, 20);
    const std::string m1 = message(LevelSet::fromField(signedDistanceField(mesh.view(), flat)));
    EXPECT_NE(m1.find("cubic voxels"), std::string::npos) << m1;
    openvdb::initialize();
    for (int kind = 0; kind < 2; ++kind) {
        auto g = openvdb::FloatGrid::create(0.3f);
        g->setName("turned");
        g->setGridClass(openvdb::GRID_LEVEL_SET);
        auto xf = openvdb::math::Transform::createLinearTransform(0.1);
        if (kind == 0)
            xf->preRotate(0.3, openvdb::math::Y_AXIS);
        else
            xf->preScale(openvdb::Vec3d(-1, 1, 1));
        g->setTransform(xf);
        g->tree().setValue(openvdb::Coord(0, 0, 0), 0.05f);
        const std::string path = dir.file("turned" + std::to_string(kind) + ".vdb");
        openvdb::io::File(path).write({g});
        const LevelSet turned = readLevelSet(path);
        EXPECT_FALSE(turned.axisAligned());
        const std::string m = message(turned);
        EXPECT_NE(m.find("not a positive scale and a translation"), std::string::npos) << m;
        EXPECT_NE(m.find("turned"), std::string::npos) << m;
    }
    const LevelSet lattice = LevelSet::fromField(signedDistanceField(mesh.view(), cubeFrame(2, 40)));
    SdfOptions full;
    full.full = true;
    EXPECT_NE(message(lattice, full).find("narrow band"), std::string::npos);
    // A broken mesh: signedDistanceField's own error.
    Mesh broken = mesh;
    broken.indices[4] = 999;
    EXPECT_THROW(levelSetOfMesh(broken.view(), lattice), Error);
    // A mesh without triangles: no active voxel, outside everywhere.
    const LevelSet none = levelSetOfMesh(MeshView{}, lattice);
    EXPECT_EQ(none.activeCount(), 0);
    EXPECT_EQ(none.value(20, 20, 20), lattice.background());
    // values() wants one output per index.
    const std::array<int32_t, 3> ijk[2] = {{0, 0, 0}, {1, 2, 3}};
    float out[1];
    EXPECT_THROW(lattice.values(ijk, out), Error);
}

TEST(SdfOffset, GrownCubeIsTheRoundedBoxDistance) {
    const AnalyticBox cube = box({-0.59375, -0.59375, -0.59375}, {0.59375, 0.59375, 0.59375});
    const Frame frame = cubeFrame(1.2, 24); // cells of 0.1, centres at +-0.05, +-0.15, ...
    const double d = 0.2, w = 0.3;
    const SignedDistanceField f = offsetSignedDistanceField(cube.mesh().view(), frame, d);
    EXPECT_NEAR(f.background, w, 1e-12);
    EXPECT_DOUBLE_EQ(f.bandVoxels, 3.0);
    int64_t wrong = 0, wrongActive = 0, active = 0, skipped = 0;
    for (int64_t k = 0; k < 24; ++k)
        for (int64_t j = 0; j < 24; ++j)
            for (int64_t i = 0; i < 24; ++i) {
                const Vec3d p = centreOf(frame, i, j, k);
                // The rounded box of radius d around the cube (convex: exact inside and out).
                const double rounded = cube.distance(p) - d;
                const float v = f.value(i, j, k);
                if (std::abs(std::abs(rounded) - w) < 1e-5) {
                    ++skipped;
                    continue;
                }
                wrong += std::abs(double(v) - clampBand(rounded, w)) > 2e-6;
                active += std::abs(rounded) < w;
            }
    // The active count: exactly the voxels within the band of the new surface.
    std::vector<std::array<int32_t, 3>> idx;
    std::vector<float> values;
    f.activeVoxels(idx, values);
    for (size_t n = 0; n < values.size(); ++n) wrongActive += !(std::abs(values[n]) < w);
    EXPECT_EQ(wrong, 0);
    EXPECT_EQ(wrongActive, 0);
    EXPECT_LE(std::abs(f.activeCount() - active), skipped); // the band's edge, within a float ulp
    EXPECT_GT(active, 1000);
}

TEST(SdfOffset, ShrunkCubeIsExactInsideAndABoundOutside) {
    const AnalyticBox cube = box({-0.59375, -0.59375, -0.59375}, {0.59375, 0.59375, 0.59375});
    const AnalyticBox eroded = box({-0.39375, -0.39375, -0.39375}, {0.39375, 0.39375, 0.39375});
    const Frame frame = cubeFrame(1.2, 24);
    const double d = -0.2, w = 0.3;
    const SignedDistanceField f = offsetSignedDistanceField(cube.mesh().view(), frame, d);
    int64_t wrongSign = 0, wrongInside = 0, overBound = 0, faceRegion = 0, wrongFace = 0, inexact = 0;
    for (int64_t k = 0; k < 24; ++k)
        for (int64_t j = 0; j < 24; ++j)
            for (int64_t i = 0; i < 24; ++i) {
                const Vec3d p = centreOf(frame, i, j, k);
                const double truth = eroded.distance(p); // the shrunk cube is the smaller box
                const float v = f.value(i, j, k);
                wrongSign += (v < 0) != eroded.inside(p);
                if (std::abs(std::abs(truth) - w) < 1e-5) continue;
                const double expected = clampBand(truth, w);
                if (truth < 0) {
                    wrongInside += std::abs(double(v) - expected) > 2e-6;
                    continue;
                }
                // Outside the shrunk cube: a lower bound, exact where one coordinate alone is out.
                overBound += double(v) > expected + 2e-6;
                int out = 0;
                for (int a = 0; a < 3; ++a) out += std::abs(p[a]) > eroded.hi[a];
                if (out == 1) {
                    ++faceRegion;
                    wrongFace += std::abs(double(v) - expected) > 2e-6;
                } else if (std::abs(double(v) - expected) > 1e-3) {
                    ++inexact;
                }
            }
    EXPECT_EQ(wrongSign, 0);
    EXPECT_EQ(wrongInside, 0);
    EXPECT_EQ(overBound, 0);
    EXPECT_EQ(wrongFace, 0);
    EXPECT_GT(faceRegion, 100);
    EXPECT_GT(inexact, 0); // near the new edges the subtraction is only a bound: the test sees it
}

TEST(LevelSetOffset, OpenVdbFilterMovesASphereByTheDistance) {
    // A fine UV sphere: its faces lie within r (1 - cos(pi / 48)) ~ 0.0015 of the true sphere.
    const double radius = 0.7, h = 0.05;
    const Mesh sphere = test::makeUvSphere({0, 0, 0}, radius, 48, 96);
    const Frame frame = cubeFrame(1.2, 48);
    const LevelSet ls = LevelSet::fromField(signedDistanceField(sphere.view(), frame));
    for (double d : {0.12, -0.12}) {
        const LevelSet moved = offsetLevelSet(ls, d);
        EXPECT_NEAR(moved.background(), ls.background(), 1e-6);
        std::vector<std::array<int32_t, 3>> idx;
        std::vector<float> values;
        moved.activeVoxels(idx, values);
        ASSERT_GT(values.size(), 1000u);
        double maxError = 0;
        int64_t near = 0;
        for (size_t n = 0; n < values.size(); ++n) {
            const Vec3d p = centreOf(frame, idx[n][0], idx[n][1], idx[n][2]);
            const double expected = length(p) - (radius + d);
            if (std::abs(expected) > 1.5 * h) continue; // the surface's neighbourhood
            ++near;
            maxError = std::max(maxError, std::abs(double(values[n]) - expected));
        }
        EXPECT_GT(near, 1000);
        // Approximate (the tracker's finite differences; 0.018 voxel measured here, the faceted
        // sphere's own error included): within a twentieth of a voxel on a sphere.
        EXPECT_LT(maxError, 0.05 * h) << "offset " << d << ": max error " << maxError;
    }
}

TEST(LevelSetIo, NonLevelSetsAndMissingFilesAreClearErrors) {
    test::TempDir dir;
    const Frame frame = cubeFrame(2, 40);
    const std::string occ = dir.file("occ.vdb"), ls = dir.file("ls.vdb");
    writeGrid(voxelize(kBoxA.mesh().view(), frame), occ);
    writeSdf(signedDistanceField(kBoxA.mesh().view(), frame), ls);
    EXPECT_TRUE(isLevelSetFile(ls));
    std::string what;
    EXPECT_FALSE(isLevelSetFile(occ, &what));
    EXPECT_NE(what.find("BoolGrid"), std::string::npos) << what;
    try {
        readLevelSet(occ);
        ADD_FAILURE() << "an occupancy grid read as a level set";
    } catch (const Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("occ.vdb"), std::string::npos) << m;
        EXPECT_NE(m.find("not a level set"), std::string::npos) << m;
    }
    try {
        readLevelSet(dir.file("missing.vdb"));
        ADD_FAILURE() << "a missing file read";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("missing.vdb"), std::string::npos) << e.what();
    }
    EXPECT_THROW(offsetLevelSet(readLevelSet(ls), std::nan("")), Error);
    EXPECT_THROW(LevelSet().background(), Error);
}

TEST(LevelSetCli, CsgOfTwoSdfFilesWritesALevelSetAndRefusesOccupancy) {
    test::TempDir dir;
    const std::string ma = writeOff(dir, kBoxA.mesh(), "a.off"), mb = writeOff(dir, kBoxB.mesh(), "b.off");
    const std::string grid = " --bounds -2 -2 -2 2 2 2 -r 40 --margin 0 -q";
    ASSERT_EQ(test::runVoxfx(dir, "sdf " + ma + " -o " + dir.file("a.vdb") + grid).exitCode, 0);
    ASSERT_EQ(test::runVoxfx(dir, "sdf " + mb + " -o " + dir.file("b.vdb") + grid).exitCode, 0);
    const std::string out = dir.file("d.vdb");
    const test::CommandRun r = test::runVoxfx(dir, "csg 'difference(" + dir.file("a.vdb") + ", " +
                                                       dir.file("b.vdb") + ")' -o " + out);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("2 level sets -> level set"), std::string::npos) << r.out;
    EXPECT_EQ(r.err.find("resampled"), std::string::npos) << r.err;
    const openvdb::FloatGrid::Ptr g = readByOpenVdb(out);
    ASSERT_TRUE(g);
    EXPECT_EQ(g->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_NEAR(g->background(), 0.3, 1e-6);
    // Signs of the difference at every voxel against the boxes.
    const Frame frame = cubeFrame(2, 40);
    int64_t wrong = 0;
    const auto acc = g->getConstAccessor();
    for (int64_t k = 0; k < 40; ++k)
        for (int64_t j = 0; j < 40; ++j)
            for (int64_t i = 0; i < 40; ++i) {
                const Vec3d p = centreOf(frame, i, j, k);
                wrong += (acc.getValue(openvdb::Coord(int(i), int(j), int(k))) < 0) !=
                         (kBoxA.inside(p) && !kBoxB.inside(p));
            }
    EXPECT_EQ(wrong, 0);

    // A level set with an occupancy grid (.vdb or another format) or a missing file: one error
    // line, no file.
    writeGrid(voxelize(kBoxB.mesh().view(), frame), dir.file("occ.vdb"));
    writeGrid(voxelize(kBoxB.mesh().view(), frame), dir.file("occ.binvox"));
    const std::pair<std::string, std::string> cases[] = {
        {"union(" + dir.file("a.vdb") + ", " + dir.file("occ.vdb") + ")",
         "BoolGrid (occupancy), not a level set"},
        {"union(" + dir.file("occ.vdb") + ", " + dir.file("a.vdb") + ")",
         "BoolGrid (occupancy), not a level set"},
        {"union(" + dir.file("a.vdb") + ", " + dir.file("occ.binvox") + ")", "is an occupancy grid"},
        {"union(" + dir.file("a.vdb") + ", " + dir.file("missing.off") + ")", "missing.off"},
        {"union(" + dir.file("a.vdb") + ", " + dir.file("missing.vdb") + ")", "missing.vdb"},
    };
    for (const auto& [expr, needle] : cases) {
        const test::CommandRun e = test::runVoxfx(dir, "csg '" + expr + "' -o " + dir.file("x.vdb"));
        EXPECT_NE(e.exitCode, 0) << expr;
        EXPECT_NE(e.err.find("voxfx: error:"), std::string::npos) << e.err;
        EXPECT_NE(e.err.find(needle), std::string::npos) << expr << ": " << e.err;
        EXPECT_FALSE(std::filesystem::exists(dir.file("x.vdb")));
    }
}

TEST(LevelSetCli, CsgOfALevelSetAndAMeshIsExactOnTheLevelSetsLattice) {
    test::TempDir dir;
    const std::string ma = writeOff(dir, kBoxA.mesh(), "a.off"), mb = writeOff(dir, kBoxOut.mesh(), "b.off");
    const std::string a = dir.file("a.vdb");
    ASSERT_EQ(test::runVoxfx(dir, "sdf " + ma + " -o " + a + " --bounds -2 -2 -2 2 2 2 -r 40 --margin 0 -q")
                  .exitCode,
              0);
    const Frame frame = cubeFrame(2, 40);
    const double w = 0.3;
    for (const bool meshFirst : {false, true}) {
        const std::string out = dir.file(meshFirst ? "m.vdb" : "d.vdb");
        const std::string expr =
            meshFirst ? "difference(" + mb + ", " + a + ")" : "difference(" + a + ", " + mb + ")";
        const test::CommandRun r = test::runVoxfx(dir, "csg '" + expr + "' -o " + out);
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_NE(r.out.find("1 level set, 1 mesh on the first's lattice -> level set"), std::string::npos)
            << r.out;
        EXPECT_NE(r.out.find("mesh distances"), std::string::npos) << r.out;
        EXPECT_EQ(r.err.find("resampled"), std::string::npos) << r.err;
        const openvdb::FloatGrid::Ptr g = readByOpenVdb(out);
        ASSERT_TRUE(g);
        EXPECT_EQ(g->getGridClass(), openvdb::GRID_LEVEL_SET);
        EXPECT_EQ(g->transform(), readByOpenVdb(a)->transform());
        // The analytic boxes at every index around both (the mesh reaches past a.vdb's 40^3).
        const auto acc = g->getConstAccessor();
        int64_t wrong = 0, checked = 0;
        for (int k = -4; k < 44; ++k)
            for (int j = -10; j < 44; ++j)
                for (int i = -4; i < 52; ++i) {
                    const Vec3d p = centreOf(frame, i, j, k);
                    double da = kBoxA.distance(p), db = kBoxOut.distance(p);
                    if (meshFirst) std::swap(da, db);
                    if (std::abs(std::abs(da) - w) < 1e-5 || std::abs(std::abs(db) - w) < 1e-5) continue;
                    ++checked;
                    const double expected = combine(CsgOp::Difference, clampBand(da, w), clampBand(db, w));
                    wrong += std::abs(double(acc.getValue(openvdb::Coord(i, j, k))) - expected) > 2e-6;
                }
        EXPECT_EQ(wrong, 0) << expr;
        EXPECT_GT(checked, 100000);
    }
}

TEST(LevelSetCli, SdfOffsetAndMorphOffsetWriteLevelSets) {
    test::TempDir dir;
    const AnalyticBox cube = box({-0.59375, -0.59375, -0.59375}, {0.59375, 0.59375, 0.59375});
    const std::string mesh = writeOff(dir, cube.mesh(), "cube.off");
    // sdf --offset: the library's offset field on the command's grid.
    const std::string npy = dir.file("grown.npy");
    const test::CommandRun r =
        test::runVoxfx(dir, "sdf " + mesh + " -o " + npy +
                                " --bounds -1.2 -1.2 -1.2 1.2 1.2 1.2 -r 24 --margin 0 --offset 0.2");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("offset by 0.2 (grown)"), std::string::npos) << r.out;
    const std::vector<float> dense =
        offsetSignedDistanceField(cube.mesh().view(), cubeFrame(1.2, 24), 0.2).dense();
    const std::string bytes = test::readFileBytes(npy);
    ASSERT_GE(bytes.size(), dense.size() * 4);
    EXPECT_EQ(0, std::memcmp(bytes.data() + bytes.size() - dense.size() * 4, dense.data(), dense.size() * 4));

    // morph --offset on a level set.
    const std::string ls = dir.file("cube.vdb"), moved = dir.file("moved.vdb");
    ASSERT_EQ(test::runVoxfx(dir, "sdf " + mesh + " -o " + ls + " --voxel-size 0.05 -q").exitCode, 0);
    const test::CommandRun m = test::runVoxfx(dir, "morph " + ls + " --offset -0.1 -o " + moved);
    ASSERT_EQ(m.exitCode, 0) << m.err;
    EXPECT_NE(m.out.find("offset by -0.1 (shrunk)"), std::string::npos) << m.out;
    const openvdb::FloatGrid::Ptr g = readByOpenVdb(moved);
    ASSERT_TRUE(g);
    EXPECT_EQ(g->getGridClass(), openvdb::GRID_LEVEL_SET);
    // The shrunk cube's face moved from 0.59375 to 0.49375: the sign changes there along x.
    const openvdb::Vec3d inside = g->worldToIndex(openvdb::Vec3d(0.46, 0.0125, 0.0125));
    const openvdb::Vec3d outside = g->worldToIndex(openvdb::Vec3d(0.53, 0.0125, 0.0125));
    const auto acc = g->getConstAccessor();
    EXPECT_LT(acc.getValue(openvdb::Coord::round(inside)), 0);
    EXPECT_GT(acc.getValue(openvdb::Coord::round(outside)), 0);

    // Occupancy grids take --op, level sets --offset.
    const std::string occ = dir.file("occ.vdb");
    writeGrid(voxelize(cube.mesh().view(), cubeFrame(1.2, 24)), occ);
    const test::CommandRun e1 = test::runVoxfx(dir, "morph " + occ + " --offset 0.1 -o " + dir.file("x.vdb"));
    EXPECT_NE(e1.exitCode, 0);
    EXPECT_NE(e1.err.find("--offset takes a level-set .vdb"), std::string::npos) << e1.err;
    const test::CommandRun e2 = test::runVoxfx(dir, "morph " + ls + " --op dilate -o " + dir.file("x.vdb"));
    EXPECT_NE(e2.exitCode, 0);
    EXPECT_NE(e2.err.find("is a level set"), std::string::npos) << e2.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.vdb")));
}

} // namespace
} // namespace voxfx
