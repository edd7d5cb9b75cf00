// voxfx tests — the CGAL types behind the exactness oracle, for tests that build their own exact
// checks (tests/test_voxelize_border.cpp). Including this costs CGAL's headers; cgal_oracle.hpp
// alone does not.
#pragma once

#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include "voxfx/mesh.hpp"

namespace voxfx::test::oracle {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point2 = K::Point_2;
using Point3 = K::Point_3;
using Triangle3 = K::Triangle_3;
using SurfaceMesh = CGAL::Surface_mesh<Point3>;

/// The mesh's triangles in world space (float coordinates widen to double exactly).
std::vector<Triangle3> triangles(const MeshView& mesh);

/// The mesh as a CGAL::Surface_mesh with world axis `lineAxis` last (cyclic permutation), vertices
/// with bit-identical positions merged (as analyzeTopology does). A vertex where separate fans
/// of triangles meet cannot be represented; orient_polygon_soup duplicates it (and may flip
/// faces, which no inside test here cares about). `valid` is false when even that fails.
SurfaceMesh surfaceMesh(const MeshView& mesh, int lineAxis, bool& valid);

} // namespace voxfx::test::oracle
