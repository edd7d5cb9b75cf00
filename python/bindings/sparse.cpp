// Sparse grids (voxfx/sparse_grid.hpp): voxfx.SparseGrid, whose cells come out as an (N, 3) int32
// coordinate array with the grid's transform (what sparse-convolution libraries take) without a
// dense array, and read_sparse_grid. voxfx.voxelize(..., sparse=True) returns one (voxelize.cpp).
#include <algorithm>
#include <cstring>

#include "common.hpp"

namespace voxfx::python {

namespace {

using SparsePtr = std::shared_ptr<SparseGrid>;

// The cells as an (N, 3) int32 array that owns the library's vector (no copy).
py::array_t<int32_t> coordinatesArray(const SparseGrid& g) {
    auto xyz = std::make_unique<std::vector<int32_t>>();
    {
        py::gil_scoped_release release;
        *xyz = g.coordinates();
    }
    const auto n = py::ssize_t(xyz->size() / 3);
    int32_t* data = xyz->data();
    py::capsule owner(xyz.release(), [](void* p) { delete static_cast<std::vector<int32_t>*>(p); });
    return py::array_t<int32_t>({n, py::ssize_t(3)}, {py::ssize_t(12), py::ssize_t(4)}, data, owner);
}

// Index-to-world of the voxel centres: world = transform @ (i, j, k, 1).
py::array_t<double> transformMatrix(const Frame& f) {
    py::array_t<double> t({4, 4});
    auto m = t.mutable_unchecked<2>();
    const Vec3d cell = f.cellSize(), lo = f.box().lo;
    for (py::ssize_t r = 0; r < 4; ++r)
        for (py::ssize_t c = 0; c < 4; ++c) m(r, c) = r == c ? 1.0 : 0.0;
    for (int a = 0; a < 3; ++a) {
        m(a, a) = cell[a];
        m(a, 3) = lo[a] + 0.5 * cell[a];
    }
    return t;
}

/// dilate or erode by `steps`, stoppable by Ctrl-C: OpenVDB's morphology runs 16 steps at a time,
/// the cancel polled between. Steps beyond the grid's extent (its dims summed: any filled cell
/// then reaches every cell of the grid, as dense morphology clamps its radius) are clamped to it,
/// and a clamped dilation is clipped to the grid's cells [0, dims), which it then fills alike.
SparseGrid& morphSteps(SparseGrid& g, int64_t steps, Neighbours n, bool erode) {
    if (steps < 0) throw ArgumentError(std::string(erode ? "erosion" : "dilation") + " steps must be >= 0");
    const Vec3i d = g.dims();
    const int64_t limit = d.x + d.y + d.z;
    const bool clamped = steps > limit;
    int64_t left = std::min(steps, limit);
    interruptible([&](Cancel& cancel) {
        while (left > 0) {
            const int k = int(std::min<int64_t>(left, 16));
            if (erode)
                g.erode(k, n);
            else
                g.dilate(k, n);
            left -= k;
            if (left > 0 && cancel.requested()) fail("cancelled");
        }
        if (clamped && !erode) g.clip(IndexBox{Vec3i{0, 0, 0}, Vec3i{d.x - 1, d.y - 1, d.z - 1}});
    });
    return g;
}

/// Pickle state: version, the frame (box lo, hi, axis, W H D) and the cells as runs along k:
/// (N, 4) int32 rows (i, j, k0, k1) (inclusive), from coordinates().
py::tuple sparseState(const SparseGrid& g) {
    std::vector<int32_t> xyz;
    {
        py::gil_scoped_release release;
        xyz = g.coordinates();
    }
    // Sorted by (i, j, k), then merged into runs.
    const std::size_t n = xyz.size() / 3;
    std::vector<std::size_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return std::lexicographical_compare(&xyz[3 * a], &xyz[3 * a + 3], &xyz[3 * b], &xyz[3 * b + 3]);
    });
    std::vector<int32_t> runs;
    for (std::size_t r = 0; r < n; ++r) {
        const int32_t* c = &xyz[3 * order[r]];
        if (!runs.empty() && runs[runs.size() - 4] == c[0] && runs[runs.size() - 3] == c[1] &&
            runs.back() + 1 == c[2])
            runs.back() = c[2];
        else
            runs.insert(runs.end(), {c[0], c[1], c[2], c[2]});
    }
    py::array_t<int32_t> arr({py::ssize_t(runs.size() / 4), py::ssize_t(4)});
    if (!runs.empty()) std::memcpy(arr.mutable_data(), runs.data(), runs.size() * sizeof(int32_t));
    const Frame& f = g.frame();
    return py::make_tuple(1, vec3(f.box().lo), vec3(f.box().hi), toString(f.axis()), f.width(), f.height(),
                          f.depth(), arr);
}

SparsePtr sparseFromState(const py::tuple& t) {
    if (t.size() != 8 || t[0].cast<int>() != 1)
        throw py::value_error("not a voxfx.SparseGrid pickle (version 1)");
    const auto lo = t[1].cast<std::vector<double>>(), hi = t[2].cast<std::vector<double>>();
    Box3d box;
    box.lo = {lo.at(0), lo.at(1), lo.at(2)};
    box.hi = {hi.at(0), hi.at(1), hi.at(2)};
    const Frame frame = Frame::orthographic(box, parseAxis(t[3].cast<std::string>()), t[4].cast<int64_t>(),
                                            t[5].cast<int64_t>(), t[6].cast<int64_t>());
    const auto runs = t[7].cast<py::array_t<int32_t, py::array::c_style | py::array::forcecast>>();
    auto out = std::make_shared<SparseGrid>(frame);
    const int32_t* r = runs.data();
    const py::ssize_t n = runs.ndim() == 2 ? runs.shape(0) : 0;
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i, r += 4)
        out->fill(IndexBox{Vec3i{r[0], r[1], r[2]}, Vec3i{r[0], r[1], r[3]}});
    return out;
}

Neighbours neighboursOf(int n) {
    if (n != 6 && n != 18 && n != 26) throw py::value_error("neighbours must be 6, 18 or 26");
    return Neighbours(n);
}

} // namespace

void bindSparse(py::module_& m) {
    py::class_<SparseGrid, SparsePtr> sparse(
        m, "SparseGrid",
        "Filled voxels without the dense grid: OpenVDB's tree (8^3 leaves where cells are mixed, tiles "
        "where uniform). Indices (i, j, k) run along world x, y, z.");
    sparse
        .def_property_readonly(
            "dims", [](const SparseGrid& g) { return vec3(g.dims()); }, "Cells along world x, y, z")
        .def_property_readonly(
            "count", [](const SparseGrid& g) { return g.count(); }, "Number of filled cells")
        .def_property_readonly("cell_size", [](const SparseGrid& g) { return vec3(g.frame().cellSize()); })
        .def_property_readonly(
            "origin", [](const SparseGrid& g) { return vec3(g.frame().box().lo); },
            "World lower corner of voxel (0, 0, 0)")
        .def_property_readonly(
            "transform", [](const SparseGrid& g) { return transformMatrix(g.frame()); },
            "4x4 index-to-world matrix of the voxel centres: world = transform @ (i, j, k, 1)")
        .def_property_readonly(
            "index_bounds",
            [](const SparseGrid& g) {
                const IndexBox b = g.bounds();
                return b.empty() ? py::object(py::none())
                                 : py::object(py::make_tuple(vec3(b.lo), vec3(b.hi)));
            },
            "The filled cells' index box (inclusive lo, hi), or None when empty")
        .def_property_readonly("memory_bytes", [](const SparseGrid& g) { return g.memoryBytes(); })
        .def("coordinates", &coordinatesArray,
             "The filled cells as an (N, 3) int32 array of (i, j, k), no dense array built (the tree's "
             "order, the same on every run); world centres: coordinates * cell_size + origin + cell_size / 2")
        .def("indices", &coordinatesArray, "coordinates(), under voxfx.Grid.indices' name")
        .def(
            "to_grid",
            [](const SparseGrid& g) {
                py::gil_scoped_release release;
                return std::make_shared<VoxelGrid>(g.toDense());
            },
            "The cells [0, dims) as a dense voxfx.Grid (it must fit in memory)")
        .def_static(
            "from_grid",
            [](const VoxelGrid& g) {
                py::gil_scoped_release release;
                return std::make_shared<SparseGrid>(SparseGrid::fromDense(g));
            },
            py::arg("grid"), "The filled cells of a dense voxfx.Grid")
        .def("save", &saveGrid<SparseGrid>, py::arg("path"), py::arg("vdb_float") = false,
             py::arg("grid_name") = "voxels",
             "Writes .vdb from the tree (other formats through the dense grid), atomically")
        .def("unite", &SparseGrid::unite, py::arg("other"), py::return_value_policy::reference_internal,
             "In place: OpenVDB's topology union with a grid of the same frame")
        .def("intersect", &SparseGrid::intersect, py::arg("other"),
             py::return_value_policy::reference_internal)
        .def("subtract", &SparseGrid::subtract, py::arg("other"), py::return_value_policy::reference_internal)
        .def(
            "dilate",
            [](SparseGrid& g, Int steps, Int neighbours) -> SparseGrid& {
                return morphSteps(g, steps, neighboursOf(int(neighbours)), false);
            },
            py::arg("steps") = 1, py::arg("neighbours") = 26, py::return_value_policy::reference_internal,
            "In place: OpenVDB's dilation by `steps` over 6, 18 or 26 neighbours (26: a box). Steps beyond "
            "the grid's extent (dims summed) are clamped to it and the result clipped to the grid's cells; "
            "Ctrl-C stops it")
        .def(
            "erode",
            [](SparseGrid& g, Int steps, Int neighbours) -> SparseGrid& {
                return morphSteps(g, steps, neighboursOf(int(neighbours)), true);
            },
            py::arg("steps") = 1, py::arg("neighbours") = 26, py::return_value_policy::reference_internal,
            "In place: OpenVDB's erosion (outside the grid counts as empty; steps clamped as dilate's); "
            "Ctrl-C stops it")
        .def("copy", [](const SparseGrid& g) { return std::make_shared<SparseGrid>(g); })
        .def("__copy__", [](const SparseGrid& g) { return std::make_shared<SparseGrid>(g); })
        .def("__deepcopy__",
             [](const SparseGrid& g, const py::object&) { return std::make_shared<SparseGrid>(g); })
        .def(py::pickle(&sparseState, &sparseFromState))
        .def("__repr__", [](const SparseGrid& g) {
            const Vec3i d = g.dims();
            return "<voxfx.SparseGrid " + std::to_string(d.x) + " x " + std::to_string(d.y) + " x " +
                   std::to_string(d.z) + ", " + std::to_string(g.count()) + " filled>";
        });

    m.def(
        "read_sparse_grid",
        [](const py::object& pathObj) {
            const std::string path = pathString(pathObj);
            py::gil_scoped_release release;
            return std::make_shared<SparseGrid>(readSparseGrid(path));
        },
        py::arg("path"), "Reads .vdb as a SparseGrid without a dense grid (.binvox and .nrrd through one)");
}

} // namespace voxfx::python
