// voxfx — the CUDA module's shared context for CudaGrid operations (internal): the voxelize
// layer owns the module and CudaGrid (device.cpp); the grid layer's GPU operations (CSG and
// morphology, grid/cuda_grid_ops.cpp) reach the module and a grid's device handle through this.
#pragma once

#include <mutex>
#include <string>

#include "cuda/cuda_api.hpp"
#include "voxfx/device.hpp"

namespace voxfx::detail {

/// The context the CudaGrid operations share (made on first use, kept for the process), and
/// the lock that serializes them on its stream.
struct CudaSharedContext {
    const CudaModule* module = nullptr;
    void* context = nullptr;
    std::mutex mutex;
};
/// voxfx::Error with the reason when no GPU can be used.
CudaSharedContext& cudaSharedContext();
/// Throws voxfx::Error "CUDA: <error>" unless ok.
void checkCuda(bool ok, const std::string& error);
/// Milliseconds of the shared context's last kernels (call with its lock held).
double lastCudaKernelMs(CudaSharedContext& s);

/// A CudaGrid's device handle and timing, for the grid layer's operations.
struct CudaGridAccess {
    static void* handle(const CudaGrid& g) { return g.handle_; }
    static void setKernelMs(CudaGrid& g, double ms) { g.kernelMs_ = ms; }
};

} // namespace voxfx::detail
