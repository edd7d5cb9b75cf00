// voxfx voxelize MESH -o GRID — mesh to voxel grid in any mode, with the summary line.
#include <iostream>

#include "cli_common.hpp"
#include "grid_input.hpp"

namespace voxfx::cli {
namespace {

struct VoxelizeArgs {
    std::string input, output;
    FitArgs fit;
    VoxelizeChoiceArgs choice;
    int threads = 0;
    std::string device = "cpu";
    bool quiet = false;
};

int runVoxelize(const VoxelizeArgs& a) {
    const auto t0 = Clock::now();
    // Everything that can be checked before the work starts is checked here, so a bad output
    // name does not cost a voxelization.
    const GridFormat format = gridFormatFromPath(a.output);
    VoxelizeOptions vo = toVoxelizeOptions(a.choice);
    vo.threads = a.threads;
    vo.device = parseDevice(a.device);
    std::string deviceNote;
    vo.deviceNote = &deviceNote;
    FitOptions fo = toFitOptions(a.fit, voxelizeFitChoices());
    fo.axis = parseAxis(a.choice.axis);

    MeshLoadReport report;
    const Mesh mesh = loadMesh(a.input, &report);
    const double loadMs = msSince(t0);

    // Fill::Auto is decided by voxelize() (reported in `decided`); an explicit parity on an open
    // mesh gets a warning.
    const bool needsInside = needsFill(vo.mode);
    VoxelizeReport decided;
    vo.report = &decided;
    if (needsInside && vo.fill == Fill::Parity && !a.quiet && !analyzeTopology(mesh.view()).closed())
        std::cerr << "voxfx: warning: " << a.input
                  << " is not closed; parity may fill wrong cells (try --fill flood, --fill gwn or "
                     "--fill vote)\n";

    const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
    ProgressLine progress("voxelizing", !a.quiet);
    vo.progress = &progress;
    const auto tv = Clock::now();
    const VoxelGrid grid = voxelize(mesh.view(), frame, vo);
    const double voxelMs = msSince(tv);
    progress.done();
    if (!decided.fillNote.empty() && !a.quiet)
        std::cerr << "voxfx: " << a.input << ": " << decided.fillNote << "\n";
    if (!deviceNote.empty() && vo.device == Device::Cuda && !a.quiet)
        std::cerr << "voxfx: --device cuda: " << deviceNote << "\n";
    const bool onGpu = vo.device != Device::Cpu && deviceNote.empty();
    const int64_t filled = grid.bits.count();

    const auto tw = Clock::now();
    GridWriteOptions wo;
    wo.vdbFloat = a.choice.vdbFloat;
    writeGrid(grid, a.output, wo);
    const double writeMs = msSince(tw);

    if (!a.quiet) {
        const Vec3i d = grid.worldDims();
        const Vec3d cell = grid.frame.cellSize();
        std::cout << a.input << ": " << withCommas(int64_t(mesh.triangleCount())) << " triangles -> " << d.x
                  << " x " << d.y << " x " << d.z << " grid (cell " << fmt(cell.x, 4);
        if (cell.y != cell.x || cell.z != cell.x)
            std::cout << " x " << fmt(cell.y, 4) << " x " << fmt(cell.z, 4);
        std::cout << ", axis " << toString(grid.frame.axis()) << ", " << toString(vo.slicing) << " slicing), "
                  << toString(vo.mode);
        if (needsInside) std::cout << " (" << toString(decided.fill) << ")";
        std::cout << ", " << withCommas(filled) << " filled voxels\n";
        std::cout << "time: load " << fmtMs(loadMs) << ", voxelize " << fmtMs(voxelMs)
                  << (onGpu ? " on " + cudaStatus().device : std::string()) << ", write " << fmtMs(writeMs)
                  << ", total " << fmtMs(msSince(t0)) << " -> " << a.output << " (" << toString(format)
                  << ")\n";
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

Devices (--device; the grid is the same bit for bit on each):
  cpu      all cores (the default)
  cuda     the CUDA back end: every mode with the parity fill, mesh upload and grid download
           included in the time; without a GPU (or for another fill) it says why and runs on
           the CPU. `voxfx devices` shows whether a GPU is usable.
  auto     the GPU when it can take the job, else the CPU without a word

Formats (by extension): .binvox .vdb (BoolGrid "voxels", or float with --vdb-float)
  .nrrd (uint8) .ply/.obj (mesh of the filled voxels' exposed faces). Written atomically.)";

const Command kVoxelize{
    "voxelize", "Voxelize a mesh into a grid file (.binvox .vdb .nrrd .ply .obj)", [](CLI::App& app) {
        app.footer(kVoxelizeHelp);
        auto a = std::make_shared<VoxelizeArgs>();
        app.add_option("MESH", a->input, "Mesh file (off, obj, ply, stl, gltf, glb, ...)")->required();
        app.add_option("-o,--output", a->output, "Output grid: .binvox .vdb .nrrd .ply .obj")->required();
        addFitOptions(app, a->fit, voxelizeFitChoices());
        addVoxelizeChoiceOptions(app, a->choice);
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (results are identical)")
            ->default_val(0)
            ->check(CLI::NonNegativeNumber);
        app.add_option("--device", a->device, "Where to voxelize: cpu, cuda or auto (see below)")
            ->default_val("cpu");
        app.add_flag("-q,--quiet", a->quiet, "No summary or progress");
        return std::function<int()>([a] { return runVoxelize(*a); });
    }};

} // namespace
} // namespace voxfx::cli
