// voxfx info MESH — what a mesh file holds: triangles, bounds, and whether it is closed.
#include <iostream>

#include "cli_common.hpp"

namespace voxfx::cli {
namespace {

int runInfo(const std::string& path) {
    const auto t0 = Clock::now();
    MeshLoadReport report;
    const Mesh mesh = loadMesh(path, &report);
    const double loadMs = msSince(t0);
    const MeshTopology topo = analyzeTopology(mesh.view());
    const Box3d b = computeBounds(mesh.view());
    std::cout << "file:       " << path << " (" << report.format << ", "
              << withCommas(int64_t(report.fileBytes)) << " bytes, loaded in " << fmtMs(loadMs) << ")\n";
    std::cout << "vertices:   " << withCommas(int64_t(mesh.positions.size())) << "\n";
    std::cout << "triangles:  " << withCommas(int64_t(mesh.triangleCount()));
    if (report.degenerateRemoved)
        std::cout << " (" << withCommas(int64_t(report.degenerateRemoved)) << " degenerate dropped)";
    std::cout << "\nbounds:     " << boxString(b) << "\n";
    const Vec3d e = b.extent();
    std::cout << "extent:     " << fmt(e.x, 6) << " x " << fmt(e.y, 6) << " x " << fmt(e.z, 6) << "\n";
    std::cout << "edges:      " << withCommas(int64_t(topo.edges)) << " (" << topo.boundaryEdges
              << " boundary, " << topo.nonManifoldEdges << " non-manifold, " << topo.misorientedEdges
              << " misoriented)\n";
    std::cout << "closed:     " << (topo.closed() ? "yes" : "no");
    if (!topo.closed())
        std::cout
            << " (parity fills need a closed mesh: voxelize uses --fill flood for it unless told otherwise)";
    std::cout << "\n";
    return 0;
}

const Command kInfo{
    "info", "Print a mesh's triangles, bounds and whether it is closed", [](CLI::App& app) {
        auto path = std::make_shared<std::string>();
        app.add_option("MESH", *path, "Mesh file (off, obj, ply, stl, gltf, glb, ...)")->required();
        return std::function<int()>([path] { return runInfo(*path); });
    }};

} // namespace
} // namespace voxfx::cli
