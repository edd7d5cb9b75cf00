// voxfx — the interface of the voxfx_cuda module (internal): the CUDA back end of the rasterizer
// and of the voxelization modes.
//
// Like OpenVDB or Embree (io/module_api.hpp), CUDA sits behind a loadable module, voxfx_cuda.so,
// that core/module_loader dlopen()s on first use: libvoxfx and the programs that link it need no
// CUDA runtime or driver, a build without nvcc simply has no module, and a machine without a GPU
// gets a clear answer from probe() instead of a failed load. The module links the CUDA runtime
// statically and uses no voxfx symbol; it compiles the same VOXFX_HOSTDEV kernels as the CPU
// (raster_impl.hpp, voxelize/consumers.hpp) with --fmad=false, so its bits are the CPU's.
//
// The context keeps a mesh and up to two grids on the device between calls: voxelizing one mesh
// into many frames (an animation, a benchmark) uploads it once. Functions return false and set
// *error instead of throwing across the module boundary.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "voxfx/frame.hpp"

namespace voxfx::detail {

/// Bump when the table changes.
inline constexpr uint32_t kCudaModuleAbi = 2;

struct CudaDeviceInfo {
    char name[256] = {};
    int computeMajor = 0, computeMinor = 0;
    int multiprocessors = 0;
    uint64_t memoryBytes = 0;
    int driverVersion = 0, runtimeVersion = 0;
};

/// Milliseconds of the last call of each kind, measured with CUDA events on the context's stream.
struct CudaTimings {
    double uploadMs = 0;   ///< setMesh: positions and indices, host to device
    double kernelMs = 0;   ///< voxelize: every kernel, from the grid's clearing to the last pass
    double downloadMs = 0; ///< download: the grid, device to host
};

/// A mesh as the module reads it (positions: x, y, z floats every positionStride bytes).
struct CudaMesh {
    const float* positions = nullptr;
    std::size_t vertexCount = 0;
    std::size_t positionStride = 12;
    const uint32_t* indices = nullptr;
    std::size_t triangleCount = 0;
};

// The library's enums as they cross the module boundary: the same values, spelled out here because
// the module uses no voxfx header above frame.hpp. The library casts its enums to these and
// static_asserts every value where it does (cuda/device.cpp, cuda/cuda_grid_ops.cpp), so a
// reordering on either side stops the build.
/// The voxelization modes, with VoxelizeMode's values (parity fill for the inside ones).
enum class CudaMode : int { Surface = 0, Conservative = 1, Solid = 2, SolidConservative = 3, Interior = 4 };
/// CsgOp's values.
enum class CudaCsgOp : int { Union = 0, Intersection = 1, Difference = 2, Xor = 3 };
/// MorphOp's values.
enum class CudaMorphOp : int { Erode = 0, Dilate = 1, Open = 2, Close = 3 };
/// MorphBorder's values.
enum class CudaMorphBorder : int { Neutral = 0, Empty = 1, Filled = 2 };

struct CudaModule {
    uint32_t abi;
    uint32_t size; ///< sizeof(CudaModule) as the module was built
    /// The first CUDA device: true and *info, or false with *error saying why there is none
    /// (no driver, no device, a driver older than the runtime...).
    bool (*probe)(CudaDeviceInfo* info, std::string* error);
    /// A context on the first device, or null with *error set.
    void* (*createContext)(std::string* error);
    void (*destroyContext)(void* context);
    /// Uploads a mesh (indices already validated by the caller), replacing the last one.
    bool (*setMesh)(void* context, const CudaMesh& mesh, std::string* error);
    /// Voxelizes the context's mesh into its device grid, sized by `frame` (W x H x D, the BitGrid
    /// layout). `frame.local`, when set, points to frame.localCount host entries (uploaded).
    /// `clipDepth` is the perspective set-up's clipping depth (RasterSetup::clipDepth).
    bool (*voxelize)(void* context, const FrameView& frame, double clipDepth, CudaMode mode,
                     std::string* error);
    /// Copies the device grid (the last voxelize's) into `words` (wordCount words).
    bool (*download)(void* context, uint64_t* words, int64_t wordCount, std::string* error);
    /// The number of set bits of the device grid.
    bool (*count)(void* context, int64_t* count, std::string* error);
    /// The timings of the last calls.
    void (*timings)(const void* context, CudaTimings* timings);

    // Grids in GPU memory (the BitGrid layout) for the toolkit's operations: handles made by
    // createGrid and freed by destroyGrid, usable from any context. Each call has finished its
    // work on the GPU when it returns.
    /// A zeroed W x H x D grid, or null with *error set (out of GPU memory...).
    void* (*createGrid)(void* context, int64_t w, int64_t h, int64_t d, std::string* error);
    void (*destroyGrid)(void* grid);
    /// Host words (the grid's wordCount) to the grid, and back.
    bool (*uploadGrid)(void* context, void* grid, const uint64_t* words, std::string* error);
    bool (*downloadGrid)(void* context, const void* grid, uint64_t* words, std::string* error);
    /// The set bits of a grid.
    bool (*countGrid)(void* context, const void* grid, int64_t* count, std::string* error);
    /// out = a op b; grids of one size; out may be a or b.
    bool (*csgGrid)(void* context, const void* a, const void* b, CudaCsgOp op, void* out, std::string* error);
    /// out = op(in) with box radii (column x, column y, slices) and the border rule; `scratch`
    /// holds the passes between. in, out and scratch are distinct grids of one size.
    bool (*morphologyGrid)(void* context, const void* in, CudaMorphOp op, const int64_t radii[3],
                           CudaMorphBorder border, void* out, void* scratch, std::string* error);
    /// Copies the context's last voxelization into `grid` (of its size).
    bool (*copyVoxelized)(void* context, void* grid, std::string* error);
};

} // namespace voxfx::detail
