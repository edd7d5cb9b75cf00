// voxfx mesh INPUT -o OUT.ply — the surface of a grid (or a voxelized mesh) by marching cubes.
#include <iostream>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/surface_mesh.hpp"

namespace voxfx::cli {
namespace {

struct MeshArgs {
    GridInput in;
    std::string output, source = "density";
    int level = 1;
    float iso = 0.5f;
};

int runMesh(const MeshArgs& a) {
    requireExtension(a.output, {".ply", ".obj"}, "surface mesh");
    const auto t0 = Clock::now();
    SurfaceOptions so;
    so.source = parseSurfaceSource(a.source);
    so.level = a.level;
    so.iso = a.iso;
    so.threads = a.in.threads;
    const VoxelGrid grid = loadGridInput(a.in, /*uniform=*/true);
    const double loadMs = msSince(t0);
    const auto tm = Clock::now();
    const SurfaceMesh mesh = extractSurface(grid, so);
    const double mcMs = msSince(tm);
    const auto tw = Clock::now();
    writeSurfaceMesh(mesh, a.output);
    const double writeMs = msSince(tw);
    if (!a.in.quiet) {
        const Vec3i d = grid.worldDims();
        std::cout << a.in.path << ": " << d.x << " x " << d.y << " x " << d.z << " grid, "
                  << withCommas(grid.bits.count()) << " filled -> marching cubes on the "
                  << toString(so.source);
        if (so.source == SurfaceSource::Density) std::cout << " (level " << so.level << ")";
        std::cout << ", iso " << fmt(so.iso) << ": " << withCommas(int64_t(mesh.positions.size()))
                  << " vertices, " << withCommas(int64_t(mesh.triangleCount())) << " triangles\n";
        std::cout << "time: input " << fmtMs(loadMs) << ", surface " << fmtMs(mcMs) << ", write "
                  << fmtMs(writeMs) << " -> " << a.output << "\n";
    }
    return 0;
}

const char* kMeshHelp = R"(
Marching cubes on a field sampled at cell centres (0 outside the grid, so surfaces are closed):
  density    occupancy of the level-L density map (count / 8^L): smooth, 2^L times coarser
  occupancy  the grid's own 0/1 cells: full resolution, blocky
Ambiguous faces are resolved with the asymptotic decider, consistently between neighbouring
cubes: the mesh is watertight (every edge shared by two triangles) and oriented outwards.
Vertex normals come from the field's gradient. Output: .ply (binary, with normals) or .obj.)";

const Command kMesh{
    "mesh", "Surface mesh of a grid or mesh by marching cubes -> .ply / .obj", [](CLI::App& app) {
        app.footer(kMeshHelp);
        auto a = std::make_shared<MeshArgs>();
        app.add_option("-o,--output", a->output, "Surface mesh: .ply or .obj")->required();
        app.add_option("--source", a->source, enumNameList<SurfaceSource>(kSurfaceSourceNames, " | "))
            ->default_val("density");
        app.add_option("-l,--level", a->level, "Density level, kernel 2^level (1..5)")
            ->check(CLI::Range(1, 5))
            ->default_val(1);
        app.add_option("--iso", a->iso, "Iso value in (0, 1)")->default_val(0.5f);
        addGridInputOptions(app, a->in);
        return std::function<int()>([a] { return runMesh(*a); });
    }};

} // namespace
} // namespace voxfx::cli
