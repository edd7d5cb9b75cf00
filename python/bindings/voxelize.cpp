// Voxelization: voxelize (as `voxfx voxelize` does) and cuda_status; the two pieces of a grid
// voxelized across a cluster (voxfx.dask.voxelize_grid): _grid_frame and _voxelize_stacks.
#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <utility>

#include <fcntl.h>
#include <unistd.h>
#include <zstd.h>

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

VoxelizeOptions stackOptions(const std::string& mode, const std::string& fill, int threads) {
    VoxelizeOptions vo;
    asArgument([&] {
        vo.mode = parseVoxelizeMode(mode);
        vo.fill = parseFill(fill);
    });
    vo.threads = threads;
    return vo;
}

// The tiles of the stacks (x0, y0, x1, y1) of bricks of `brick` cells.
TileOptions stackRange(int64_t brick, const std::vector<int64_t>& stacks) {
    if (stacks.size() != 4) throw ArgumentError("stacks must be (x0, y0, x1, y1)");
    TileOptions to;
    to.brickSize = brick;
    to.stackX0 = stacks[0];
    to.stackY0 = stacks[1];
    to.stackX1 = stacks[2];
    to.stackY1 = stacks[3];
    return to;
}

// The columns of a brick's packed bits (column (x, y) at words (y * width + x) * wpc, slice s at bit
// s of them) as bools indexed [x, y, z]: eight bits at a time through a table of their eight bytes.
void unpackColumns(const uint64_t* words, int64_t wpc, int64_t width, int64_t height, int64_t depth,
                   bool* out) {
    static const std::array<uint64_t, 256> bytes = [] {
        std::array<uint64_t, 256> t{};
        for (int v = 0; v < 256; ++v)
            for (int b = 0; b < 8; ++b) t[size_t(v)] |= uint64_t((v >> b) & 1) << (8 * b); // little-endian
        return t;
    }();
    static_assert(sizeof(bool) == 1 && std::endian::native == std::endian::little);
    const int64_t whole = depth / 8;
    for (int64_t x = 0; x < width; ++x)
        for (int64_t y = 0; y < height; ++y) {
            const uint64_t* col = words + (y * width + x) * wpc;
            unsigned char* dst = reinterpret_cast<unsigned char*>(out + (x * height + y) * depth);
            for (int64_t g = 0; g < whole; ++g) {
                const uint64_t e = bytes[(col[g >> 3] >> (8 * (g & 7))) & 0xffu];
                std::memcpy(dst + 8 * g, &e, 8);
            }
            for (int64_t s = 8 * whole; s < depth; ++s) dst[s] = (col[s >> 6] >> (s & 63)) & 1u;
        }
}

// A brick as numcodecs' PackBits encodes a zarr chunk of B^3 bools (order C, [x, y, z], cells past
// the brick's w x h x d False): one byte of padding bits (0: B^3 is a multiple of 8), then 8 cells
// per byte, the first in the high bit. `out` holds 1 + B^3 / 8 bytes.
void packChunk(const uint64_t* words, int64_t wpc, int64_t width, int64_t height, int64_t depth, int64_t B,
               uint8_t* out) {
    static const std::array<uint8_t, 256> reversed = [] {
        std::array<uint8_t, 256> t{};
        for (int v = 0; v < 256; ++v)
            for (int b = 0; b < 8; ++b)
                if (v >> b & 1) t[size_t(v)] |= uint8_t(0x80u >> b);
        return t;
    }();
    std::memset(out, 0, size_t(1 + B * B * B / 8));
    const int64_t bytes = (depth + 7) / 8;
    const unsigned lastMask = depth % 8 ? (1u << (depth % 8)) - 1 : 0xffu;
    for (int64_t x = 0; x < width; ++x)
        for (int64_t y = 0; y < height; ++y) {
            const uint64_t* col = words + (y * width + x) * wpc;
            uint8_t* dst = out + 1 + (x * B + y) * (B / 8);
            for (int64_t g = 0; g < bytes; ++g) {
                unsigned v = unsigned(col[g >> 3] >> (8 * (g & 7))) & 0xffu;
                if (g == bytes - 1) v &= lastMask;
                dst[g] = reversed[v];
            }
        }
}

// The written bricks of one stack, or of a run of its slices, gathered for one call of the
// visitor: the z0 of its full bricks, and of its mixed ones with their PackBits chunks end to end.
struct StackBatch {
    std::vector<int64_t> full, mixed;
    std::vector<uint8_t> packed; ///< its first mixed.size() chunks of 1 + B^3 / 8 bytes; kept, not shrunk
};

// The batches' buffers kept from one task's call to the next (a worker runs many): fresh ones
// cost a page fault per 4 KiB, and on every call where the allocator trims eagerly, as Dask's
// workers make it (MALLOC_TRIM_THRESHOLD_=65536).
std::mutex& stackBatchesMutex() {
    static std::mutex m;
    return m;
}
std::vector<StackBatch>& keptStackBatches() {
    static std::vector<StackBatch> kept;
    return kept;
}
std::vector<StackBatch> takeStackBatches() {
    const std::lock_guard lock(stackBatchesMutex());
    return std::exchange(keptStackBatches(), {});
}
void giveStackBatches(std::vector<StackBatch>&& batches) {
    constexpr size_t kMaxKeptBytes = size_t(256) << 20;
    const std::lock_guard lock(stackBatchesMutex());
    size_t bytes = 0;
    for (const StackBatch& b : keptStackBatches()) bytes += b.packed.capacity();
    for (StackBatch& b : batches)
        if ((bytes += b.packed.capacity()) <= kMaxKeptBytes) keptStackBatches().push_back(std::move(b));
}

// Bricks written to a zarr DirectoryStore's array folder here, without the GIL: each chunk
// FOLDER/bx<sep>by<sep>bz holds the store's encoding of the brick, written as zarr writes one (a
// temporary file in the folder, then renamed over the chunk: never half-written). Full bricks get
// `bytes` (the store's encoding of a full chunk, made once by zarr); with zstdLevel > 0 (a store of
// PackBits then numcodecs.Zstd(level)), mixed bricks too: their PackBits bytes compressed as
// numcodecs does (ZSTD_compress at the level: one zstd frame), by a context kept per thread.
struct ChunkFiles {
    std::string folder, separator, bytes;
    int zstdLevel = 0;
    std::string tag =
        std::to_string(std::random_device{}()) + "-" + std::to_string(::getpid()) + "-"; ///< unique
    std::atomic<int64_t> written{0};
    std::atomic<int64_t> serial{0};
};

void writeChunkFile(ChunkFiles& files, int64_t bx, int64_t by, int64_t bz, const char* data, size_t size) {
    const std::string& sep = files.separator;
    const std::string path =
        files.folder + "/" + std::to_string(bx) + sep + std::to_string(by) + sep + std::to_string(bz);
    const std::string tmp = path + "." + files.tag + std::to_string(files.serial++) + ".partial";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    bool ok = fd >= 0;
    for (size_t done = 0; ok && done < size;) {
        const ssize_t n = ::write(fd, data + done, size - done);
        if (n < 0 && errno == EINTR) continue;
        ok = n > 0;
        done += ok ? size_t(n) : 0;
    }
    const int error = ok ? 0 : errno;
    if (fd >= 0 && ::close(fd) != 0 && ok) ok = false;
    if (ok && std::rename(tmp.c_str(), path.c_str()) == 0) {
        ++files.written;
        return;
    }
    const std::string why = std::strerror(error ? error : errno);
    std::remove(tmp.c_str());
    throw Error(path + ": cannot write the chunk: " + why);
}

// A mixed brick's chunk file: packed (PackBits) and compressed in this thread's buffers, which
// are kept from brick to brick and task to task (fresh ones cost page faults, and a fresh zstd
// context per chunk, as numcodecs makes one, zeroes its tables every time). False when the
// brick has no cell set (a chunk of the fill value is never written).
bool writeMixedChunkFile(ChunkFiles& files, const GridTile& t, int64_t brick) {
    struct Buffers {
        std::vector<uint8_t> packed;
        std::vector<char> compressed;
        std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> context{ZSTD_createCCtx(), ZSTD_freeCCtx};
    };
    thread_local Buffers local;
    const auto chunkBytes = size_t(1 + brick * brick * brick / 8);
    local.packed.resize(chunkBytes);
    packChunk(t.bits.words, t.bits.wordsPerColumn, t.width, t.height, t.depth, brick, local.packed.data());
    if (std::none_of(local.packed.begin() + 1, local.packed.end(), [](uint8_t v) { return v != 0; }))
        return false;
    local.compressed.resize(ZSTD_compressBound(chunkBytes));
    if (!local.context) throw Error("cannot make a zstd compression context");
    const size_t n = ZSTD_compressCCtx(local.context.get(), local.compressed.data(), local.compressed.size(),
                                       local.packed.data(), chunkBytes, files.zstdLevel);
    if (ZSTD_isError(n)) throw Error(std::string("zstd: ") + ZSTD_getErrorName(n));
    writeChunkFile(files, t.x0 / brick, t.y0 / brick, t.s0 / brick, local.compressed.data(), n);
    return true;
}

// The batches handed to visit(x0, y0, full, mixed, packed): one call per stack (or per
// `batchBytes` of packed chunks within a stack, so memory stays bounded at any brick size), the
// GIL taken once for it. Empty bricks and mixed bricks with no cell set are left out (a zarr
// chunk of the fill value is never written); packed is a uint8 array (mixed count, 1 + B^3/8) over a
// buffer reused from stack to stack (valid during the call only: fresh pages for every stack cost
// more in page faults than the packing). With `files`, full bricks are written there instead and
// not handed to visit.
void visitStackBatches(const PyMesh& mesh, const Frame& frame, VoxelizeOptions vo, const TileOptions& to,
                       int64_t brick, const py::object& visit, int64_t batchBytes, ChunkFiles* files) {
    const auto chunkBytes = size_t(1 + brick * brick * brick / 8);
    std::map<std::pair<int64_t, int64_t>, StackBatch> open; // by stack (x0, y0); nodes are stable
    std::vector<StackBatch> spare = takeStackBatches();     // the buffers of finished stacks
    std::mutex openMutex, one;
    auto flush = [&](int64_t x0, int64_t y0, StackBatch& b) {
        if (b.full.empty() && b.mixed.empty()) return;
        const std::lock_guard lock(one);
        const py::gil_scoped_acquire gil;
        const py::capsule borrowed(b.packed.data(), [](void*) {});
        py::array_t<uint8_t> packed({py::ssize_t(b.mixed.size()), py::ssize_t(chunkBytes)}, b.packed.data(),
                                    borrowed);
        visit(x0, y0, py::cast(b.full), py::cast(b.mixed), packed);
        b.full.clear();
        b.mixed.clear();
    };
    interruptible([&](Cancel& cancel) {
        vo.progress = &cancel;
        voxelizeTiles(mesh.mesh.view(), frame, vo, to, [&](const GridTile& t) {
            StackBatch* b = nullptr;
            {
                const std::lock_guard lock(openMutex);
                auto [it, made] = open.try_emplace({t.x0, t.y0});
                if (made && !spare.empty()) {
                    it->second = std::move(spare.back());
                    spare.pop_back();
                }
                b = &it->second;
            }
            if (t.uniform && t.value && files) {
                writeChunkFile(*files, t.x0 / brick, t.y0 / brick, t.s0 / brick, files->bytes.data(),
                               files->bytes.size());
            } else if (!t.uniform && files && files->zstdLevel > 0) {
                writeMixedChunkFile(*files, t, brick);
            } else if (t.uniform && t.value) {
                b->full.push_back(t.s0);
            } else if (!t.uniform) {
                const size_t at = b->mixed.size() * chunkBytes;
                if (b->packed.size() < at + chunkBytes) b->packed.resize(std::max(2 * at, at + chunkBytes));
                uint8_t* chunk = b->packed.data() + at;
                packChunk(t.bits.words, t.bits.wordsPerColumn, t.width, t.height, t.depth, brick, chunk);
                if (std::any_of(chunk + 1, chunk + chunkBytes, [](uint8_t v) { return v != 0; }))
                    b->mixed.push_back(t.s0);
            }
            const bool last = t.s0 + t.depth >= frame.depth();
            if (last || int64_t(b->mixed.size() * chunkBytes) >= batchBytes) flush(t.x0, t.y0, *b);
            if (last) {
                const std::lock_guard lock(openMutex);
                auto it = open.find({t.x0, t.y0});
                spare.push_back(std::move(it->second));
                open.erase(it);
            }
        });
    });
    giveStackBatches(std::move(spare));
}

// One brick as a task returns it: the packed bits copied out of the visitor's call.
struct KeptBrick {
    GridTile tile;
    std::vector<uint64_t> words;
    int64_t wordsPerColumn = 0;
};

// The bricks of the stacks [sx0, sx1) x [sy0, sy1), in the grid's [x, y, z] order: a list of
// (x0, y0, z0, value) with value a bool (a uniform brick) or a bool array (w, h, d).
py::list voxelizeStacks(const PyMesh& mesh, const py::tuple& state, const std::vector<int64_t>& stacks,
                        int64_t brick, const std::string& mode, const std::string& fill, int threads,
                        const py::object& visit, bool packbits) {
    const Frame frame = frameFromState(state);
    if (frame.axis() != Axis::Z) throw ArgumentError("the bricks of a grid are written along axis z only");
    VoxelizeOptions vo = stackOptions(mode, fill, threads);
    TileOptions to = stackRange(brick, stacks);
    if (!visit.is_none()) {
        // Each brick handed to `visit` as it is made (memory: one stack's, not the task's), one
        // call at a time (the lock, then the GIL), mixed bricks unpacked into one buffer.
        // Only the buffer of the form asked for (a brick^3 bool array is 2 MiB at brick 128).
        py::array_t<bool> buffer(py::ssize_t(packbits ? 0 : std::max<int64_t>(brick, 8) * brick * brick));
        py::array_t<uint8_t> packed(py::ssize_t(packbits ? 1 + brick * brick * brick / 8 : 0));
        std::mutex one;
        interruptible([&](Cancel& cancel) {
            vo.progress = &cancel;
            voxelizeTiles(mesh.mesh.view(), frame, vo, to, [&](const GridTile& t) {
                const std::lock_guard lock(one);
                const py::gil_scoped_acquire gil;
                py::object value;
                if (t.uniform) {
                    value = py::bool_(t.value);
                } else if (packbits) {
                    packChunk(t.bits.words, t.bits.wordsPerColumn, t.width, t.height, t.depth, brick,
                              packed.mutable_data());
                    value = packed;
                } else {
                    unpackColumns(t.bits.words, t.bits.wordsPerColumn, t.width, t.height, t.depth,
                                  buffer.mutable_data());
                    value =
                        py::array_t<bool>({py::ssize_t(t.width), py::ssize_t(t.height), py::ssize_t(t.depth)},
                                          buffer.data(), buffer);
                }
                visit(t.x0, t.y0, t.s0, value);
            });
        });
        return py::list();
    }
    std::vector<KeptBrick> kept;
    std::mutex keptMutex;
    interruptible([&](Cancel& cancel) {
        vo.progress = &cancel;
        voxelizeTiles(mesh.mesh.view(), frame, vo, to, [&](const GridTile& tile) {
            KeptBrick k{tile, {}, tile.bits.wordsPerColumn};
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
        py::object value = py::bool_(t.value);
        if (!t.uniform) {
            py::array_t<bool> a({py::ssize_t(t.width), py::ssize_t(t.height), py::ssize_t(t.depth)});
            unpackColumns(k.words.data(), k.wordsPerColumn, t.width, t.height, t.depth, a.mutable_data());
            value = std::move(a);
        }
        out.append(py::make_tuple(t.x0, t.y0, t.s0, value));
    }
    return out;
}

// voxfx.dask's triangles per task: task (tx, ty) of a k x k rectangle of stacks of `brick` columns
// gets the triangles whose footprint on the grid's x-y plane, widened by one cell on every side,
// meets its columns (a column-local fill, parity or winding, sees in its columns exactly the
// crossings of those), as a mesh of its own: the vertices it uses, compacted, and the same origin.
// Row-major list (ty * tasksX + tx); None for a task no triangle reaches.
py::list taskMeshes(const PyMesh& mesh, const Frame& frame, int64_t brick, int64_t k) {
    if (brick <= 0 || k <= 0) throw ArgumentError("brick and stacks per task must be positive");
    const int64_t span = brick * k; // columns per task along x and y
    const int64_t tasksX = (frame.width() + span - 1) / span, tasksY = (frame.height() + span - 1) / span;
    const Vec3d lo = frame.box().lo, cell = frame.cellSize();
    const MeshView view = mesh.mesh.view();
    std::vector<std::vector<uint32_t>> lists(size_t(tasksX * tasksY));
    auto taskOf = [&](double g, int64_t n) {
        return std::clamp<int64_t>(int64_t(std::floor(g / double(span))), 0, n - 1);
    };
    for (std::size_t t = 0; t < view.triangleCount; ++t) {
        Vec3d a = view.vertex(view.index(t, 0)), b = view.vertex(view.index(t, 1)),
              c = view.vertex(view.index(t, 2));
        const double x0 = (std::min({a.x, b.x, c.x}) - lo.x) / cell.x - 1,
                     x1 = (std::max({a.x, b.x, c.x}) - lo.x) / cell.x + 1;
        const double y0 = (std::min({a.y, b.y, c.y}) - lo.y) / cell.y - 1,
                     y1 = (std::max({a.y, b.y, c.y}) - lo.y) / cell.y + 1;
        if (x1 < 0 || y1 < 0 || x0 > double(frame.width()) || y0 > double(frame.height())) continue;
        for (int64_t ty = taskOf(y0, tasksY), ty1 = taskOf(y1, tasksY); ty <= ty1; ++ty)
            for (int64_t tx = taskOf(x0, tasksX), tx1 = taskOf(x1, tasksX); tx <= tx1; ++tx)
                lists[size_t(ty * tasksX + tx)].push_back(uint32_t(t));
    }
    // Compaction: remap[v] is v's index in the current task's mesh, valid when stamp[v] is the task.
    std::vector<uint32_t> remap(view.vertexCount), stamp(view.vertexCount, UINT32_MAX);
    py::list out;
    for (std::size_t task = 0; task < lists.size(); ++task) {
        if (lists[task].empty()) {
            out.append(py::none());
            continue;
        }
        auto part = std::make_shared<PyMesh>();
        part->origin = mesh.origin;
        part->source = mesh.source;
        part->mesh.indices.reserve(3 * lists[task].size());
        for (const uint32_t t : lists[task])
            for (int c = 0; c < 3; ++c) {
                const uint32_t v = view.index(t, c);
                if (stamp[v] != uint32_t(task)) {
                    stamp[v] = uint32_t(task);
                    remap[v] = uint32_t(part->mesh.positions.size());
                    part->mesh.positions.push_back(mesh.mesh.positions[v]);
                }
                part->mesh.indices.push_back(remap[v]);
            }
        out.append(py::cast(part));
    }
    return out;
}

// voxfx.voxelize: a mesh (or vertices and faces) into a grid, dense or sparse.
void bindVoxelizeFunction(py::module_& m) {
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
}

// voxfx.dask's planning steps (private): the frame a grid gets, and its stacks of bricks voxelized.
void bindDaskPlanning(py::module_& m) {
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
           const std::string& mode, const std::string& fill, int threads, const py::object& visit,
           bool packbits, const py::object& visitStack, Int batchBytes, const py::object& fullChunk,
           const py::object& chunkFolder, const std::string& separator, int zstdLevel) {
            const auto mesh = meshArgument(meshObj, py::none());
            if (!visitStack.is_none()) {
                if (!visit.is_none()) throw ArgumentError("give visit or visit_stack, not both");
                if (batchBytes <= 0) throw ArgumentError("batch_bytes must be positive");
                const Frame f = frameFromState(frame);
                if (f.axis() != Axis::Z)
                    throw ArgumentError("the bricks of a grid are written along axis z only");
                std::unique_ptr<ChunkFiles> files;
                if (!fullChunk.is_none()) {
                    files = std::make_unique<ChunkFiles>();
                    files->bytes = py::cast<std::string>(py::bytes(fullChunk));
                    files->folder = py::cast<std::string>(py::str(chunkFolder));
                    files->separator = separator;
                    files->zstdLevel = zstdLevel;
                }
                visitStackBatches(*mesh, f, stackOptions(mode, fill, threads), stackRange(brick, stacks),
                                  brick, visitStack, batchBytes, files.get());
                return py::object(py::int_(files ? files->written.load() : 0));
            }
            return py::object(
                voxelizeStacks(*mesh, frame, stacks, brick, mode, fill, threads, visit, packbits));
        },
        py::arg("mesh"), py::arg("frame"), py::arg("stacks"), py::kw_only(), py::arg("brick") = 128,
        py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("threads") = 0,
        py::arg("visit") = py::none(), py::arg("packbits") = false, py::arg("visit_stack") = py::none(),
        py::arg("batch_bytes") = Int(int64_t(64) << 20), py::arg("full_chunk") = py::none(),
        py::arg("chunk_folder") = py::none(), py::arg("separator") = ".", py::arg("zstd_level") = 0,
        "One task of voxfx.dask.voxelize_grid: the bricks of the stacks (x0, y0, x1, y1) (in bricks "
        "along x and y) of the grid `frame` (from _grid_frame), voxelized on their own: a list of "
        "(x0, y0, z0, value), value a bool for a uniform brick or a bool array indexed [x, y, z]. "
        "visit: called as visit(x0, y0, z0, value) for each brick as it is made instead (one call at a "
        "time, in no set order; an empty list returned); its arrays share one buffer, valid during the "
        "call only. packbits=True (with visit): a mixed brick comes as the uint8 array numcodecs.PackBits "
        "makes of its whole zarr chunk (brick^3 bools, False past the grid). visit_stack: called as "
        "visit_stack(x0, y0, full, mixed, packed) once per stack instead (or per batch_bytes of packed "
        "chunks in it), the GIL taken once for it: full and mixed the z0 of its full bricks and of its "
        "mixed bricks with a cell set, packed a uint8 array of the mixed ones' PackBits chunks, one row "
        "each (over one buffer, valid during the call only); empty bricks are left out. full_chunk (bytes) "
        "and chunk_folder (with visit_stack): full "
        "bricks are written here, without the GIL, as the files CHUNK_FOLDER/bx<separator>by<separator>bz "
        "of those bytes (a zarr DirectoryStore's chunks) and not handed to visit_stack; with zstd_level > 0 "
        "(a store of PackBits then numcodecs.Zstd(level=zstd_level)) mixed bricks too, compressed as "
        "numcodecs does; returns how many files were written.");
}

// voxfx.dask's region steps (private): the fill a mesh needs, its triangles split per task, a
// region voxelized into a sparse .vdb.
void bindDaskRegions(py::module_& m) {
    m.def(
        "_resolve_fill",
        [](const py::object& meshObj, const py::tuple& frame, const std::string& mode,
           const std::string& fill) {
            const auto mesh = meshArgument(meshObj, py::none());
            const VoxelizeOptions vo = stackOptions(mode, fill, 1);
            const Frame f = frameFromState(frame);
            return std::string(toString(asArgument([&] { return resolveFill(mesh->mesh.view(), f, vo); })));
        },
        py::arg("mesh"), py::arg("frame"), py::kw_only(), py::arg("mode") = "solid", py::arg("fill") = "auto",
        "voxfx.dask's planning step: the fill voxelize() runs for `fill` on this mesh (auto: parity for a "
        "closed mesh, else flood), decided once on the whole mesh before its triangles are split.");
    m.def(
        "_task_meshes",
        [](const py::object& meshObj, const py::tuple& frame, Int brick, Int k) {
            const auto mesh = meshArgument(meshObj, py::none());
            return taskMeshes(*mesh, frameFromState(frame), brick, k);
        },
        py::arg("mesh"), py::arg("frame"), py::kw_only(), py::arg("brick"), py::arg("stacks_per_task"),
        "voxfx.dask's split: for each task of k x k stacks (row-major), the triangles over its columns "
        "(and a cell around them) as a voxfx.Mesh of their own, or None. For column-local fills (parity, "
        "winding) a task's bricks from its part equal those from the whole mesh.");
    m.def(
        "_voxelize_region",
        [](const py::object& meshObj, const py::tuple& state, const std::vector<int64_t>& stacks,
           const std::string& path, Int brick, const std::string& mode, const std::string& fill,
           int threads) {
            const auto mesh = meshArgument(meshObj, py::none());
            const Frame frame = frameFromState(state);
            VoxelizeOptions vo = stackOptions(mode, fill, threads);
            TileOptions to = stackRange(brick, stacks);
            int64_t count = 0;
            interruptible([&](Cancel& cancel) {
                vo.progress = &cancel;
                SparseGrid grid = voxelizeSparse(mesh->mesh.view(), frame, vo, to);
                if (mesh->shifted()) grid.translate(mesh->origin);
                count = grid.count();
                writeGrid(grid, path);
            });
            return count;
        },
        py::arg("mesh"), py::arg("frame"), py::arg("stacks"), py::arg("path"), py::kw_only(),
        py::arg("brick") = 128, py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("threads") = 0,
        "One task of voxfx.dask.voxelize_regions: the stacks (x0, y0, x1, y1) of the grid `frame` as a "
        "sparse grid written to the .vdb `path` (atomically; the whole grid's frame and dims, so that "
        "`voxfx merge` unites the regions); returns its filled cells.");
}

} // namespace

void bindVoxelize(py::module_& m) {
    bindVoxelizeFunction(m);
    bindDaskPlanning(m);
    bindDaskRegions(m);
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
