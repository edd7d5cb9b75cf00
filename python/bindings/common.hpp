// voxfx Python module (voxfx._voxfx): what the binding areas share. The module is bound area by
// area, one file each (mesh.cpp, grid.cpp, ...), over the public C++ API only; module.cpp lists the
// areas (areas.inc) and binds them in that order.
//
// Conventions:
//   - Arrays in and out are NumPy arrays. Vertices are (N, 3) floating point; the library holds
//     positions as float32, so float64 input is rounded to float32 once (a mesh loaded with
//     load_mesh round-trips exactly). Faces are (M, 3) integers, checked by the library.
//   - Grid.to_numpy() is a bool array indexed [x, y, z] (world axes), whatever the slicing axis.
//   - Grid.words is the slicemap's packed 64-bit words without a copy: shape (H, W, P) for
//     columns (x, y) of the frame and P = ceil(D / 64) words per column; the array keeps the
//     grid alive.
//   - voxfx::Error becomes voxfx.Error (a RuntimeError) with the library's message; the GIL is
//     released while the library works.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "voxfx/voxfx.hpp"

namespace voxfx::python {

namespace py = pybind11;

/// Binds one area of the library into the module (one definition per file, listed in areas.inc).
#define VOXFX_PYTHON_AREA(Area) void bind##Area(py::module_& m);
#include "areas.inc"
#undef VOXFX_PYTHON_AREA

using GridPtr = std::shared_ptr<VoxelGrid>;

// ---- meshes ---------------------------------------------------------------------------------

/// A mesh in the library's layout (float32 positions, uint32 indices), owned by Python objects.
struct PyMesh {
    Mesh mesh;
    std::string source = "mesh";
};

/// Converts (vertices, faces) arrays into a library mesh: float32 positions, uint32 indices.
/// Shapes and index signs are checked here, the rest (range, finite) by validateMesh.
std::shared_ptr<PyMesh> meshFromArrays(const py::handle& verticesObj, const py::handle& facesObj);

/// A mesh argument: a voxfx.Mesh (used as is) or a vertices array with `faces`.
std::shared_ptr<PyMesh> meshArgument(const py::object& meshOrVertices, const py::object& faces);

py::array_t<double> verticesArray(const Mesh& m);
py::array_t<int64_t> facesArray(const std::vector<uint32_t>& indices);

// ---- grids ----------------------------------------------------------------------------------

py::tuple vec3(const Vec3d& v);
py::tuple vec3(const Vec3i& v);

void requireOrthographic(const VoxelGrid& g, const char* what);

/// The grid sliced along Z with uniform slicing: columns are (x, y), slices z.
VoxelGrid uniformZ(const VoxelGrid& g);

// ---- options and text -----------------------------------------------------------------------

/// The frame fitting of voxelize and batch: at most one of resolution, voxel size and dims
/// (none: resolution 256, the command line's default), bounds, margin, slicing axis.
FitOptions fitOptions(const std::optional<int64_t>& resolution, const std::optional<double>& voxelSize,
                      const std::optional<std::vector<int64_t>>& dims,
                      const std::optional<std::vector<double>>& bounds, int64_t margin,
                      const std::string& axis);

/// A Python str from bytes that should be UTF-8 (messages quote file contents, which need not be):
/// invalid bytes become U+FFFD, as in the JSON report.
py::str utf8Text(const std::string& s);

/// A path argument: str or os.PathLike.
std::string pathString(const py::handle& p);

} // namespace voxfx::python
