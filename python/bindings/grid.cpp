// Grids: voxfx.Grid (the slicemap and its frame), NumPy conversions, read_grid.
#include <cmath>
#include <cstring>
#include <span>

#include "common.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/grid_query.hpp"

namespace voxfx::python {
namespace {

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
    // Numbers other than 0 and 1 are refused, not cast (0.3 would be True): threshold them first.
    if (!arr.dtype().is(py::dtype::of<bool>())) {
        const auto v = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(arr);
        if (!v) throw py::type_error("from_numpy needs a bool array (or numbers that are all 0 or 1)");
        const double* d = v.data();
        for (py::ssize_t i = 0; i < v.size(); ++i)
            if (d[i] != 0 && d[i] != 1)
                throw ArgumentError("from_numpy: value " + std::string(py::str(py::float_(d[i]))) +
                                    " is neither 0 nor 1; threshold it first (from_numpy(a > 0.5)) or pass "
                                    "a bool array");
    }
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
    py::array out(py::dtype::of<uint64_t>(),
                  {py::ssize_t(b.height()), py::ssize_t(b.width()), py::ssize_t(b.wordsPerColumn())},
                  {py::ssize_t(b.width() * b.wordsPerColumn()) * e, py::ssize_t(b.wordsPerColumn()) * e, e},
                  b.words(), owner);
    // Read-only: a write could set padding bits, which every count and comparison assumes zero.
    out.attr("flags").attr("writeable") = false;
    return out;
}

/// Grid.set_words: the packed words from an (H, W, P) array, copied, padding bits cleared.
void setWords(VoxelGrid& g, const py::object& words) {
    BitGrid& b = g.bits;
    const auto a = py::array_t<uint64_t, py::array::c_style | py::array::forcecast>::ensure(words);
    if (!a || a.ndim() != 3 || a.shape(0) != b.height() || a.shape(1) != b.width() ||
        a.shape(2) != b.wordsPerColumn())
        throw ArgumentError("set_words needs a uint64 array of shape (" + std::to_string(b.height()) + ", " +
                            std::to_string(b.width()) + ", " + std::to_string(b.wordsPerColumn()) +
                            "), as Grid.words");
    const uint64_t* src = a.data();
    py::gil_scoped_release release;
    const int64_t P = b.wordsPerColumn();
    const uint64_t mask = b.lastWordMask();
    parallelFor(0, b.columnCount(), 1024, [&](int64_t c0, int64_t c1) {
        std::memcpy(b.column(c0), src + c0 * P, std::size_t((c1 - c0) * P) * sizeof(uint64_t));
        for (int64_t c = c0; c < c1; ++c) b.column(c)[P - 1] &= mask;
    });
}

void requireAxisAligned(const VoxelGrid& g, const char* what) {
    if (g.frame.isPerspective() || g.frame.isOriented())
        throw ArgumentError(std::string(what) + " needs an axis-aligned orthographic grid");
}

void requireUniform(const VoxelGrid& g, const char* what) {
    requireAxisAligned(g, what);
    if (g.frame.slicing() != Slicing::Uniform)
        throw ArgumentError(std::string(what) + " needs uniform slicing: resample_to_uniform(grid) first");
}

/// Pickle state: version, box lo and hi, axis, slicemap W H D, the words.
py::tuple gridState(const py::object& self) {
    const VoxelGrid& g = self.cast<const VoxelGrid&>();
    requireUniform(g, "pickling a grid");
    const py::array words = wordsArray(self.cast<GridPtr>(), self);
    return py::make_tuple(1, vec3(g.frame.box().lo), vec3(g.frame.box().hi), toString(g.frame.axis()),
                          g.bits.width(), g.bits.height(), g.bits.depth(), words.attr("copy")());
}

GridPtr gridFromState(const py::tuple& t) {
    if (t.size() != 8 || t[0].cast<int>() != 1) throw py::value_error("not a voxfx.Grid pickle (version 1)");
    const auto lo = t[1].cast<std::vector<double>>(), hi = t[2].cast<std::vector<double>>();
    Box3d box;
    box.lo = {lo.at(0), lo.at(1), lo.at(2)};
    box.hi = {hi.at(0), hi.at(1), hi.at(2)};
    auto g = std::make_shared<VoxelGrid>();
    g->frame = Frame::orthographic(box, parseAxis(t[3].cast<std::string>()), t[4].cast<int64_t>(),
                                   t[5].cast<int64_t>(), t[6].cast<int64_t>());
    g->bits = BitGrid(g->frame.width(), g->frame.height(), g->frame.depth());
    setWords(*g, t[7]);
    return g;
}

/// (K, 3) world-axis cell indices of world points (floor of the frame's grid coordinates: the
/// cell grid.contains looks up; may lie outside the grid).
py::array_t<int64_t> worldToIndex(const VoxelGrid& g, const py::object& pointsObj) {
    requireUniform(g, "world_to_index");
    const auto pts = pointsArgument(pointsObj);
    const py::ssize_t n = pts.shape(0);
    py::array_t<int64_t> out({n, py::ssize_t(3)});
    const double* p = pts.data();
    int64_t* o = out.mutable_data();
    const Axis a = g.frame.axis();
    const int cx = columnXAxis(a), cy = columnYAxis(a), cs = sliceAxis(a);
    for (py::ssize_t i = 0; i < n; ++i) {
        const Vec3d q = g.frame.gridFromWorld({p[3 * i], p[3 * i + 1], p[3 * i + 2]});
        const double f[3] = {std::floor(q.x), std::floor(q.y), std::floor(q.z)};
        if (!std::isfinite(f[0]) || !std::isfinite(f[1]) || !std::isfinite(f[2]) || std::abs(f[0]) > 9e18 ||
            std::abs(f[1]) > 9e18 || std::abs(f[2]) > 9e18)
            throw ArgumentError("world_to_index: point " + std::to_string(i) +
                                " is not finite or too far away");
        o[3 * i + cx] = int64_t(f[0]);
        o[3 * i + cy] = int64_t(f[1]);
        o[3 * i + cs] = int64_t(f[2]);
    }
    return out;
}

/// World centres of (K, 3) world-axis cell indices: lo + (index + 0.5) * cell (as centers()).
py::array_t<double> indexToWorld(const VoxelGrid& g, const py::object& indicesObj) {
    requireUniform(g, "index_to_world");
    const auto idx = pointsArgument(indicesObj);
    const py::ssize_t n = idx.shape(0);
    py::array_t<double> out({n, py::ssize_t(3)});
    const double* s = idx.data();
    double* o = out.mutable_data();
    const Vec3d lo = g.frame.box().lo, cell = g.frame.cellSize();
    for (py::ssize_t i = 0; i < 3 * n; ++i) o[i] = lo[int(i % 3)] + (s[i] + 0.5) * cell[int(i % 3)];
    return out;
}

/// The 4 x 4 matrix taking homogeneous world-axis indices (i, j, k, 1) to cell centres.
py::array_t<double> affine(const VoxelGrid& g) {
    requireUniform(g, "affine");
    py::array_t<double> out({py::ssize_t(4), py::ssize_t(4)});
    double* a = out.mutable_data();
    std::fill(a, a + 16, 0.0);
    const Vec3d lo = g.frame.box().lo, cell = g.frame.cellSize();
    for (int k = 0; k < 3; ++k) {
        a[4 * k + k] = cell[k];
        a[4 * k + 3] = lo[k] + 0.5 * cell[k];
    }
    a[15] = 1;
    return out;
}

/// indices() or centers(): (N, 3) arrays of the filled cells, two passes over the words.
template <class T> py::array_t<T> filledCells(const VoxelGrid& g) {
    requireUniform(g, "indices() and centers()");
    int64_t n;
    {
        py::gil_scoped_release release;
        n = g.bits.count();
    }
    py::array_t<T> out({py::ssize_t(n), py::ssize_t(3)});
    std::span<T> o(out.mutable_data(), std::size_t(3 * n));
    py::gil_scoped_release release;
    if constexpr (std::is_same_v<T, int32_t>)
        filledCellIndices(g, o);
    else
        filledCellCenters(g, o);
    return out;
}

py::array_t<bool> lookup(const VoxelGrid& g, const py::object& pointsObj) {
    requireAxisAligned(g, "Grid.contains");
    const auto pts = pointsArgument(pointsObj);
    requireFinitePoints(pts, "Grid.contains");
    const std::size_t n = std::size_t(pts.shape(0));
    py::array_t<bool> out{py::ssize_t(n)};
    const auto* p = reinterpret_cast<const Vec3d*>(pts.data());
    auto* o = reinterpret_cast<uint8_t*>(out.mutable_data());
    py::gil_scoped_release release;
    filledAt(g, std::span<const Vec3d>(p, n), std::span<uint8_t>(o, n));
    return out;
}

/// grid[i, j, k] with three integers (negative ones count from the end); anything else indexes
/// the dense array to_numpy() gives.
py::object getItem(const py::object& self, const py::object& key) {
    const VoxelGrid& g = self.cast<const VoxelGrid&>();
    if (py::isinstance<py::tuple>(key) && py::len(key) == 3) {
        const auto t = py::reinterpret_borrow<py::tuple>(key);
        bool ints = true;
        for (const auto& k : t) ints = ints && py::isinstance<py::int_>(k) && !py::isinstance<py::bool_>(k);
        if (ints) {
            requireUniform(g, "grid[i, j, k]");
            const Vec3i d = g.worldDims();
            int64_t ijk[3];
            for (int a = 0; a < 3; ++a) {
                int64_t v = t[std::size_t(a)].cast<int64_t>();
                if (v < 0) v += d[a];
                if (v < 0 || v >= d[a])
                    throw py::index_error("index " + std::to_string(t[std::size_t(a)].cast<int64_t>()) +
                                          " is out of bounds for axis " + std::to_string(a) + " with size " +
                                          std::to_string(d[a]));
                ijk[a] = v;
            }
            return py::bool_(g.atWorldIndex(ijk[0], ijk[1], ijk[2]));
        }
    }
    return self.attr("to_numpy")()[key];
}

std::string reprOf(const VoxelGrid& g) {
    const Vec3i d = g.worldDims();
    const Vec3d lo = g.frame.box().lo, c = g.frame.cellSize();
    const auto num = [](double v) { return std::string(py::str(py::float_(v))); };
    std::string cell =
        c.x == c.y && c.y == c.z ? num(c.x) : "(" + num(c.x) + ", " + num(c.y) + ", " + num(c.z) + ")";
    return "<voxfx.Grid " + std::to_string(d.x) + " x " + std::to_string(d.y) + " x " + std::to_string(d.z) +
           ", origin (" + num(lo.x) + ", " + num(lo.y) + ", " + num(lo.z) + "), cell " + cell + ", " +
           std::to_string(g.bits.count()) + " filled, axis " + toString(g.frame.axis()) +
           (g.frame.slicing() == Slicing::Local ? ", local slicing" : "") + ">";
}

/// The operators |, &, -, ^ (csg of grids in the same frame); NotImplemented for other types.
void bindOperators(py::class_<VoxelGrid, GridPtr>& grid) {
    const std::pair<const char*, CsgOp> ops[] = {{"__or__", CsgOp::Union},
                                                 {"__and__", CsgOp::Intersection},
                                                 {"__sub__", CsgOp::Difference},
                                                 {"__xor__", CsgOp::Xor}};
    for (const auto& [name, op] : ops)
        grid.def(name, [op = op](const VoxelGrid& a, const py::object& b) -> py::object {
            if (!py::isinstance<VoxelGrid>(b)) return py::reinterpret_borrow<py::object>(Py_NotImplemented);
            const VoxelGrid& other = b.cast<const VoxelGrid&>();
            if (!a.frame.sameGrid(other.frame))
                throw ArgumentError("grids combine only in the same frame (origin, cell size, dims, axis): "
                                    "voxelize the second with like=first");
            py::gil_scoped_release release;
            return py::cast(std::make_shared<VoxelGrid>(csg(a, other, op)));
        });
    grid.def("__eq__", [](const VoxelGrid& a, const py::object& b) -> py::object {
        if (!py::isinstance<VoxelGrid>(b)) return py::reinterpret_borrow<py::object>(Py_NotImplemented);
        const VoxelGrid& o = b.cast<const VoxelGrid&>();
        return py::bool_(a.frame.sameGrid(o.frame) && a.bits == o.bits);
    });
    grid.attr("__hash__") = py::none();
}

/// indices, centers, affine, the index/world maps, contains, [], __array__.
void bindArrays(py::class_<VoxelGrid, GridPtr>& grid) {
    grid.def("indices", &filledCells<int32_t>,
             "(N, 3) int32 world-axis indices (i, j, k) of the filled cells, in "
             "np.argwhere(grid.to_numpy())'s "
             "order, without a dense array")
        .def(
            "centers",
            [](const VoxelGrid& g, const py::object& dtype) -> py::object {
                const py::dtype dt = py::dtype::from_args(dtype);
                if (dt.is(py::dtype::of<float>())) return filledCells<float>(g);
                if (dt.is(py::dtype::of<double>())) return filledCells<double>(g);
                throw ArgumentError("centers: dtype must be float32 or float64");
            },
            py::arg("dtype") = py::dtype::of<double>(),
            "(N, 3) world centres of the filled cells (origin + (index + 0.5) * cell_size), in indices()' "
            "order")
        .def_property_readonly("affine", &affine,
                               "4 x 4 float64: (i, j, k, 1) -> the world centre of cell (i, j, k)")
        .def("world_to_index", &worldToIndex, py::arg("points"),
             "(K, 3) int64 indices of the cells holding world points (may lie outside the grid)")
        .def("index_to_world", &indexToWorld, py::arg("indices"), "(K, 3) world centres of cells (i, j, k)")
        .def("contains", &lookup, py::arg("points"),
             "(K,) bool: whether the cell holding each world point is filled (outside: False)")
        .def("__getitem__", &getItem)
        .def(
            "__array__",
            [](const py::object& self, const py::object& dtype, const py::object&) {
                py::object a = self.attr("to_numpy")();
                return dtype.is_none() ? a : a.attr("astype")(dtype);
            },
            py::arg("dtype") = py::none(), py::arg("copy") = py::none());
}

} // namespace

void bindGrid(py::module_& m) {
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
            [](const VoxelGrid& g) { return py::make_tuple(vec3(g.frame.box().lo), vec3(g.frame.box().hi)); },
            "((xmin, ymin, zmin), (xmax, ymax, zmax)); voxelize(bounds=grid.bounds, dims=grid.dims) makes "
            "the same frame")
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
            "The packed words without a copy, read-only, shape (H, W, P): column (x, y) holds slices "
            "s = 64k + b in bit b of word k; the array keeps the grid alive. set_words() writes them")
        .def("set_words", &setWords, py::arg("words"),
             "Copies an (H, W, P) uint64 array into the words (bits of slices >= D are cleared)")
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
        .def("save", &saveGrid<VoxelGrid>, py::arg("path"), py::arg("vdb_float") = false,
             py::arg("grid_name") = "voxels",
             "Writes .binvox .vdb .nrrd .ply .obj (by extension, atomically), as `voxfx voxelize` does")
        .def("copy", [](const VoxelGrid& g) { return std::make_shared<VoxelGrid>(g); })
        .def("__copy__", [](const VoxelGrid& g) { return std::make_shared<VoxelGrid>(g); })
        .def("__deepcopy__",
             [](const VoxelGrid& g, const py::object&) { return std::make_shared<VoxelGrid>(g); })
        .def(py::pickle(&gridState, &gridFromState))
        .def("__repr__", &reprOf);
    bindArrays(grid);
    bindOperators(grid);

    m.def(
        "read_grid",
        [](const py::object& pathObj) {
            const std::string path = pathString(pathObj);
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(readGrid(path));
        },
        py::arg("path"), "Reads a .binvox .vdb .nrrd grid");
    m.def("from_numpy", &fromNumpy, py::arg("array"), py::arg("origin") = std::vector<double>{0, 0, 0},
          py::arg("cell_size") = std::vector<double>{1, 1, 1},
          "A grid from a bool array indexed [x, y, z] (numbers only when all are 0 or 1; else an "
          "ArgumentError: "
          "threshold them first); voxel (0, 0, 0) has its lower corner at origin");
}

} // namespace voxfx::python
