// voxfx voxelize MESH -o GRID — mesh to voxel grid in any mode, with the summary line; a volume
// with --threshold T becomes a bit grid on its own lattice (voxelize_volume.cpp).
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <vector>

#include <unistd.h>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxelize_volume.hpp"

namespace voxfx::cli {
namespace {

struct VoxelizeArgs {
    std::string input, output;
    FitArgs fit;
    VoxelizeChoiceArgs choice;
    int threads = 0;
    std::string device = "cpu";
    std::string memory;
    bool dense = false;
    bool quiet = false;
    bool volume = false; ///< --threshold given: the input is a volume
    double threshold = 0;
    std::string scheduler; ///< -o GRID.zarr: the Dask scheduler's address (none: a local cluster)
    int64_t brick = 128;   ///< -o GRID.zarr: the chunk edge
};

// -o GRID.zarr (or -o GRID.vdb --scheduler): one grid across a Dask cluster, brick by brick into
// a Zarr store (or .vdb regions, then merged). The work is Python's (voxfx.dask: Dask, Zarr), so this command
// hands its arguments to voxfx.dask._main in Python and becomes that process. The interpreter: VOXFX_PYTHON,
// else Debian's /usr/bin/python3 (the one with Dask and Zarr), else python3 on PATH; voxfx's package: the
// build tree's python/ beside this program, or the installed package this program is in.
[[noreturn]] void runVoxelizeZarr(const VoxelizeArgs& a) {
    if (a.volume) fail("-o ", a.output, ": volumes (--threshold) are not voxelized on a Dask cluster");
    if (a.choice.axis != "z" || a.choice.slicing != "uniform" || a.device != "cpu" || a.fit.padding ||
        a.dense || a.choice.vdbFloat)
        fail("-o ", a.output,
             ": a grid of a Dask cluster is sliced along z, uniformly, on the CPU (no --axis, --slicing, ",
             "--device, --padding, --dense or --vdb-float)");
    const auto exact = [](double v) { // every digit: the same frame in Python
        std::ostringstream o;
        o << std::setprecision(17) << v;
        return o.str();
    };
    // -c, not -m voxfx.dask: a local cluster's worker processes start by re-running the main
    // module (multiprocessing's spawn), which must not be this run's.
    std::vector<std::string> args = {"python3", "-c",
                                     "import sys, voxfx.dask; sys.exit(voxfx.dask._main(sys.argv[1:]))"};
    args.insert(args.end(), {"voxelize", a.input, "-o", a.output, "-m", a.choice.mode, "--fill",
                             a.choice.fill, "--brick", std::to_string(a.brick)});
    if (a.fit.voxelSize > 0) {
        args.insert(args.end(), {"--voxel-size", exact(a.fit.voxelSize)});
    } else if (a.fit.dims.size() == 3) {
        args.push_back("--dims");
        for (int64_t d : a.fit.dims) args.push_back(std::to_string(d));
    } else {
        args.insert(args.end(), {"-r", std::to_string(toFitOptions(a.fit, voxelizeFitChoices()).resolution)});
    }
    if (a.fit.bounds.size() == 6) {
        args.push_back("--bounds");
        for (double b : a.fit.bounds) args.push_back(exact(b));
    }
    if (a.fit.margin > 0) args.insert(args.end(), {"--margin", std::to_string(a.fit.margin)});
    if (a.fit.cube) args.push_back("--cube");
    if (!a.scheduler.empty()) args.insert(args.end(), {"--scheduler", a.scheduler});
    if (a.quiet) args.push_back("-q");
    // Where voxfx's Python package is, ahead of whatever PYTHONPATH holds.
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec),
                                dir = exe.parent_path();
    std::string path;
    for (const std::filesystem::path& p : {dir / "python", dir.parent_path()})
        if (std::filesystem::exists(p / "voxfx" / "dask.py", ec)) path += p.string() + ":";
    const char* old = std::getenv("PYTHONPATH");
    path += old ? old : "";
    if (!path.empty()) setenv("PYTHONPATH", path.c_str(), 1);
    const char* chosen = std::getenv("VOXFX_PYTHON");
    const std::string python = chosen && *chosen                                 ? chosen
                               : std::filesystem::exists("/usr/bin/python3", ec) ? "/usr/bin/python3"
                                                                                 : "python3";
    args[0] = python; // sys.executable, which a local cluster's worker processes are started with
    std::vector<char*> argv;
    for (std::string& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    std::cout.flush();
    execvp(python.c_str(), argv.data());
    fail("-o ", a.output, ": cannot run ", python, " for the Zarr output (", std::strerror(errno),
         "); it needs Python 3 with voxfx, Dask and Zarr (apt install python3-distributed python3-zarr)");
}

// --memory: the budget of every size check of the run, as VOXFX_MEMORY_LIMIT (which it sets, so
// the library's checks and the tiles' budget all see it).
void applyMemoryBudget(const std::string& memory) {
    if (memory.empty()) return;
    setenv("VOXFX_MEMORY_LIMIT", memory.c_str(), 1);
    try {
        availableMemoryBytes();
    } catch (const Error&) {
        fail("--memory must be bytes or a size with K, M, G or T (powers of 1024), got '", memory, "'");
    }
}

// What a run produced, for the summary.
struct VoxelizeRun {
    Frame frame;
    int64_t filled = 0;
    double voxelMs = 0, writeMs = 0;
    bool onGpu = false, sparse = false, tiled = false;
    std::string path; ///< which path ran and why (dense or tiled), for .vdb and for tiles
};

// "1.50 GiB" from 1 GiB up, "64.0 MiB" below.
std::string memoryText(uint64_t bytes) {
    const bool gib = bytes >= (uint64_t(1) << 30);
    return fmt(double(bytes) / double(uint64_t(1) << (gib ? 30 : 20)), 3) + (gib ? " GiB" : " MiB");
}

// .vdb without the dense grid: tiles straight into OpenVDB's tree (voxfx/sparse_grid.hpp).
VoxelizeRun runSparse(const Mesh& mesh, const Frame& frame, const VoxelizeOptions& vo,
                      const VoxelizeArgs& a) {
    VoxelizeRun r;
    r.sparse = true;
    ProgressLine progress("voxelizing", !a.quiet);
    VoxelizeOptions o = vo;
    o.progress = &progress;
    const auto tv = Clock::now();
    const SparseGrid grid = voxelizeSparse(mesh.view(), frame, o);
    r.voxelMs = msSince(tv);
    progress.done();
    // Flood and vote (asked for, or what auto chose) went through the whole grid.
    VoxelizeOptions chosen = o;
    if (o.report) chosen.fill = o.report->fill;
    r.tiled = wholeGridReason(frame, chosen).empty();
    r.frame = grid.frame();
    r.filled = grid.count();
    const auto tw = Clock::now();
    GridWriteOptions wo;
    wo.vdbFloat = a.choice.vdbFloat;
    writeGrid(grid, a.output, wo);
    r.writeMs = msSince(tw);
    return r;
}

VoxelizeRun runDense(const Mesh& mesh, const Frame& frame, VoxelizeOptions vo, const VoxelizeArgs& a) {
    VoxelizeRun r;
    std::string deviceNote;
    vo.deviceNote = &deviceNote;
    ProgressLine progress("voxelizing", !a.quiet);
    vo.progress = &progress;
    const auto tv = Clock::now();
    const VoxelGrid grid = voxelize(mesh.view(), frame, vo);
    r.voxelMs = msSince(tv);
    progress.done();
    if (!deviceNote.empty() && vo.device == Device::Cuda && !a.quiet)
        std::cerr << "voxfx: --device cuda: " << deviceNote << "\n";
    r.onGpu = vo.device != Device::Cpu && deviceNote.empty();
    r.frame = grid.frame;
    r.filled = grid.bits.count();
    r.writeMs = writeGridOutput(grid, a.output, a.choice.vdbFloat);
    return r;
}

int runVoxelize(const VoxelizeArgs& a) {
    if (a.volume) {
        refuseMeshOnlyOptions(a.fit, a.choice, a.device);
        return runVoxelizeVolume(
            {a.input, a.output, a.threshold, a.choice.axis, a.choice.vdbFloat, a.threads, a.quiet});
    }
    if (a.output.ends_with(".zarr") || a.output.ends_with(".zarr/")) runVoxelizeZarr(a);
    if (!a.scheduler.empty() && gridFormatFromPath(a.output) == GridFormat::Vdb) runVoxelizeZarr(a);
    if (!a.scheduler.empty())
        fail("--scheduler needs -o GRID.zarr or -o GRID.vdb (one grid across a Dask cluster)");
    const auto t0 = Clock::now();
    // Everything that can be checked before the work starts is checked here, so a bad output
    // name does not cost a voxelization.
    const GridFormat format = gridFormatFromPath(a.output);
    // A .vdb's OpenVDB module (~40 ms of the dynamic linker) loads beside the mesh load; what is
    // left of it is waited for before the voxelization (beside it, it took a core from the
    // rasterizer on 2 cores and cost more than it saved) and counted in the write.
    prepareGridFormat(a.output, /*background=*/true);
    applyMemoryBudget(a.memory);
    VoxelizeOptions vo = toVoxelizeOptions(a.choice);
    vo.threads = a.threads;
    vo.device = parseDevice(a.device);
    vo.emptyBorder = a.fit.padding; // --padding: the ring stays empty in every mode
    FitOptions fo = toFitOptions(a.fit, voxelizeFitChoices());
    fo.axis = parseAxis(a.choice.axis);
    // .vdb goes tile by tile into a sparse tree unless the dense grid is asked for (--dense,
    // local slicing, a GPU device); so do .binvox and .nrrd when the dense grid does not fit
    // (decided once the frame is known), streamed from the tree into the file in slabs.
    const bool canSparse = !a.dense && vo.slicing == Slicing::Uniform && vo.device == Device::Cpu;
    const bool streamable = format == GridFormat::Binvox || format == GridFormat::Nrrd;
    fo.checkDenseMemory = !canSparse || !(format == GridFormat::Vdb || streamable);

    MeshLoadReport report;
    const Mesh mesh = loadMesh(a.input, &report);
    const double loadMs = msSince(t0);
    const auto tm = Clock::now();
    prepareGridFormat(a.output);
    const double moduleMs = msSince(tm);

    // Fill::Auto is decided by voxelize() or voxelizeSparse() (reported in `decided`); an explicit
    // parity on an open mesh gets a warning.
    const bool needsInside = needsFill(vo.mode);
    VoxelizeReport decided;
    vo.report = &decided;
    if (needsInside && vo.fill == Fill::Parity && !a.quiet && !analyzeTopology(mesh.view()).closed())
        std::cerr << "voxfx: warning: " << a.input
                  << " is not closed; parity may fill wrong cells (try --fill flood, --fill gwn or "
                     "--fill vote)\n";

    const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
    // The whole grid when it fits the budget (the fast path), tiles into the sparse tree when it
    // does not. For .vdb the whole grid's path also holds the tree built from it, which for a
    // grid of surface (a leaf of 8^3 cells wherever the surface passes) can take about twice
    // the grid's bytes: it is estimated at three times the grid's bytes.
    bool sparse = false;
    std::string why;
    if (canSparse && (format == GridFormat::Vdb || streamable)) {
        const uint64_t denseBytes = BitGrid::requiredBytes(frame.width(), frame.height(), frame.depth());
        const uint64_t factor = format == GridFormat::Vdb ? 3 : 1;
        const uint64_t need = denseBytes > ~uint64_t(0) / factor ? ~uint64_t(0) : factor * denseBytes;
        const uint64_t budget = availableMemoryBytes();
        sparse = need > budget;
        why = detail::concat(memoryText(need), " for the whole grid",
                             format == GridFormat::Vdb ? " and its tree" : "", sparse ? ", over" : ", within",
                             " the budget of ", memoryText(budget));
    } else if (format == GridFormat::Vdb) {
        why = a.dense                          ? "--dense"
              : vo.slicing != Slicing::Uniform ? "local slicing needs the whole grid"
                                               : "--device needs the whole grid";
    }
    VoxelizeRun r = sparse ? runSparse(mesh, frame, vo, a) : runDense(mesh, frame, vo, a);
    r.writeMs += moduleMs;
    if (sparse)
        r.path = detail::concat(r.tiled ? "tiled: " : "whole grid, then the tree: ", why);
    else if (format == GridFormat::Vdb)
        r.path = detail::concat("dense: ", why);
    if (!decided.fillNote.empty() && !a.quiet)
        std::cerr << "voxfx: " << a.input << ": " << decided.fillNote << "\n";

    if (!a.quiet) {
        const VoxelGrid shape{r.frame, {}};
        const Vec3i d = shape.worldDims();
        const Vec3d cell = r.frame.cellSize();
        std::cout << a.input << ": " << withCommas(int64_t(mesh.triangleCount())) << " triangles -> " << d.x
                  << " x " << d.y << " x " << d.z << " grid (cell " << fmt(cell.x, 4);
        if (cell.y != cell.x || cell.z != cell.x)
            std::cout << " x " << fmt(cell.y, 4) << " x " << fmt(cell.z, 4);
        std::cout << ", axis " << toString(r.frame.axis()) << ", " << toString(vo.slicing) << " slicing), "
                  << toString(vo.mode);
        if (needsInside) std::cout << " (" << toString(decided.fill) << ")";
        std::cout << ", " << withCommas(r.filled) << " filled voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", voxelize " << fmtMs(r.voxelMs)
                  << (r.onGpu ? " on " + cudaStatus().device : std::string())
                  << (r.path.empty() ? std::string() : " (" + r.path + ")") << ", write " << fmtMs(r.writeMs)
                  << ", total " << fmtMs(msSince(t0)) << " -> " << a.output << " (" << toString(format)
                  << (r.sparse ? ", sparse" : "") << ")\n";
    }
    return 0;
}

const char* kVoxelizeHelp = R"(
Grid placement (the half-voxel rule other tools trip over):
  The grid is a box of nx x ny x nz cubic cells. Voxel (i, j, k) covers
  [lo + (i, j, k) * cell, lo + (i+1, j+1, k+1) * cell]; its CENTRE is lo + (i + 0.5) * cell.
  Indices i, j, k run along world x, y, z. Solid/interior tests are made at voxel centres.
  --resolution N: the longest side of the mesh bounds gets exactly N cells and the box equals
    the bounds along it; the other axes get ceil(extent / cell) cells, centred on the bounds.
  --voxel-size S: cells of edge S, ceil(extent / S) of them per axis, centred on the bounds.
  --dims NX NY NZ: the bounds split into exactly that many (possibly non-cubic) cells.
  --margin M adds M empty cells on every side (default 0: surface voxels may touch the border).
  Mesh vertices are floats: a vertex coordinate equal to a side of the box at float precision
  lies on that side (a face at y = -20.8600788 with --bounds -20.8600788 ... touches row 0).

Modes:
  surface             ED06: one voxel per column and triangle (holes on steep triangles)
  conservative        every voxel the surface touches (26-separating; exact to 1e-9 voxel)
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
  gwn      generalized winding number >= 0.5: closes holes wider than a voxel (needs
           consistent orientation)

Memory and tiles (--memory, VOXFX_MEMORY_LIMIT):
  .vdb output builds the whole grid and the tree from it when both fit the budget (estimated
  at 3x the grid's bytes: the fast path), and otherwise is voxelized tile by tile (bricks of
  128^3 cells, each column's parity carried from brick to brick) straight into OpenVDB's sparse
  tree: memory grows with the surface, not the volume (the bunny at -r 16384 fits in 4 GiB).
  The time line says which path ran and why. The voxels are the same bit for bit either way.
  Fills: parity, winding and gwn work tile by tile, in every mode. flood and vote need the
  whole grid: they voxelize it whole and convert it when that fits the budget. --fill auto
  picks flood for a mesh that is not closed, so for open meshes at large sizes give --fill gwn.
  .binvox and .nrrd build the whole grid when it fits the budget; when it does not, they go
  tile by tile into the sparse tree too and are streamed from it into the file in slabs (x for
  binvox, z for nrrd; an eighth of the budget each), the same bytes as the whole grid's file.
  .ply, .obj, --slicing local and --device cuda|auto build the whole grid (so does --dense).
  --memory SIZE caps what the run may use (bytes, or K, M, G, T in powers of 1024: 4G), for
  every size check, as VOXFX_MEMORY_LIMIT does; the default is the memory available now
  (MemAvailable, or VOXFX_MEMORY_LIMIT when smaller). A size that cannot fit stops before
  anything large is allocated, with one line saying what it needs and the budget: the whole
  grid's bytes, or the tiles' triangle lists; the sparse tree is checked as it grows. No output
  file is left behind by a run that fails.

Devices (--device; the grid is the same bit for bit on each):
  cpu      all cores (the default)
  cuda     the CUDA back end: every mode with the parity fill, mesh upload and grid download
           included in the time; without a GPU (or for another fill) it says why and runs on
           the CPU. `voxfx devices` shows whether a GPU is usable.
  auto     the GPU when it can take the job, else the CPU without a word

Volumes (--threshold T): the input is a scalar volume (.inr .inr.gz .nrrd .nhdr .json .vdb, any
  scalar type) and the grid is its own lattice, voxel for voxel, placed where the volume is: a
  cell is filled where its sample is >= T (GI08's bit grids of scans, for density, morph, csg
  and mesh). The fitting options, --mode, --fill, --slicing and --device do not apply.

Formats (by extension): .binvox .vdb (BoolGrid "voxels", or float with --vdb-float)
  .nrrd (uint8) .ply/.obj (mesh of the filled voxels' exposed faces). Written atomically.

One grid across a Dask cluster (-o GRID.zarr): bricks of --brick cells (default 128) voxelized
  as Dask tasks (voxfx.dask.voxelize_grid) on the cluster of --scheduler ADDRESS (none: a local
  cluster of this machine's cores) into a Zarr store: bool array "voxels" indexed [x, y, z], one
  chunk per brick (bits packed, zstd), empty bricks not written, the affine in its attributes;
  dask.array.from_zarr(GRID.zarr, component="voxels") reads it lazily. A rerun skips the bricks
  already done. Needs python3-distributed and python3-zarr; fills parity, winding and gwn.
  -o GRID.vdb with --scheduler: the same tasks write one .vdb per region into GRID.regions/
  (voxfx.dask.voxelize_regions; a rerun skips the regions done), then this command unites
  them into GRID.vdb as `voxfx merge GRID.regions -o GRID.vdb` does.)";

const Command kVoxelize{
    "voxelize", "Voxelize a mesh into a grid file (.binvox .vdb .nrrd .ply .obj .npy .npz)",
    [](CLI::App& app) {
        app.footer(kVoxelizeHelp);
        auto a = std::make_shared<VoxelizeArgs>();
        app.add_option("MESH", a->input,
                       "Mesh file (off, obj, ply, stl, gltf, glb, ...), or a volume with --threshold")
            ->required();
        app.add_option("-o,--output", a->output,
                       "Output grid: .binvox .vdb .nrrd .ply .obj .npy .npz, or .zarr (see below)")
            ->required();
        addFitOptions(app, a->fit, voxelizeFitChoices());
        addVoxelizeChoiceOptions(app, a->choice);
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (results are identical)")
            ->default_val(0)
            ->check(CLI::NonNegativeNumber);
        app.add_option("--device", a->device, "Where to voxelize: cpu, cuda or auto (see below)")
            ->default_val("cpu");
        app.add_option("--memory", a->memory, "Memory budget: bytes, or K, M, G, T (see below)");
        app.add_flag("--dense", a->dense, "Build the whole grid first for .vdb too (the path before tiles)");
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        app.add_option("--scheduler", a->scheduler,
                       "-o GRID.zarr: the Dask scheduler's address (tcp://host:8786); none: a local "
                       "cluster. With -o GRID.vdb: regions on that cluster, then merged");
        app.add_option("--brick", a->brick, "-o GRID.zarr: the chunk edge in cells (a multiple of 8)")
            ->default_val(128)
            ->check(CLI::PositiveNumber);
        CLI::Option* threshold =
            app.add_option("--threshold", a->threshold,
                           "The input is a volume: fill the cells whose sample is >= this value (see below)");
        return std::function<int()>([a, threshold] {
            a->volume = threshold->count() > 0;
            return runVoxelize(*a);
        });
    }};

} // namespace
} // namespace voxfx::cli
