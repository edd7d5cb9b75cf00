// voxfx Python module (voxfx._voxfx): meshes, voxelization, grids as NumPy arrays, the grid
// toolkit and exact point occupancy, over the public C++ API only.
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
#include <algorithm>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "voxfx/contains.hpp"
#include "voxfx/voxfx.hpp"

namespace py = pybind11;
using namespace voxfx;

namespace {

using GridPtr = std::shared_ptr<VoxelGrid>;

// ---- meshes ---------------------------------------------------------------------------------

/// A mesh in the library's layout (float32 positions, uint32 indices), owned by Python objects.
struct PyMesh {
    Mesh mesh;
    std::string source = "mesh";
};

/// Converts (vertices, faces) arrays into a library mesh: float32 positions, uint32 indices.
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

// ---- grids ----------------------------------------------------------------------------------

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

/// Occupancy as a bool array indexed [x, y, z].
py::array_t<bool> toNumpy(const VoxelGrid& g) {
    requireOrthographic(g, "to_numpy");
    const Vec3i d = g.worldDims();
    py::array_t<bool> out({py::ssize_t(d.x), py::ssize_t(d.y), py::ssize_t(d.z)});
    bool* o = out.mutable_data();
    {
        py::gil_scoped_release release;
        const VoxelGrid z =
            g.frame.axis() == Axis::Z && g.frame.slicing() == Slicing::Uniform ? VoxelGrid{} : uniformZ(g);
        const VoxelGrid& src = z.bits.empty() ? g : z;
        const int64_t nx = d.x, ny = d.y, nz = d.z;
        parallelFor(0, nx * ny, 256, [&](int64_t b, int64_t e) {
            for (int64_t c = b; c < e; ++c) {
                const int64_t x = c / ny, y = c % ny;
                const uint64_t* col = src.bits.column(x, y);
                bool* dst = o + c * nz;
                for (int64_t s = 0; s < nz; ++s) dst[s] = (col[s >> 6] >> (s & 63)) & 1u;
            }
        });
    }
    return out;
}

/// A grid from a bool array indexed [x, y, z], placed in the box lo + dims * cell.
GridPtr fromNumpy(const py::array& arr, const std::vector<double>& origin, const std::vector<double>& cell) {
    const auto a = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(arr);
    if (!a || a.ndim() != 3)
        throw py::value_error("from_numpy needs a 3-dimensional array indexed [x, y, z]");
    if (origin.size() != 3 || cell.size() != 3) throw py::value_error("origin and cell_size need 3 values");
    const int64_t nx = a.shape(0), ny = a.shape(1), nz = a.shape(2);
    Box3d box;
    box.lo = {origin[0], origin[1], origin[2]};
    box.hi = {origin[0] + double(nx) * cell[0], origin[1] + double(ny) * cell[1],
              origin[2] + double(nz) * cell[2]};
    auto g = std::make_shared<VoxelGrid>();
    const bool* src = a.data();
    {
        py::gil_scoped_release release;
        g->frame = Frame::orthographic(box, Axis::Z, nx, ny, nz);
        g->bits = BitGrid(nx, ny, nz);
        BitGrid& bits = g->bits;
        parallelFor(0, nx * ny, 256, [&](int64_t b, int64_t e) {
            for (int64_t c = b; c < e; ++c) {
                const int64_t x = c / ny, y = c % ny;
                uint64_t* col = bits.column(x, y);
                const bool* s = src + c * nz;
                for (int64_t k = 0; k < nz; ++k)
                    if (s[k]) col[k >> 6] |= uint64_t(1) << (k & 63);
            }
        });
    }
    return g;
}

py::array wordsArray(const GridPtr& g, const py::object& owner) {
    const BitGrid& b = g->bits;
    const py::ssize_t e = sizeof(uint64_t);
    return py::array(
        py::dtype::of<uint64_t>(),
        {py::ssize_t(b.height()), py::ssize_t(b.width()), py::ssize_t(b.wordsPerColumn())},
        {py::ssize_t(b.width() * b.wordsPerColumn()) * e, py::ssize_t(b.wordsPerColumn()) * e, e}, b.words(),
        owner);
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

struct VoxelizeResult {
    GridPtr grid;
    Fill fill;
    std::string deviceNote; ///< why a device="cuda" request ran on the CPU
};

/// What `voxfx voxelize` does between loading and writing: the fill ("auto": parity for closed
/// meshes, flood otherwise), the fitted frame, the voxelization.
VoxelizeResult voxelizeMesh(const Mesh& mesh, const FitOptions& fo, const std::string& mode,
                            const std::string& fill, const std::string& slicing, int threads,
                            const std::string& device = "cpu") {
    VoxelizeOptions vo;
    vo.device = parseDevice(device);
    std::string note;
    vo.deviceNote = &note;
    vo.mode = parseVoxelizeMode(mode);
    vo.slicing = parseSlicing(slicing);
    vo.threads = threads;
    const bool inside = vo.mode == VoxelizeMode::Solid || vo.mode == VoxelizeMode::SolidConservative ||
                        vo.mode == VoxelizeMode::Interior;
    if (fill == "auto") {
        // The topology (hashing every edge) only matters where the fill does.
        vo.fill = inside && analyzeTopology(mesh.view()).closed() ? Fill::Parity : Fill::Flood;
    } else {
        vo.fill = parseFill(fill);
    }
    validateMesh(mesh.view(), "mesh");
    const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
    auto grid = std::make_shared<VoxelGrid>(voxelize(mesh.view(), frame, vo));
    return {std::move(grid), vo.fill, vo.device == Device::Cuda ? note : std::string()};
}

/// The world radii of a morphology: one number for all axes or three.
Vec3i radii(const py::object& r) {
    if (py::isinstance<py::int_>(r)) {
        const int64_t v = r.cast<int64_t>();
        return {v, v, v};
    }
    const auto v = r.cast<std::vector<int64_t>>();
    if (v.size() != 3) throw py::value_error("radius needs one value or three (along x, y, z)");
    return {v[0], v[1], v[2]};
}

// ---- density --------------------------------------------------------------------------------

/// A density map of a grid sliced along Z (so its cells are in world order), with the fine
/// frame it was computed from.
struct PyDensity {
    DensityGrid density;
    Frame fine;
};

// ---- batch ----------------------------------------------------------------------------------

/// A Python str from bytes that should be UTF-8 (messages quote file contents, which need not be):
/// invalid bytes become U+FFFD, as in the JSON report.
py::str utf8Text(const std::string& s) {
    PyObject* o = PyUnicode_DecodeUTF8(s.data(), py::ssize_t(s.size()), "replace");
    if (!o) throw py::error_already_set();
    return py::reinterpret_steal<py::str>(o);
}

/// A path argument: str or os.PathLike.
std::string pathString(const py::handle& p) { return py::str(py::module_::import("os").attr("fspath")(p)); }

/// JSON text of the library's batch report (batchReportJson, batchResultJson) as Python objects:
/// the dicts voxfx.batch returns and hands to progress have the report file's shape by construction.
py::object batchJsonObject(const std::string& text) {
    return py::module_::import("json").attr("loads")(text);
}

/// The batch's grid format from an extension, with or without its dot.
GridFormat batchGridFormat(const std::string& format) {
    return gridFormatFromPath("x" + (format.starts_with(".") ? format : "." + format));
}

/// The jobs of a batch argument: a manifest path (str or os.PathLike) or an iterable of mesh paths.
std::vector<BatchJob> batchJobsArgument(const py::object& manifestOrList, const std::string& outDir,
                                        GridFormat format) {
    if (py::isinstance<py::str>(manifestOrList) || py::hasattr(manifestOrList, "__fspath__")) {
        const std::string manifest = pathString(manifestOrList);
        py::gil_scoped_release release;
        return readBatchManifest(manifest, outDir, format);
    }
    std::vector<std::string> meshes;
    for (const py::handle p : manifestOrList) meshes.push_back(pathString(p));
    return batchJobs(meshes, outDir, format);
}

/// Calls a Python callable per finished job, from the worker thread that finished it (runBatch
/// serializes the calls), holding the GIL for the call only. The first exception it raises stops
/// further calls (the meshes go on) and is raised again when the batch is over.
class PyBatchProgress : public BatchProgress {
public:
    explicit PyBatchProgress(py::object fn) : fn_(std::move(fn)) {}
    void jobDone(const BatchResult& r, int64_t done, int64_t total) override {
        if (error_) return;
        py::gil_scoped_acquire gil;
        try {
            fn_(batchJsonObject(batchResultJson(r)), done, total);
        } catch (...) { error_ = std::current_exception(); }
    }
    void raiseIfFailed() const {
        if (error_) std::rethrow_exception(error_);
    }

private:
    py::object fn_;
    std::exception_ptr error_;
};

} // namespace

PYBIND11_MODULE(_voxfx, m) {
    m.doc() = "voxfx: voxelization of triangle meshes into bit grids (slicemaps), with NumPy arrays";
    static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
    error.attr("__module__") = "voxfx";
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const Error& e) {
            // Messages quote file contents, which need not be UTF-8: invalid bytes are replaced
            // (PyErr_SetString would raise UnicodeDecodeError instead of voxfx.Error).
            const py::str message = utf8Text(e.what());
            PyErr_SetObject(error.ptr(), message.ptr());
        }
    });

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

    // ---- Grid
    py::class_<VoxelGrid, GridPtr> grid(m, "Grid",
                                        "A voxel grid: packed bits (slicemap) and the frame placing them.");
    grid.def_property_readonly(
            "origin", [](const VoxelGrid& g) { return vec3(g.frame.box().lo); },
            "World lower corner of voxel (0, 0, 0)")
        .def_property_readonly("cell_size", [](const VoxelGrid& g) { return vec3(g.frame.cellSize()); })
        .def_property_readonly(
            "dims", [](const VoxelGrid& g) { return vec3(g.worldDims()); }, "Cells along world x, y, z")
        .def_property_readonly(
            "bounds",
            [](const VoxelGrid& g) { return py::make_tuple(vec3(g.frame.box().lo), vec3(g.frame.box().hi)); })
        .def_property_readonly("axis",
                               [](const VoxelGrid& g) { return std::string(toString(g.frame.axis())); })
        .def_property_readonly("slicing",
                               [](const VoxelGrid& g) { return std::string(toString(g.frame.slicing())); })
        .def_property_readonly(
            "shape",
            [](const VoxelGrid& g) {
                return py::make_tuple(g.bits.width(), g.bits.height(), g.bits.depth());
            },
            "Slicemap dimensions (W, H, D): columns x, columns y, slices")
        .def_property_readonly(
            "words", [](py::object self) { return wordsArray(self.cast<GridPtr>(), self); },
            "The packed words without a copy, shape (H, W, P): column (x, y) holds slices s = 64k + b in "
            "bit b of word k; the array keeps the grid alive and writes go to the grid")
        .def("count",
             [](const VoxelGrid& g) {
                 py::gil_scoped_release release;
                 return g.bits.count();
             })
        .def("filled_volume",
             [](const VoxelGrid& g) {
                 py::gil_scoped_release release;
                 return filledVolume(g);
             })
        .def("to_numpy", &toNumpy, "Occupancy as a bool array indexed [x, y, z]")
        .def(
            "save",
            [](const VoxelGrid& g, const std::string& path, bool vdbFloat, const std::string& gridName) {
                GridWriteOptions wo;
                wo.vdbFloat = vdbFloat;
                wo.gridName = gridName;
                py::gil_scoped_release release;
                writeGrid(g, path, wo);
            },
            py::arg("path"), py::arg("vdb_float") = false, py::arg("grid_name") = "voxels",
            "Writes .binvox .vdb .nrrd .ply .obj (by extension, atomically), as `voxfx voxelize` does")
        .def("copy", [](const VoxelGrid& g) { return std::make_shared<VoxelGrid>(g); })
        .def("__eq__", [](const VoxelGrid& a,
                          const VoxelGrid& b) { return a.frame.sameGrid(b.frame) && a.bits == b.bits; })
        .def("__repr__", [](const VoxelGrid& g) {
            const Vec3i d = g.worldDims();
            return "<voxfx.Grid " + std::to_string(d.x) + " x " + std::to_string(d.y) + " x " +
                   std::to_string(d.z) + ", axis " + toString(g.frame.axis()) + ">";
        });
    grid.attr("__hash__") = py::none();

    m.def(
        "voxelize",
        [](const py::object& meshOrVertices, const py::object& faces, std::optional<int64_t> resolution,
           std::optional<double> voxelSize, std::optional<std::vector<int64_t>> dims,
           std::optional<std::vector<double>> bounds, int64_t margin, const std::string& mode,
           const std::string& fill, const std::string& axis, const std::string& slicing, int threads,
           const std::string& device) {
            const auto mesh = meshArgument(meshOrVertices, faces);
            const FitOptions fo = fitOptions(resolution, voxelSize, dims, bounds, margin, axis);
            if (threads < 0) throw py::value_error("threads must be >= 0");
            VoxelizeResult result;
            {
                py::gil_scoped_release release;
                result = voxelizeMesh(mesh->mesh, fo, mode, fill, slicing, threads, device);
            }
            // device="cuda" without a usable GPU: the CPU's grid, and a RuntimeWarning saying why.
            if (!result.deviceNote.empty() &&
                PyErr_WarnEx(PyExc_RuntimeWarning, ("device='cuda': " + result.deviceNote).c_str(), 1) != 0)
                throw py::error_already_set();
            return result.grid;
        },
        py::arg("vertices"), py::arg("faces") = py::none(), py::kw_only(), py::arg("resolution") = py::none(),
        py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(), py::arg("bounds") = py::none(),
        py::arg("margin") = 0, py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("axis") = "z",
        py::arg("slicing") = "uniform", py::arg("threads") = 0, py::arg("device") = "cpu",
        "Voxelizes a mesh (a voxfx.Mesh, or vertices and faces arrays) like `voxfx voxelize`: resolution "
        "(default 256), voxel_size or dims; bounds (xmin ymin zmin xmax ymax zmax); mode surface | "
        "conservative | solid | solid-conservative | interior; fill auto | parity | flood | vote | winding | "
        "gwn "
        "(auto: parity for closed meshes, flood otherwise); threads 0 = all; device cpu | cuda | auto "
        "(the same grid; cuda without a usable GPU warns and runs on the CPU; see cuda_status()).");

    m.def(
        "cuda_status",
        [] {
            const CudaStatus& s = cudaStatus();
            py::dict d;
            d["built"] = s.built;
            d["available"] = s.available;
            d["device"] = s.device;
            d["reason"] = s.reason;
            return d;
        },
        "Whether the CUDA back end can run here: {'built', 'available', 'device', 'reason'}.");

    m.def(
        "read_grid",
        [](const std::string& path) {
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(readGrid(path));
        },
        py::arg("path"), "Reads a .binvox .vdb .nrrd grid");
    m.def("from_numpy", &fromNumpy, py::arg("array"), py::arg("origin") = std::vector<double>{0, 0, 0},
          py::arg("cell_size") = std::vector<double>{1, 1, 1},
          "A grid from a bool array indexed [x, y, z]; voxel (0, 0, 0) has its lower corner at origin");

    // ---- toolkit
    m.def(
        "reslice",
        [](const VoxelGrid& g, const std::string& axis) {
            const Axis a = parseAxis(axis);
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
            const MorphOp o = parseMorphOp(op);
            MorphologyOptions mo;
            mo.border = parseMorphBorder(border);
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
                mo.border = parseMorphBorder(border);
                mo.threads = threads;
                const Vec3i r = radii(radius);
                const MorphOp o = parseMorphOp(op);
                py::gil_scoped_release release;
                return std::make_shared<VoxelGrid>(morphology(g, o, r, mo));
            },
            py::arg("grid"), py::arg("radius") = 1, py::kw_only(), py::arg("border") = "neutral",
            py::arg("threads") = 0);
    }
    m.def(
        "csg",
        [](const VoxelGrid& a, const VoxelGrid& b, const std::string& op) {
            const CsgOp o = parseCsgOp(op);
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(csg(a, b, o));
        },
        py::arg("a"), py::arg("b"), py::arg("op"),
        "a op b (union | intersection | difference | xor) for grids in the same frame");

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
            [](const PyDensity& d, const std::string& path) {
                py::gil_scoped_release release;
                writeDensity(d.density, d.fine, path);
            },
            py::arg("path"), "Writes .nrrd (uint8/16 counts) or .vdb (FloatGrid \"density\")");
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
            [](const SurfaceMesh& s, const std::string& path) {
                py::gil_scoped_release release;
                writeSurfaceMesh(s, path);
            },
            py::arg("path"), "Writes .ply or .obj");
    m.def(
        "extract_surface",
        [](const VoxelGrid& g, const std::string& source, int level, float iso, int threads) {
            SurfaceOptions so;
            so.source = parseSurfaceSource(source);
            so.level = level;
            so.iso = iso;
            so.threads = threads;
            py::gil_scoped_release release;
            return std::make_shared<SurfaceMesh>(extractSurface(g, so));
        },
        py::arg("grid"), py::kw_only(), py::arg("source") = "density", py::arg("level") = 1,
        py::arg("iso") = 0.5f, py::arg("threads") = 0,
        "Marching cubes over the grid's density map (or its 0/1 occupancy)");

    // ---- exact point occupancy
    // Points as a (K, 3) float64 array (converted when needed), answers as a (K,) bool array.
    const auto classifyPoints = [](const PointClassifier& c, const py::object& pointsObj) {
        const auto pts = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(pointsObj);
        if (!pts || pts.ndim() != 2 || pts.shape(1) != 3)
            throw py::value_error("points must be an array of shape (K, 3)");
        const std::size_t n = std::size_t(pts.shape(0));
        py::array_t<bool> out(std::vector<py::ssize_t>{py::ssize_t(n)});
        static_assert(sizeof(bool) == 1);
        auto* o = reinterpret_cast<uint8_t*>(out.mutable_data());
        const auto* p = reinterpret_cast<const Vec3d*>(pts.data());
        py::gil_scoped_release release;
        c.classify(std::span<const Vec3d>(p, n), std::span<uint8_t>(o, n));
        return out;
    };
    const auto containsOptions = [](const std::string& method, std::optional<int64_t> resolution, int threads,
                                    double windingBeta) {
        ContainsOptions co;
        if (!(windingBeta >= 0)) throw py::value_error("winding_beta must be >= 0");
        co.windingBeta = windingBeta;
        co.method = parseContainsMethod(method);
        if (resolution && *resolution < 1) throw py::value_error("resolution must be at least 1");
        co.resolution = resolution.value_or(0);
        if (threads < 0) throw py::value_error("threads must be >= 0");
        co.threads = threads;
        return co;
    };
    m.def(
        "contains",
        [classifyPoints, containsOptions](
            const py::object& meshOrVertices, const py::object& faces, const py::object& pointsObj,
            const std::string& method, std::optional<int64_t> resolution, int threads, double windingBeta) {
            // contains(mesh, points): a voxfx.Mesh takes the faces' place.
            py::object facesArg = faces, pointsArg = pointsObj;
            if (py::isinstance<PyMesh>(meshOrVertices) && pointsArg.is_none()) std::swap(facesArg, pointsArg);
            const auto mesh = meshArgument(meshOrVertices, facesArg);
            ContainsOptions co = containsOptions(method, resolution, threads, windingBeta);
            const auto n = py::len(pointsArg);
            if (co.resolution == 0) co.resolution = defaultContainsResolution(mesh->mesh.triangleCount(), n);
            std::unique_ptr<PointClassifier> c;
            {
                py::gil_scoped_release release;
                c = std::make_unique<PointClassifier>(mesh->mesh.view(), co);
            }
            return classifyPoints(*c, pointsArg);
        },
        py::arg("vertices"), py::arg("faces") = py::none(), py::arg("points") = py::none(), py::kw_only(),
        py::arg("method") = "parity", py::arg("resolution") = py::none(), py::arg("threads") = 0,
        py::arg("winding_beta") = 3.0,
        "Whether each point (K, 3) lies inside the mesh: parity (exact, voxel centres' tie rule), winding "
        "(generalized winding number >= 0.5, Barill et al.'s approximation with winding_beta; 0 = exact "
        "sum) or flood (cells sealed off from the border, for open meshes)");
    py::class_<PointClassifier>(m, "PointClassifier",
                                "A mesh prepared for repeated contains() queries (the grids are built once)")
        .def(py::init([containsOptions](const py::object& meshOrVertices, const py::object& faces,
                                        const std::string& method, std::optional<int64_t> resolution,
                                        int threads, double windingBeta) {
                 const auto mesh = meshArgument(meshOrVertices, faces);
                 ContainsOptions co = containsOptions(method, resolution, threads, windingBeta);
                 if (co.resolution == 0)
                     co.resolution = defaultContainsResolution(mesh->mesh.triangleCount(), 1000000);
                 py::gil_scoped_release release;
                 return std::make_unique<PointClassifier>(mesh->mesh.view(), co);
             }),
             py::arg("vertices"), py::arg("faces") = py::none(), py::kw_only(), py::arg("method") = "parity",
             py::arg("resolution") = py::none(), py::arg("threads") = 0, py::arg("winding_beta") = 3.0)
        .def("__call__", classifyPoints, py::arg("points"), "(K,) bool: whether each point lies inside")
        .def_property_readonly("resolution", &PointClassifier::resolution);

    // ---- batch
    m.def(
        "batch",
        [](const py::object& manifestOrList, const py::object& outDirObj, const std::string& format,
           std::optional<int64_t> resolution, std::optional<double> voxelSize,
           std::optional<std::vector<int64_t>> dims, std::optional<std::vector<double>> bounds,
           int64_t margin, const std::string& mode, const std::string& fill, const std::string& axis,
           const std::string& slicing, bool vdbFloat, int threads, bool nested, bool skipExisting,
           const py::object& report, const py::object& progress) {
            const std::string outDir = pathString(outDirObj);
            const GridFormat gridFormat = batchGridFormat(format);
            BatchOptions bo;
            bo.fit = fitOptions(resolution, voxelSize, dims, bounds, margin, axis);
            bo.voxelize.mode = parseVoxelizeMode(mode);
            bo.voxelize.slicing = parseSlicing(slicing);
            bo.autoFill = fill == "auto";
            if (!bo.autoFill) bo.voxelize.fill = parseFill(fill);
            bo.write.vdbFloat = vdbFloat;
            if (threads < 0) throw py::value_error("threads must be >= 0");
            bo.threads = threads;
            bo.nested = nested;
            bo.skipExisting = skipExisting;
            std::string reportPath;
            if (report.is_none()) {
                reportPath = (std::filesystem::path(outDir) / "report.json").string();
            } else if (!(py::isinstance<py::bool_>(report) && !report.cast<bool>())) {
                reportPath = pathString(report);
            }
            const std::vector<BatchJob> jobs = batchJobsArgument(manifestOrList, outDir, gridFormat);
            std::optional<PyBatchProgress> pyProgress;
            if (!progress.is_none()) {
                if (!PyCallable_Check(progress.ptr()))
                    throw py::type_error("progress must be callable as progress(job, done, total), or None");
                bo.progress = &pyProgress.emplace(progress);
            }
            BatchSummary summary;
            {
                py::gil_scoped_release release;
                std::error_code ec;
                std::filesystem::create_directories(outDir, ec);
                if (ec) fail("cannot create output folder '", outDir, "': ", ec.message());
                summary = runBatch(jobs, bo);
                if (!reportPath.empty()) writeBatchReport(summary, reportPath);
            }
            if (pyProgress) pyProgress->raiseIfFailed();
            return batchJsonObject(batchReportJson(summary, -1));
        },
        py::arg("meshes"), py::arg("out_dir"), py::kw_only(), py::arg("format") = ".binvox",
        py::arg("resolution") = py::none(), py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(),
        py::arg("bounds") = py::none(), py::arg("margin") = 0, py::arg("mode") = "solid",
        py::arg("fill") = "auto", py::arg("axis") = "z", py::arg("slicing") = "uniform",
        py::arg("vdb_float") = false, py::arg("threads") = 0, py::arg("nested") = false,
        py::arg("skip_existing") = true, py::arg("report") = py::none(), py::arg("progress") = py::none(),
        "Voxelizes many meshes in this process, as `voxfx batch` does (the same outputs, byte for byte): "
        "meshes is a manifest file (one path per line, relative to its folder, '#' comments) or a list of "
        "paths; mesh M is written to out_dir/<stem of M><format>. Options as voxelize; threads: workers for "
        "the whole batch (0 = all), each mesh on one of them (nested=True: on all). A mesh that fails is "
        "recorded with its error and the rest go on; existing outputs are skipped (skip_existing=False "
        "redoes them). report: the JSON report's path (None: out_dir/report.json, False: none). progress: "
        "progress(job, done, total) after each mesh, from a worker thread. Returns the report as a dict: "
        "ok, skipped, errors, seconds, ok_per_second (meshes written per second; failed ones are not in "
        "it) and jobs, a list of {mesh, output, status ('ok', 'skipped', 'error'), error, triangles, ms} "
        "in the order given. The GIL is released while meshes are processed.");

    m.def(
        "batch_jobs",
        [](const py::object& manifestOrList, const py::object& outDirObj, const std::string& format) {
            py::list out;
            for (const BatchJob& j :
                 batchJobsArgument(manifestOrList, pathString(outDirObj), batchGridFormat(format)))
                out.append(py::make_tuple(utf8Text(j.mesh), utf8Text(j.output)));
            return out;
        },
        py::arg("meshes"), py::arg("out_dir"), py::kw_only(), py::arg("format") = ".binvox",
        "The (mesh, output) pairs voxfx.batch(meshes, out_dir, format=...) would process, in order, "
        "without running them: the manifest read and the outputs named as `voxfx batch` does, with "
        "its error for two meshes of the same stem.");

    m.attr("__version__") = "0.1.0";
}
