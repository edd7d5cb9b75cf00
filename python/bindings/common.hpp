// voxfx Python module (voxfx._voxfx): what the binding areas share. The module is bound area by
// area, one file each (mesh.cpp, grid.cpp, ...), over the public C++ API only; module.cpp lists the
// areas (areas.inc) and binds them in that order.
//
// Conventions:
//   - Arrays in and out are NumPy arrays. Vertices are (N, 3) floating point; the library holds
//     positions as float32. float32 input, and float64 input whose values float32 holds exactly,
//     is kept as is; other float64 input far from the origin (farther than twice its extent) is
//     recentred in double first, the offset kept in PyMesh::origin and carried into the grids'
//     frames and the points of queries, so a small mesh far away keeps its shape.
//   - Grid.to_numpy() is a bool array indexed [x, y, z] (world axes), whatever the slicing axis.
//   - Grid.words is the slicemap's packed 64-bit words without a copy, read-only: shape (H, W, P)
//     for columns (x, y) of the frame and P = ceil(D / 64) words per column; the array keeps the
//     grid alive. Grid.set_words writes them (a copy, padding bits cleared).
//   - voxfx::Error becomes voxfx.Error (a RuntimeError) with the library's message; a bad
//     argument (a name, a size, a path) voxfx.ArgumentError, which is also a ValueError. Long
//     calls release the GIL and, on the main thread, stop at Ctrl-C (interruptible()).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "voxfx/voxfx.hpp"

namespace voxfx::python {

namespace py = pybind11;

/// An integer argument (a resolution, a count, a padding) that refuses bool: resolution=True is a
/// TypeError, not 1 (bool is an int in Python). Converts to int64_t.
struct Int {
    int64_t value = 0;
    Int() = default;
    Int(int64_t v) : value(v) {}
    operator int64_t() const { return value; }
};

/// Binds one area of the library into the module (one definition per file, listed in areas.inc).
#define VOXFX_PYTHON_AREA(Area) void bind##Area(py::module_& m);
#include "areas.inc"
#undef VOXFX_PYTHON_AREA

using GridPtr = std::shared_ptr<VoxelGrid>;

} // namespace voxfx::python

namespace pybind11::detail {
template <> struct type_caster<voxfx::python::Int> {
    PYBIND11_TYPE_CASTER(voxfx::python::Int, const_name("int"));
    bool load(handle src, bool convert) {
        if (PyBool_Check(src.ptr()))
            throw type_error("expected an integer, got bool " + std::string(str(src)));
        make_caster<int64_t> c;
        if (!c.load(src, convert)) return false;
        value.value = cast_op<int64_t>(c);
        return true;
    }
    static handle cast(const voxfx::python::Int& v, return_value_policy, handle) {
        return PyLong_FromLongLong(v.value);
    }
};
} // namespace pybind11::detail

namespace voxfx::python {

// ---- errors and interruption ----------------------------------------------------------------

/// A bad argument: raised in Python as voxfx.ArgumentError (a voxfx.Error and a ValueError).
struct ArgumentError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Runs f, turning a voxfx::Error it throws (the library's parsers and checks of arguments) into
/// an ArgumentError with the same message.
template <class F> auto asArgument(F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const MemoryLimitError&) {
        throw; // a refusal for want of memory stays one
    } catch (const Error& e) { throw ArgumentError(e.what()); }
}

/// The cancellation the library polls (Progress): set by Ctrl-C or by a Python callback that
/// raised. Thread-safe.
class Cancel final : public Progress {
public:
    bool update(double) override { return !stop_.load(std::memory_order_relaxed); }
    void request() { stop_ = true; }
    bool requested() const { return stop_; }

private:
    std::atomic<bool> stop_{false};
};

/// Runs work(cancel) without the GIL. On the main thread (where Python runs signal handlers) it
/// runs on a helper thread while this one checks for signals every 20 ms; a signal handler that
/// raises (KeyboardInterrupt at Ctrl-C) requests the cancel, waits for the work to stop at the
/// library's next poll, and that exception is raised instead of the work's result. Elsewhere the
/// work runs on the calling thread. The work must take the GIL itself for any Python call.
void interruptible(const std::function<void(Cancel&)>& work);

// ---- meshes ---------------------------------------------------------------------------------

/// A mesh in the library's layout (float32 positions, uint32 indices), owned by Python objects.
/// World position = origin + position (origin zero unless float64 input was recentred).
struct PyMesh {
    Mesh mesh;
    Vec3d origin{0, 0, 0};
    std::string source = "mesh";
    bool shifted() const { return origin.x != 0 || origin.y != 0 || origin.z != 0; }
};

/// Converts (vertices, faces) arrays into a library mesh (see the conventions above). Shapes,
/// dtypes and index signs are checked here (TypeError, ArgumentError), the rest (range, finite)
/// by validateMesh.
std::shared_ptr<PyMesh> meshFromArrays(const py::handle& verticesObj, const py::handle& facesObj);

/// A mesh argument: a voxfx.Mesh (used as is); an object with .vertices and .faces (trimesh, a
/// voxfx.SurfaceMesh) or .triangles (Open3D), or .points and .cells_dict (meshio: its triangles,
/// quads split in two); a (vertices, faces) pair; or a vertices array with `faces`.
std::shared_ptr<PyMesh> meshArgument(const py::object& mesh, const py::object& faces);

/// World positions (origin + position) as an (N, 3) float64 array.
py::array_t<double> verticesArray(const Mesh& m, const Vec3d& origin = {0, 0, 0});
py::array_t<int64_t> facesArray(const std::vector<uint32_t>& indices);

/// (K, 3) points as doubles, moved by -origin (a copy then); TypeError/ArgumentError otherwise.
/// The array keeps the data alive.
py::array_t<double> pointsArgument(const py::object& points, const Vec3d& origin = {0, 0, 0});

/// ArgumentError naming the first point with a NaN or infinite coordinate (inside tests have no
/// answer for them; distances give NaN instead).
void requireFinitePoints(const py::array_t<double>& points, const char* what);

/// `a` made read-only (writes would be lost: the arrays are copies) and returned.
template <class A> A readOnly(A a) {
    a.attr("setflags")(py::arg("write") = false);
    return a;
}

// ---- grids ----------------------------------------------------------------------------------

py::tuple vec3(const Vec3d& v);
py::tuple vec3(const Vec3i& v);
/// A narrow band's active voxels as NumPy arrays: (indices (N, 3) int32, values (N,) float32), the
/// GIL released while `collect(indices, values)` gathers them (SignedDistanceField::activeVoxels,
/// LevelSet::activeVoxels).
py::tuple activeVoxelArrays(
    const std::function<void(std::vector<std::array<int32_t, 3>>&, std::vector<float>&)>& collect);

void requireOrthographic(const VoxelGrid& g, const char* what);

/// The grid sliced along Z with uniform slicing: columns are (x, y), slices z.
VoxelGrid uniformZ(const VoxelGrid& g);

// ---- options and text -----------------------------------------------------------------------

/// The frame fitting of voxelize and batch: at most one of resolution, voxel size and dims
/// (none: resolution 256, the command line's default), bounds (six numbers, or the (lo, hi) pair
/// that Grid.bounds gives), margin, slicing axis, cube (resolution^3 cubic cells).
FitOptions fitOptions(const std::optional<int64_t>& resolution, const std::optional<double>& voxelSize,
                      const std::optional<std::vector<int64_t>>& dims, const py::object& bounds,
                      int64_t margin, const std::string& axis, bool cube = false);

/// A Python str from bytes that should be UTF-8 (messages quote file contents, which need not be):
/// invalid bytes become U+FFFD, as in the JSON report.
py::str utf8Text(const std::string& s);

/// A path argument: str, bytes or os.PathLike (os.fspath, then os.fsdecode). TypeError for other
/// types, ArgumentError for a NUL byte (the C library would open the path up to it: another file).
std::string pathString(const py::handle& p);

/// voxfx.sdf: the signed distance field of a mesh argument on a grid fitted as voxelize() fits it
/// (band: a width in voxels or "full"), in world coordinates (a recentred mesh's origin added back).
std::shared_ptr<SignedDistanceField>
makeSdf(const py::object& meshObj, const py::object& faces, std::optional<int64_t> resolution,
        std::optional<double> voxelSize, const py::object& bounds, std::optional<int64_t> margin, bool cube,
        const std::variant<double, std::string>& band, const std::string& fill, int threads,
        std::optional<int64_t> padding = std::nullopt, const py::object& like = py::none());

/// Grid.save and SparseGrid.save: writeGrid with the GIL released (by extension, atomically).
template <class G>
void saveGrid(const G& grid, const py::object& pathObj, bool vdbFloat, const std::string& gridName) {
    GridWriteOptions wo;
    wo.vdbFloat = vdbFloat;
    wo.gridName = gridName;
    const std::string path = pathString(pathObj);
    py::gil_scoped_release release;
    writeGrid(grid, path, wo);
}

} // namespace voxfx::python
