// Density maps: voxfx.Density and compute_density.
#include <cstring>

#include "common.hpp"

namespace voxfx::python {
namespace {

// ---- density --------------------------------------------------------------------------------

/// A density map of a grid sliced along Z (so its cells are in world order), with the fine
/// frame it was computed from.
struct PyDensity {
    DensityGrid density;
    Frame fine;
};

/// Pickle state: version, level, W' H' D', the fine frame (box lo, hi, axis, W H D), the words.
py::tuple densityState(const PyDensity& d) {
    const DensityGrid& g = d.density;
    py::array_t<uint64_t> words(py::ssize_t(g.wordCount()));
    if (g.wordCount() > 0) std::memcpy(words.mutable_data(), g.words(), std::size_t(g.byteCount()));
    return py::make_tuple(1, g.level(), g.width(), g.height(), g.depth(), vec3(d.fine.box().lo),
                          vec3(d.fine.box().hi), toString(d.fine.axis()), d.fine.width(), d.fine.height(),
                          d.fine.depth(), words);
}

std::shared_ptr<PyDensity> densityFromState(const py::tuple& t) {
    if (t.size() != 12 || t[0].cast<int>() != 1)
        throw py::value_error("not a voxfx.Density pickle (version 1)");
    auto out = std::make_shared<PyDensity>();
    out->density =
        DensityGrid(t[1].cast<int>(), t[2].cast<int64_t>(), t[3].cast<int64_t>(), t[4].cast<int64_t>());
    const auto lo = t[5].cast<std::vector<double>>(), hi = t[6].cast<std::vector<double>>();
    Box3d box;
    box.lo = {lo.at(0), lo.at(1), lo.at(2)};
    box.hi = {hi.at(0), hi.at(1), hi.at(2)};
    out->fine = Frame::orthographic(box, parseAxis(t[7].cast<std::string>()), t[8].cast<int64_t>(),
                                    t[9].cast<int64_t>(), t[10].cast<int64_t>());
    const auto w = t[11].cast<py::array_t<uint64_t, py::array::c_style | py::array::forcecast>>();
    if (w.size() != out->density.wordCount()) throw py::value_error("voxfx.Density pickle: wrong word count");
    if (w.size() > 0) std::memcpy(out->density.words(), w.data(), std::size_t(w.size()) * sizeof(uint64_t));
    return out;
}

} // namespace

void bindDensity(py::module_& m) {
    py::class_<PyDensity, std::shared_ptr<PyDensity>>(m, "Density",
                                                      "A density map: filled fine cells per 2^level block")
        .def_property_readonly("level", [](const PyDensity& d) { return d.density.level(); })
        .def_property_readonly("dims",
                               [](const PyDensity& d) {
                                   return py::make_tuple(d.density.width(), d.density.height(),
                                                         d.density.depth());
                               })
        .def_property_readonly("origin", [](const PyDensity& d) { return vec3(d.fine.box().lo); })
        .def_property_readonly(
            "cell_size",
            [](const PyDensity& d) { return vec3(densityFrame(d.fine, d.density.level()).cellSize()); })
        .def("total", [](const PyDensity& d) { return d.density.total(); })
        .def(
            "occupancy",
            [](const PyDensity& d) {
                const DensityGrid& g = d.density;
                // Cell order (y * W + x) * D + z of a Z-sliced map, returned indexed [x, y, z].
                py::array_t<float> out(
                    {py::ssize_t(g.width()), py::ssize_t(g.height()), py::ssize_t(g.depth())});
                float* o = out.mutable_data();
                py::gil_scoped_release release;
                const std::vector<float> f = occupancyField(g);
                const int64_t w = g.width(), h = g.height(), dd = g.depth();
                for (int64_t x = 0; x < w; ++x)
                    for (int64_t y = 0; y < h; ++y)
                        std::memcpy(o + (x * h + y) * dd, f.data() + (y * w + x) * dd,
                                    std::size_t(dd) * sizeof(float));
                return out;
            },
            "Occupancy (count / 8^level) as a float32 array indexed [x, y, z]")
        .def(
            "save",
            [](const PyDensity& d, const py::object& pathObj) {
                const std::string path = pathString(pathObj);
                py::gil_scoped_release release;
                writeDensity(d.density, d.fine, path);
            },
            py::arg("path"), "Writes .nrrd (uint8/16 counts) or .vdb (FloatGrid \"density\")")
        .def("__eq__",
             [](const PyDensity& a, const py::object& b) -> py::object {
                 if (!py::isinstance<PyDensity>(b))
                     return py::reinterpret_borrow<py::object>(Py_NotImplemented);
                 const PyDensity& o = b.cast<const PyDensity&>();
                 return py::bool_(a.density == o.density && a.fine.sameGrid(o.fine));
             })
        .def(py::pickle(&densityState, &densityFromState));
    m.def(
        "compute_density",
        [](const VoxelGrid& g, int level, int threads) {
            requireOrthographic(g, "compute_density");
            auto out = std::make_shared<PyDensity>();
            DensityOptions o;
            o.level = level;
            o.threads = threads;
            py::gil_scoped_release release;
            const VoxelGrid z = uniformZ(g);
            out->density = computeDensity(z.bits, o);
            out->fine = z.frame;
            return out;
        },
        py::arg("grid"), py::arg("level") = 1, py::kw_only(), py::arg("threads") = 0,
        "Density map at kernel 2^level (level 1..5), computed on the grid sliced along z");
}

} // namespace voxfx::python
