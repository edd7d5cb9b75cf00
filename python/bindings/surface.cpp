// Marching cubes: voxfx.SurfaceMesh and extract_surface.
#include <cstring>

#include "common.hpp"

namespace voxfx::python {

namespace {

/// Pickle state: float32 positions and normals (N, 3), uint32 indices.
py::tuple surfaceState(const SurfaceMesh& s) {
    const auto vecs = [](const std::vector<Vec3f>& v) {
        py::array_t<float> a({py::ssize_t(v.size()), py::ssize_t(3)});
        if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(Vec3f));
        return a;
    };
    py::array_t<uint32_t> idx(py::ssize_t(s.indices.size()));
    if (!s.indices.empty()) std::memcpy(idx.mutable_data(), s.indices.data(), s.indices.size() * 4);
    return py::make_tuple(1, vecs(s.positions), vecs(s.normals), idx);
}

std::shared_ptr<SurfaceMesh> surfaceFromState(const py::tuple& t) {
    if (t.size() != 4 || t[0].cast<int>() != 1)
        throw py::value_error("not a voxfx.SurfaceMesh pickle (version 1)");
    auto out = std::make_shared<SurfaceMesh>();
    const auto vecs = [](const py::handle& h, std::vector<Vec3f>& v) {
        const auto a = h.cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
        v.resize(std::size_t(a.size() / 3));
        if (!v.empty()) std::memcpy(static_cast<void*>(v.data()), a.data(), v.size() * sizeof(Vec3f));
    };
    vecs(t[1], out->positions);
    vecs(t[2], out->normals);
    const auto i = t[3].cast<py::array_t<uint32_t, py::array::c_style | py::array::forcecast>>();
    out->indices.assign(i.data(), i.data() + i.size());
    return out;
}

} // namespace

void bindSurface(py::module_& m) {
    py::class_<SurfaceMesh, std::shared_ptr<SurfaceMesh>>(m, "SurfaceMesh", "A triangle mesh with normals")
        .def_property_readonly("vertices",
                               [](const SurfaceMesh& s) {
                                   Mesh tmp;
                                   tmp.positions = s.positions;
                                   return readOnly(verticesArray(tmp));
                               })
        .def_property_readonly("normals",
                               [](const SurfaceMesh& s) {
                                   py::array_t<float> out({py::ssize_t(s.normals.size()), py::ssize_t(3)});
                                   std::memcpy(out.mutable_data(), s.normals.data(),
                                               s.normals.size() * sizeof(Vec3f));
                                   return out;
                               })
        .def_property_readonly("faces", [](const SurfaceMesh& s) { return readOnly(facesArray(s.indices)); })
        .def("__eq__",
             [](const SurfaceMesh& a, const py::object& b) -> py::object {
                 if (!py::isinstance<SurfaceMesh>(b))
                     return py::reinterpret_borrow<py::object>(Py_NotImplemented);
                 const SurfaceMesh& o = b.cast<const SurfaceMesh&>();
                 const auto same = [](const std::vector<Vec3f>& x, const std::vector<Vec3f>& y) {
                     return x.size() == y.size() &&
                            (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(Vec3f)) == 0);
                 };
                 return py::bool_(same(a.positions, o.positions) && same(a.normals, o.normals) &&
                                  a.indices == o.indices);
             })
        .def(py::pickle(&surfaceState, &surfaceFromState))
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
