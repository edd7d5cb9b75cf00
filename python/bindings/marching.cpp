// Marching cubes on fields (voxfx/volume_to_mesh.hpp): marching_cubes of a voxfx.LevelSet, a
// voxfx.SignedDistanceField or a 3-D float array, by OpenVDB's volumeToMesh. It returns the
// voxfx.SurfaceMesh of extract_surface (surface.cpp).
#include <cmath>
#include <memory>

#include "common.hpp"
#include "voxfx/volume_to_mesh.hpp"

namespace voxfx::python {
namespace {

/// A scalar or three numbers (spacing, origin).
Vec3d marchingTriple(const py::object& o, const char* name, double fallback) {
    if (o.is_none()) return {fallback, fallback, fallback};
    if (py::isinstance<py::float_>(o) || py::isinstance<py::int_>(o)) {
        const double v = o.cast<double>();
        return {v, v, v};
    }
    std::vector<double> v;
    try {
        v = o.cast<std::vector<double>>();
    } catch (const py::cast_error&) {
        throw py::type_error(std::string(name) + " must be a number or three numbers");
    }
    if (v.size() != 3) throw ArgumentError(std::string(name) + " needs 3 values (x, y, z)");
    return {v[0], v[1], v[2]};
}

std::shared_ptr<SurfaceMesh> marchingCubes(const py::object& field, double iso, const py::object& spacing,
                                           const py::object& origin, double adaptivity,
                                           const std::string& inside, int threads) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
    if (inside != "below" && inside != "above")
        throw ArgumentError(
            "inside must be 'below' (negative inside: signed distances) or 'above' (occupancy, "
            "density, positive-inside distances), got '" +
            inside + "'");
    VolumeToMeshOptions o;
    o.isovalue = iso;
    o.adaptivity = adaptivity;
    o.insideAbove = inside == "above";
    auto out = std::make_shared<SurfaceMesh>();
    const bool isLevelSet = py::isinstance<LevelSet>(field),
               isSdf = py::isinstance<SignedDistanceField>(field);
    if (isLevelSet || isSdf) {
        if (!spacing.is_none() || !origin.is_none())
            throw ArgumentError(
                "spacing and origin are for arrays: a level set or field has its own transform");
        if (o.insideAbove)
            throw ArgumentError(
                "a level set or signed distance field is negative inside: inside='above' does not "
                "apply (negate an array instead)");
        if (isLevelSet) {
            const auto ls = field.cast<std::shared_ptr<LevelSet>>();
            interruptible([&](Cancel&) {
                withThreads(threads, [&] { *out = asArgument([&] { return volumeToMesh(*ls, o); }); });
            });
        } else {
            const auto f = field.cast<std::shared_ptr<SignedDistanceField>>();
            interruptible([&](Cancel&) {
                withThreads(threads, [&] { *out = asArgument([&] { return volumeToMesh(*f, o); }); });
            });
        }
        return out;
    }
    const py::array any = py::array::ensure(field);
    if (!any || any.ndim() != 3 ||
        (any.size() > 0 && std::string("fiub").find(any.dtype().kind()) == std::string::npos))
        throw py::type_error(
            "field must be a voxfx.LevelSet, a voxfx.SignedDistanceField or a 3-D array of numbers "
            "indexed [i, j, k]");
    // [i, j, k] in either memory order without a copy (C order: k fastest, as NumPy makes arrays;
    // Fortran order: i fastest, as SignedDistanceField.to_numpy() gives them); anything else is
    // copied into C order.
    const bool fortran = (any.flags() & py::array::f_style) && !(any.flags() & py::array::c_style);
    const py::array values =
        fortran ? py::array(py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(any))
                : py::array(py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(any));
    ScalarFieldView view;
    view.values = static_cast<const float*>(values.data());
    view.dims = {int64_t(values.shape(0)), int64_t(values.shape(1)), int64_t(values.shape(2))};
    view.zFastest = !fortran;
    view.spacing = marchingTriple(spacing, "spacing", 1.0);
    view.origin = marchingTriple(origin, "origin", 0.0);
    interruptible([&](Cancel&) {
        withThreads(threads, [&] { *out = asArgument([&] { return volumeToMesh(view, o); }); });
    });
    return out;
}

} // namespace

void bindMarching(py::module_& m) {
    m.def("marching_cubes", &marchingCubes, py::arg("field"), py::arg("iso") = 0.0, py::kw_only(),
          py::arg("spacing") = py::none(), py::arg("origin") = py::none(), py::arg("adaptivity") = 0.0,
          py::arg("inside") = "below", py::arg("threads") = 0,
          "The iso-surface of a field as a voxfx.SurfaceMesh (vertices, faces, normals, save), by OpenVDB's "
          "volumeToMesh. field: a voxfx.LevelSet or voxfx.SignedDistanceField (world coordinates; iso within "
          "the band), or a 3-D array indexed [i, j, k] whose value (i, j, k) lies at origin + (i, j, k) * "
          "spacing (spacing: a number or three, default 1; origin default 0). inside: 'below' (values below "
          "iso are inside: signed distances, voxfx's convention, negative inside) or 'above' (occupancy, "
          "density, trimesh's positive-inside distances). Triangles are counter-clockwise seen from outside "
          "and normals point outwards; beyond an array the field counts as outside, so the mesh is closed. "
          "adaptivity in [0, 1] (0: uniform; larger merges flat regions). The GIL is released.");
}

} // namespace voxfx::python
