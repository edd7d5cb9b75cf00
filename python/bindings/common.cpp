// Helpers shared by the binding areas (see common.hpp).
#include "common.hpp"

#include <cstring>

namespace voxfx::python {

/// Shapes and index signs are checked here, the rest (range, finite) by validateMesh.
std::shared_ptr<PyMesh> meshFromArrays(const py::handle& verticesObj, const py::handle& facesObj) {
    auto out = std::make_shared<PyMesh>();
    const auto v = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(verticesObj);
    if (!v) throw py::type_error("vertices must be an array of numbers of shape (N, 3)");
    if (v.ndim() != 2 || v.shape(1) != 3)
        throw py::value_error("vertices must have shape (N, 3), got " +
                              std::string(py::str(py::reinterpret_borrow<py::object>(v).attr("shape"))));
    const auto f = py::array::ensure(facesObj);
    if (!f) throw py::type_error("faces must be an integer array of shape (M, 3)");
    if (f.ndim() != 2 || f.shape(1) != 3)
        throw py::value_error("faces must have shape (M, 3), got " +
                              std::string(py::str(py::reinterpret_borrow<py::object>(f).attr("shape"))));
    if (f.size() > 0 && f.dtype().kind() != 'i' && f.dtype().kind() != 'u')
        throw py::type_error("faces must hold integers, got dtype " + std::string(py::str(f.dtype())));
    const auto fi = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(f);
    const std::size_t n = std::size_t(v.shape(0)), m = std::size_t(fi.shape(0));
    out->mesh.positions.resize(n);
    if (n > 0) std::memcpy(&out->mesh.positions[0].x, v.data(), n * 3 * sizeof(float));
    out->mesh.indices.resize(3 * m);
    const int64_t* idx = fi.data();
    for (std::size_t i = 0; i < 3 * m; ++i) {
        if (idx[i] < 0 || idx[i] > int64_t(UINT32_MAX))
            fail("face ", i / 3, " has vertex index ", idx[i], " outside 0..", n == 0 ? 0 : n - 1);
        out->mesh.indices[i] = uint32_t(idx[i]);
    }
    return out;
}

/// A mesh argument: a voxfx.Mesh (used as is) or a vertices array with `faces`.
std::shared_ptr<PyMesh> meshArgument(const py::object& meshOrVertices, const py::object& faces) {
    if (py::isinstance<PyMesh>(meshOrVertices)) {
        if (!faces.is_none()) throw py::type_error("faces must not be given with a voxfx.Mesh");
        return meshOrVertices.cast<std::shared_ptr<PyMesh>>();
    }
    if (faces.is_none()) throw py::type_error("faces are required when vertices are given as an array");
    return meshFromArrays(meshOrVertices, faces);
}

py::array_t<double> verticesArray(const Mesh& m) {
    py::array_t<double> out({py::ssize_t(m.positions.size()), py::ssize_t(3)});
    double* d = out.mutable_data();
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        for (int k = 0; k < 3; ++k) d[3 * i + k] = double(m.positions[i][k]);
    return out;
}

py::array_t<int64_t> facesArray(const std::vector<uint32_t>& indices) {
    py::array_t<int64_t> out({py::ssize_t(indices.size() / 3), py::ssize_t(3)});
    std::copy(indices.begin(), indices.end(), out.mutable_data());
    return out;
}

py::tuple vec3(const Vec3d& v) { return py::make_tuple(v.x, v.y, v.z); }
py::tuple vec3(const Vec3i& v) { return py::make_tuple(v.x, v.y, v.z); }

void requireOrthographic(const VoxelGrid& g, const char* what) {
    if (g.frame.isPerspective()) fail(what, " needs an orthographic grid");
}

/// The grid sliced along Z with uniform slicing: columns are (x, y), slices z.
VoxelGrid uniformZ(const VoxelGrid& g) {
    VoxelGrid u = g.frame.slicing() == Slicing::Local ? resampleToUniform(g) : g;
    if (u.frame.axis() != Axis::Z) u = reslice(u, Axis::Z);
    return u;
}

// ---- options --------------------------------------------------------------------------------

FitOptions fitOptions(const std::optional<int64_t>& resolution, const std::optional<double>& voxelSize,
                      const std::optional<std::vector<int64_t>>& dims,
                      const std::optional<std::vector<double>>& bounds, int64_t margin,
                      const std::string& axis) {
    const int given = int(resolution.has_value()) + int(voxelSize.has_value()) + int(dims.has_value());
    if (given > 1) throw py::value_error("give at most one of resolution, voxel_size and dims");
    FitOptions fo;
    if (resolution) {
        if (*resolution < 1) throw py::value_error("resolution must be at least 1");
        fo.resolution = *resolution;
    }
    if (voxelSize) {
        if (!(*voxelSize > 0)) throw py::value_error("voxel_size must be positive");
        fo.voxelSize = *voxelSize;
    }
    if (dims) {
        if (dims->size() != 3) throw py::value_error("dims needs 3 values (cells along x, y, z)");
        for (const int64_t n : *dims)
            if (n < 1) throw py::value_error("dims must be at least 1 along every axis");
        fo.dims = {(*dims)[0], (*dims)[1], (*dims)[2]};
    }
    if (given == 0) fo.resolution = 256; // the command line's default
    if (bounds) {
        if (bounds->size() != 6)
            throw py::value_error("bounds needs 6 values: xmin ymin zmin xmax ymax zmax");
        fo.bounds.lo = {(*bounds)[0], (*bounds)[1], (*bounds)[2]};
        fo.bounds.hi = {(*bounds)[3], (*bounds)[4], (*bounds)[5]};
        if (fo.bounds.empty()) throw py::value_error("bounds needs min <= max on every axis");
    }
    if (margin < 0) throw py::value_error("margin must be >= 0");
    fo.marginCells = margin;
    fo.axis = parseAxis(axis);
    return fo;
}

/// A Python str from bytes that should be UTF-8 (messages quote file contents, which need not be):
/// invalid bytes become U+FFFD, as in the JSON report.
py::str utf8Text(const std::string& s) {
    PyObject* o = PyUnicode_DecodeUTF8(s.data(), py::ssize_t(s.size()), "replace");
    if (!o) throw py::error_already_set();
    return py::reinterpret_steal<py::str>(o);
}

/// A path argument: str or os.PathLike.
std::string pathString(const py::handle& p) { return py::str(py::module_::import("os").attr("fspath")(p)); }

} // namespace voxfx::python
