// voxfx — the command line: a thin client of the public headers in include/voxfx/.
// It parses arguments, calls the library, prints a summary, and is the one place that catches.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include "voxfx/voxfx.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string withCommas(int64_t v) {
    std::string s = std::to_string(v < 0 ? -v : v);
    for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(size_t(i), ",");
    return v < 0 ? "-" + s : s;
}

std::string fmt(double v, int precision = 3) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    return buf;
}

std::string fmtMs(double ms) {
    char buf[64];
    if (ms < 1000)
        std::snprintf(buf, sizeof buf, "%.1f ms", ms);
    else
        std::snprintf(buf, sizeof buf, "%.2f s", ms / 1000);
    return buf;
}

// A one-line progress indicator on stderr, shown only on a terminal and only for long work.
class ProgressLine : public voxfx::Progress {
public:
    ProgressLine(std::string label, bool enabled)
        : label_(std::move(label)), enabled_(enabled && isatty(2)) {}
    ~ProgressLine() override { done(); }
    bool update(double fraction) override {
        if (!enabled_ || msSince(start_) < 300) return true;
        const int pct = int(fraction * 100);
        if (pct != last_) {
            std::fprintf(stderr, "\r%s %3d%%", label_.c_str(), pct);
            std::fflush(stderr);
            last_ = pct;
            shown_ = true;
        }
        return true;
    }
    void done() {
        if (shown_) std::fprintf(stderr, "\r%*s\r", int(label_.size()) + 6, "");
        shown_ = false;
    }

private:
    std::string label_;
    bool enabled_;
    bool shown_ = false;
    int last_ = -1;
    Clock::time_point start_ = Clock::now();
};

std::string boxString(const voxfx::Box3d& b) {
    return "[" + fmt(b.lo.x, 6) + ", " + fmt(b.lo.y, 6) + ", " + fmt(b.lo.z, 6) + "] .. [" + fmt(b.hi.x, 6) +
           ", " + fmt(b.hi.y, 6) + ", " + fmt(b.hi.z, 6) + "]";
}

int runInfo(const std::string& path) {
    const auto t0 = Clock::now();
    voxfx::MeshLoadReport report;
    const voxfx::Mesh mesh = voxfx::loadMesh(path, &report);
    const double loadMs = msSince(t0);
    const voxfx::MeshTopology topo = voxfx::analyzeTopology(mesh.view());
    const voxfx::Box3d b = voxfx::computeBounds(mesh.view());
    std::cout << "file:       " << path << " (" << report.format << ", "
              << withCommas(int64_t(report.fileBytes)) << " bytes, loaded in " << fmtMs(loadMs) << ")\n";
    std::cout << "vertices:   " << withCommas(int64_t(mesh.positions.size())) << "\n";
    std::cout << "triangles:  " << withCommas(int64_t(mesh.triangleCount()));
    if (report.degenerateRemoved)
        std::cout << " (" << withCommas(int64_t(report.degenerateRemoved)) << " degenerate dropped)";
    std::cout << "\nbounds:     " << boxString(b) << "\n";
    const voxfx::Vec3d e = b.extent();
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

struct VoxelizeArgs {
    std::string input, output;
    int64_t resolution = 0;
    double voxelSize = 0;
    std::vector<int64_t> dims;
    std::vector<double> bounds;
    int64_t margin = 0;
    std::string mode = "solid", fill = "auto", axis = "z", slicing = "uniform";
    int threads = 0;
    bool vdbFloat = false, quiet = false;
};

int runVoxelize(const VoxelizeArgs& a) {
    const auto t0 = Clock::now();
    // Everything that can be checked before the work starts is checked here, so a bad output
    // name does not cost a voxelization.
    const voxfx::GridFormat format = voxfx::gridFormatFromPath(a.output);
    voxfx::VoxelizeOptions vo;
    vo.mode = voxfx::parseVoxelizeMode(a.mode);
    vo.slicing = voxfx::parseSlicing(a.slicing);
    vo.threads = a.threads;
    voxfx::FitOptions fo;
    fo.axis = voxfx::parseAxis(a.axis);
    fo.resolution = a.resolution;
    fo.voxelSize = a.voxelSize;
    fo.marginCells = a.margin;
    if (!a.dims.empty()) fo.dims = {a.dims[0], a.dims[1], a.dims[2]};
    if (!a.bounds.empty()) {
        fo.bounds.lo = {a.bounds[0], a.bounds[1], a.bounds[2]};
        fo.bounds.hi = {a.bounds[3], a.bounds[4], a.bounds[5]};
        if (fo.bounds.empty()) voxfx::fail("--bounds needs min <= max on every axis");
    }
    if (fo.resolution == 0 && fo.voxelSize == 0 && a.dims.empty()) fo.resolution = 256;

    voxfx::MeshLoadReport report;
    const voxfx::Mesh mesh = voxfx::loadMesh(a.input, &report);
    const double loadMs = msSince(t0);

    // Parity is exact for closed meshes only: detect open ones and pick the robust fill.
    const voxfx::MeshTopology topo = voxfx::analyzeTopology(mesh.view());
    const bool needsInside = vo.mode == voxfx::VoxelizeMode::Solid ||
                             vo.mode == voxfx::VoxelizeMode::SolidConservative ||
                             vo.mode == voxfx::VoxelizeMode::Interior;
    if (a.fill == "auto") {
        vo.fill = topo.closed() ? voxfx::Fill::Parity : voxfx::Fill::Flood;
        if (needsInside && !topo.closed() && !a.quiet)
            std::cerr
                << "voxfx: " << a.input << " is not closed (" << topo.boundaryEdges << " boundary, "
                << topo.nonManifoldEdges << " non-manifold, " << topo.misorientedEdges
                << " misoriented edges): using --fill flood (holes wider than a voxel let the flood in)\n";
    } else {
        vo.fill = voxfx::parseFill(a.fill);
        if (needsInside && !topo.closed() && vo.fill == voxfx::Fill::Parity && !a.quiet)
            std::cerr << "voxfx: warning: " << a.input
                      << " is not closed; parity may fill wrong cells (try --fill flood or --fill vote)\n";
    }

    const voxfx::Frame frame = voxfx::fitFrame(voxfx::computeBounds(mesh.view()), fo);
    ProgressLine progress("voxelizing", !a.quiet);
    vo.progress = &progress;
    const auto tv = Clock::now();
    const voxfx::VoxelGrid grid = voxfx::voxelize(mesh.view(), frame, vo);
    const double voxelMs = msSince(tv);
    progress.done();
    const int64_t filled = grid.bits.count();

    const auto tw = Clock::now();
    voxfx::GridWriteOptions wo;
    wo.vdbFloat = a.vdbFloat;
    voxfx::writeGrid(grid, a.output, wo);
    const double writeMs = msSince(tw);

    if (!a.quiet) {
        const voxfx::Vec3i d = grid.worldDims();
        const voxfx::Vec3d cell = grid.frame.cellSize();
        std::cout << a.input << ": " << withCommas(int64_t(mesh.triangleCount())) << " triangles -> " << d.x
                  << " x " << d.y << " x " << d.z << " grid (cell " << fmt(cell.x, 4);
        if (cell.y != cell.x || cell.z != cell.x)
            std::cout << " x " << fmt(cell.y, 4) << " x " << fmt(cell.z, 4);
        std::cout << ", axis " << voxfx::toString(grid.frame.axis()) << ", " << voxfx::toString(vo.slicing)
                  << " slicing), " << voxfx::toString(vo.mode);
        if (needsInside) std::cout << " (" << voxfx::toString(vo.fill) << ")";
        std::cout << ", " << withCommas(filled) << " filled voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", voxelize " << fmtMs(voxelMs) << ", write "
                  << fmtMs(writeMs) << ", total " << fmtMs(msSince(t0)) << " -> " << a.output << " ("
                  << voxfx::toString(format) << ")\n";
    }
    return 0;
}

const char* kVoxelizeHelp = R"(Voxelize a mesh into a grid file.

Grid placement (the half-voxel rule other tools trip over):
  The grid is a box of nx x ny x nz cubic cells. Voxel (i, j, k) covers
  [lo + (i, j, k) * cell, lo + (i+1, j+1, k+1) * cell]; its CENTRE is lo + (i + 0.5) * cell.
  Indices i, j, k run along world x, y, z. Solid/interior tests are made at voxel centres.
  --resolution N: the longest side of the mesh bounds gets exactly N cells and the box equals
    the bounds along it; the other axes get ceil(extent / cell) cells, centred on the bounds.
  --voxel-size S: cells of edge S, ceil(extent / S) of them per axis, centred on the bounds.
  --dims NX NY NZ: the bounds split into exactly that many (possibly non-cubic) cells.
  --margin M adds M empty cells on every side (default 0: surface voxels may touch the border).

Modes:
  surface             ED06: one voxel per column and triangle (holes on steep triangles)
  conservative        every voxel the surface touches (26-separating, exact)
  solid               voxels whose centre is inside (parity of crossings, exact; GI08)
  solid-conservative  solid + conservative surface
  interior            solid minus conservative surface: strictly inside

Fills (how inside is decided; default auto = parity for closed meshes, flood otherwise):
  parity   exact for closed meshes; overlapping parts give their symmetric difference
  flood    not reachable from the border through the conservative surface: robust to
           holes narrower than a voxel, includes the surface voxels
  vote     majority of parity along x, y and z: robust to a few bad triangles, 3x cost
  winding  nonzero winding number: union of overlapping closed parts (needs consistent
           orientation)

Formats (by extension): .binvox .vdb (BoolGrid "voxels", or float with --vdb-float)
  .nrrd (uint8) .ply/.obj (mesh of the filled voxels' exposed faces). Written atomically.)";

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"voxfx: fast, exact voxelization of triangle meshes into bit grids (slicemaps)"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "voxfx 0.1.0");

    std::string infoPath;
    auto* info = app.add_subcommand("info", "Print a mesh's triangles, bounds and whether it is closed");
    info->add_option("MESH", infoPath, "Mesh file (off, obj, ply, stl, gltf, glb, ...)")->required();

    VoxelizeArgs va;
    auto* vox = app.add_subcommand("voxelize", kVoxelizeHelp);
    vox->add_option("MESH", va.input, "Mesh file (off, obj, ply, stl, gltf, glb, ...)")->required();
    vox->add_option("-o,--output", va.output, "Output grid: .binvox .vdb .nrrd .ply .obj")->required();
    auto* res =
        vox->add_option("-r,--resolution", va.resolution, "Cells along the longest side (default 256)")
            ->check(CLI::Range(int64_t(1), int64_t(1) << 20));
    auto* vs = vox->add_option("--voxel-size", va.voxelSize, "Edge length of a cubic cell, in mesh units")
                   ->check(CLI::PositiveNumber);
    auto* dims = vox->add_option("--dims", va.dims, "Exact cell counts along x y z (non-cubic cells)")
                     ->expected(3)
                     ->check(CLI::Range(int64_t(1), int64_t(1) << 20));
    res->excludes(vs)->excludes(dims);
    vs->excludes(dims);
    vox->add_option("--bounds", va.bounds,
                    "Box to voxelize instead of the mesh bounds: xmin ymin zmin xmax ymax zmax")
        ->expected(6);
    vox->add_option("--margin", va.margin, "Empty cells added on every side (default 0)")
        ->check(CLI::NonNegativeNumber);
    vox->add_option("-m,--mode", va.mode, "surface | conservative | solid | solid-conservative | interior")
        ->default_val("solid");
    vox->add_option("--fill", va.fill, "auto | parity | flood | vote | winding")->default_val("auto");
    vox->add_option("--axis", va.axis, "Slicing axis x | y | z (the result is the same voxels)")
        ->default_val("z");
    vox->add_option("--slicing", va.slicing,
                    "uniform | local (ED06 per-column near/far; resampled on export)")
        ->default_val("uniform");
    vox->add_option("-j,--threads", va.threads, "Worker threads, 0 = all (results are identical)")
        ->default_val(0)
        ->check(CLI::NonNegativeNumber);
    vox->add_flag("--vdb-float", va.vdbFloat,
                  "Write a FloatGrid (fog volume, 1 inside) instead of a BoolGrid");
    vox->add_flag("-q,--quiet", va.quiet, "No summary or progress");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) { return app.exit(e); }
    try {
        if (*info) return runInfo(infoPath);
        if (*vox) return runVoxelize(va);
    } catch (const voxfx::Error& e) {
        std::cerr << "voxfx: error: " << e.what() << "\n";
        return 1;
    } catch (const std::bad_alloc&) {
        std::cerr << "voxfx: error: out of memory\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "voxfx: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
