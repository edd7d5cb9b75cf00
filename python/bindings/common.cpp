// Helpers shared by the binding areas (see common.hpp).
#include "common.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <mutex>
#include <thread>

namespace voxfx::python {

// ---- interruption ---------------------------------------------------------------------------

namespace {

/// Whether this is the thread Python runs signal handlers on. Without the threading module no
/// other Python thread was started through it, so this is the main one (and `import voxfx` need
/// not import threading).
bool onMainThread() {
    static unsigned long mainThread = 0;
    if (mainThread == 0) {
        const py::dict modules = py::module_::import("sys").attr("modules");
        if (!modules.contains("threading")) return true;
        mainThread = modules["threading"].attr("main_thread")().attr("ident").cast<unsigned long>();
    }
    return PyThread_get_thread_ident() == mainThread;
}

} // namespace

void interruptible(const std::function<void(Cancel&)>& work) {
    Cancel cancel;
    if (!onMainThread()) {
        py::gil_scoped_release release;
        work(cancel);
        return;
    }
    std::mutex mutex;
    std::condition_variable finished;
    bool done = false;
    std::exception_ptr error;
    bool interrupted = false;
    {
        py::gil_scoped_release release;
        std::thread worker([&] {
            try {
                work(cancel);
            } catch (...) { error = std::current_exception(); }
            const std::lock_guard lock(mutex);
            done = true;
            finished.notify_one();
        });
        std::unique_lock lock(mutex);
        while (!finished.wait_for(lock, std::chrono::milliseconds(20), [&] { return done; })) {
            if (interrupted) continue;
            lock.unlock();
            {
                // A handler that raises leaves its exception set on this thread until we return.
                py::gil_scoped_acquire gil;
                if (PyErr_CheckSignals() != 0) {
                    interrupted = true;
                    cancel.request();
                }
            }
            lock.lock();
        }
        lock.unlock();
        worker.join();
    }
    if (interrupted) throw py::error_already_set();
    if (error) std::rethrow_exception(error);
}

// ---- meshes ---------------------------------------------------------------------------------

namespace {

std::string shapeText(const py::handle& a) { return py::str(a.attr("shape")); }

/// The recentring of float64 vertices (see common.hpp): zero unless some value is not a float32
/// and the mesh lies farther from the origin than twice its extent; else the bounds' centre.
Vec3d recentringOrigin(const double* v, std::size_t n) {
    bool exact = true;
    Vec3d lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const double x = v[3 * i + std::size_t(k)];
            exact = exact && (double(float(x)) == x || std::isnan(x));
            if (std::isfinite(x)) {
                lo[k] = std::min(lo[k], x);
                hi[k] = std::max(hi[k], x);
            }
        }
    if (exact || !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) return {0, 0, 0};
    double extent = 0, magnitude = 0;
    for (int k = 0; k < 3; ++k) {
        extent = std::max(extent, hi[k] - lo[k]);
        magnitude = std::max({magnitude, std::abs(lo[k]), std::abs(hi[k])});
    }
    if (!(magnitude > 2 * extent)) return {0, 0, 0};
    return (lo + hi) * 0.5;
}

/// Warns (UserWarning) when float32 positions lie so far from the origin for the part's size that
/// float32 keeps fewer than 256 steps across it (a small part far away collapses towards a point).
/// float64 input far away was recentred before, so its positions are near zero here.
void warnIfCollapsed(const Mesh& m) {
    if (m.positions.empty()) return;
    double extent = 0, magnitude = 0;
    for (int k = 0; k < 3; ++k) {
        float lo = INFINITY, hi = -INFINITY;
        for (const Vec3f& p : m.positions)
            if (std::isfinite(p[k])) lo = std::min(lo, p[k]), hi = std::max(hi, p[k]);
        if (!(lo <= hi)) return;
        extent = std::max(extent, double(hi) - double(lo));
        magnitude = std::max({magnitude, std::abs(double(lo)), std::abs(double(hi))});
    }
    if (!(magnitude > 0) || extent >= magnitude * 0x1p-16) return;
    const std::string text = "the mesh spans " + std::to_string(extent) + " but lies " +
                             std::to_string(magnitude) +
                             " from the origin: float32 positions keep fewer than 256 steps across it "
                             "(it collapses towards a point); pass float64 vertices (recentred "
                             "exactly) or move it to the origin";
    if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 2) != 0) throw py::error_already_set();
}

} // namespace

namespace {

/// `obj` as an array of numbers of shape (rows, 3): TypeError for other types, ArgumentError for
/// other shapes (`what` names it, `rows` the row count's letter).
py::array rowsOfThree(const py::handle& obj, const std::string& what, const std::string& rows) {
    const auto a = py::array::ensure(obj);
    const auto kind = a ? a.dtype().kind() : 'O';
    if (!a || (a.size() > 0 && kind != 'f' && kind != 'i' && kind != 'u'))
        throw py::type_error(what + " must be an array of numbers of shape (" + rows + ", 3)");
    if (a.ndim() != 2 || a.shape(1) != 3)
        throw ArgumentError(what + " must have shape (" + rows + ", 3), got " + shapeText(a));
    return a;
}

} // namespace

std::shared_ptr<PyMesh> meshFromArrays(const py::handle& verticesObj, const py::handle& facesObj) {
    auto out = std::make_shared<PyMesh>();
    const py::array asArray = rowsOfThree(verticesObj, "vertices", "N");
    const auto f = py::array::ensure(facesObj);
    if (!f) throw py::type_error("faces must be an integer array of shape (M, 3)");
    if (f.ndim() != 2 || f.shape(1) != 3)
        throw ArgumentError("faces must have shape (M, 3), got " + shapeText(f));
    if (f.size() > 0 && f.dtype().kind() != 'i' && f.dtype().kind() != 'u')
        throw py::type_error("faces must hold integers, got dtype " + std::string(py::str(f.dtype())));
    const std::size_t n = std::size_t(asArray.shape(0));
    out->mesh.positions.resize(n);
    if (asArray.dtype().is(py::dtype::of<float>())) {
        const auto v = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(asArray);
        if (n > 0) std::memcpy(&out->mesh.positions[0].x, v.data(), n * 3 * sizeof(float));
    } else {
        const auto v = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(asArray);
        const double* d = v.data();
        out->origin = recentringOrigin(d, n);
        for (std::size_t i = 0; i < n; ++i)
            for (int k = 0; k < 3; ++k)
                out->mesh.positions[i][k] = float(d[3 * i + std::size_t(k)] - out->origin[k]);
    }
    warnIfCollapsed(out->mesh);
    const auto fi = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(f);
    const std::size_t m = std::size_t(fi.shape(0));
    out->mesh.indices.resize(3 * m);
    const int64_t* idx = fi.data();
    for (std::size_t i = 0; i < 3 * m; ++i) {
        if (idx[i] < 0 || idx[i] > int64_t(UINT32_MAX))
            throw ArgumentError(detail::concat("face ", i / 3, " has vertex index ", idx[i], " outside 0..",
                                               n == 0 ? 0 : n - 1));
        out->mesh.indices[i] = uint32_t(idx[i]);
    }
    return out;
}

namespace {

/// meshio's cells as triangles: its "triangle" blocks, and "quad" blocks split along a diagonal.
py::array meshioTriangles(const py::object& cellsDict) {
    const py::module_ np = py::module_::import("numpy");
    py::list parts;
    if (cellsDict.contains("triangle")) parts.append(np.attr("asarray")(cellsDict["triangle"]));
    if (cellsDict.contains("quad")) {
        const py::object q = np.attr("asarray")(cellsDict["quad"]);
        const py::object a =
            q[py::make_tuple(py::slice(py::none(), py::none(), py::none()), py::make_tuple(0, 1, 2))];
        const py::object b =
            q[py::make_tuple(py::slice(py::none(), py::none(), py::none()), py::make_tuple(0, 2, 3))];
        parts.append(a);
        parts.append(b);
    }
    if (parts.empty()) throw ArgumentError("the meshio mesh has no triangle or quad cells");
    return np.attr("concatenate")(parts);
}

} // namespace

std::shared_ptr<PyMesh> meshArgument(const py::object& mesh, const py::object& faces) {
    if (py::isinstance<PyMesh>(mesh)) {
        if (!faces.is_none()) throw py::type_error("faces must not be given with a voxfx.Mesh");
        return mesh.cast<std::shared_ptr<PyMesh>>();
    }
    const py::module_ np = py::module_::import("numpy");
    const auto fromParts = [&](const py::object& v, const py::object& f) {
        if (!faces.is_none())
            throw py::type_error("faces must not be given with a mesh object or a (vertices, faces) pair");
        return meshFromArrays(np.attr("asarray")(v), np.attr("asarray")(f));
    };
    if (!py::isinstance<py::array>(mesh)) {
        if (py::hasattr(mesh, "vertices") && py::hasattr(mesh, "faces"))
            return fromParts(mesh.attr("vertices"), mesh.attr("faces"));
        if (py::hasattr(mesh, "vertices") && py::hasattr(mesh, "triangles")) // Open3D
            return fromParts(mesh.attr("vertices"), mesh.attr("triangles"));
        if (py::hasattr(mesh, "points") && py::hasattr(mesh, "cells_dict")) // meshio
            return fromParts(mesh.attr("points"), meshioTriangles(mesh.attr("cells_dict")));
        if ((py::isinstance<py::tuple>(mesh) || py::isinstance<py::list>(mesh)) && py::len(mesh) == 2 &&
            faces.is_none())
            return fromParts(py::reinterpret_borrow<py::sequence>(mesh)[0],
                             py::reinterpret_borrow<py::sequence>(mesh)[1]);
    }
    if (faces.is_none())
        throw py::type_error("a mesh is a voxfx.Mesh, an object with .vertices and .faces (or Open3D's "
                             ".triangles, meshio's .points and .cells_dict), a (vertices, faces) pair, or "
                             "vertices with faces=; got " +
                             std::string(py::str(py::type::of(mesh).attr("__name__"))) + " without faces");
    return meshFromArrays(mesh, faces);
}

py::array_t<double> verticesArray(const Mesh& m, const Vec3d& origin) {
    py::array_t<double> out({py::ssize_t(m.positions.size()), py::ssize_t(3)});
    double* d = out.mutable_data();
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        for (int k = 0; k < 3; ++k) d[3 * i + std::size_t(k)] = origin[k] + double(m.positions[i][k]);
    return out;
}

py::array_t<int64_t> facesArray(const std::vector<uint32_t>& indices) {
    py::array_t<int64_t> out({py::ssize_t(indices.size() / 3), py::ssize_t(3)});
    std::copy(indices.begin(), indices.end(), out.mutable_data());
    return out;
}

void requireFinitePoints(const py::array_t<double>& points, const char* what) {
    const double* p = points.data();
    for (py::ssize_t i = 0; i < points.shape(0); ++i)
        if (!std::isfinite(p[3 * i]) || !std::isfinite(p[3 * i + 1]) || !std::isfinite(p[3 * i + 2]))
            throw ArgumentError(std::string(what) + ": point " + std::to_string(i) +
                                " is not finite (NaN or infinite coordinates have no inside)");
}

py::array_t<double> pointsArgument(const py::object& points, const Vec3d& origin) {
    const py::array asArray = rowsOfThree(points, "points", "K");
    auto pts = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(asArray);
    if (origin.x == 0 && origin.y == 0 && origin.z == 0) return pts;
    py::array_t<double> moved({pts.shape(0), py::ssize_t(3)});
    const double* s = pts.data();
    double* d = moved.mutable_data();
    for (py::ssize_t i = 0; i < pts.shape(0); ++i)
        for (int k = 0; k < 3; ++k) d[3 * i + k] = s[3 * i + k] - origin[k];
    return moved;
}

// ---- grids ----------------------------------------------------------------------------------

py::tuple vec3(const Vec3d& v) { return py::make_tuple(v.x, v.y, v.z); }
py::tuple vec3(const Vec3i& v) { return py::make_tuple(v.x, v.y, v.z); }

py::tuple activeVoxelArrays(
    const std::function<void(std::vector<std::array<int32_t, 3>>&, std::vector<float>&)>& collect) {
    std::vector<std::array<int32_t, 3>> idx;
    std::vector<float> vals;
    {
        py::gil_scoped_release release;
        collect(idx, vals);
    }
    const py::ssize_t n = py::ssize_t(idx.size());
    py::array_t<int32_t> indices({n, py::ssize_t(3)});
    py::array_t<float> values(n);
    if (n > 0) {
        std::memcpy(indices.mutable_data(), idx.data(), idx.size() * sizeof(idx[0]));
        std::memcpy(values.mutable_data(), vals.data(), vals.size() * sizeof(float));
    }
    return py::make_tuple(indices, values);
}

void requireOrthographic(const VoxelGrid& g, const char* what) {
    if (g.frame.isPerspective()) fail(what, " needs an orthographic grid");
}

VoxelGrid uniformZ(const VoxelGrid& g) {
    VoxelGrid u = g.frame.slicing() == Slicing::Local ? resampleToUniform(g) : g;
    if (u.frame.axis() != Axis::Z) u = reslice(u, Axis::Z);
    return u;
}

// ---- options --------------------------------------------------------------------------------

namespace {

/// Bounds as six numbers (xmin ymin zmin xmax ymax zmax) or a (lo, hi) pair of triples.
Box3d boundsArgument(const py::object& bounds) {
    std::vector<double> v;
    try {
        const auto seq = py::reinterpret_borrow<py::sequence>(bounds);
        if (py::len(seq) == 2)
            for (const auto& part : seq)
                for (const auto& x : py::reinterpret_borrow<py::sequence>(part))
                    v.push_back(x.cast<double>());
        else
            for (const auto& x : seq) v.push_back(x.cast<double>());
    } catch (const py::error_already_set&) {
        throw py::type_error("bounds must be six numbers or a (lo, hi) pair of triples");
    } catch (const py::cast_error&) {
        throw py::type_error("bounds must be six numbers or a (lo, hi) pair of triples");
    }
    if (v.size() != 6)
        throw ArgumentError(
            "bounds needs 6 values (xmin ymin zmin xmax ymax zmax) or (lo, hi) as Grid.bounds "
            "gives them");
    Box3d b;
    b.lo = {v[0], v[1], v[2]};
    b.hi = {v[3], v[4], v[5]};
    if (b.empty()) throw ArgumentError("bounds needs min <= max on every axis");
    return b;
}

} // namespace

FitOptions fitOptions(const std::optional<int64_t>& resolution, const std::optional<double>& voxelSize,
                      const std::optional<std::vector<int64_t>>& dims, const py::object& bounds,
                      int64_t margin, const std::string& axis, bool cube) {
    const int given = int(resolution.has_value()) + int(voxelSize.has_value()) + int(dims.has_value());
    if (given > 1) throw ArgumentError("give at most one of resolution, voxel_size and dims");
    FitOptions fo;
    if (resolution) {
        if (*resolution < 1) throw ArgumentError("resolution must be at least 1");
        fo.resolution = *resolution;
    }
    if (voxelSize) {
        if (!(*voxelSize > 0)) throw ArgumentError("voxel_size must be positive");
        fo.voxelSize = *voxelSize;
    }
    if (dims) {
        if (dims->size() != 3) throw ArgumentError("dims needs 3 values (cells along x, y, z)");
        for (const int64_t n : *dims)
            if (n < 1) throw ArgumentError("dims must be at least 1 along every axis");
        fo.dims = {(*dims)[0], (*dims)[1], (*dims)[2]};
    }
    if (given == 0) fo.resolution = 256; // the command line's default
    if (cube && fo.resolution == 0)
        throw ArgumentError("cube=True needs a resolution (not voxel_size or dims)");
    fo.cube = cube;
    if (!bounds.is_none()) fo.bounds = boundsArgument(bounds);
    if (margin < 0) throw ArgumentError("margin must be >= 0");
    fo.marginCells = margin;
    fo.axis = asArgument([&] { return parseAxis(axis); });
    return fo;
}

py::str utf8Text(const std::string& s) {
    PyObject* o = PyUnicode_DecodeUTF8(s.data(), py::ssize_t(s.size()), "replace");
    if (!o) throw py::error_already_set();
    return py::reinterpret_steal<py::str>(o);
}

std::string pathString(const py::handle& p) {
    const py::module_ os = py::module_::import("os");
    if (!py::isinstance<py::str>(p) && !py::isinstance<py::bytes>(p) && !py::hasattr(p, "__fspath__"))
        throw py::type_error("a path must be a str, bytes or os.PathLike, got " +
                             std::string(py::str(py::type::of(p).attr("__name__"))));
    // The file system's bytes (os.fsencode undoes the surrogate escapes of undecodable names).
    const std::string s = os.attr("fsencode")(os.attr("fspath")(p)).cast<std::string>();
    if (s.find('\0') != std::string::npos)
        throw ArgumentError("path holds a NUL byte: " + std::string(py::repr(os.attr("fspath")(p))));
    return s;
}

} // namespace voxfx::python
