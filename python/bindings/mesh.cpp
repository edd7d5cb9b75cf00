// Meshes: voxfx.Mesh (arrays in the library's layout) and load_mesh.
#include <algorithm>
#include <cstring>

#include "common.hpp"

namespace voxfx::python {

namespace {

/// Pickle state: float32 positions, uint32 indices, the origin, the source text.
py::tuple meshState(const PyMesh& s) {
    py::array_t<float> positions({py::ssize_t(s.mesh.positions.size()), py::ssize_t(3)});
    if (!s.mesh.positions.empty())
        std::memcpy(positions.mutable_data(), s.mesh.positions.data(),
                    s.mesh.positions.size() * sizeof(Vec3f));
    py::array_t<uint32_t> indices(py::ssize_t(s.mesh.indices.size()));
    std::copy(s.mesh.indices.begin(), s.mesh.indices.end(), indices.mutable_data());
    return py::make_tuple(positions, indices, vec3(s.origin), s.source);
}

std::shared_ptr<PyMesh> meshFromState(const py::tuple& t) {
    if (t.size() != 4) throw py::value_error("not a voxfx.Mesh pickle");
    auto out = std::make_shared<PyMesh>();
    const auto p = t[0].cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
    const auto i = t[1].cast<py::array_t<uint32_t, py::array::c_style | py::array::forcecast>>();
    out->mesh.positions.resize(std::size_t(p.size() / 3));
    if (p.size() > 0) std::memcpy(&out->mesh.positions[0].x, p.data(), std::size_t(p.size()) * sizeof(float));
    out->mesh.indices.assign(i.data(), i.data() + i.size());
    const auto o = t[2].cast<std::vector<double>>();
    out->origin = {o.at(0), o.at(1), o.at(2)};
    out->source = t[3].cast<std::string>();
    return out;
}

} // namespace

void bindMesh(py::module_& m) {
    py::class_<PyMesh, std::shared_ptr<PyMesh>>(
        m, "Mesh",
        "A triangle mesh in the library's layout: float32 positions (float64 input far from the origin "
        "is recentred first, the offset kept in `origin`, so its shape survives), uint32 indices.")
        .def(py::init([](const py::object& mesh, const py::object& faces) {
                 const auto in = meshArgument(mesh, faces);
                 auto out = std::make_shared<PyMesh>(*in);
                 asArgument([&] { validateMesh(out->mesh.view(), "mesh"); });
                 return out;
             }),
             py::arg("mesh"), py::arg("faces") = py::none(),
             "Mesh(vertices, faces), or Mesh(m) for any mesh object voxelize accepts (a copy)")
        .def_property_readonly(
            "vertices", [](const PyMesh& s) { return readOnly(verticesArray(s.mesh, s.origin)); },
            "(N, 3) float64 array: origin + the float32 positions (a read-only copy: writes would be lost; "
            "make a new Mesh from changed arrays)")
        .def_property_readonly(
            "faces", [](const PyMesh& s) { return readOnly(facesArray(s.mesh.indices)); },
            "(M, 3) int64 array (a read-only copy)")
        .def_property_readonly(
            "origin", [](const PyMesh& s) { return vec3(s.origin); },
            "World position of the float32 positions' origin (0, 0, 0 unless float64 input was recentred)")
        .def_property_readonly("vertex_count", [](const PyMesh& s) { return s.mesh.positions.size(); })
        .def_property_readonly("triangle_count", [](const PyMesh& s) { return s.mesh.triangleCount(); })
        .def_property_readonly(
            "bounds",
            [](const PyMesh& s) {
                const Box3d b = computeBounds(s.mesh.view());
                return py::make_tuple(vec3(b.lo + s.origin), vec3(b.hi + s.origin));
            },
            "((xmin, ymin, zmin), (xmax, ymax, zmax))")
        .def("is_closed", [](const PyMesh& s) { return analyzeTopology(s.mesh.view()).closed(); })
        .def("__len__", [](const PyMesh&) { return 2; })
        .def("__iter__",
             [](const PyMesh& s) {
                 return py::iter(py::make_tuple(verticesArray(s.mesh, s.origin), facesArray(s.mesh.indices)));
             })
        .def("__copy__", [](const PyMesh& s) { return std::make_shared<PyMesh>(s); })
        .def("__deepcopy__", [](const PyMesh& s, const py::object&) { return std::make_shared<PyMesh>(s); })
        .def(py::pickle(&meshState, &meshFromState))
        .def("__repr__", [](const PyMesh& s) {
            return "<voxfx.Mesh " + s.source + ": " + std::to_string(s.mesh.positions.size()) +
                   " vertices, " + std::to_string(s.mesh.triangleCount()) + " triangles>";
        });

    m.def(
        "load_mesh",
        [](const py::object& pathObj) {
            auto out = std::make_shared<PyMesh>();
            out->source = pathString(pathObj);
            py::gil_scoped_release release;
            out->mesh = loadMesh(out->source);
            return out;
        },
        py::arg("path"),
        "Loads a mesh file (OFF, OBJ, PLY, STL, glTF, and what Assimp reads); path is a str or os.PathLike. "
        "The result unpacks as vertices, faces = load_mesh(path).");
}

} // namespace voxfx::python
