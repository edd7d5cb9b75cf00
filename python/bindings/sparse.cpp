// Sparse grids (voxfx/sparse_grid.hpp): voxfx.SparseGrid, whose cells come out as an (N, 3) int32
// coordinate array with the grid's transform (what sparse-convolution libraries take) without a
// dense array, and read_sparse_grid. voxfx.voxelize(..., sparse=True) returns one (voxelize.cpp).
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
            [](SparseGrid& g, int steps, int neighbours) -> SparseGrid& {
                return g.dilate(steps, neighboursOf(neighbours));
            },
            py::arg("steps") = 1, py::arg("neighbours") = 26, py::return_value_policy::reference_internal,
            "In place: OpenVDB's dilation by `steps` over 6, 18 or 26 neighbours (26: a box)")
        .def(
            "erode",
            [](SparseGrid& g, int steps, int neighbours) -> SparseGrid& {
                return g.erode(steps, neighboursOf(neighbours));
            },
            py::arg("steps") = 1, py::arg("neighbours") = 26, py::return_value_policy::reference_internal,
            "In place: OpenVDB's erosion (outside the grid counts as empty)")
        .def("copy", [](const SparseGrid& g) { return std::make_shared<SparseGrid>(g); })
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
