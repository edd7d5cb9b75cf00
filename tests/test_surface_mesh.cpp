// Tests of src/grid/surface_mesh.cpp: hand-derived meshes of single cells and of the ambiguous
// face case, watertightness and orientation on voxelized meshes (voxfx::analyzeTopology, which
// merges bit-identical positions and counts boundary, non-manifold and misoriented edges),
// enclosed volume against the exact volume of the voxelized shape, and the written files.
#include <numeric>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/surface_mesh.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

// Connected components of the triangles (sharing a vertex index).
int components(const SurfaceMesh& m) {
    std::vector<uint32_t> parent(m.positions.size());
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    };
    for (size_t t = 0; t < m.triangleCount(); ++t)
        for (int k = 1; k < 3; ++k) parent[find(m.indices[3 * t + k])] = find(m.indices[3 * t]);
    int n = 0;
    for (uint32_t v = 0; v < parent.size(); ++v) n += find(v) == v;
    return n;
}

VoxelGrid unitGrid(int64_t n) {
    return {Frame::orthographic({{0, 0, 0}, {double(n), double(n), double(n)}}, Axis::Z, n, n, n),
            BitGrid(n, n, n)};
}

SurfaceOptions occupancy(float iso = 0.5f) {
    SurfaceOptions o;
    o.source = SurfaceSource::Occupancy;
    o.iso = iso;
    return o;
}

TEST(SurfaceMeshTest, OneCellGivesAnOctahedronAroundItsCentre) {
    // Field 1 at the cell's centre and 0 at the six neighbours: the iso 0.5 crossings sit half way,
    // at centre +- 0.5 along each axis: an octahedron of 6 vertices, 8 faces, volume 4/3 * 0.5^3.
    VoxelGrid g = unitGrid(3);
    g.bits.set(1, 1, 1);
    const SurfaceMesh m = extractSurface(g, occupancy());
    EXPECT_EQ(m.positions.size(), 6u);
    EXPECT_EQ(m.triangleCount(), 8u);
    for (const Vec3f& p : m.positions) EXPECT_NEAR(length(Vec3d(p) - Vec3d{1.5, 1.5, 1.5}), 0.5, 1e-6);
    EXPECT_NEAR(test::meshVolume(m.view()), 4.0 / 3.0 * 0.125, 1e-6);
    EXPECT_TRUE(analyzeTopology(m.view()).closed());
    // Normals point away from the centre.
    for (size_t i = 0; i < m.positions.size(); ++i)
        EXPECT_NEAR(dot(Vec3d(m.normals[i]), normalize(Vec3d(m.positions[i]) - Vec3d{1.5, 1.5, 1.5})), 1.0,
                    1e-6);
}

TEST(SurfaceMeshTest, AmbiguousFaceFollowsTheAsymptoticDecider) {
    // Two cells touching along an edge: the face between their centres has values 1 0 / 0 1,
    // whose bilinear saddle value is (1*1 - 0*0) / (1 + 1 - 0 - 0) = 0.5. Iso 0.5: the inside
    // corners stay apart (two octahedra); iso 0.4: they connect into one closed surface.
    VoxelGrid g = unitGrid(4);
    g.bits.set(1, 1, 1);
    g.bits.set(2, 2, 1);
    const SurfaceMesh apart = extractSurface(g, occupancy(0.5f));
    EXPECT_EQ(components(apart), 2);
    EXPECT_EQ(apart.positions.size(), 12u);
    EXPECT_TRUE(analyzeTopology(apart.view()).closed());
    const SurfaceMesh joined = extractSurface(g, occupancy(0.4f));
    EXPECT_EQ(components(joined), 1);
    EXPECT_EQ(joined.positions.size(), 12u);
    EXPECT_TRUE(analyzeTopology(joined.view()).closed());
    EXPECT_GT(test::meshVolume(joined.view()), test::meshVolume(apart.view()));
}

void expectWatertight(const SurfaceMesh& m, const std::string& what) {
    const MeshTopology t = analyzeTopology(m.view());
    EXPECT_TRUE(t.closed()) << what << ": " << t.edges << " edges, " << t.boundaryEdges << " boundary, "
                            << t.nonManifoldEdges << " non-manifold, " << t.misorientedEdges
                            << " misoriented";
    // Every edge is shared by exactly two triangles: E = 3T / 2.
    EXPECT_EQ(2 * t.edges, 3 * m.triangleCount()) << what;
    EXPECT_GT(test::meshVolume(m.view()), 0) << what << ": triangles must face outwards";
}

TEST(SurfaceMeshTest, SurfacesOfVoxelizedMeshesAreWatertightAndOutward) {
    for (const char* name : {"bunny00", "knot1", "elephant"}) {
        VOXFX_REQUIRE_DATA(std::string("meshes/") + name + ".off");
        const std::string path = test::dataPath(std::string("meshes/") + name + ".off");
        const Mesh mesh = loadMesh(path);
        FitOptions fit;
        fit.resolution = 61;
        const VoxelGrid g = voxelize(mesh.view(), fitFrame(computeBounds(mesh.view()), fit));
        expectWatertight(extractSurface(g, occupancy()), std::string(name) + " occupancy");
        for (const int level : {1, 2}) {
            SurfaceOptions o;
            o.level = level;
            for (const float iso : {0.5f, 0.3f, 0.77f}) {
                o.iso = iso;
                expectWatertight(extractSurface(g, o),
                                 detail::concat(name, " density level ", level, " iso ", iso));
            }
        }
    }
    // Random grids have many ambiguous faces and cubes.
    VoxelGrid r = test::randomVoxelGrid({{0, 0, 0}, {13, 11, 70}}, Axis::Y, {13, 11, 70}, 0.5, 21);
    expectWatertight(extractSurface(r, occupancy()), "random occupancy");
    expectWatertight(extractSurface(r, SurfaceOptions{}), "random density");
}

TEST(SurfaceMeshTest, EnclosedVolumeApproachesTheVoxelizedSphere) {
    // Sphere of radius 20 cells. The iso 0.5 surface of the 0/1 field passes half way between
    // inside and outside cell centres, so it stays within one cell of the true surface: the
    // volumes differ by less than area * cell.
    const double R = 20;
    const Mesh sphere = test::makeUvSphere({24, 24, 24}, R, 48, 96);
    VoxelGrid g = unitGrid(48);
    g.bits = voxelize(sphere.view(), g.frame).bits;
    const double exact = test::meshVolume(sphere.view());
    for (const SurfaceOptions& o : {occupancy(), SurfaceOptions{}}) {
        const SurfaceMesh m = extractSurface(g, o);
        EXPECT_NEAR(test::meshVolume(m.view()), exact, 4 * M_PI * R * R * 1.0) << toString(o.source);
        // Vertex normals agree with the radial direction (the shape's true normal) on average.
        double sum = 0;
        for (size_t i = 0; i < m.positions.size(); ++i)
            sum += dot(Vec3d(m.normals[i]), normalize(Vec3d(m.positions[i]) - Vec3d{24, 24, 24}));
        // Staircase aliasing of the voxelized field (measured mean cosines: 0.957 for the 0/1
        // field, 0.985 for the density); a flipped or permuted normal gives <= 0.
        EXPECT_GT(sum / double(m.positions.size()), o.source == SurfaceSource::Occupancy ? 0.94 : 0.975)
            << toString(o.source);
    }
}

TEST(SurfaceMeshTest, FilesReadBackAsTheSameClosedMesh) {
    test::TempDir dir;
    const Mesh torus = test::makeTorus({8, 8, 8}, 5, 2, 32, 16);
    VoxelGrid g = unitGrid(16);
    g.bits = voxelize(torus.view(), g.frame).bits;
    SurfaceOptions o;
    o.threads = 1;
    const SurfaceMesh m = extractSurface(g, o);
    o.threads = 2;
    const SurfaceMesh m2 = extractSurface(g, o);
    EXPECT_EQ(m.indices, m2.indices);
    EXPECT_EQ(m.positions, m2.positions);
    for (const char* ext : {".ply", ".obj"}) {
        const std::string path = dir.file(std::string("s") + ext);
        writeSurfaceMesh(m, path);
        const Mesh back = test::meshOfSoup(test::readWithCgal(path)); // CGAL's reader, not voxfx's
        EXPECT_EQ(back.triangleCount(), m.triangleCount()) << ext;
        EXPECT_TRUE(analyzeTopology(back.view()).closed()) << ext;
        EXPECT_NEAR(test::meshVolume(back.view()), test::meshVolume(m.view()),
                    1e-3 * test::meshVolume(m.view()));
    }
    EXPECT_THROW(writeSurfaceMesh(m, dir.file("s.stl")), Error);
}

TEST(SurfaceMeshTest, BadInputIsAnError) {
    VoxelGrid g = unitGrid(4);
    EXPECT_EQ(extractSurface(g).triangleCount(), 0u);
    EXPECT_THROW(extractSurface(g, occupancy(1.0f)), Error);
    EXPECT_THROW(extractSurface(g, occupancy(0.0f)), Error);
    const VoxelGrid p{Frame::perspective({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 1.0, 4, 4, 1, 10, 4),
                      BitGrid(4, 4, 4)};
    EXPECT_THROW(extractSurface(p), Error);
}

TEST(SurfaceMeshTest, CommandLineWritesAClosedMesh) {
    test::TempDir dir;
    const Mesh torus = test::makeTorus({8, 8, 8}, 5, 2, 32, 16);
    VoxelGrid g = unitGrid(16);
    g.bits = voxelize(torus.view(), g.frame).bits;
    writeGrid(g, dir.file("t.binvox"));
    for (const char* source : {"density", "occupancy"}) {
        const test::CommandRun run = test::runVoxfx(dir, "mesh " + dir.file("t.binvox") + " --source " +
                                                             source + " -q -o " + dir.file("t.ply"));
        ASSERT_EQ(run.exitCode, 0) << run.err;
        const Mesh m = test::meshOfSoup(test::readWithCgal(dir.file("t.ply")));
        EXPECT_TRUE(analyzeTopology(m.view()).closed()) << source;
        EXPECT_GT(test::meshVolume(m.view()), 0) << source;
    }
}

} // namespace
} // namespace voxfx
