// The grid toolkit: reslice, resample_to_uniform, morphology and its four shorthands, csg.
#include "common.hpp"

namespace voxfx::python {
namespace {

/// The world radii of a morphology: one number for all axes or three.
Vec3i radii(const py::object& r) {
    Vec3i out;
    if (py::isinstance<py::int_>(r)) {
        const int64_t v = r.cast<int64_t>();
        out = {v, v, v};
    } else {
        const auto v = r.cast<std::vector<int64_t>>();
        if (v.size() != 3) throw ArgumentError("radius needs one value or three (along x, y, z)");
        out = {v[0], v[1], v[2]};
    }
    if (out.x < 0 || out.y < 0 || out.z < 0) throw ArgumentError("morphology radii must be >= 0");
    return out;
}

} // namespace

void bindToolkit(py::module_& m) {
    // ---- toolkit
    m.def(
        "reslice",
        [](const VoxelGrid& g, const std::string& axis) {
            const Axis a = asArgument([&] { return parseAxis(axis); });
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(reslice(g, a));
        },
        py::arg("grid"), py::arg("axis"));
    m.def(
        "resample_to_uniform",
        [](const VoxelGrid& g) {
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(resampleToUniform(g));
        },
        py::arg("grid"));
    m.def(
        "morphology",
        [](const VoxelGrid& g, const std::string& op, const py::object& radius, const std::string& border,
           int threads) {
            const MorphOp o = asArgument([&] { return parseMorphOp(op); });
            MorphologyOptions mo;
            mo.border = asArgument([&] { return parseMorphBorder(border); });
            mo.threads = threads;
            const Vec3i r = radii(radius);
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(morphology(g, o, r, mo));
        },
        py::arg("grid"), py::arg("op"), py::arg("radius") = 1, py::kw_only(), py::arg("border") = "neutral",
        py::arg("threads") = 0,
        "Box erosion, dilation, opening or closing (op erode | dilate | open | close) with radii along "
        "world x, y, z (one number or three)");
    for (const char* op : {"erode", "dilate", "open", "close"}) {
        const std::string name = op == std::string("open")    ? "opening"
                                 : op == std::string("close") ? "closing"
                                                              : op;
        m.def(
            name.c_str(),
            [op](const VoxelGrid& g, const py::object& radius, const std::string& border, int threads) {
                MorphologyOptions mo;
                mo.border = asArgument([&] { return parseMorphBorder(border); });
                mo.threads = threads;
                const Vec3i r = radii(radius);
                const MorphOp o = asArgument([&] { return parseMorphOp(op); });
                py::gil_scoped_release release;
                return std::make_shared<VoxelGrid>(morphology(g, o, r, mo));
            },
            py::arg("grid"), py::arg("radius") = 1, py::kw_only(), py::arg("border") = "neutral",
            py::arg("threads") = 0);
    }
    m.def(
        "csg",
        [](const VoxelGrid& a, const VoxelGrid& b, const std::string& op) {
            const CsgOp o = asArgument([&] { return parseCsgOp(op); });
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(csg(a, b, o));
        },
        py::arg("a"), py::arg("b"), py::arg("op"),
        "a op b (union | intersection | difference | xor) for grids in the same frame");
}

} // namespace voxfx::python
