// Voxelization: voxelize (as `voxfx voxelize` does) and cuda_status.
#include "common.hpp"

namespace voxfx::python {
namespace {

struct VoxelizeRequest {
    std::string mode, fill, slicing, device;
    int threads = 0;
    bool sparse = false;
    int64_t padding = 0;
};

struct VoxelizeResult {
    GridPtr grid;
    std::shared_ptr<SparseGrid> sparse; ///< sparse=True: the tiles' tree, no dense grid
    std::string deviceNote;             ///< why a device="cuda" request ran on the CPU
};

/// What `voxfx voxelize` does between loading and writing: the voxelization into `frame` (in the
/// mesh's own coordinates); fill "auto" is the library's Fill::Auto (parity for closed meshes,
/// flood otherwise).
VoxelizeResult voxelizeMesh(const Mesh& mesh, const Frame& frame, const VoxelizeRequest& r,
                            Progress* progress, VoxelizeReport* report) {
    VoxelizeOptions vo;
    vo.device = parseDevice(r.device);
    std::string note;
    vo.deviceNote = &note;
    vo.mode = parseVoxelizeMode(r.mode);
    vo.slicing = parseSlicing(r.slicing);
    vo.threads = r.threads;
    vo.progress = progress;
    vo.fill = parseFill(r.fill); // Fill::Auto: voxelize() decides, as the CLI's does
    vo.emptyBorder = r.padding;  // the padding ring stays empty in every mode
    vo.report = report;
    if (r.sparse)
        return {nullptr, std::make_shared<SparseGrid>(voxelizeSparse(mesh.view(), frame, vo)),
                vo.device == Device::Cuda ? note : std::string()};
    auto grid = std::make_shared<VoxelGrid>(voxelize(mesh.view(), frame, vo));
    return {std::move(grid), nullptr, vo.device == Device::Cuda ? note : std::string()};
}

/// The frame in the mesh's own coordinates: like's (moved by -origin), or fitted to the mesh.
/// Fitting a padding p keeps p empty cells inside the resolution: resolution - 2p for the mesh,
/// p more on every side.
Frame voxelizeFrame(const PyMesh& mesh, FitOptions fo, const py::object& like, int64_t padding) {
    if (!like.is_none()) {
        if (!py::isinstance<VoxelGrid>(like)) throw py::type_error("like must be a voxfx.Grid");
        const Frame& f = like.cast<const VoxelGrid&>().frame;
        return mesh.shifted() ? asArgument([&] { return f.translated(mesh.origin * -1.0); }) : f;
    }
    if (padding < 0) throw ArgumentError("padding must be >= 0");
    if (padding > 0) {
        if (fo.resolution <= 2 * padding)
            throw ArgumentError("padding needs a resolution above 2 * padding (the cells left for the mesh)");
        fo.resolution -= 2 * padding;
        fo.marginCells += padding;
    }
    if (!fo.bounds.empty() && mesh.shifted()) {
        fo.bounds.lo = fo.bounds.lo - mesh.origin;
        fo.bounds.hi = fo.bounds.hi - mesh.origin;
    }
    asArgument([&] { validateMesh(mesh.mesh.view(), "mesh"); });
    return fitFrame(computeBounds(mesh.mesh.view()), fo);
}

/// Warns when dims make the cells of a fitted grid unequal (the mesh stretched).
void warnIfStretched(const Frame& frame, const std::optional<std::vector<int64_t>>& dims) {
    if (!dims) return;
    const Vec3d c = frame.cellSize();
    const double lo = std::min({c.x, c.y, c.z}), hi = std::max({c.x, c.y, c.z});
    if (hi <= lo * (1 + 1e-9)) return;
    const std::string text =
        "voxelize: dims (" + std::to_string((*dims)[0]) + ", " + std::to_string((*dims)[1]) + ", " +
        std::to_string((*dims)[2]) + ") give cells of " + std::string(py::str(vec3(c))) +
        ": not cubic, the mesh is stretched; resolution=N with cube=True keeps cells cubic";
    if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 2) != 0) throw py::error_already_set();
}

} // namespace

void bindVoxelize(py::module_& m) {
    m.def(
        "voxelize",
        [](const py::object& meshObj, const py::object& faces, std::optional<Int> resolution,
           std::optional<double> voxelSize, std::optional<std::vector<int64_t>> dims,
           const py::object& bounds, Int margin, bool cube, Int padding, const py::object& like,
           const std::string& mode, const std::string& fill, const std::string& axis,
           const std::string& slicing, int threads, const std::string& device, bool sparse) -> py::object {
            const auto mesh = meshArgument(meshObj, faces);
            if (!like.is_none() &&
                (resolution || voxelSize || dims || !bounds.is_none() || margin || cube || padding))
                throw ArgumentError(
                    "like=grid takes that grid's frame: give no resolution, voxel_size, dims, "
                    "bounds, margin, cube or padding with it");
            const FitOptions fo = fitOptions(resolution, voxelSize, dims, bounds, margin, axis, cube);
            if (threads < 0) throw ArgumentError("threads must be >= 0");
            const VoxelizeRequest request{
                mode, fill, slicing, device, threads, sparse, like.is_none() ? int64_t(padding) : 0};
            asArgument([&] {
                parseVoxelizeMode(mode), parseSlicing(slicing), parseDevice(device);
                parseFill(fill);
            });
            FitOptions fit = fo;
            fit.checkDenseMemory = !sparse; // a sparse grid is checked against the budget as it grows
            const Frame frame = voxelizeFrame(*mesh, fit, like, padding);
            if (like.is_none()) warnIfStretched(frame, dims);
            VoxelizeResult result;
            VoxelizeReport report;
            interruptible(
                [&](Cancel& cancel) { result = voxelizeMesh(mesh->mesh, frame, request, &cancel, &report); });
            // A fill that cannot be trusted on this mesh says so (the CLI's line on stderr): an
            // open mesh filled by flood leaks where its holes are wider than a voxel.
            if (!report.fillNote.empty() &&
                PyErr_WarnEx(PyExc_RuntimeWarning, ("voxelize: the mesh is " + report.fillNote).c_str(), 1) !=
                    0)
                throw py::error_already_set();
            if (mesh->shifted() && result.sparse) {
                result.sparse->translate(mesh->origin);
            } else if (mesh->shifted()) {
                VoxelGrid& g = *result.grid;
                g.frame = g.frame.translated(mesh->origin);
            }
            // device="cuda" without a usable GPU: the CPU's grid, and a RuntimeWarning saying why.
            if (!result.deviceNote.empty() &&
                PyErr_WarnEx(PyExc_RuntimeWarning, ("device='cuda': " + result.deviceNote).c_str(), 1) != 0)
                throw py::error_already_set();
            if (result.sparse) return py::cast(result.sparse);
            return py::cast(result.grid);
        },
        py::arg("mesh"), py::arg("faces") = py::none(), py::kw_only(), py::arg("resolution") = py::none(),
        py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(), py::arg("bounds") = py::none(),
        py::arg("margin") = 0, py::arg("cube") = false, py::arg("padding") = 0, py::arg("like") = py::none(),
        py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("axis") = "z",
        py::arg("slicing") = "uniform", py::arg("threads") = 0, py::arg("device") = "cpu",
        py::arg("sparse") = false,
        "Voxelizes a mesh like `voxfx voxelize`. mesh: a voxfx.Mesh, an object with .vertices and .faces "
        "(trimesh; Open3D's .triangles; meshio's .points and .cells_dict), a (vertices, faces) pair, or "
        "vertices with faces=. The grid: resolution (cells along the longest side, default 256), voxel_size "
        "or dims (cells along x, y, z; a warning when they make cells unequal); cube=True: resolution^3 "
        "cubic cells, the mesh centred and never stretched; padding: empty cells kept on each side within "
        "the resolution; margin: empty cells added outside it; bounds (xmin ymin zmin xmax ymax zmax, or "
        "Grid.bounds' (lo, hi)); like=grid: that grid's frame exactly. mode surface | conservative | solid "
        "| solid-conservative | interior; fill auto | parity | flood | vote | winding | gwn (auto: parity "
        "for closed meshes, flood otherwise); threads 0 = all; device cpu | cuda | auto (the same grid; "
        "cuda without a usable GPU warns and runs on the CPU; see cuda_status()). sparse=True: a "
        "voxfx.SparseGrid voxelized tile by tile, no dense grid at any point (the same voxels; its "
        "coordinates() are the (N, 3) int32 cells; VOXFX_MEMORY_LIMIT caps it; like= takes no sparse "
        "grid). Ctrl-C stops it.");

    m.def(
        "cuda_status",
        [] {
            const CudaStatus& s = cudaStatus();
            py::dict d;
            d["built"] = s.built;
            d["available"] = s.available;
            d["device"] = s.device;
            d["reason"] = s.reason;
            return d;
        },
        "Whether the CUDA back end can run here: {'built', 'available', 'device', 'reason'}.");
}

} // namespace voxfx::python
