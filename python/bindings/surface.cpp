// Marching cubes: voxfx.SurfaceMesh and extract_surface.
#include <cstring>

#include "common.hpp"

namespace voxfx::python {

void bindSurface(py::module_& m) {
    py::class_<SurfaceMesh, std::shared_ptr<SurfaceMesh>>(m, "SurfaceMesh", "A triangle mesh with normals")
        .def_property_readonly("vertices",
                               [](const SurfaceMesh& s) {
                                   Mesh tmp;
                                   tmp.positions = s.positions;
                                   return verticesArray(tmp);
                               })
        .def_property_readonly("normals",
                               [](const SurfaceMesh& s) {
                                   py::array_t<float> out({py::ssize_t(s.normals.size()), py::ssize_t(3)});
                                   std::memcpy(out.mutable_data(), s.normals.data(),
                                               s.normals.size() * sizeof(Vec3f));
                                   return out;
                               })
        .def_property_readonly("faces", [](const SurfaceMesh& s) { return facesArray(s.indices); })
        .def("to_mesh",
             [](const SurfaceMesh& s) {
                 auto out = std::make_shared<PyMesh>();
                 out->mesh.positions = s.positions;
                 out->mesh.indices = s.indices;
                 out->source = "surface";
                 return out;
             })
        .def(
            "save",
            [](const SurfaceMesh& s, const py::object& pathObj) {
                const std::string path = pathString(pathObj);
                py::gil_scoped_release release;
                writeSurfaceMesh(s, path);
            },
            py::arg("path"), "Writes .ply or .obj");
    m.def(
        "extract_surface",
        [](const VoxelGrid& g, const std::string& source, int level, float iso, int threads) {
            SurfaceOptions so;
            so.source = asArgument([&] { return parseSurfaceSource(source); });
            so.level = level;
            so.iso = iso;
            so.threads = threads;
            py::gil_scoped_release release;
            return std::make_shared<SurfaceMesh>(extractSurface(g, so));
        },
        py::arg("grid"), py::kw_only(), py::arg("source") = "density", py::arg("level") = 1,
        py::arg("iso") = 0.5f, py::arg("threads") = 0,
        "Marching cubes over the grid's density map (or its 0/1 occupancy)");
}

} // namespace voxfx::python
