// voxfx — where voxelization runs: the CPU, or the CUDA back end.
//
// The CUDA back end runs the same rasterizer kernels as the CPU (raster_impl.hpp, compiled for
// the GPU without fused multiply-adds), so its grids equal the CPU's bit for bit. It is a
// loadable module (voxfx_cuda.so, built when CMake finds nvcc): programs linking voxfx need no
// CUDA runtime, and a machine without a GPU, a driver or the module gets the CPU path and a
// one-line reason (cudaStatus().reason) instead of a failure.
//
// What runs on the GPU: every voxelization mode (surface, conservative, solid, solid-conservative,
// interior) with the parity fill, for orthographic, oriented (light-space) and perspective frames,
// uniform or local slicing; and on grids kept there (CudaGrid), CSG, morphology and counting.
// The robust fills (flood, vote, winding, gwn) run on the CPU.
//
// Thread-safety: cudaStatus() may be called from any thread (it probes once). A CudaVoxelizer is
// one device context: use it from one thread at a time; separate voxelizers may run concurrently.
// CudaGrid operations share one context per process and are serialized on it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "voxfx/bitgrid.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/types.hpp"

namespace voxfx {

enum class VoxelizeMode : uint8_t;
class CudaGrid;

const char* toString(Device d);
/// Parses "cpu", "cuda", "auto"; throws voxfx::Error listing them otherwise.
Device parseDevice(const std::string& name);

struct CudaStatus {
    bool built = false;     ///< this voxfx was built with the CUDA module (nvcc was found)
    bool available = false; ///< the module loaded and a device answered
    std::string device;     ///< e.g. "NVIDIA H100 80GB HBM3 (compute 9.0, 79.1 GiB)"
    std::string reason;     ///< why it is not available (empty when it is)
};
/// Probes the CUDA back end once per process (loads the module, asks the driver).
const CudaStatus& cudaStatus();

/// Milliseconds of the last call of each kind, taken with CUDA events.
struct DeviceTimings {
    double uploadMs = 0;   ///< setMesh: the mesh, host to device
    double kernelMs = 0;   ///< voxelize: every kernel (vertex transform, rasterization, prefix, combine)
    double downloadMs = 0; ///< download: the grid, device to host
};

/// A voxelizer that keeps one mesh and its grid on the GPU between calls: voxelizing one mesh
/// into many frames uploads it once. voxelize(..., {.device = Device::Cuda}) uses one per call.
class CudaVoxelizer {
public:
    /// Throws voxfx::Error with cudaStatus().reason when no GPU can be used.
    CudaVoxelizer();
    ~CudaVoxelizer();
    CudaVoxelizer(const CudaVoxelizer&) = delete;
    CudaVoxelizer& operator=(const CudaVoxelizer&) = delete;

    /// Validates (validateMesh) and uploads the mesh; the view need not outlive the call (a host
    /// copy is kept: perspective frames clip by the eye's distance to it, as the CPU does).
    void setMesh(const MeshView& mesh);
    /// Voxelizes the mesh into `frame` on the GPU (parity fill for the inside modes); the grid
    /// stays there until download(). Throws voxfx::Error (GPU out of memory, driver errors).
    void voxelize(const Frame& frame, VoxelizeMode mode);
    /// The last voxelize's grid, in the BitGrid layout.
    BitGrid download();
    /// Filled cells of the last voxelize's grid, counted on the GPU.
    int64_t count();
    /// A copy of the last voxelize's grid that stays on the GPU, for the toolkit's operations.
    CudaGrid grid();
    DeviceTimings timings() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// A BitGrid in GPU memory (the same layout), for chains of the toolkit's operations without
/// transfers between them: csg (csg.hpp), morphology (morphology.hpp) and count give the CPU's
/// results bit for bit. Calls have
/// finished on the GPU when they return; a CudaGrid may be used from one thread at a time.
class CudaGrid {
public:
    /// An empty grid (no GPU memory).
    CudaGrid();
    /// A zeroed W x H x D grid; voxfx::Error when no GPU can be used or it does not fit.
    CudaGrid(int64_t w, int64_t h, int64_t d);
    /// Uploads `grid`.
    explicit CudaGrid(const BitGrid& grid);
    ~CudaGrid();
    CudaGrid(CudaGrid&&) noexcept;
    CudaGrid& operator=(CudaGrid&&) noexcept;

    int64_t width() const { return w_; }
    int64_t height() const { return h_; }
    int64_t depth() const { return d_; }
    bool empty() const { return !handle_; }
    /// The grid in host memory.
    BitGrid download() const;
    /// Filled cells, counted on the GPU.
    int64_t count() const;
    /// Milliseconds of the last operation that wrote this grid (CUDA events; transfers excluded).
    double lastKernelMs() const { return kernelMs_; }
    /// The CUDA module's handle of the grid (opaque; null when empty) and the timing of the
    /// operation that wrote it: what the library's GPU operations (csg, morphology) read and set.
    void* deviceHandle() const { return handle_; }
    void setLastKernelMs(double ms) { kernelMs_ = ms; }

private:
    void* handle_ = nullptr;
    int64_t w_ = 0, h_ = 0, d_ = 0;
    double kernelMs_ = 0;
};

} // namespace voxfx
