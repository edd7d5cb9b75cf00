// Exact point occupancy: contains and PointClassifier.
#include "voxfx/contains.hpp"

#include <memory>
#include <span>

#include "common.hpp"

namespace voxfx::python {

void bindContains(py::module_& m) {
    // ---- exact point occupancy
    // Points as a (K, 3) float64 array (converted when needed), answers as a (K,) bool array.
    const auto classifyPoints = [](const PointClassifier& c, const py::object& pointsObj) {
        const auto pts = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(pointsObj);
        if (!pts || pts.ndim() != 2 || pts.shape(1) != 3)
            throw py::value_error("points must be an array of shape (K, 3)");
        const std::size_t n = std::size_t(pts.shape(0));
        py::array_t<bool> out(std::vector<py::ssize_t>{py::ssize_t(n)});
        static_assert(sizeof(bool) == 1);
        auto* o = reinterpret_cast<uint8_t*>(out.mutable_data());
        const auto* p = reinterpret_cast<const Vec3d*>(pts.data());
        py::gil_scoped_release release;
        c.classify(std::span<const Vec3d>(p, n), std::span<uint8_t>(o, n));
        return out;
    };
    const auto containsOptions = [](const std::string& method, std::optional<int64_t> resolution, int threads,
                                    double windingBeta) {
        ContainsOptions co;
        if (!(windingBeta >= 0)) throw py::value_error("winding_beta must be >= 0");
        co.windingBeta = windingBeta;
        co.method = parseContainsMethod(method);
        if (resolution && *resolution < 1) throw py::value_error("resolution must be at least 1");
        co.resolution = resolution.value_or(0);
        if (threads < 0) throw py::value_error("threads must be >= 0");
        co.threads = threads;
        return co;
    };
    m.def(
        "contains",
        [classifyPoints, containsOptions](
            const py::object& meshOrVertices, const py::object& faces, const py::object& pointsObj,
            const std::string& method, std::optional<int64_t> resolution, int threads, double windingBeta) {
            // contains(mesh, points): a voxfx.Mesh takes the faces' place.
            py::object facesArg = faces, pointsArg = pointsObj;
            if (py::isinstance<PyMesh>(meshOrVertices) && pointsArg.is_none()) std::swap(facesArg, pointsArg);
            const auto mesh = meshArgument(meshOrVertices, facesArg);
            ContainsOptions co = containsOptions(method, resolution, threads, windingBeta);
            const auto n = py::len(pointsArg);
            if (co.resolution == 0) co.resolution = defaultContainsResolution(mesh->mesh.triangleCount(), n);
            std::unique_ptr<PointClassifier> c;
            {
                py::gil_scoped_release release;
                c = std::make_unique<PointClassifier>(mesh->mesh.view(), co);
            }
            return classifyPoints(*c, pointsArg);
        },
        py::arg("vertices"), py::arg("faces") = py::none(), py::arg("points") = py::none(), py::kw_only(),
        py::arg("method") = "parity", py::arg("resolution") = py::none(), py::arg("threads") = 0,
        py::arg("winding_beta") = 3.0,
        "Whether each point (K, 3) lies inside the mesh: parity (exact, voxel centres' tie rule), winding "
        "(generalized winding number >= 0.5, Barill et al.'s approximation with winding_beta; 0 = exact "
        "sum) or flood (cells sealed off from the border, for open meshes)");
    py::class_<PointClassifier>(m, "PointClassifier",
                                "A mesh prepared for repeated contains() queries (the grids are built once)")
        .def(py::init([containsOptions](const py::object& meshOrVertices, const py::object& faces,
                                        const std::string& method, std::optional<int64_t> resolution,
                                        int threads, double windingBeta) {
                 const auto mesh = meshArgument(meshOrVertices, faces);
                 ContainsOptions co = containsOptions(method, resolution, threads, windingBeta);
                 if (co.resolution == 0)
                     co.resolution = defaultContainsResolution(mesh->mesh.triangleCount(), 1000000);
                 py::gil_scoped_release release;
                 return std::make_unique<PointClassifier>(mesh->mesh.view(), co);
             }),
             py::arg("vertices"), py::arg("faces") = py::none(), py::kw_only(), py::arg("method") = "parity",
             py::arg("resolution") = py::none(), py::arg("threads") = 0, py::arg("winding_beta") = 3.0)
        .def("__call__", classifyPoints, py::arg("points"), "(K,) bool: whether each point lies inside")
        .def_property_readonly("resolution", &PointClassifier::resolution);
}

} // namespace voxfx::python
