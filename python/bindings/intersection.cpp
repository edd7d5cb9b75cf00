// Intersection volumes with an error bound (GI08 §7, voxfx/intersection_volume.hpp):
// intersection_volume and VolumeEstimate.
#include "common.hpp"
#include "voxfx/intersection_volume.hpp"

namespace voxfx::python {
namespace {

/// An affine map from a (4, 4) or (3, 4) array (row-major, acting on column vectors), or the
/// identity for None. A (4, 4) array must have the last row (0, 0, 0, 1).
Mat4d affineArgument(const py::object& obj, const char* name) {
    Mat4d t;
    if (obj.is_none()) return t;
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
    if (!a || a.ndim() != 2 || a.shape(1) != 4 || (a.shape(0) != 3 && a.shape(0) != 4))
        throw ArgumentError(std::string(name) + " must be an array of shape (4, 4) or (3, 4)");
    for (py::ssize_t i = 0; i < a.shape(0); ++i)
        for (py::ssize_t j = 0; j < 4; ++j) t.m[i][j] = a.at(i, j);
    if (a.shape(0) == 4 && !(t.m[3][0] == 0 && t.m[3][1] == 0 && t.m[3][2] == 0 && t.m[3][3] == 1))
        throw ArgumentError(std::string(name) + " must be affine: last row (0, 0, 0, 1)");
    return t;
}

VoxelizeOptions fillOptions(const std::string& fill, int threads) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
    VoxelizeOptions vo;
    vo.fill = asArgument([&] { return parseFill(fill); });
    vo.threads = threads;
    return vo;
}

/// The map from a mesh's stored positions to world: `transform` after the mesh's origin (float64
/// input recentred by meshArgument).
Mat4d placement(const PyMesh& mesh, const Mat4d& transform) {
    Mat4d shift;
    for (int a = 0; a < 3; ++a) shift.m[a][3] = mesh.origin[a];
    return transform * shift;
}

/// Runs f(cancel) without the GIL, stopping at Ctrl-C (interruptible).
template <class F> VolumeEstimate estimate(F&& f) {
    VolumeEstimate e;
    interruptible([&](Cancel& cancel) { e = f(cancel); });
    return e;
}

} // namespace

void bindIntersection(py::module_& m) {
    py::class_<VolumeEstimate>(m, "VolumeEstimate",
                               "A volume in world units cubed and its bound: |volume - exact| <= error_bound")
        .def_readonly("volume", &VolumeEstimate::volume)
        .def_readonly("cells", &VolumeEstimate::cells)
        .def_readonly("error_bound", &VolumeEstimate::errorBound)
        .def_readonly("uncertain_cells", &VolumeEstimate::uncertainCells)
        .def_readonly("lower_volume", &VolumeEstimate::lowerVolume)
        .def_readonly("upper_volume", &VolumeEstimate::upperVolume)
        .def("__repr__", [](const VolumeEstimate& e) {
            return "VolumeEstimate(volume=" + std::to_string(e.volume) +
                   ", error_bound=" + std::to_string(e.errorBound) + ", cells=" + std::to_string(e.cells) +
                   ")";
        });
    m.def(
        "intersection_volume",
        [](const py::object& a, const py::object& b, const py::object& transform,
           const py::object& transformB, std::optional<int64_t> resolution, std::optional<double> voxelSize,
           const std::string& fill, int threads) {
            const VoxelizeOptions vo = fillOptions(fill, threads);
            if (py::isinstance<VoxelGrid>(a) && py::isinstance<VoxelGrid>(b)) {
                if (!transform.is_none() || !transformB.is_none())
                    throw ArgumentError("two grids share one frame: no transform applies");
                const auto& ga = a.cast<const VoxelGrid&>();
                const auto& gb = b.cast<const VoxelGrid&>();
                return estimate([&](Cancel&) { return intersectionVolume(ga, gb); });
            }
            if (py::isinstance<VoxelGrid>(a)) {
                if (!transformB.is_none())
                    throw ArgumentError("grid and mesh: the mesh's map is `transform`");
                const auto& g = a.cast<const VoxelGrid&>();
                const auto mesh = meshArgument(b, py::none());
                const Mat4d t = placement(*mesh, affineArgument(transform, "transform"));
                return estimate([&](Cancel& cancel) {
                    VoxelizeOptions o = vo;
                    o.progress = &cancel;
                    return intersectionVolume(g, mesh->mesh.view(), t, o);
                });
            }
            const auto ma = meshArgument(a, py::none()), mb = meshArgument(b, py::none());
            const Mat4d ta = placement(*ma, affineArgument(transform, "transform")),
                        tb = placement(*mb, affineArgument(transformB, "transform_b"));
            const FitOptions fo = fitOptions(resolution, voxelSize, std::nullopt, py::none(), 0, "z");
            return estimate([&](Cancel& cancel) {
                VoxelizeOptions o = vo;
                o.progress = &cancel;
                return intersectionVolume(ma->mesh.view(), ta, mb->mesh.view(), tb, fo, o);
            });
        },
        py::arg("a"), py::arg("b"), py::kw_only(), py::arg("transform") = py::none(),
        py::arg("transform_b") = py::none(), py::arg("resolution") = py::none(),
        py::arg("voxel_size") = py::none(), py::arg("fill") = "auto", py::arg("threads") = 0,
        "Volume of the intersection of two solids, in world units cubed, with its error bound (a "
        "VolumeEstimate): two grids of one frame (their common cells, exact); a grid and a closed mesh "
        "placed by `transform` (a (4, 4) or (3, 4) affine array), voxelized into the grid's frame; or two "
        "meshes placed by `transform` and `transform_b` in a grid fitted to the overlap of their bounds "
        "(resolution, default 256, or voxel_size). fill: auto | parity | flood | vote | winding | gwn.");
}

} // namespace voxfx::python
