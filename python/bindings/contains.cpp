// Exact point occupancy: contains and PointClassifier.
#include "voxfx/contains.hpp"

#include <memory>
#include <span>

#include "common.hpp"

namespace voxfx::python {
namespace {

/// A PointClassifier with what made it (to pickle and copy it: the classifier is rebuilt from the
/// mesh and options) and the mesh's origin (points are moved into the mesh's coordinates).
struct PyClassifier {
    std::shared_ptr<PyMesh> mesh;
    ContainsOptions options;
    std::unique_ptr<PointClassifier> classifier;
};

ContainsOptions containsOptions(const std::string& method, std::optional<int64_t> resolution, int threads,
                                double windingBeta) {
    ContainsOptions co;
    if (!(windingBeta >= 0)) throw ArgumentError("winding_beta must be >= 0");
    co.windingBeta = windingBeta;
    co.method = asArgument([&] { return parseContainsMethod(method); });
    if (resolution && *resolution < 1) throw ArgumentError("resolution must be at least 1");
    co.resolution = resolution.value_or(0);
    if (threads < 0) throw ArgumentError("threads must be >= 0");
    co.threads = threads;
    return co;
}

std::shared_ptr<PyClassifier> makeClassifier(std::shared_ptr<PyMesh> mesh, const ContainsOptions& options) {
    // A bad mesh is a bad argument, as in voxelize (voxfx.ArgumentError, a ValueError).
    asArgument([&] { validateMesh(mesh->mesh.view(), "mesh"); });
    auto out = std::make_shared<PyClassifier>();
    out->mesh = std::move(mesh);
    out->options = options;
    interruptible([&](Cancel& cancel) {
        ContainsOptions o = out->options;
        o.progress = &cancel;
        out->classifier = std::make_unique<PointClassifier>(out->mesh->mesh.view(), o);
    });
    return out;
}

/// (K,) bool answers for (K, 3) world points, moved into the mesh's coordinates.
py::array_t<bool> classifyPoints(const PyClassifier& c, const py::object& pointsObj) {
    const auto pts = pointsArgument(pointsObj, c.mesh->origin);
    requireFinitePoints(pts, "contains");
    const std::size_t n = std::size_t(pts.shape(0));
    py::array_t<bool> out(std::vector<py::ssize_t>{py::ssize_t(n)});
    static_assert(sizeof(bool) == 1);
    auto* o = reinterpret_cast<uint8_t*>(out.mutable_data());
    const auto* p = reinterpret_cast<const Vec3d*>(pts.data());
    interruptible([&](Cancel& cancel) {
        c.classifier->classify(std::span<const Vec3d>(p, n), std::span<uint8_t>(o, n), nullptr, &cancel);
    });
    return out;
}

py::tuple classifierState(const PyClassifier& c) {
    return py::make_tuple(py::cast(c.mesh), toString(c.options.method), c.options.resolution,
                          c.options.threads, c.options.windingBeta);
}

std::shared_ptr<PyClassifier> classifierFromState(const py::tuple& t) {
    if (t.size() != 5) throw py::value_error("not a voxfx.PointClassifier pickle");
    return makeClassifier(t[0].cast<std::shared_ptr<PyMesh>>(),
                          containsOptions(t[1].cast<std::string>(), t[2].cast<int64_t>(), t[3].cast<int>(),
                                          t[4].cast<double>()));
}

} // namespace

void bindContains(py::module_& m) {
    m.def(
        "contains",
        [](const py::object& meshObj, const py::object& faces, const py::object& pointsObj,
           const std::string& method, std::optional<Int> resolution, Int threads, double windingBeta) {
            // contains(mesh, points): the mesh object takes the faces' place.
            py::object facesArg = faces, pointsArg = pointsObj;
            if (pointsArg.is_none()) std::swap(facesArg, pointsArg);
            if (pointsArg.is_none()) throw py::type_error("contains needs points: contains(mesh, points)");
            const auto mesh = meshArgument(meshObj, facesArg);
            ContainsOptions co =
                containsOptions(method, resolution ? std::optional<int64_t>(*resolution) : std::nullopt,
                                int(threads), windingBeta);
            if (co.resolution == 0)
                co.resolution =
                    defaultContainsResolution(mesh->mesh.triangleCount(), std::size_t(py::len(pointsArg)));
            return classifyPoints(*makeClassifier(mesh, co), pointsArg);
        },
        py::arg("mesh"), py::arg("faces") = py::none(), py::arg("points") = py::none(), py::kw_only(),
        py::arg("method") = "parity", py::arg("resolution") = py::none(), py::arg("threads") = 0,
        py::arg("winding_beta") = 3.0,
        "Whether each point (K, 3) lies inside the mesh (any mesh voxelize accepts; contains(mesh, points) "
        "or "
        "contains(vertices, faces, points)): parity (exact, voxel centres' tie rule), winding (generalized "
        "winding number |w| >= 0.5, so meshes oriented inward work too; Barill et al.'s approximation with "
        "winding_beta, 0 = exact sum) or flood (cells sealed off from the border, for open meshes). "
        "A point with a NaN or infinite coordinate is an ArgumentError (a ValueError). Ctrl-C stops it.");
    py::class_<PyClassifier, std::shared_ptr<PyClassifier>>(
        m, "PointClassifier", "A mesh prepared for repeated contains() queries (the grids are built once)")
        .def(py::init([](const py::object& meshObj, const py::object& faces, const std::string& method,
                         std::optional<Int> resolution, Int threads, double windingBeta) {
                 const auto mesh = meshArgument(meshObj, faces);
                 ContainsOptions co =
                     containsOptions(method, resolution ? std::optional<int64_t>(*resolution) : std::nullopt,
                                     int(threads), windingBeta);
                 if (co.resolution == 0)
                     co.resolution = defaultContainsResolution(mesh->mesh.triangleCount(), 1000000);
                 return makeClassifier(mesh, co);
             }),
             py::arg("mesh"), py::arg("faces") = py::none(), py::kw_only(), py::arg("method") = "parity",
             py::arg("resolution") = py::none(), py::arg("threads") = 0, py::arg("winding_beta") = 3.0)
        .def("__call__", &classifyPoints, py::arg("points"), "(K,) bool: whether each point lies inside")
        .def_property_readonly("resolution", [](const PyClassifier& c) { return c.classifier->resolution(); })
        .def_property_readonly("method", [](const PyClassifier& c) { return toString(c.options.method); })
        .def("__copy__", [](const py::object& self) { return self; })
        .def("__deepcopy__", [](const py::object& self, const py::object&) { return self; })
        .def(py::pickle(&classifierState, &classifierFromState))
        .def("__repr__", [](const PyClassifier& c) {
            return "<voxfx.PointClassifier " + std::string(toString(c.options.method)) + ", resolution " +
                   std::to_string(c.classifier->resolution()) + ", " +
                   std::to_string(c.mesh->mesh.triangleCount()) + " triangles>";
        });
}

} // namespace voxfx::python
