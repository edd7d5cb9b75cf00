// Batches as arrays: voxelize_many, many meshes (paths or mesh objects) voxelized in one call into
// one (B, R, R, R) bool array, or the filled cells with their batch index as (N, 4) int32 rows
// (b, i, j, k), the form sparse-convolution libraries take (MinkowskiEngine's batched coordinates,
// spconv's indices: batch index first). The Python wrapper (voxfx/_datasets.py) adds torch tensors.
#include <bit>
#include <cstring>
#include <exception>
#include <mutex>

#include "common.hpp"

namespace voxfx::python {
namespace {

/// One item of the batch: a mesh already converted (under the GIL), or a path loaded by a worker.
struct ManyItem {
    std::shared_ptr<PyMesh> mesh;
    std::string path;
};

/// The frame of voxelize(mesh, resolution=R, cube=True, padding=p) (or dims=): padding p keeps p
/// empty cells inside the resolution, as voxelize does (voxelize.cpp).
Frame manyFrame(const Mesh& mesh, FitOptions fo, int64_t padding) {
    if (padding > 0) {
        fo.resolution -= 2 * padding;
        fo.marginCells += padding;
    }
    validateMesh(mesh.view(), "mesh");
    return fitFrame(computeBounds(mesh.view()), fo);
}

/// Bits of a grid sliced along z with uniform slicing into a bool array [x, y, z] (C order).
void manyDense(const VoxelGrid& g, bool* out) {
    const Vec3i d = g.worldDims();
    for (int64_t x = 0; x < d.x; ++x)
        for (int64_t y = 0; y < d.y; ++y) {
            const uint64_t* col = g.bits.column(x, y);
            bool* dst = out + (x * d.y + y) * d.z;
            for (int64_t s = 0; s < d.z; ++s) dst[s] = (col[s >> 6] >> (s & 63)) & 1u;
        }
}

/// The filled cells as (b, i, j, k) rows in np.argwhere's order of the dense array: counted
/// first (popcounts), then written into an array of exactly that size.
void manyCoordinates(const VoxelGrid& g, int32_t b, std::vector<int32_t>& out) {
    const Vec3i d = g.worldDims();
    const int64_t words = (d.z + 63) / 64;
    int64_t n = 0;
    for (int64_t x = 0; x < d.x; ++x)
        for (int64_t y = 0; y < d.y; ++y) {
            const uint64_t* col = g.bits.column(x, y);
            for (int64_t w = 0; w < words; ++w) n += std::popcount(col[w]);
        }
    out.resize(std::size_t(4 * n));
    int32_t* o = out.data();
    for (int64_t x = 0; x < d.x; ++x)
        for (int64_t y = 0; y < d.y; ++y) {
            const uint64_t* col = g.bits.column(x, y);
            for (int64_t w = 0; w < words; ++w)
                for (uint64_t word = col[w]; word; word &= word - 1) {
                    o[0] = b, o[1] = int32_t(x), o[2] = int32_t(y),
                    o[3] = int32_t(w * 64 + std::countr_zero(word));
                    o += 4;
                }
        }
}

py::object voxelizeMany(const py::object& meshes, std::optional<Int> resolution,
                        std::optional<std::vector<int64_t>> dims, bool cube, Int padding,
                        const std::string& mode, const std::string& fill, int threads, bool sparse) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
    if (padding < 0) throw ArgumentError("padding must be >= 0");
    if (dims && cube) throw ArgumentError("give cube=True with a resolution, or dims= with cube=False");
    if (!dims && !cube)
        throw ArgumentError(
            "voxelize_many stacks the grids: they need one shape, so give cube=True (resolution^3 "
            "cells) or dims=(nx, ny, nz)");
    if (!dims && !resolution) resolution = 64;
    if (dims && padding) throw ArgumentError("padding needs cube=True and a resolution");
    const FitOptions fo = fitOptions(resolution, std::nullopt, dims, py::none(), 0, "z", cube);
    if (padding > 0 && fo.resolution <= 2 * padding)
        throw ArgumentError("padding needs a resolution above 2 * padding (the cells left for the mesh)");
    VoxelizeOptions vo;
    asArgument([&] {
        vo.mode = parseVoxelizeMode(mode);
        vo.fill = parseFill(fill);
    });
    vo.slicing = Slicing::Uniform;
    vo.emptyBorder = padding; // the ring stays empty in every mode (the flood enters through it)
    vo.threads = 0;           // nested in the loop over meshes: TBB shares the workers

    if (py::isinstance<py::str>(meshes) || py::isinstance<py::bytes>(meshes) ||
        !py::hasattr(meshes, "__iter__"))
        throw py::type_error("meshes must be a list of mesh paths or mesh objects (one path is not a batch)");
    std::vector<ManyItem> items;
    for (const py::handle h : meshes) {
        const py::object o = py::reinterpret_borrow<py::object>(h);
        if (py::isinstance<py::str>(o) || py::isinstance<py::bytes>(o) || py::hasattr(o, "__fspath__"))
            items.push_back({nullptr, pathString(o)});
        else
            items.push_back({meshArgument(o, py::none()), {}});
    }
    const auto B = int64_t(items.size());
    const Vec3i shape =
        dims ? Vec3i{(*dims)[0], (*dims)[1], (*dims)[2]} : Vec3i{fo.resolution, fo.resolution, fo.resolution};
    const uint64_t perGrid = uint64_t(shape.x) * uint64_t(shape.y) * uint64_t(shape.z);
    if (!sparse)
        asArgument([&] { checkMemory(uint64_t(B) * perGrid, "voxelize_many's (B, nx, ny, nz) array"); });
    py::array_t<bool> dense;
    bool* denseData = nullptr;
    if (!sparse) {
        dense = py::array_t<bool>(
            {py::ssize_t(B), py::ssize_t(shape.x), py::ssize_t(shape.y), py::ssize_t(shape.z)});
        denseData = dense.mutable_data();
    }
    std::vector<std::vector<int32_t>> coordinates(sparse ? std::size_t(B) : 0);
    // The first failure by item index (the others may run on; their errors are dropped).
    std::mutex errorMutex;
    int64_t errorItem = B;
    std::string errorText;
    interruptible([&](Cancel& cancel) {
        vo.progress = &cancel;
        withThreads(threads, [&] {
            parallelFor(0, B, 1, [&](int64_t b, int64_t e) {
                for (int64_t i = b; i < e; ++i) {
                    if (cancel.requested()) return;
                    const ManyItem& item = items[std::size_t(i)];
                    try {
                        Mesh loaded;
                        if (!item.mesh) loaded = loadMesh(item.path);
                        const Mesh& mesh = item.mesh ? item.mesh->mesh : loaded;
                        const Frame frame = manyFrame(mesh, fo, padding);
                        const VoxelGrid g = voxelize(mesh.view(), frame, vo);
                        const Vec3i d = g.worldDims();
                        if (d.x != shape.x || d.y != shape.y || d.z != shape.z)
                            fail("its grid is ", d.x, " x ", d.y, " x ", d.z, ", not ", shape.x, " x ",
                                 shape.y, " x ", shape.z);
                        if (sparse)
                            manyCoordinates(g, int32_t(i), coordinates[std::size_t(i)]);
                        else
                            manyDense(g, denseData + uint64_t(i) * perGrid);
                    } catch (const std::exception& ex) {
                        const std::lock_guard lock(errorMutex);
                        if (i < errorItem) {
                            errorItem = i;
                            errorText = ex.what();
                        }
                    }
                }
            });
        });
        if (cancel.requested()) fail("voxelize_many: cancelled");
    });
    if (errorItem < B) {
        const ManyItem& item = items[std::size_t(errorItem)];
        throw Error("voxelize_many: item " + std::to_string(errorItem) +
                    (item.mesh ? " (" + item.mesh->source + ")" : " ('" + item.path + "')") + ": " +
                    errorText);
    }
    if (!sparse) return dense;
    std::size_t rows = 0;
    for (const auto& c : coordinates) rows += c.size() / 4;
    py::array_t<int32_t> out({py::ssize_t(rows), py::ssize_t(4)});
    int32_t* o = out.mutable_data();
    for (const auto& c : coordinates) {
        if (!c.empty()) std::memcpy(o, c.data(), c.size() * sizeof(int32_t));
        o += c.size();
    }
    return out;
}

} // namespace

void bindDatasets(py::module_& m) {
    m.def(
        "voxelize_many", &voxelizeMany, py::arg("meshes"), py::arg("resolution") = py::none(), py::kw_only(),
        py::arg("dims") = py::none(), py::arg("cube") = true, py::arg("padding") = 0,
        py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("threads") = 0,
        py::arg("sparse") = false,
        "Voxelizes many meshes (a list of paths, or of anything voxelize takes) in one call, the meshes in "
        "parallel (threads: 0 = all), each grid as voxelize(mesh, resolution=R, cube=True, padding=p, mode=, "
        "fill=) gives it (default R = 64), or with dims=(nx, ny, nz) and cube=False. Returns one bool array "
        "(B, R, R, R) indexed [b, x, y, z]; sparse=True instead returns the filled cells as an (N, 4) int32 "
        "array of rows (b, i, j, k), batch index first (MinkowskiEngine's and spconv's convention; within a "
        "grid in np.argwhere's order), no dense array built. A mesh that fails raises voxfx.Error naming the "
        "first failing item. The GIL is released; Ctrl-C stops it between meshes and tiles.");
}

} // namespace voxfx::python
