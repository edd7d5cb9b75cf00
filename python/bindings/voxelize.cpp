// Voxelization: voxelize (as `voxfx voxelize` does) and cuda_status.
#include "common.hpp"

namespace voxfx::python {
namespace {

struct VoxelizeResult {
    GridPtr grid;
    Fill fill;
    std::string deviceNote; ///< why a device="cuda" request ran on the CPU
};

/// What `voxfx voxelize` does between loading and writing: the fill ("auto": parity for closed
/// meshes, flood otherwise), the fitted frame, the voxelization.
VoxelizeResult voxelizeMesh(const Mesh& mesh, const FitOptions& fo, const std::string& mode,
                            const std::string& fill, const std::string& slicing, int threads,
                            const std::string& device = "cpu") {
    VoxelizeOptions vo;
    vo.device = parseDevice(device);
    std::string note;
    vo.deviceNote = &note;
    vo.mode = parseVoxelizeMode(mode);
    vo.slicing = parseSlicing(slicing);
    vo.threads = threads;
    const bool inside = vo.mode == VoxelizeMode::Solid || vo.mode == VoxelizeMode::SolidConservative ||
                        vo.mode == VoxelizeMode::Interior;
    if (fill == "auto") {
        // The topology (hashing every edge) only matters where the fill does.
        vo.fill = inside && analyzeTopology(mesh.view()).closed() ? Fill::Parity : Fill::Flood;
    } else {
        vo.fill = parseFill(fill);
    }
    validateMesh(mesh.view(), "mesh");
    const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
    auto grid = std::make_shared<VoxelGrid>(voxelize(mesh.view(), frame, vo));
    return {std::move(grid), vo.fill, vo.device == Device::Cuda ? note : std::string()};
}

} // namespace

void bindVoxelize(py::module_& m) {
    m.def(
        "voxelize",
        [](const py::object& meshOrVertices, const py::object& faces, std::optional<int64_t> resolution,
           std::optional<double> voxelSize, std::optional<std::vector<int64_t>> dims,
           std::optional<std::vector<double>> bounds, int64_t margin, const std::string& mode,
           const std::string& fill, const std::string& axis, const std::string& slicing, int threads,
           const std::string& device) {
            const auto mesh = meshArgument(meshOrVertices, faces);
            const FitOptions fo = fitOptions(resolution, voxelSize, dims, bounds, margin, axis);
            if (threads < 0) throw py::value_error("threads must be >= 0");
            VoxelizeResult result;
            {
                py::gil_scoped_release release;
                result = voxelizeMesh(mesh->mesh, fo, mode, fill, slicing, threads, device);
            }
            // device="cuda" without a usable GPU: the CPU's grid, and a RuntimeWarning saying why.
            if (!result.deviceNote.empty() &&
                PyErr_WarnEx(PyExc_RuntimeWarning, ("device='cuda': " + result.deviceNote).c_str(), 1) != 0)
                throw py::error_already_set();
            return result.grid;
        },
        py::arg("vertices"), py::arg("faces") = py::none(), py::kw_only(), py::arg("resolution") = py::none(),
        py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(), py::arg("bounds") = py::none(),
        py::arg("margin") = 0, py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("axis") = "z",
        py::arg("slicing") = "uniform", py::arg("threads") = 0, py::arg("device") = "cpu",
        "Voxelizes a mesh (a voxfx.Mesh, or vertices and faces arrays) like `voxfx voxelize`: resolution "
        "(default 256), voxel_size or dims; bounds (xmin ymin zmin xmax ymax zmax); mode surface | "
        "conservative | solid | solid-conservative | interior; fill auto | parity | flood | vote | winding | "
        "gwn "
        "(auto: parity for closed meshes, flood otherwise); threads 0 = all; device cpu | cuda | auto "
        "(the same grid; cuda without a usable GPU warns and runs on the CPU; see cuda_status()).");

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
