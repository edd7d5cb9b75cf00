// voxfx — the CUDA module's shared context for CudaGrid operations (internal): device.cpp owns
// the module and CudaGrid; the GPU's CSG and morphology (cuda_grid_ops.cpp) reach the module
// through this, and a grid's device handle through CudaGrid::deviceHandle.
#pragma once

#include <mutex>
#include <string>

#include "cuda/cuda_api.hpp"

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

} // namespace voxfx::detail
