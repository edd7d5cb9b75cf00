// voxfx csg EXPRESSION -o OUT — a CSG tree of meshes, voxelized into one shared frame.
#include <algorithm>
#include <iostream>
#include <map>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/grid_io.hpp"

namespace voxfx::cli {
namespace {

struct CsgArgs {
    std::string expression, output, fill = "auto";
    FitArgs fit;
    int threads = 0;
    bool vdbFloat = false, quiet = false;
};

const FitChoices kCsgFit = [] {
    FitChoices c;
    c.voxelSize = true;
    return c;
}();

int runCsg(const CsgArgs& a) {
    const auto t0 = Clock::now();
    const GridFormat format = gridFormatFromPath(a.output);
    const CsgNode root = parseCsgExpression(a.expression);
    const Fill fill = parseFill(a.fill);

    // Every leaf is loaded once: grid files (.binvox .vdb .nrrd) as grids, anything else as a
    // mesh; open meshes get the flood fill unless a fill is forced.
    std::map<std::string, Mesh> meshes;
    std::map<std::string, VoxelGrid> grids;
    std::vector<CsgMesh> list;
    std::string firstGrid;
    for (const std::string& path : csgMeshes(root)) {
        if (isGridFile(path)) {
            const VoxelGrid& g = grids.emplace(path, readGrid(path)).first->second;
            if (firstGrid.empty()) firstGrid = path;
            const Frame& f0 = grids.at(firstGrid).frame;
            if (!g.frame.sameGrid(f0))
                fail("CSG: grids '", firstGrid, "' (", f0.width(), " x ", f0.height(), " x ", f0.depth(),
                     ", box ", boxString(f0.box()), ") and '", path, "' (", g.frame.width(), " x ",
                     g.frame.height(), " x ", g.frame.depth(), ", box ", boxString(g.frame.box()),
                     ") lie in different frames; grids combined by CSG must share one frame");
            continue;
        }
        const Mesh& mesh = meshes.emplace(path, loadMesh(path)).first->second;
        list.push_back({path, mesh.view(), fill, nullptr});
    }
    const double loadMs = msSince(t0);
    // What voxelize() decides per mesh (Fill::Auto: flood for an open one), printed below.
    std::vector<VoxelizeReport> reports(list.size());
    for (size_t i = 0; i < list.size(); ++i) list[i].report = &reports[i];

    const FitOptions fit = toFitOptions(a.fit, kCsgFit);
    VoxelizeOptions vo;
    vo.threads = a.threads;
    const auto tv = Clock::now();
    VoxelGrid grid;
    if (grids.empty()) {
        grid = voxelizeCsg(root, list, fit, vo);
    } else {
        // With grid leaves the frame is theirs; meshes are voxelized into it.
        grid.frame = grids.at(firstGrid).frame;
        grid.bits = evaluateCsg(root, [&](const std::string& path) {
            if (auto it = grids.find(path); it != grids.end()) return it->second.bits;
            const CsgMesh& m =
                *std::find_if(list.begin(), list.end(), [&](const CsgMesh& x) { return x.path == path; });
            VoxelizeOptions mv = vo;
            mv.fill = m.fill;
            mv.report = m.report;
            return std::move(voxelize(m.mesh, grid.frame, mv).bits);
        });
    }
    const double csgMs = msSince(tv);
    for (size_t i = 0; i < list.size(); ++i)
        if (!reports[i].fillNote.empty() && !a.quiet)
            std::cerr << "voxfx: " << list[i].path << ": " << reports[i].fillNote << "\n";
    const double writeMs = writeGridOutput(grid, a.output, a.vdbFloat);
    if (!a.quiet) {
        const Vec3i d = grid.worldDims();
        std::cout << toString(root) << ": " << list.size() << " meshes"
                  << (grids.empty() ? std::string() : ", " + std::to_string(grids.size()) + " grids")
                  << " -> " << d.x << " x " << d.y << " x " << d.z << " grid (cell "
                  << fmt(grid.frame.cellSize().x, 4) << "), " << withCommas(grid.bits.count())
                  << " filled voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", voxelize + csg " << fmtMs(csgMs) << ", write "
                  << fmtMs(writeMs) << " -> " << a.output << " (" << toString(format) << ")\n";
    }
    return 0;
}

const char* kCsgHelp = R"(
Expression syntax (one argument; quote it for the shell):
  functional  difference(bunny.off, union(a.stl, "name with spaces.obj"))
  JSON        {"op":"difference","args":["bunny.off",{"op":"union","args":["a.stl","b.stl"]}]}
Operations: union, intersection, difference, xor (aliases: or, and, minus, sub). They take one
or more arguments and fold left: difference(a, b, c) = (a - b) - c.
Every mesh is voxelized as a solid (voxel centres inside) into one frame fitted to the union of
all their bounds; the operations are then bitwise OR, AND, AND-NOT and XOR of the grids.
Leaves may also be grid files (.binvox .vdb .nrrd): they must all share one frame (an error
says how they differ), and the meshes are then voxelized into that frame (-r is ignored).
Parse errors give the column where parsing stopped.)";

const Command kCsg{
    "csg", "Voxelize a CSG expression of meshes into one grid", [](CLI::App& app) {
        app.footer(kCsgHelp);
        auto a = std::make_shared<CsgArgs>();
        app.add_option("EXPRESSION", a->expression,
                       "CSG expression over mesh or grid paths (functional or JSON)")
            ->required();
        app.add_option("-o,--output", a->output, "Output grid: .binvox .vdb .nrrd .ply .obj")->required();
        addFitOptions(app, a->fit, kCsgFit);
        app.add_option("--fill", a->fill,
                       "auto | parity | flood | vote | winding (auto: parity for closed meshes)")
            ->default_val("auto");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (results are identical)")
            ->check(CLI::NonNegativeNumber)
            ->default_val(0);
        app.add_flag("--vdb-float", a->vdbFloat, "Write a FloatGrid instead of a BoolGrid");
        app.add_flag("-q,--quiet", a->quiet, "No summary");
        return std::function<int()>([a] { return runCsg(*a); });
    }};

} // namespace
} // namespace voxfx::cli
