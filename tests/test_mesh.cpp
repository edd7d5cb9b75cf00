// Tests of src/core/mesh.cpp: bounds, validation, degenerate triangles and edge topology.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/error.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx {
namespace {

// The cube [0,1]^3 with outward counter-clockwise triangles, two per face, faces in the order
// -z, +z, -y, +y, -x, +x. Vertex i is at (i & 1, (i >> 1) & 1, (i >> 2) & 1).
Mesh unitCube() {
    Mesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)});
    m.indices = {0, 2, 3, 0, 3, 1,  // -z
                 4, 5, 7, 4, 7, 6,  // +z
                 0, 1, 5, 0, 5, 4,  // -y
                 2, 6, 7, 2, 7, 3,  // +y
                 0, 4, 6, 0, 6, 2,  // -x
                 1, 3, 7, 1, 7, 5}; // +x
    return m;
}

std::string errorMessage(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) { return e.what(); }
    return "(no voxfx::Error thrown)";
}

// Reference edge classification by brute force: positions compared by value in a std::map,
// directed edges counted per undirected pair.
MeshTopology bruteForceTopology(const Mesh& m) {
    std::map<std::tuple<float, float, float>, int> id;
    std::vector<int> canon(m.positions.size());
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
        const auto& p = m.positions[v];
        canon[v] = id.emplace(std::make_tuple(p.x, p.y, p.z), int(id.size())).first->second;
    }
    std::map<std::pair<int, int>, std::array<int, 2>> uses; // [forward, backward] from min to max
    for (std::size_t t = 0; t < m.triangleCount(); ++t) {
        const int a = canon[m.indices[3 * t]], b = canon[m.indices[3 * t + 1]],
                  c = canon[m.indices[3 * t + 2]];
        if (a == b || b == c || a == c) continue;
        for (auto [p, q] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
            ++uses[{std::min(p, q), std::max(p, q)}][p < q ? 0 : 1];
    }
    MeshTopology topo;
    for (const auto& [edge, n] : uses) {
        ++topo.edges;
        const int total = n[0] + n[1];
        if (total == 1)
            ++topo.boundaryEdges;
        else if (total >= 3)
            ++topo.nonManifoldEdges;
        else if (n[0] != 1)
            ++topo.misorientedEdges;
    }
    return topo;
}

void expectTopology(const MeshTopology& got, std::size_t edges, std::size_t boundary, std::size_t nonManifold,
                    std::size_t misoriented) {
    EXPECT_EQ(got.edges, edges);
    EXPECT_EQ(got.boundaryEdges, boundary);
    EXPECT_EQ(got.nonManifoldEdges, nonManifold);
    EXPECT_EQ(got.misorientedEdges, misoriented);
}

TEST(MeshTest, BoundsCoverOnlyVerticesUsedByTriangles) {
    Mesh m;
    m.positions = {{1, 2, 3}, {100, 100, 100}, {-4, 5, 0.5f}, {2, -6, 7}};
    m.indices = {0, 2, 3};
    const Box3d box = computeBounds(m.view());
    EXPECT_EQ(box.lo, (Vec3d{-4, -6, 0.5}));
    EXPECT_EQ(box.hi, (Vec3d{2, 5, 7}));
}

TEST(MeshTest, BoundsOfMeshWithoutTrianglesAreEmpty) {
    Mesh m;
    m.positions = {{1, 2, 3}};
    EXPECT_TRUE(computeBounds(m.view()).empty());
}

TEST(MeshTest, BoundsFollowThePositionStride) {
    // Interleaved position + normal, 24 bytes per vertex; the normals hold values far outside.
    const std::vector<float> interleaved = {0, 0, 0, 9, 9, 9, 1, 0, 0, -9, -9, -9, 0, 2, 3, 9, 9, 9};
    const uint32_t indices[] = {0, 1, 2};
    MeshView view{interleaved.data(), 3, 6 * sizeof(float), indices, 1};
    const Box3d box = computeBounds(view);
    EXPECT_EQ(box.lo, (Vec3d{0, 0, 0}));
    EXPECT_EQ(box.hi, (Vec3d{1, 2, 3}));
}

TEST(MeshTest, ValidateAcceptsAValidMesh) {
    const Mesh m = unitCube();
    EXPECT_NO_THROW(validateMesh(m.view(), "cube"));
}

TEST(MeshTest, ValidateNamesTheTriangleAndTheOutOfRangeIndex) {
    Mesh m = unitCube();
    m.indices[3 * 5 + 1] = 8;
    const std::string msg = errorMessage([&] { validateMesh(m.view(), "my-cube"); });
    EXPECT_NE(msg.find("my-cube"), std::string::npos) << msg;
    EXPECT_NE(msg.find("triangle 5"), std::string::npos) << msg;
    EXPECT_NE(msg.find("index 8"), std::string::npos) << msg;
}

TEST(MeshTest, ValidateNamesTheNonFiniteVertex) {
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        Mesh m = unitCube();
        m.positions[6].y = bad;
        const std::string msg = errorMessage([&] { validateMesh(m.view(), "my-cube"); });
        EXPECT_NE(msg.find("my-cube"), std::string::npos) << msg;
        EXPECT_NE(msg.find("vertex 6"), std::string::npos) << msg;
        EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
    }
}

TEST(MeshTest, ValidateIgnoresNonFiniteVerticesNoTriangleUses) {
    Mesh m = unitCube();
    m.positions.push_back({std::numeric_limits<float>::quiet_NaN(), 0, 0});
    EXPECT_NO_THROW(validateMesh(m.view(), "cube"));
}

TEST(MeshTest, RemoveDegenerateDropsRepeatedIndicesAndZeroAreaKeepingOrder) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {1, 0, 0}, {0.5f, 0.5f, 7}};
    m.indices = {0, 1, 2,  // kept
                 0, 0, 2,  // repeated index
                 0, 1, 3,  // collinear along x
                 1, 4, 2,  // two corners at one position (distinct indices)
                 1, 2, 5}; // kept
    EXPECT_EQ(removeDegenerateTriangles(m), 3u);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 1, 2, 5}));
}

TEST(MeshTest, RemoveDegenerateIsExactOnFloatCoordinates) {
    // Collinear in 3D along (1,1,1), with coordinates that are not small integers.
    const float s = 0.1f;
    Mesh m;
    m.positions = {{s, s, s}, {3 * s, 3 * s, 3 * s}, {-7 * s, -7 * s, -7 * s}};
    // 3s and -7s are rounded floats, so the points are collinear only if they stay on the
    // diagonal, which they do: each point has three equal coordinates.
    m.indices = {0, 1, 2};
    EXPECT_EQ(removeDegenerateTriangles(m), 1u);

    // One ulp off the line: a real (tiny) triangle that must be kept.
    Mesh n;
    n.positions = {{0, 0, 0}, {1, 1, 1}, {2, 2, std::nextafter(2.0f, 3.0f)}};
    n.indices = {0, 1, 2};
    EXPECT_EQ(removeDegenerateTriangles(n), 0u);

    // Area B*t/2 with B = 1e20, t = 1e-20 in the xy plane: (t + B) rounds to B in double, so a
    // plain double cross product computes exactly zero, but the triangle is not degenerate.
    const float B = 1e20f, t = 1e-20f;
    Mesh w;
    w.positions = {{-t, 0, 0}, {B, B, 0}, {2 * B, 2 * B, 0}};
    w.indices = {0, 1, 2};
    EXPECT_EQ(removeDegenerateTriangles(w), 0u);
}

TEST(MeshTest, TopologyOfClosedCube) {
    const Mesh m = unitCube();
    const MeshTopology topo = analyzeTopology(m.view());
    expectTopology(topo, 18, 0, 0, 0); // 12 cube edges + 6 face diagonals
    EXPECT_TRUE(topo.closed());
}

TEST(MeshTest, TopologyOfCubeWithAFaceRemoved) {
    Mesh m = unitCube();
    m.indices.erase(m.indices.begin() + 6, m.indices.begin() + 12); // the +z face
    const MeshTopology topo = analyzeTopology(m.view());
    expectTopology(topo, 17, 4, 0, 0);
    EXPECT_FALSE(topo.closed());
}

TEST(MeshTest, TopologyOfCubeWithAFlippedFace) {
    Mesh m = unitCube();
    std::swap(m.indices[1], m.indices[2]); // both triangles of the -z face
    std::swap(m.indices[4], m.indices[5]);
    const MeshTopology topo = analyzeTopology(m.view());
    expectTopology(topo, 18, 0, 0, 4); // the face's 4 outer edges; its diagonal stays consistent
    EXPECT_FALSE(topo.closed());
}

TEST(MeshTest, TopologyOfCubeWithANonManifoldFin) {
    Mesh m = unitCube();
    m.positions.push_back({0.5f, -1, -1});
    m.indices.insert(m.indices.end(), {0, 1, 8}); // a fin on the edge 0-1
    const MeshTopology topo = analyzeTopology(m.view());
    expectTopology(topo, 20, 2, 1, 0);
    EXPECT_FALSE(topo.closed());
}

TEST(MeshTest, TopologyMergesIdenticalPositionsOfATriangleSoup) {
    const Mesh cube = unitCube();
    Mesh soup;
    for (uint32_t i : cube.indices) {
        soup.indices.push_back(uint32_t(soup.positions.size()));
        soup.positions.push_back(cube.positions[i]);
    }
    // -0 and +0 are the same point: one copy written as -0 must not open the mesh.
    ASSERT_EQ(soup.positions[0].x, 0.0f);
    soup.positions[0].x = -0.0f;
    const MeshTopology topo = analyzeTopology(soup.view());
    expectTopology(topo, 18, 0, 0, 0);
    EXPECT_TRUE(topo.closed());
}

TEST(MeshTest, TopologyOfEmptyAndDegenerateMeshes) {
    Mesh empty;
    EXPECT_FALSE(analyzeTopology(empty.view()).closed());
    expectTopology(analyzeTopology(empty.view()), 0, 0, 0, 0);

    Mesh degenerate;
    degenerate.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}};
    degenerate.indices = {0, 1, 2, 0, 0, 1};
    expectTopology(analyzeTopology(degenerate.view()), 0, 0, 0, 0);
}

TEST(MeshTest, TopologyMatchesBruteForceOnRandomMeshes) {
    std::mt19937 rng(12345);
    for (int round = 0; round < 200; ++round) {
        Mesh m;
        // Few distinct positions (coordinates in {0, 1, 2}) so that edges get shared, reused
        // with both orientations, and duplicated vertices occur.
        std::uniform_int_distribution<int> coord(0, 2);
        const int vertices = 4 + round % 20;
        for (int v = 0; v < vertices; ++v)
            m.positions.push_back({float(coord(rng)), float(coord(rng)), float(coord(rng))});
        std::uniform_int_distribution<uint32_t> vertex(0, uint32_t(vertices - 1));
        const int triangles = 1 + round % 40;
        for (int i = 0; i < 3 * triangles; ++i) m.indices.push_back(vertex(rng));
        const MeshTopology want = bruteForceTopology(m);
        const MeshTopology got = analyzeTopology(m.view());
        SCOPED_TRACE("round " + std::to_string(round));
        expectTopology(got, want.edges, want.boundaryEdges, want.nonManifoldEdges, want.misorientedEdges);
    }
}

TEST(MeshTest, TopologyOfFansAroundOneVertexMatchesBruteForce) {
    // Every edge's uses are summed at its larger endpoint, one vertex's edges at a time: a hub
    // with thousands of edges (a cone's apex), closed or with some spokes used three times, and
    // after it a small mesh (the calls reuse their scratch memory), against the brute force.
    for (const int spokes : {3, 17, 2000}) {
        for (const bool fins : {false, true}) {
            Mesh m;
            m.positions.push_back({0, 0, 1});  // the apex
            m.positions.push_back({0, 0, -1}); // the bottom's centre
            for (int k = 0; k < spokes; ++k) {
                const double a = 2 * 3.141592653589793 * k / spokes;
                m.positions.push_back({float(std::cos(a)), float(std::sin(a)), 0});
            }
            for (int k = 0; k < spokes; ++k) {
                const auto p = uint32_t(2 + k), q = uint32_t(2 + (k + 1) % spokes);
                m.indices.insert(m.indices.end(), {0, p, q, 1, q, p});
                if (fins && k % 7 == 0) m.indices.insert(m.indices.end(), {0, p, 1});
            }
            const MeshTopology want = bruteForceTopology(m);
            SCOPED_TRACE(std::to_string(spokes) + (fins ? " spokes with fins" : " spokes"));
            expectTopology(analyzeTopology(m.view()), want.edges, want.boundaryEdges, want.nonManifoldEdges,
                           want.misorientedEdges);
            EXPECT_EQ(want.closed(), !fins);
            expectTopology(analyzeTopology(unitCube().view()), 18, 0, 0, 0);
        }
    }
}

TEST(MeshTest, TopologySkipsTrianglesWithOutOfRangeIndices) {
    Mesh m = unitCube();
    m.indices.insert(m.indices.end(), {0, 1, 99});
    expectTopology(analyzeTopology(m.view()), 18, 0, 0, 0);
}

} // namespace
} // namespace voxfx
