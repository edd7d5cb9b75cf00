// voxfx — the CUDA back end (module voxfx_cuda.so): the one rasterizer's kernels on the GPU.
//
// The per-triangle work is the CPU's own code: setupTriangle, coveredRows, rasterizePiece and the
// slicemap sinks (SurfaceConsumer, ConservativeConsumer, ParityConsumer) are VOXFX_HOSTDEV and
// compiled here with --fmad=false, so every fragment, span and bit equals the CPU's. The CPU's
// direct path already writes with atomic OR / XOR, which commute, so the bits do not depend on
// which thread writes first. What is particular to the GPU is how work is spread:
//
//   1. project   one thread per vertex: projectVertex (grid or camera coordinates, doubles).
//   2. small     one thread per triangle rasterizes it whole when its pieces cover at most
//                directCells(C) columns (nearly every triangle of a dense mesh); larger ones are
//                appended to the medium or the large list (warp-aggregated atomics).
//   3. medium    kRowSlots threads per triangle of up to kSmallCells columns take its rows in turn.
//      large     one block per larger triangle; its threads take the covered rows in turn
//                (rasterizePiece over one row each), so a triangle spanning the grid is spread
//                over a block instead of serializing one thread.
//   4. prefix    (solid modes) one warp per column: each lane prefix-XORs one word, a shuffle scan
//                carries the parity across words (what prefixXorRows does word by word).
//   5. combine   (solid-conservative, interior) word-wise OR / AND-NOT of the two grids.
#include <algorithm>
#include <cstdio>
#include <new>
#include <string>

#include <cooperative_groups.h>
#include <cuda_runtime.h>
#include <dlfcn.h>

#include "cuda/cuda_api.hpp"
#include "voxelize/consumers.hpp"

namespace voxfx::detail {
namespace {

#define VOXFX_CUDA_TRY(call)                                                                                 \
    do {                                                                                                     \
        const cudaError_t status_ = (call);                                                                  \
        if (status_ != cudaSuccess) {                                                                        \
            if (error) *error = std::string(#call) + ": " + cudaGetErrorString(status_);                     \
            return false;                                                                                    \
        }                                                                                                    \
    } while (false)

/// Triangles whose pieces cover at most directCells(C) columns (rows times the bounding box's
/// width) are rasterized by one thread each; up to kSmallCells by kRowSlots threads each; larger
/// ones by a block each. A conservative row costs more (clipping) than a centre-sampled one, so
/// it is split sooner.
constexpr int64_t kSmallCells = 256;
__host__ __device__ constexpr int64_t directCells(Coverage c) { return c == Coverage::Center ? 64 : 16; }
constexpr int kThreads = 256;
constexpr int kLargeThreads = 128;
/// Threads per medium triangle: each takes every kRowSlots-th of its rows, so that a mesh of few
/// triangles (72 K for the bunny) still fills the GPU, while a dense mesh's triangles (most of a
/// column or less) are set up once.
constexpr int kRowSlots = 8;

struct Context {
    int device = 0;
    int multiprocessors = 1;
    cudaStream_t stream = nullptr;
    cudaEvent_t start = nullptr, stop = nullptr;
    // The mesh.
    unsigned char* positions = nullptr; // raw, positionStride bytes per vertex
    std::size_t positionBytes = 0, positionStride = 12, vertexCount = 0;
    uint32_t* indices = nullptr;
    std::size_t triangleCount = 0, indexCapacity = 0;
    Vec3d* projected = nullptr;
    std::size_t projectedCapacity = 0;
    uint32_t* largeList = nullptr; // the medium triangles, then (from triangleCount on) the large ones
    std::size_t largeCapacity = 0;
    unsigned* largeCount = nullptr; // [0] medium, [1] large
    unsigned long long* bitCount = nullptr;
    // The grids: [0] the result, [1] the second grid of the combined modes.
    uint64_t* grid[2] = {nullptr, nullptr};
    int64_t gridCapacity[2] = {0, 0};
    int64_t words = 0; // words of the last voxelize's grid
    DepthToSlice* local = nullptr;
    int64_t localCapacity = 0;
    CudaTimings timings;
};

/// Grows a device buffer to at least `count` elements (contents not kept).
template <class T> bool reserve(T*& buffer, std::size_t& capacity, std::size_t count, std::string* error) {
    if (count <= capacity && buffer) return true;
    if (buffer) cudaFree(buffer);
    buffer = nullptr;
    capacity = 0;
    VOXFX_CUDA_TRY(
        cudaMalloc(reinterpret_cast<void**>(&buffer), std::max<std::size_t>(1, count) * sizeof(T)));
    capacity = count;
    return true;
}

bool elapsed(Context& c, double& ms, std::string* error) {
    VOXFX_CUDA_TRY(cudaEventRecord(c.stop, c.stream));
    VOXFX_CUDA_TRY(cudaEventSynchronize(c.stop));
    float f = 0;
    VOXFX_CUDA_TRY(cudaEventElapsedTime(&f, c.start, c.stop));
    ms = double(f);
    return true;
}

__global__ void projectKernel(const unsigned char* positions, std::size_t stride, std::size_t count,
                              Projection projection, Vec3d* out) {
    const std::size_t i = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= count) return;
    const float* p = reinterpret_cast<const float*>(positions + i * stride);
    // MeshView::vertex's float -> double conversion, then the CPU's transform.
    out[i] = projectVertex(projection, Vec3d{double(p[0]), double(p[1]), double(p[2])});
}

/// A slot in a list whose length is *counter: one atomic per group of converged threads of a warp
/// (one per thread serializes on the counter when most triangles of a dense mesh append).
__device__ unsigned appendIndex(unsigned* counter) {
    namespace cg = cooperative_groups;
    const cg::coalesced_group group = cg::coalesced_threads();
    unsigned base = 0;
    if (group.thread_rank() == 0) base = atomicAdd(counter, group.size());
    return group.shfl(base, 0) + group.thread_rank();
}

/// Columns a piece covers at most: covered rows times the columns of its bounding box.
__device__ int64_t pieceCells(const RasterTriangle& r, Coverage coverage, int64_t width, int64_t height) {
    int64_t first, last;
    coveredRows(r, coverage, height, first, last);
    if (first > last) return 0;
    const double lo = fmin(fmin(r.x[0], r.x[1]), r.x[2]), hi = fmax(fmax(r.x[0], r.x[1]), r.x[2]);
    const double cols = fmin(double(width), fmax(0.0, hi - lo + 2.0));
    return (last - first + 1) * int64_t(cols);
}

template <Coverage C, class Sink>
__global__ void smallKernel(const Vec3d* v, const uint32_t* indices, std::size_t triangles, FrameView frame,
                            double clipDepth, Sink sink, uint32_t* lists, unsigned* counts,
                            std::size_t capacity) {
    const std::size_t t = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (t >= triangles) return;
    const Vec3d a = v[indices[3 * t]], b = v[indices[3 * t + 1]], c = v[indices[3 * t + 2]];
    int64_t cells = 0;
    setupTriangle(frame.projection, a, b, c, uint32_t(t), clipDepth,
                  [&](const RasterTriangle& r) { cells += pieceCells(r, C, frame.width, frame.height); });
    if (cells == 0) return;
    if (cells > directCells(C)) {
        // Medium triangles to list 0, large ones to list 1 (the order of a list does not matter:
        // the writes commute).
        if (cells > kSmallCells)
            lists[capacity + appendIndex(&counts[1])] = uint32_t(t);
        else
            lists[appendIndex(&counts[0])] = uint32_t(t);
        return;
    }
    Sink s = sink;
    setupTriangle(frame.projection, a, b, c, uint32_t(t), clipDepth,
                  [&](const RasterTriangle& r) { rasterizePiece(r, C, frame, 0, frame.height, s); });
}

/// The medium triangles: kRowSlots neighbouring threads per triangle take its rows in turn.
template <Coverage C, class Sink>
__global__ void mediumKernel(const Vec3d* v, const uint32_t* indices, const uint32_t* list,
                             const unsigned* count, FrameView frame, double clipDepth, Sink sink) {
    const std::size_t n = std::size_t(*count) * kRowSlots;
    const std::size_t stride = std::size_t(gridDim.x) * blockDim.x;
    Sink s = sink;
    for (std::size_t i = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride) {
        const uint32_t t = list[i / kRowSlots];
        const int slot = int(i % kRowSlots);
        const Vec3d a = v[indices[3 * std::size_t(t)]], b = v[indices[3 * std::size_t(t) + 1]],
                    c = v[indices[3 * std::size_t(t) + 2]];
        setupTriangle(frame.projection, a, b, c, t, clipDepth, [&](const RasterTriangle& r) {
            int64_t first, last;
            coveredRows(r, C, frame.height, first, last);
            for (int64_t y = first + slot; y <= last; y += kRowSlots)
                rasterizePiece(r, C, frame, y, y + 1, s);
        });
    }
}

template <Coverage C, class Sink>
__global__ void largeKernel(const Vec3d* v, const uint32_t* indices, const uint32_t* largeList,
                            const unsigned* largeCount, FrameView frame, double clipDepth, Sink sink) {
    const unsigned n = *largeCount;
    Sink s = sink;
    for (unsigned item = blockIdx.x; item < n; item += gridDim.x) {
        const uint32_t t = largeList[item];
        const Vec3d a = v[indices[3 * std::size_t(t)]], b = v[indices[3 * std::size_t(t) + 1]],
                    c = v[indices[3 * std::size_t(t) + 2]];
        setupTriangle(frame.projection, a, b, c, t, clipDepth, [&](const RasterTriangle& r) {
            int64_t first, last;
            coveredRows(r, C, frame.height, first, last);
            for (int64_t y = first + threadIdx.x; y <= last; y += blockDim.x)
                rasterizePiece(r, C, frame, y, y + 1, s);
        });
    }
}

/// One warp per column: bit s becomes the XOR of bits 0..s of the column (prefixXorRows).
__global__ void prefixXorKernel(BitGridView grid) {
    const unsigned lane = threadIdx.x & 31u;
    const int64_t warp = (int64_t(blockIdx.x) * blockDim.x + threadIdx.x) >> 5;
    const int64_t warps = (int64_t(gridDim.x) * blockDim.x) >> 5;
    const int64_t wpc = grid.wordsPerColumn, columns = grid.columnCount();
    const uint64_t lastMask = grid.lastWordMask();
    for (int64_t c = warp; c < columns; c += warps) {
        uint64_t* col = grid.column(c);
        unsigned carry = 0; // parity of the words before this group of 32
        for (int64_t w0 = 0; w0 < wpc; w0 += 32) {
            const int64_t w = w0 + lane;
            uint64_t v = w < wpc ? prefixXor(col[w]) : 0;
            const unsigned p = unsigned(v >> 63); // the parity of the word
            unsigned s = p;                       // inclusive XOR scan over the lanes
            for (unsigned o = 1; o < 32; o <<= 1) {
                const unsigned n = __shfl_up_sync(0xffffffffu, s, o);
                if (lane >= o) s ^= n;
            }
            const unsigned before = (s ^ p) ^ carry; // parity of all words before w
            v ^= uint64_t(0) - uint64_t(before);
            if (w < wpc) col[w] = w == wpc - 1 ? (v & lastMask) : v;
            carry ^= __shfl_sync(0xffffffffu, s, 31);
        }
    }
}

__global__ void combineKernel(uint64_t* a, const uint64_t* b, int64_t words, bool andNot) {
    const int64_t stride = int64_t(gridDim.x) * blockDim.x;
    for (int64_t i = int64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < words; i += stride)
        a[i] = andNot ? (a[i] & ~b[i]) : (a[i] | b[i]);
}

__global__ void countKernel(const uint64_t* words, int64_t n, unsigned long long* total) {
    const int64_t stride = int64_t(gridDim.x) * blockDim.x;
    unsigned long long sum = 0;
    for (int64_t i = int64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride)
        sum += static_cast<unsigned long long>(__popcll(words[i]));
    for (int o = 16; o > 0; o >>= 1) sum += __shfl_down_sync(0xffffffffu, sum, o);
    if ((threadIdx.x & 31u) == 0) atomicAdd(total, sum);
}

unsigned blocksFor(std::size_t items, int threads) {
    return unsigned(std::max<std::size_t>(1, (items + std::size_t(threads) - 1) / std::size_t(threads)));
}

/// Rasterizes the context's projected mesh with coverage C into `sink`'s grid (already zeroed).
template <Coverage C, class Sink>
bool rasterizeDevice(Context& c, const FrameView& frame, double clipDepth, Sink sink, std::string* error) {
    if (c.triangleCount == 0) return true;
    VOXFX_CUDA_TRY(cudaMemsetAsync(c.largeCount, 0, 2 * sizeof(unsigned), c.stream));
    const std::size_t T = c.triangleCount;
    smallKernel<C><<<blocksFor(T, kThreads), kThreads, 0, c.stream>>>(
        c.projected, c.indices, T, frame, clipDepth, sink, c.largeList, c.largeCount, T);
    VOXFX_CUDA_TRY(cudaGetLastError());
    mediumKernel<C><<<unsigned(c.multiprocessors * 16), kThreads, 0, c.stream>>>(
        c.projected, c.indices, c.largeList, c.largeCount, frame, clipDepth, sink);
    VOXFX_CUDA_TRY(cudaGetLastError());
    largeKernel<C><<<unsigned(c.multiprocessors * 16), kLargeThreads, 0, c.stream>>>(
        c.projected, c.indices, c.largeList + T, c.largeCount + 1, frame, clipDepth, sink);
    VOXFX_CUDA_TRY(cudaGetLastError());
    return true;
}

bool probe(CudaDeviceInfo* info, std::string* error) {
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (status != cudaSuccess) {
        if (!error) return false;
        int runtime = 0, driver = 0;
        cudaRuntimeGetVersion(&runtime);
        const auto version = [](int v) {
            return std::to_string(v / 1000) + "." + std::to_string(v % 1000 / 10);
        };
        if (status == cudaErrorInsufficientDriver) {
            // The runtime says this both when there is no driver at all and when it is too old.
            void* driverLibrary = dlopen("libcuda.so.1", RTLD_LAZY | RTLD_LOCAL);
            if (!driverLibrary) {
                *error = "no NVIDIA driver (libcuda.so.1 is not installed)";
            } else {
                dlclose(driverLibrary);
                cudaDriverGetVersion(&driver);
                *error = "the NVIDIA driver (CUDA " + version(driver) +
                         ") is older than this build's CUDA runtime (" + version(runtime) + ")";
            }
        } else {
            *error = cudaGetErrorString(status);
        }
        return false;
    }
    if (count == 0) {
        if (error) *error = "the driver reports no CUDA device";
        return false;
    }
    cudaDeviceProp prop{};
    VOXFX_CUDA_TRY(cudaGetDeviceProperties(&prop, 0));
    if (info) {
        std::snprintf(info->name, sizeof(info->name), "%s", prop.name);
        info->computeMajor = prop.major;
        info->computeMinor = prop.minor;
        info->multiprocessors = prop.multiProcessorCount;
        info->memoryBytes = uint64_t(prop.totalGlobalMem);
        cudaDriverGetVersion(&info->driverVersion);
        cudaRuntimeGetVersion(&info->runtimeVersion);
    }
    return true;
}

void destroyContext(void* handle) {
    auto* c = static_cast<Context*>(handle);
    if (!c) return;
    cudaFree(c->positions);
    cudaFree(c->indices);
    cudaFree(c->projected);
    cudaFree(c->largeList);
    cudaFree(c->largeCount);
    cudaFree(c->bitCount);
    cudaFree(c->grid[0]);
    cudaFree(c->grid[1]);
    cudaFree(c->local);
    if (c->start) cudaEventDestroy(c->start);
    if (c->stop) cudaEventDestroy(c->stop);
    if (c->stream) cudaStreamDestroy(c->stream);
    delete c;
}

bool initContext(Context& c, std::string* error) {
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(cudaDeviceGetAttribute(&c.multiprocessors, cudaDevAttrMultiProcessorCount, c.device));
    VOXFX_CUDA_TRY(cudaStreamCreateWithFlags(&c.stream, cudaStreamNonBlocking));
    VOXFX_CUDA_TRY(cudaEventCreate(&c.start));
    VOXFX_CUDA_TRY(cudaEventCreate(&c.stop));
    VOXFX_CUDA_TRY(cudaMalloc(reinterpret_cast<void**>(&c.largeCount), 2 * sizeof(unsigned)));
    VOXFX_CUDA_TRY(cudaMalloc(reinterpret_cast<void**>(&c.bitCount), sizeof(unsigned long long)));
    return true;
}

void* createContext(std::string* error) {
    auto* c = new (std::nothrow) Context;
    if (!c) {
        if (error) *error = "out of host memory";
        return nullptr;
    }
    if (!initContext(*c, error)) {
        destroyContext(c);
        return nullptr;
    }
    return c;
}

bool setMesh(void* handle, const CudaMesh& mesh, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    const std::size_t bytes = mesh.vertexCount == 0 ? 0 : (mesh.vertexCount - 1) * mesh.positionStride + 12;
    std::size_t positionCapacity = c.positionBytes;
    if (!reserve(c.positions, positionCapacity, bytes, error)) return false;
    c.positionBytes = positionCapacity;
    if (!reserve(c.indices, c.indexCapacity, 3 * mesh.triangleCount, error)) return false;
    if (!reserve(c.projected, c.projectedCapacity, mesh.vertexCount, error)) return false;
    if (!reserve(c.largeList, c.largeCapacity, 2 * mesh.triangleCount, error)) return false;
    VOXFX_CUDA_TRY(cudaEventRecord(c.start, c.stream));
    if (bytes)
        VOXFX_CUDA_TRY(cudaMemcpyAsync(c.positions, mesh.positions, bytes, cudaMemcpyHostToDevice, c.stream));
    if (mesh.triangleCount)
        VOXFX_CUDA_TRY(cudaMemcpyAsync(c.indices, mesh.indices, 3 * mesh.triangleCount * sizeof(uint32_t),
                                       cudaMemcpyHostToDevice, c.stream));
    c.vertexCount = mesh.vertexCount;
    c.positionStride = mesh.positionStride;
    c.triangleCount = mesh.triangleCount;
    return elapsed(c, c.timings.uploadMs, error);
}

bool allocateGrid(Context& c, int k, int64_t words, std::string* error) {
    if (words <= c.gridCapacity[k] && c.grid[k]) return true;
    cudaFree(c.grid[k]);
    c.grid[k] = nullptr;
    c.gridCapacity[k] = 0;
    std::size_t freeBytes = 0, totalBytes = 0;
    VOXFX_CUDA_TRY(cudaMemGetInfo(&freeBytes, &totalBytes));
    const double need = double(words) * 8.0;
    if (need > double(freeBytes)) {
        if (error)
            *error = "the grid needs " + std::to_string(need / double(1 << 30)).substr(0, 5) +
                     " GiB of GPU memory, but only " +
                     std::to_string(double(freeBytes) / double(1 << 30)).substr(0, 5) + " GiB is free";
        return false;
    }
    VOXFX_CUDA_TRY(cudaMalloc(reinterpret_cast<void**>(&c.grid[k]), std::size_t(words) * 8));
    c.gridCapacity[k] = words;
    return true;
}

bool voxelizeImpl(Context& c, FrameView frame, double clipDepth, CudaMode mode, std::string* error) {
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    const int64_t wpc = (frame.depth + 63) / 64;
    const int64_t words = frame.width * frame.height * wpc;
    const bool two = mode == CudaMode::SolidConservative || mode == CudaMode::Interior;
    if (!allocateGrid(c, 0, words, error)) return false;
    if (two && !allocateGrid(c, 1, words, error)) return false;
    if (frame.local) {
        std::size_t capacity = std::size_t(c.localCapacity);
        if (!reserve(c.local, capacity, std::size_t(frame.localCount), error)) return false;
        c.localCapacity = int64_t(capacity);
        VOXFX_CUDA_TRY(cudaMemcpyAsync(c.local, frame.local,
                                       std::size_t(frame.localCount) * sizeof(DepthToSlice),
                                       cudaMemcpyHostToDevice, c.stream));
        frame.local = c.local;
    }
    VOXFX_CUDA_TRY(cudaEventRecord(c.start, c.stream));
    const BitGridView g0{c.grid[0], frame.width, frame.height, frame.depth, wpc};
    const BitGridView g1{c.grid[1], frame.width, frame.height, frame.depth, wpc};
    VOXFX_CUDA_TRY(cudaMemsetAsync(c.grid[0], 0, std::size_t(words) * 8, c.stream));
    if (two) VOXFX_CUDA_TRY(cudaMemsetAsync(c.grid[1], 0, std::size_t(words) * 8, c.stream));
    if (c.vertexCount) {
        projectKernel<<<blocksFor(c.vertexCount, kThreads), kThreads, 0, c.stream>>>(
            c.positions, c.positionStride, c.vertexCount, frame.projection, c.projected);
        VOXFX_CUDA_TRY(cudaGetLastError());
    }
    const unsigned streamBlocks = unsigned(c.multiprocessors * 8);
    bool ok = true;
    switch (mode) {
    case CudaMode::Surface:
        ok = rasterizeDevice<Coverage::Center>(c, frame, clipDepth, SurfaceConsumer::Sink<true>{frame, g0},
                                               error);
        break;
    case CudaMode::Conservative:
        ok = rasterizeDevice<Coverage::Conservative>(c, frame, clipDepth,
                                                     ConservativeConsumer::Sink<true>{frame, g0}, error);
        break;
    case CudaMode::Solid:
    case CudaMode::SolidConservative:
    case CudaMode::Interior:
        ok = rasterizeDevice<Coverage::Center>(c, frame, clipDepth, ParityConsumer::Sink<true>{frame, g0, {}},
                                               error);
        if (!ok) break;
        prefixXorKernel<<<streamBlocks * 4, kThreads, 0, c.stream>>>(g0);
        VOXFX_CUDA_TRY(cudaGetLastError());
        if (!two) break;
        ok = rasterizeDevice<Coverage::Conservative>(c, frame, clipDepth,
                                                     ConservativeConsumer::Sink<true>{frame, g1}, error);
        if (!ok) break;
        combineKernel<<<streamBlocks * 4, kThreads, 0, c.stream>>>(c.grid[0], c.grid[1], words,
                                                                   mode == CudaMode::Interior);
        VOXFX_CUDA_TRY(cudaGetLastError());
        break;
    }
    if (!ok) return false;
    c.words = words;
    return elapsed(c, c.timings.kernelMs, error);
}

bool voxelize(void* handle, const FrameView& frame, double clipDepth, CudaMode mode, std::string* error) {
    return voxelizeImpl(*static_cast<Context*>(handle), frame, clipDepth, mode, error);
}

bool download(void* handle, uint64_t* words, int64_t wordCount, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    if (wordCount != c.words) {
        if (error) *error = "download: the host grid has another size than the device grid";
        return false;
    }
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(cudaEventRecord(c.start, c.stream));
    if (wordCount)
        VOXFX_CUDA_TRY(
            cudaMemcpyAsync(words, c.grid[0], std::size_t(wordCount) * 8, cudaMemcpyDeviceToHost, c.stream));
    return elapsed(c, c.timings.downloadMs, error);
}

bool countWords(Context& c, const uint64_t* words, int64_t n, int64_t* result, std::string* error);

bool count(void* handle, int64_t* result, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    return countWords(c, c.grid[0], c.words, result, error);
}

void timings(const void* handle, CudaTimings* out) { *out = static_cast<const Context*>(handle)->timings; }

// ---- Grids and the toolkit's operations -------------------------------------------------------

struct Grid {
    uint64_t* words = nullptr;
    BitGridView view;
    int64_t wordCount() const { return view.width * view.height * view.wordsPerColumn; }
};

void* createGrid(void* handle, int64_t w, int64_t h, int64_t d, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    auto* g = new (std::nothrow) Grid;
    if (!g) {
        if (error) *error = "out of host memory";
        return nullptr;
    }
    g->view = {nullptr, w, h, d, (d + 63) / 64};
    const auto fail = [&](cudaError_t status) -> void* {
        if (error) *error = std::string("creating a grid on the GPU: ") + cudaGetErrorString(status);
        cudaFree(g->words);
        delete g;
        return nullptr;
    };
    cudaError_t status = cudaSetDevice(c.device);
    if (status == cudaSuccess)
        status = cudaMalloc(reinterpret_cast<void**>(&g->words),
                            std::size_t(std::max<int64_t>(1, g->wordCount())) * 8);
    if (status == cudaSuccess)
        status = cudaMemsetAsync(g->words, 0, std::size_t(g->wordCount()) * 8, c.stream);
    if (status == cudaSuccess) status = cudaStreamSynchronize(c.stream);
    if (status != cudaSuccess) return fail(status);
    g->view.words = g->words;
    return g;
}

void destroyGrid(void* grid) {
    auto* g = static_cast<Grid*>(grid);
    if (!g) return;
    cudaFree(g->words);
    delete g;
}

bool uploadGrid(void* handle, void* grid, const uint64_t* words, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    const Grid& g = *static_cast<const Grid*>(grid);
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(cudaEventRecord(c.start, c.stream));
    VOXFX_CUDA_TRY(
        cudaMemcpyAsync(g.words, words, std::size_t(g.wordCount()) * 8, cudaMemcpyHostToDevice, c.stream));
    return elapsed(c, c.timings.uploadMs, error);
}

bool downloadGrid(void* handle, const void* grid, uint64_t* words, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    const Grid& g = *static_cast<const Grid*>(grid);
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(cudaEventRecord(c.start, c.stream));
    VOXFX_CUDA_TRY(
        cudaMemcpyAsync(words, g.words, std::size_t(g.wordCount()) * 8, cudaMemcpyDeviceToHost, c.stream));
    return elapsed(c, c.timings.downloadMs, error);
}

bool countWords(Context& c, const uint64_t* words, int64_t n, int64_t* result, std::string* error) {
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(cudaMemsetAsync(c.bitCount, 0, sizeof(unsigned long long), c.stream));
    if (n) {
        countKernel<<<unsigned(c.multiprocessors * 8), kThreads, 0, c.stream>>>(words, n, c.bitCount);
        VOXFX_CUDA_TRY(cudaGetLastError());
    }
    unsigned long long host = 0;
    VOXFX_CUDA_TRY(cudaMemcpyAsync(&host, c.bitCount, sizeof(host), cudaMemcpyDeviceToHost, c.stream));
    VOXFX_CUDA_TRY(cudaStreamSynchronize(c.stream));
    *result = int64_t(host);
    return true;
}

bool countGrid(void* handle, const void* grid, int64_t* result, std::string* error) {
    const Grid& g = *static_cast<const Grid*>(grid);
    return countWords(*static_cast<Context*>(handle), g.words, g.wordCount(), result, error);
}

__global__ void csgKernel(const uint64_t* a, const uint64_t* b, uint64_t* out, int64_t words, CudaCsgOp op) {
    const int64_t stride = int64_t(gridDim.x) * blockDim.x;
    for (int64_t i = int64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < words; i += stride) {
        const uint64_t x = a[i], y = b[i];
        out[i] = op == CudaCsgOp::Union          ? (x | y)
                 : op == CudaCsgOp::Intersection ? (x & y)
                 : op == CudaCsgOp::Difference   ? (x & ~y)
                                                 : (x ^ y);
    }
}

bool csgGrid(void* handle, const void* a, const void* b, CudaCsgOp op, void* out, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    const Grid &ga = *static_cast<const Grid*>(a), &gb = *static_cast<const Grid*>(b);
    Grid& go = *static_cast<Grid*>(out);
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(cudaEventRecord(c.start, c.stream));
    csgKernel<<<unsigned(c.multiprocessors * 32), kThreads, 0, c.stream>>>(ga.words, gb.words, go.words,
                                                                           ga.wordCount(), op);
    VOXFX_CUDA_TRY(cudaGetLastError());
    return elapsed(c, c.timings.kernelMs, error);
}

/// One separable pass of a box window along one axis (0: column x, 1: column y, 2: slices): each
/// output word is the OR (And false) or AND of the input words (x, y) or bit positions (slices)
/// within `radius`, cells outside the grid counting as `fill` (the operation's identity for the
/// neutral border). One thread per output word; the padding bits are cleared.
template <bool And>
__global__ void morphPassKernel(BitGridView in, BitGridView out, int axis, int64_t radius, uint64_t fill) {
    const int64_t wpc = in.wordsPerColumn, W = in.width, H = in.height, D = in.depth;
    const int64_t words = W * H * wpc, stride = int64_t(gridDim.x) * blockDim.x;
    const uint64_t lastMask = in.lastWordMask();
    for (int64_t i = int64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < words; i += stride) {
        const int64_t c = i / wpc, w = i - c * wpc;
        const int64_t x = c % W, y = c / W;
        uint64_t acc = And ? ~uint64_t(0) : 0;
        if (axis == 0) {
            for (int64_t xx = x - radius; xx <= x + radius; ++xx) {
                const uint64_t v = xx >= 0 && xx < W ? in.words[(y * W + xx) * wpc + w] : fill;
                acc = And ? (acc & v) : (acc | v);
            }
        } else if (axis == 1) {
            for (int64_t yy = y - radius; yy <= y + radius; ++yy) {
                const uint64_t v = yy >= 0 && yy < H ? in.words[(yy * W + x) * wpc + w] : fill;
                acc = And ? (acc & v) : (acc | v);
            }
        } else {
            const uint64_t* col = in.words + c * wpc;
            // Word j of the column with the cells outside [0, D) set to the fill.
            const auto wordAt = [&](int64_t j) -> uint64_t {
                if (j < 0 || j >= wpc) return fill;
                return j == wpc - 1 ? (col[j] & lastMask) | (fill & ~lastMask) : col[j];
            };
            for (int64_t k = -radius; k <= radius; ++k) {
                // The 64 cells starting at slice 64 w + k.
                const int64_t p = 64 * w + k;
                const int64_t q = p >= 0 ? p / 64 : -((-p + 63) / 64);
                const int r = int(p - 64 * q);
                const uint64_t lo = wordAt(q);
                const uint64_t v = r == 0 ? lo : (lo >> r) | (wordAt(q + 1) << (64 - r));
                acc = And ? (acc & v) : (acc | v);
            }
        }
        out.words[i] = w == wpc - 1 ? (acc & lastMask) : acc;
        (void)D;
    }
}

bool morphologyGrid(void* handle, const void* inGrid, CudaMorphOp op, const int64_t radii[3],
                    CudaMorphBorder border, void* outGrid, void* scratchGrid, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    const Grid& in = *static_cast<const Grid*>(inGrid);
    Grid& out = *static_cast<Grid*>(outGrid);
    Grid& scratch = *static_cast<Grid*>(scratchGrid);
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(cudaEventRecord(c.start, c.stream));
    // Erode, dilate, open (erode then dilate), close (dilate then erode), in CudaMorphOp's order.
    const bool steps[4][2] = {{true, true}, {false, false}, {true, false}, {false, true}};
    const int stepCount = op == CudaMorphOp::Open || op == CudaMorphOp::Close ? 2 : 1;
    const int64_t dims[3] = {in.view.width, in.view.height, in.view.depth};
    const Grid* src = &in;
    const unsigned blocks = unsigned(c.multiprocessors * 32);
    for (int step = 0; step < stepCount; ++step) {
        const bool isAnd = steps[int(op)][step];
        // Neutral is the operation's identity: filled for an AND pass, empty for an OR pass.
        const bool fillBit =
            border == CudaMorphBorder::Filled || (border == CudaMorphBorder::Neutral && isAnd);
        const uint64_t fill = fillBit ? ~uint64_t(0) : 0;
        for (int axis = 0; axis < 3; ++axis) {
            // A window wider than the grid sees the same cells (and the fill) as one as wide.
            const int64_t radius = std::min(radii[axis], dims[axis]);
            if (radius == 0) continue;
            Grid* dst = src == &out ? &scratch : &out;
            if (isAnd)
                morphPassKernel<true>
                    <<<blocks, kThreads, 0, c.stream>>>(src->view, dst->view, axis, radius, fill);
            else
                morphPassKernel<false>
                    <<<blocks, kThreads, 0, c.stream>>>(src->view, dst->view, axis, radius, fill);
            VOXFX_CUDA_TRY(cudaGetLastError());
            src = dst;
        }
    }
    if (src != &out)
        VOXFX_CUDA_TRY(cudaMemcpyAsync(out.words, src->words, std::size_t(out.wordCount()) * 8,
                                       cudaMemcpyDeviceToDevice, c.stream));
    return elapsed(c, c.timings.kernelMs, error);
}

bool copyVoxelized(void* handle, void* grid, std::string* error) {
    Context& c = *static_cast<Context*>(handle);
    Grid& g = *static_cast<Grid*>(grid);
    if (g.wordCount() != c.words) {
        if (error) *error = "the grid has another size than the voxelization";
        return false;
    }
    VOXFX_CUDA_TRY(cudaSetDevice(c.device));
    VOXFX_CUDA_TRY(
        cudaMemcpyAsync(g.words, c.grid[0], std::size_t(c.words) * 8, cudaMemcpyDeviceToDevice, c.stream));
    VOXFX_CUDA_TRY(cudaStreamSynchronize(c.stream));
    return true;
}

const CudaModule kTable = {kCudaModuleAbi, sizeof(CudaModule), probe,        createContext, destroyContext,
                           setMesh,        voxelize,           download,     count,         timings,
                           createGrid,     destroyGrid,        uploadGrid,   downloadGrid,  countGrid,
                           csgGrid,        morphologyGrid,     copyVoxelized};

} // namespace
} // namespace voxfx::detail

extern "C" __attribute__((visibility("default"))) const void* voxfx_module_cuda(uint32_t abi) {
    return abi == voxfx::detail::kCudaModuleAbi ? &voxfx::detail::kTable : nullptr;
}
