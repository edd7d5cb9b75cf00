// Meshes: voxfx.Mesh (arrays in the library's layout) and load_mesh.
#include "common.hpp"

namespace voxfx::python {

void bindMesh(py::module_& m) {
    // ---- Mesh
    py::class_<PyMesh, std::shared_ptr<PyMesh>>(
        m, "Mesh", "A triangle mesh in the library's layout (float32 positions).")
        .def(py::init([](const py::object& vertices, const py::object& faces) {
                 auto mesh = meshFromArrays(vertices, faces);
                 validateMesh(mesh->mesh.view(), "mesh");
                 return mesh;
             }),
             py::arg("vertices"), py::arg("faces"))
        .def_property_readonly(
            "vertices", [](const PyMesh& s) { return verticesArray(s.mesh); },
            "(N, 3) float64 array (a copy of the float32 positions)")
        .def_property_readonly(
            "faces", [](const PyMesh& s) { return facesArray(s.mesh.indices); },
            "(M, 3) int64 array (a copy)")
        .def_property_readonly("vertex_count", [](const PyMesh& s) { return s.mesh.positions.size(); })
        .def_property_readonly("triangle_count", [](const PyMesh& s) { return s.mesh.triangleCount(); })
        .def_property_readonly("bounds",
                               [](const PyMesh& s) {
                                   const Box3d b = computeBounds(s.mesh.view());
                                   return py::make_tuple(vec3(b.lo), vec3(b.hi));
                               })
        .def("is_closed", [](const PyMesh& s) { return analyzeTopology(s.mesh.view()).closed(); })
        .def("__len__", [](const PyMesh&) { return 2; })
        .def("__iter__",
             [](const PyMesh& s) {
                 return py::iter(py::make_tuple(verticesArray(s.mesh), facesArray(s.mesh.indices)));
             })
        .def("__repr__", [](const PyMesh& s) {
            return "<voxfx.Mesh " + s.source + ": " + std::to_string(s.mesh.positions.size()) +
                   " vertices, " + std::to_string(s.mesh.triangleCount()) + " triangles>";
        });

    m.def(
        "load_mesh",
        [](const std::string& path) {
            auto out = std::make_shared<PyMesh>();
            out->source = path;
            py::gil_scoped_release release;
            out->mesh = loadMesh(path);
            return out;
        },
        py::arg("path"),
        "Loads a mesh file (OFF, OBJ, PLY, STL, glTF, and what Assimp reads). The result unpacks as "
        "vertices, faces = load_mesh(path).");
}

} // namespace voxfx::python
