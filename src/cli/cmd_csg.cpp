// voxfx csg EXPRESSION -o OUT — a CSG tree of meshes, voxelized into one shared frame.
#include <algorithm>
#include <iostream>
#include <map>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/intersection_volume.hpp"
#include "voxfx/level_set.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/sparse_grid.hpp"

namespace voxfx::cli {
namespace {

struct CsgArgs {
    std::string expression, output, fill = "auto";
    FitArgs fit;
    int threads = 0;
    bool vdbFloat = false, quiet = false, volume = false, dense = false, sparse = false;
};

std::string frameString(const Frame& f) {
    return std::to_string(f.width()) + " x " + std::to_string(f.height()) + " x " +
           std::to_string(f.depth()) + ", box " + boxString(f.box());
}

// .vdb grid leaves (and meshes voxelized into their frame tile by tile) to a .vdb: OpenVDB's
// topology operations on the sparse trees, the dense grids never built.
// Returns false, with the grids made dense in `dense`, when they fit in memory (all leaves, the
// result and a mesh's grid) and --sparse was not given.
bool runSparseCsg(const CsgArgs& a, const CsgNode& root, const std::vector<std::string>& paths,
                  std::map<std::string, VoxelGrid>& dense) {
    const auto t0 = Clock::now();
    const Fill fill = parseFill(a.fill);
    std::map<std::string, SparseGrid> grids;
    std::map<std::string, Mesh> meshes;
    std::string firstGrid;
    for (const std::string& path : paths) {
        if (!isGridFile(path)) {
            meshes.emplace(path, loadMesh(path));
            continue;
        }
        const SparseGrid& g = grids.emplace(path, readSparseGrid(path)).first->second;
        if (firstGrid.empty()) firstGrid = path;
        const SparseGrid& g0 = grids.at(firstGrid);
        if (!g.frame().sameGrid(g0.frame()) || !(g.treeOrigin() == g0.treeOrigin()))
            fail("CSG: grids '", firstGrid, "' (", frameString(g0.frame()), ") and '", path, "' (",
                 frameString(g.frame()), ") lie in different frames",
                 g.frame().sameGrid(g0.frame()) ? " (index origins differ)" : "",
                 "; grids combined by CSG must share one frame");
    }
    const double loadMs = msSince(t0);
    const Frame frame = grids.at(firstGrid).frame();
    const Vec3i n = grids.at(firstGrid).dims();
    if (!a.sparse && (grids.size() + 2) * BitGrid::requiredBytes(n.x, n.y, n.z) <= availableMemoryBytes()) {
        for (auto& [path, g] : grids) dense.emplace(path, g.toDense());
        return false;
    }
    const auto tv = Clock::now();
    std::vector<std::pair<std::string, VoxelizeReport>> reports;
    const SparseGrid result = evaluateCsg(root, [&](const std::string& path) {
        if (auto it = grids.find(path); it != grids.end()) return it->second;
        VoxelizeOptions mv;
        mv.threads = a.threads;
        mv.fill = fill;
        VoxelizeReport report;
        mv.report = &report;
        SparseGrid g = voxelizeSparse(meshes.at(path).view(), frame, mv);
        if (!(g.treeOrigin() == grids.at(firstGrid).treeOrigin()))
            fail("CSG: the grids' index origin is not (0, 0, 0); combine them with meshes with --dense");
        reports.emplace_back(path, report);
        return g;
    });
    const double csgMs = msSince(tv);
    if (!a.quiet)
        for (const auto& [path, report] : reports)
            if (!report.fillNote.empty()) std::cerr << "voxfx: " << path << ": " << report.fillNote << "\n";
    const auto tw = Clock::now();
    GridWriteOptions wo;
    wo.vdbFloat = a.vdbFloat;
    writeGrid(result, a.output, wo);
    const double writeMs = msSince(tw);
    if (!a.quiet) {
        const Vec3i d = result.dims();
        std::cout << toString(root) << ": " << meshes.size() << " meshes, " << grids.size() << " grids -> "
                  << d.x << " x " << d.y << " x " << d.z << " grid (cell " << fmt(frame.cellSize().x, 4)
                  << ", sparse), " << withCommas(result.count()) << " filled voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", voxelize + csg " << fmtMs(csgMs)
                  << " (OpenVDB, sparse), write " << fmtMs(writeMs) << " -> " << a.output << " (vdb)\n";
    }
    return true;
}

// A level-set .vdb among the leaves (voxfx sdf ... -o x.vdb): OpenVDB's level-set CSG to a level
// set. paths[0] is the first level set: its lattice is the result's, and each mesh leaf becomes a
// level set on it (levelSetOfMesh: exact, nothing resampled).
int runLevelSetCsg(const CsgArgs& a, const CsgNode& root, const std::vector<std::string>& paths) {
    const auto t0 = Clock::now();
    if (a.output.empty() || gridFormatFromPath(a.output) != GridFormat::Vdb)
        fail("CSG of level sets writes a level set: give -o OUT.vdb");
    if (a.volume) fail("--volume counts cells of occupancy grids; it does not take level sets");
    SdfOptions so;
    so.fill = parseFill(a.fill);
    so.threads = a.threads;
    std::map<std::string, LevelSet> sets;
    std::map<std::string, Mesh> meshes;
    for (const std::string& path : paths) {
        if (!isGridFile(path)) {
            meshes.emplace(path, loadMesh(path));
            continue;
        }
        if (gridFormatFromPath(path) != GridFormat::Vdb)
            fail("CSG: '", paths.front(), "' is a level set but '", path,
                 "' is an occupancy grid; level sets combine with level sets and meshes (make one with "
                 "`voxfx sdf MESH -o x.vdb`)");
        std::string what;
        if (!isLevelSetFile(path, &what))
            fail("CSG: '", paths.front(), "' is a level set but '", path, "' is not: ", what,
                 "; level sets combine with level sets and meshes (make one with `voxfx sdf MESH -o x.vdb`)");
        sets.emplace(path, readLevelSet(path));
    }
    const double loadMs = msSince(t0);
    const LevelSet& lattice = sets.at(paths.front());
    if (!meshes.empty()) {
        // Checked before the distances are computed: what levelSetOfMesh needs of the lattice.
        const Vec3d vs = lattice.voxelSize();
        if (!lattice.axisAligned() || !(vs.x == vs.y && vs.y == vs.z))
            fail("CSG: meshes join level set '", paths.front(),
                 "' on its lattice, which needs axis-aligned cubic "
                 "voxels; its voxels are ",
                 vs.x, " x ", vs.y, " x ", vs.z,
                 lattice.axisAligned() ? "" : " in a rotated, sheared, mirrored or non-linear transform",
                 " (make the mesh's level set with `voxfx sdf` and combine the two: resampled)");
    }
    // The meshes' exact fields on the lattice.
    const auto ts = Clock::now();
    ProgressLine progress("distances", !a.quiet && !meshes.empty());
    so.progress = &progress;
    std::vector<std::string> notes;
    withThreads(a.threads, [&] {
        for (const auto& [path, mesh] : meshes) {
            if (so.fill == Fill::Auto && !a.quiet && !analyzeTopology(mesh.view()).closed())
                notes.push_back(path +
                                ": not closed: the sign is the generalized winding number's (gwn >= 1/2)");
            sets.emplace(path, levelSetOfMesh(mesh.view(), lattice, so));
        }
    });
    progress.done();
    for (const std::string& note : notes) std::cerr << "voxfx: " << note << "\n";
    const double sdfMs = msSince(ts);
    const auto tc = Clock::now();
    int resampled = 0;
    LevelSet result;
    withThreads(a.threads, [&] {
        result = evaluateLevelSetCsg(
            root, [&](const std::string& path) { return sets.at(path); }, &resampled);
    });
    const double csgMs = msSince(tc);
    if (resampled > 0 && !a.quiet)
        std::cerr << "voxfx: " << resampled << " operand" << (resampled > 1 ? "s" : "")
                  << " resampled onto the first level set's grid (OpenVDB's resampleToMatch: a level-set "
                     "rebuild, approximate)\n";
    const auto tw = Clock::now();
    writeLevelSet(result, a.output);
    const double writeMs = msSince(tw);
    if (!a.quiet) {
        std::cout << toString(root) << ": " << sets.size() - meshes.size() << " level set"
                  << (sets.size() - meshes.size() > 1 ? "s" : "");
        if (!meshes.empty())
            std::cout << ", " << meshes.size() << " mesh" << (meshes.size() > 1 ? "es" : "")
                      << " on the first's lattice";
        std::cout << " -> level set (voxel " << fmt(result.voxelSize().x, 4) << ", band "
                  << fmt(result.bandVoxels(), 4) << " voxels (" << fmt(result.background(), 4) << ")), "
                  << withCommas(result.activeCount()) << " active voxels\n";
        std::cout << "time: load " << fmtMs(loadMs);
        if (!meshes.empty()) std::cout << ", mesh distances " << fmtMs(sdfMs);
        std::cout << ", csg " << fmtMs(csgMs) << " (OpenVDB level sets), write " << fmtMs(writeMs) << " -> "
                  << a.output << " (vdb level set)\n";
    }
    return 0;
}

const FitChoices kCsgFit = [] {
    FitChoices c;
    c.voxelSize = true;
    return c;
}();

// GI08 §7: the volume of the result (intersection(a, b): the objects' intersection volume, for
// collision and haptics) with its bound from every leaf's cells (voxfx/intersection_volume.hpp).
void printVolume(const CsgNode& root, const VoxelGrid& grid, const std::map<std::string, VoxelGrid>& grids,
                 const std::vector<CsgMesh>& meshes, const VoxelizeOptions& vo) {
    const CsgBounds bounds = evaluateCsgBounds(root, [&](const std::string& path) {
        if (auto it = grids.find(path); it != grids.end()) return CsgBounds{it->second.bits, it->second.bits};
        const CsgMesh& m =
            *std::find_if(meshes.begin(), meshes.end(), [&](const CsgMesh& x) { return x.path == path; });
        VoxelizeOptions mv = vo;
        mv.fill = m.fill;
        return voxelizeCsgBounds(m.mesh, grid.frame, mv);
    });
    const VolumeEstimate e = estimateVolume(grid, bounds);
    std::cout << "volume: " << fmt(e.volume, 8) << " +- " << fmt(e.errorBound, 3) << " ("
              << withCommas(e.cells) << " cells of "
              << fmt(e.volume / double(std::max<int64_t>(e.cells, 1)), 4) << "; the exact volume lies in ["
              << fmt(e.lowerVolume, 8) << ", " << fmt(e.upperVolume, 8) << "], "
              << withCommas(e.uncertainCells) << " cells on a surface)\n";
}

int runCsg(const CsgArgs& a) {
    const auto t0 = Clock::now();
    if (a.output.empty() && !a.volume) fail("csg needs -o OUT, --volume or both");
    const GridFormat format = a.output.empty() ? GridFormat::Vdb : gridFormatFromPath(a.output);
    const CsgNode root = parseCsgExpression(a.expression);
    const Fill fill = parseFill(a.fill);
    std::map<std::string, VoxelGrid> preloaded;
    {
        // Grid leaves all .vdb, output .vdb, no --volume: the sparse path.
        const std::vector<std::string> paths = csgMeshes(root);
        // Level sets: when any leaf is one (the others must be level sets or meshes).
        for (const std::string& path : paths)
            if (isGridFile(path) && gridFormatFromPath(path) == GridFormat::Vdb && isLevelSetFile(path)) {
                std::vector<std::string> ordered{path};
                for (const std::string& p : paths)
                    if (p != path) ordered.push_back(p);
                return runLevelSetCsg(a, root, ordered);
            }
        bool anyGrid = false, allVdb = true;
        for (const std::string& path : paths)
            if (isGridFile(path)) {
                anyGrid = true;
                allVdb = allVdb && gridFormatFromPath(path) == GridFormat::Vdb;
            }
        if (!a.dense && !a.volume && !a.output.empty() && format == GridFormat::Vdb && anyGrid && allVdb) {
            bool done = false;
            withThreads(a.threads, [&] { done = runSparseCsg(a, root, paths, preloaded); });
            if (done) return 0;
        } else if (a.sparse) {
            fail("--sparse needs .vdb grid leaves, a .vdb output and no --volume");
        }
    }

    // Every leaf is loaded once: grid files (.binvox .vdb .nrrd) as grids, anything else as a
    // mesh; open meshes get the flood fill unless a fill is forced.
    std::map<std::string, Mesh> meshes;
    std::map<std::string, VoxelGrid> grids;
    std::vector<CsgMesh> list;
    std::string firstGrid;
    for (const std::string& path : csgMeshes(root)) {
        if (isGridFile(path)) {
            auto pre = preloaded.find(path);
            const VoxelGrid& g =
                grids.emplace(path, pre != preloaded.end() ? std::move(pre->second) : readGrid(path))
                    .first->second;
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
    if (a.volume) printVolume(root, grid, grids, list, vo);
    const double writeMs = a.output.empty() ? 0.0 : writeGridOutput(grid, a.output, a.vdbFloat);
    if (!a.quiet) {
        const Vec3i d = grid.worldDims();
        std::cout << toString(root) << ": " << list.size() << " meshes"
                  << (grids.empty() ? std::string() : ", " + std::to_string(grids.size()) + " grids")
                  << " -> " << d.x << " x " << d.y << " x " << d.z << " grid (cell "
                  << fmt(grid.frame.cellSize().x, 4) << "), " << withCommas(grid.bits.count())
                  << " filled voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", voxelize + csg " << fmtMs(csgMs);
        if (!a.output.empty())
            std::cout << ", write " << fmtMs(writeMs) << " -> " << a.output << " (" << toString(format)
                      << ")";
        std::cout << "\n";
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
Parse errors give the column where parsing stopped.
--volume prints the result's volume: its cells times their volume, with the bound that holds
against the meshes' exact solids (cells a surface passes through may hold any part of their
volume; a grid leaf counts as exact). intersection(a, b) is GI08's intersection volume, for
collision and haptics.
When every grid leaf is a .vdb and so is the output (without --volume), and the dense grids do
not fit in memory (or VOXFX_MEMORY_LIMIT), the grids stay sparse: OpenVDB's topology union,
intersection and difference on their trees (xor as (a | b) - (a & b)), meshes voxelized into the
grids' frame tile by tile, bit for bit the dense result, in memory that grows with the surface.
--sparse forces that path, --dense refuses it.
Level sets: when the leaves are level-set .vdb files (voxfx sdf MESH -o x.vdb, or any OpenVDB
FloatGrid of class level set), the result is a level set .vdb by OpenVDB's csgUnion,
csgIntersection and csgDifference (xor as union minus intersection): per voxel min(a, b),
max(a, b) and max(a, -b). The sign is exact (the combined solid's, where the inputs' are); the
value is the exact distance where the nearest surface point lies on one input's part of the
result (outside a union, inside an intersection) and a lower bound near the creases where the
surfaces meet. The result has the first leaf's transform and band. A leaf with another
transform (another voxel size or origin, e.g. fitted to another mesh) is resampled onto it
with OpenVDB's resampleToMatch (a level-set rebuild: approximate, within about a voxel, edges
slightly rounded, and much slower; a note says so). For exact results make the
level sets on one grid: voxfx sdf with the same --bounds and -r or --voxel-size.
Meshes may join level sets: each mesh leaf becomes the level set of its exact signed distance
field on the first level set's lattice (its voxel centres, band and transform; the voxels
around the mesh, wherever it lies), so nothing is resampled and the result is exact as above
(difference(a.vdb, b.obj): max(a, -distance to b) at every voxel). That lattice needs cubic,
axis-aligned voxels. --fill picks the meshes' sign (auto: parity when closed, else the
generalized winding number). An occupancy grid among level-set leaves is an error.)";

const Command kCsg{
    "csg", "Voxelize a CSG expression of meshes into one grid", [](CLI::App& app) {
        app.footer(kCsgHelp);
        auto a = std::make_shared<CsgArgs>();
        app.add_option("EXPRESSION", a->expression,
                       "CSG expression over mesh or grid paths (functional or JSON)")
            ->required();
        app.add_option("-o,--output", a->output, "Output grid: .binvox .vdb .nrrd .ply .obj");
        addFitOptions(app, a->fit, kCsgFit);
        app.add_option("--fill", a->fill,
                       "auto | parity | flood | vote | winding (auto: parity for closed meshes)")
            ->default_val("auto");
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (results are identical)")
            ->check(CLI::NonNegativeNumber)
            ->default_val(0);
        app.add_flag("--vdb-float", a->vdbFloat, "Write a FloatGrid instead of a BoolGrid");
        auto* dense = app.add_flag("--dense", a->dense, ".vdb grids to .vdb: never the sparse trees");
        app.add_flag("--sparse", a->sparse, ".vdb grids to .vdb: the sparse trees even when dense grids fit")
            ->excludes(dense);
        app.add_flag("--volume", a->volume,
                     "Print the result's volume (world units) and its error bound (-o then optional)");
        app.add_flag("-q,--quiet", a->quiet, "No summary");
        return std::function<int()>([a] { return runCsg(*a); });
    }};

} // namespace
} // namespace voxfx::cli
