// The CGAL oracle's exact Boolean operation (see cgal_oracle.hpp), in a file of its own: CGAL's
// corefinement on exact constructions is the costliest part of the oracle to compile, and apart
// from the rest of the oracle the two build in parallel.
#include <cmath>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include "cgal_oracle.hpp"

namespace voxfx::test {

// See cgal_oracle.hpp.
double oracleIntersectionVolume(const MeshView& a, const MeshView& b) {
    namespace PMP = CGAL::Polygon_mesh_processing;
    using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
    using ExactMesh = CGAL::Surface_mesh<Exact::Point_3>;
    auto exactMesh = [](const MeshView& m, bool& ok) {
        ExactMesh sm;
        for (std::size_t i = 0; i < m.vertexCount; ++i) {
            const Vec3d p = m.vertex(i);
            sm.add_vertex(Exact::Point_3(p.x, p.y, p.z));
        }
        ok = true;
        for (std::size_t t = 0; t < m.triangleCount && ok; ++t)
            ok = sm.add_face(ExactMesh::Vertex_index(m.index(t, 0)), ExactMesh::Vertex_index(m.index(t, 1)),
                             ExactMesh::Vertex_index(m.index(t, 2))) != ExactMesh::null_face();
        ok = ok && CGAL::is_closed(sm) && !PMP::does_self_intersect(sm) && PMP::does_bound_a_volume(sm);
        return sm;
    };
    bool okA = false, okB = false;
    ExactMesh ma = exactMesh(a, okA), mb = exactMesh(b, okB), out;
    if (!okA || !okB || !PMP::corefine_and_compute_intersection(ma, mb, out)) return std::nan("");
    return CGAL::to_double(PMP::volume(out));
}

} // namespace voxfx::test
