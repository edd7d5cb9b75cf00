// Voxelization: voxelize (as `voxfx voxelize` does) and cuda_status; the two pieces of a grid
// voxelized across a cluster (voxfx.dask.voxelize_grid): _grid_frame and _voxelize_stacks.
#include <cstring>

#include "common.hpp"
#include "voxfx/tiled.hpp"

namespace voxfx::python {
namespace {

struct VoxelizeRequest {
    std::string mode, fill, slicing, device;
    int threads = 0;
    bool sparse = false;
    int64_t padding = 0;
};

struct VoxelizeResult {
    GridPtr grid;
    std::shared_ptr<SparseGrid> sparse; ///< sparse=True: the tiles' tree, no dense grid
    std::string deviceNote;             ///< why a device="cuda" request ran on the CPU
};

/// What `voxfx voxelize` does between loading and writing: the voxelization into `frame` (in the
/// mesh's own coordinates); fill "auto" is the library's Fill::Auto (parity for closed meshes,
/// flood otherwise).
VoxelizeResult voxelizeMesh(const Mesh& mesh, const Frame& frame, const VoxelizeRequest& r,
                            Progress* progress, VoxelizeReport* report) {
    VoxelizeOptions vo;
    vo.device = parseDevice(r.device);
    std::string note;
    vo.deviceNote = &note;
    vo.mode = parseVoxelizeMode(r.mode);
    vo.slicing = parseSlicing(r.slicing);
    vo.threads = r.threads;
    vo.progress = progress;
    vo.fill = parseFill(r.fill); // Fill::Auto: voxelize() decides, as the CLI's does
    vo.emptyBorder = r.padding;  // the padding ring stays empty in every mode
    vo.report = report;
    if (r.sparse)
        return {nullptr, std::make_shared<SparseGrid>(voxelizeSparse(mesh.view(), frame, vo)),
                vo.device == Device::Cuda ? note : std::string()};
    auto grid = std::make_shared<VoxelGrid>(voxelize(mesh.view(), frame, vo));
    return {std::move(grid), nullptr, vo.device == Device::Cuda ? note : std::string()};
}

/// The frame in the mesh's own coordinates: like's (moved by -origin), or fitted to the mesh.
/// Fitting a padding p keeps p empty cells inside the resolution: resolution - 2p for the mesh,
/// p more on every side.
Frame voxelizeFrame(const PyMesh& mesh, FitOptions fo, const py::object& like, int64_t padding) {
    if (!like.is_none()) {
        if (!py::isinstance<VoxelGrid>(like)) throw py::type_error("like must be a voxfx.Grid");
        const Frame& f = like.cast<const VoxelGrid&>().frame;
        return mesh.shifted() ? asArgument([&] { return f.translated(mesh.origin * -1.0); }) : f;
    }
    if (padding < 0) throw ArgumentError("padding must be >= 0");
    if (padding > 0) {
        if (fo.resolution <= 2 * padding)
            throw ArgumentError("padding needs a resolution above 2 * padding (the cells left for the mesh)");
        fo.resolution -= 2 * padding;
        fo.marginCells += padding;
    }
    if (!fo.bounds.empty() && mesh.shifted()) {
        fo.bounds.lo = fo.bounds.lo - mesh.origin;
        fo.bounds.hi = fo.bounds.hi - mesh.origin;
    }
    asArgument([&] { validateMesh(mesh.mesh.view(), "mesh"); });
    return fitFrame(computeBounds(mesh.mesh.view()), fo);
}

/// Warns when dims make the cells of a fitted grid unequal (the mesh stretched).
void warnIfStretched(const Frame& frame, const std::optional<std::vector<int64_t>>& dims) {
    if (!dims) return;
    const Vec3d c = frame.cellSize();
    const double lo = std::min({c.x, c.y, c.z}), hi = std::max({c.x, c.y, c.z});
    if (hi <= lo * (1 + 1e-9)) return;
    const std::string text =
        "voxelize: dims (" + std::to_string((*dims)[0]) + ", " + std::to_string((*dims)[1]) + ", " +
        std::to_string((*dims)[2]) + ") give cells of " + std::string(py::str(vec3(c))) +
        ": not cubic, the mesh is stretched; resolution=N with cube=True keeps cells cubic";
    if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 2) != 0) throw py::error_already_set();
}

// A frame as plain values, (lo, hi, axis, width, height, depth): what a task needs to rebuild it
// exactly (Frame::orthographic, as SparseGrid's pickle does).
py::tuple frameState(const Frame& f) {
    return py::make_tuple(vec3(f.box().lo), vec3(f.box().hi), toString(f.axis()), f.width(), f.height(),
                          f.depth());
}

Frame frameFromState(const py::tuple& t) {
    if (t.size() != 6) throw ArgumentError("a frame is (lo, hi, axis, width, height, depth)");
    const auto lo = t[0].cast<std::vector<double>>(), hi = t[1].cast<std::vector<double>>();
    Box3d box;
    box.lo = {lo.at(0), lo.at(1), lo.at(2)};
    box.hi = {hi.at(0), hi.at(1), hi.at(2)};
    return asArgument([&] {
        return Frame::orthographic(box, parseAxis(t[2].cast<std::string>()), t[3].cast<int64_t>(),
                                   t[4].cast<int64_t>(), t[5].cast<int64_t>());
    });
}

// One brick as a task returns it: the packed bits copied out of the visitor's call.
struct KeptBrick {
    GridTile tile;
    std::vector<uint64_t> words;
};

// The bricks of the stacks [sx0, sx1) x [sy0, sy1), in the grid's [x, y, z] order: a list of
// (x0, y0, z0, value) with value a bool (a uniform brick) or a bool array (w, h, d).
py::list voxelizeStacks(const PyMesh& mesh, const py::tuple& state, const std::vector<int64_t>& stacks,
                        int64_t brick, const std::string& mode, const std::string& fill, int threads) {
    if (stacks.size() != 4) throw ArgumentError("stacks must be (x0, y0, x1, y1)");
    const Frame frame = frameFromState(state);
    if (frame.axis() != Axis::Z) throw ArgumentError("the bricks of a grid are written along axis z only");
    VoxelizeOptions vo;
    asArgument([&] {
        vo.mode = parseVoxelizeMode(mode);
        vo.fill = parseFill(fill);
    });
    vo.threads = threads;
    TileOptions to;
    to.brickSize = brick;
    to.stackX0 = stacks[0];
    to.stackY0 = stacks[1];
    to.stackX1 = stacks[2];
    to.stackY1 = stacks[3];
    std::vector<KeptBrick> kept;
    std::mutex keptMutex;
    interruptible([&](Cancel& cancel) {
        vo.progress = &cancel;
        voxelizeTiles(mesh.mesh.view(), frame, vo, to, [&](const GridTile& tile) {
            KeptBrick k{tile, {}};
            if (!tile.uniform) {
                const BitGridView& b = tile.bits;
                k.words.assign(b.words, b.words + b.columnCount() * b.wordsPerColumn);
            }
            k.tile.bits = {};
            const std::lock_guard lock(keptMutex);
            kept.push_back(std::move(k));
        });
    });
    // The same order whatever the threads did: by stack, then slice.
    std::sort(kept.begin(), kept.end(), [](const KeptBrick& a, const KeptBrick& b) {
        return std::tie(a.tile.y0, a.tile.x0, a.tile.s0) < std::tie(b.tile.y0, b.tile.x0, b.tile.s0);
    });
    py::list out;
    for (const KeptBrick& k : kept) {
        const GridTile& t = k.tile;
        py::object value;
        if (t.uniform) {
            value = py::bool_(t.value);
        } else {
            py::array_t<bool> a({py::ssize_t(t.width), py::ssize_t(t.height), py::ssize_t(t.depth)});
            bool* o = a.mutable_data();
            const int64_t wpc = (t.depth + 63) / 64;
            for (int64_t x = 0; x < t.width; ++x)
                for (int64_t y = 0; y < t.height; ++y) {
                    const uint64_t* col = k.words.data() + (y * t.width + x) * wpc;
                    bool* dst = o + (x * t.height + y) * t.depth;
                    for (int64_t s = 0; s < t.depth; ++s) dst[s] = (col[s >> 6] >> (s & 63)) & 1u;
                }
            value = std::move(a);
        }
        out.append(py::make_tuple(t.x0, t.y0, t.s0, value));
    }
    return out;
}

} // namespace

void bindVoxelize(py::module_& m) {
    m.def(
        "voxelize",
        [](const py::object& meshObj, const py::object& faces, std::optional<Int> resolution,
           std::optional<double> voxelSize, std::optional<std::vector<int64_t>> dims,
           const py::object& bounds, Int margin, bool cube, Int padding, const py::object& like,
           const std::string& mode, const std::string& fill, const std::string& axis,
           const std::string& slicing, int threads, const std::string& device, bool sparse) -> py::object {
            const auto mesh = meshArgument(meshObj, faces);
            if (!like.is_none() &&
                (resolution || voxelSize || dims || !bounds.is_none() || margin || cube || padding))
                throw ArgumentError(
                    "like=grid takes that grid's frame: give no resolution, voxel_size, dims, "
                    "bounds, margin, cube or padding with it");
            const FitOptions fo = fitOptions(resolution, voxelSize, dims, bounds, margin, axis, cube);
            if (threads < 0) throw ArgumentError("threads must be >= 0");
            const VoxelizeRequest request{
                mode, fill, slicing, device, threads, sparse, like.is_none() ? int64_t(padding) : 0};
            asArgument([&] {
                parseVoxelizeMode(mode), parseSlicing(slicing), parseDevice(device);
                parseFill(fill);
            });
            FitOptions fit = fo;
            fit.checkDenseMemory = !sparse; // a sparse grid is checked against the budget as it grows
            const Frame frame = voxelizeFrame(*mesh, fit, like, padding);
            if (like.is_none()) warnIfStretched(frame, dims);
            VoxelizeResult result;
            VoxelizeReport report;
            interruptible(
                [&](Cancel& cancel) { result = voxelizeMesh(mesh->mesh, frame, request, &cancel, &report); });
            // A fill that cannot be trusted on this mesh says so (the CLI's line on stderr): an
            // open mesh filled by flood leaks where its holes are wider than a voxel.
            if (!report.fillNote.empty() &&
                PyErr_WarnEx(PyExc_RuntimeWarning, ("voxelize: the mesh is " + report.fillNote).c_str(), 1) !=
                    0)
                throw py::error_already_set();
            if (mesh->shifted() && result.sparse) {
                result.sparse->translate(mesh->origin);
            } else if (mesh->shifted()) {
                VoxelGrid& g = *result.grid;
                g.frame = g.frame.translated(mesh->origin);
            }
            // device="cuda" without a usable GPU: the CPU's grid, and a RuntimeWarning saying why.
            if (!result.deviceNote.empty() &&
                PyErr_WarnEx(PyExc_RuntimeWarning, ("device='cuda': " + result.deviceNote).c_str(), 1) != 0)
                throw py::error_already_set();
            if (result.sparse) return py::cast(result.sparse);
            return py::cast(result.grid);
        },
        py::arg("mesh"), py::arg("faces") = py::none(), py::kw_only(), py::arg("resolution") = py::none(),
        py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(), py::arg("bounds") = py::none(),
        py::arg("margin") = 0, py::arg("cube") = false, py::arg("padding") = 0, py::arg("like") = py::none(),
        py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("axis") = "z",
        py::arg("slicing") = "uniform", py::arg("threads") = 0, py::arg("device") = "cpu",
        py::arg("sparse") = false,
        "Voxelizes a mesh like `voxfx voxelize`. mesh: a voxfx.Mesh, an object with .vertices and .faces "
        "(trimesh; Open3D's .triangles; meshio's .points and .cells_dict), a (vertices, faces) pair, or "
        "vertices with faces=. The grid: resolution (cells along the longest side, default 256), voxel_size "
        "or dims (cells along x, y, z; a warning when they make cells unequal); cube=True: resolution^3 "
        "cubic cells, the mesh centred and never stretched; padding: empty cells kept on each side within "
        "the resolution; margin: empty cells added outside it; bounds (xmin ymin zmin xmax ymax zmax, or "
        "Grid.bounds' (lo, hi)); like=grid: that grid's frame exactly. mode surface | conservative | solid "
        "| solid-conservative | interior; fill auto | parity | flood | vote | winding | gwn (auto: parity "
        "for closed meshes, flood otherwise); threads 0 = all; device cpu | cuda | auto (the same grid; "
        "cuda without a usable GPU warns and runs on the CPU; see cuda_status()). sparse=True: a "
        "voxfx.SparseGrid voxelized tile by tile, no dense grid at any point (the same voxels; its "
        "coordinates() are the (N, 3) int32 cells; VOXFX_MEMORY_LIMIT caps it; like= takes no sparse "
        "grid). Ctrl-C stops it.");

    m.def(
        "_grid_frame",
        [](const py::object& meshObj, std::optional<Int> resolution, std::optional<double> voxelSize,
           std::optional<std::vector<int64_t>> dims, const py::object& bounds, Int margin, bool cube) {
            const auto mesh = meshArgument(meshObj, py::none());
            FitOptions fit = fitOptions(resolution, voxelSize, dims, bounds, margin, "z", cube);
            fit.checkDenseMemory = false; // the grid is never whole in one process
            const Frame frame = voxelizeFrame(*mesh, fit, py::none(), 0);
            py::dict d;
            d["frame"] = frameState(frame);
            d["dims"] = py::make_tuple(frame.width(), frame.height(), frame.depth());
            // Index-to-world of the voxel centres, the mesh's recentring added back.
            const Frame world = mesh->shifted() ? frame.translated(mesh->origin) : frame;
            py::list rows;
            const Vec3d cell = world.cellSize(), lo = world.box().lo;
            for (int r = 0; r < 4; ++r) {
                py::list row;
                for (int c = 0; c < 4; ++c)
                    row.append(r == 3   ? (c == 3 ? 1.0 : 0.0)
                               : c == r ? cell[r]
                               : c == 3 ? lo[r] + 0.5 * cell[r]
                                        : 0.0);
                rows.append(row);
            }
            d["affine"] = rows;
            return d;
        },
        py::arg("mesh"), py::kw_only(), py::arg("resolution") = py::none(),
        py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(), py::arg("bounds") = py::none(),
        py::arg("margin") = 0, py::arg("cube") = false,
        "voxfx.dask's planning step: the frame voxelize() fits with these arguments (axis z) as plain "
        "values for _voxelize_stacks, its dims and the index-to-world affine of the voxel centres.");
    m.def(
        "_voxelize_stacks",
        [](const py::object& meshObj, const py::tuple& frame, const std::vector<int64_t>& stacks, Int brick,
           const std::string& mode, const std::string& fill, int threads) {
            const auto mesh = meshArgument(meshObj, py::none());
            return voxelizeStacks(*mesh, frame, stacks, brick, mode, fill, threads);
        },
        py::arg("mesh"), py::arg("frame"), py::arg("stacks"), py::kw_only(), py::arg("brick") = 128,
        py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("threads") = 0,
        "One task of voxfx.dask.voxelize_grid: the bricks of the stacks (x0, y0, x1, y1) (in bricks "
        "along x and y) of the grid `frame` (from _grid_frame), voxelized on their own: a list of "
        "(x0, y0, z0, value), value a bool for a uniform brick or a bool array indexed [x, y, z].");

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
}

} // namespace voxfx::python
