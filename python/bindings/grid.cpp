// Grids: voxfx.Grid (the slicemap and its frame), NumPy conversions, read_grid.
#include <cstring>

#include "common.hpp"

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

} // namespace

void bindGrid(py::module_& m) {
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
        "read_grid",
        [](const std::string& path) {
            py::gil_scoped_release release;
            return std::make_shared<VoxelGrid>(readGrid(path));
        },
        py::arg("path"), "Reads a .binvox .vdb .nrrd grid");
    m.def("from_numpy", &fromNumpy, py::arg("array"), py::arg("origin") = std::vector<double>{0, 0, 0},
          py::arg("cell_size") = std::vector<double>{1, 1, 1},
          "A grid from a bool array indexed [x, y, z]; voxel (0, 0, 0) has its lower corner at origin");
}

} // namespace voxfx::python
