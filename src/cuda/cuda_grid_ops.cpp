// voxfx — CSG and morphology of grids kept on the GPU (CudaGrid, voxfx/device.hpp), through the
// voxfx_cuda module; the same results as grid/csg.cpp and grid/morphology.cpp, bit for bit.
#include <cstdint>
#include <mutex>
#include <string>

#include "cuda/cuda_api.hpp"
#include "cuda/cuda_context.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/device.hpp"
#include "voxfx/error.hpp"
#include "voxfx/morphology.hpp"

namespace voxfx {

// The enums cross the module boundary as the module's own: the values must agree.
static_assert(int(CsgOp::Union) == int(detail::CudaCsgOp::Union) &&
              int(CsgOp::Intersection) == int(detail::CudaCsgOp::Intersection) &&
              int(CsgOp::Difference) == int(detail::CudaCsgOp::Difference) &&
              int(CsgOp::Xor) == int(detail::CudaCsgOp::Xor));
static_assert(int(MorphOp::Erode) == int(detail::CudaMorphOp::Erode) &&
              int(MorphOp::Dilate) == int(detail::CudaMorphOp::Dilate) &&
              int(MorphOp::Open) == int(detail::CudaMorphOp::Open) &&
              int(MorphOp::Close) == int(detail::CudaMorphOp::Close));
static_assert(int(MorphBorder::Neutral) == int(detail::CudaMorphBorder::Neutral) &&
              int(MorphBorder::Empty) == int(detail::CudaMorphBorder::Empty) &&
              int(MorphBorder::Filled) == int(detail::CudaMorphBorder::Filled));

CudaGrid csg(const CudaGrid& a, const CudaGrid& b, CsgOp op) {
    if (a.width() != b.width() || a.height() != b.height() || a.depth() != b.depth())
        fail("csg: the grids differ in size (", a.width(), " x ", a.height(), " x ", a.depth(), " and ",
             b.width(), " x ", b.height(), " x ", b.depth(), ")");
    if (a.empty()) return {};
    CudaGrid out(a.width(), a.height(), a.depth());
    detail::CudaSharedContext& s = detail::cudaSharedContext();
    const std::lock_guard lock(s.mutex);
    std::string error;
    detail::checkCuda(s.module->csgGrid(s.context, a.deviceHandle(), b.deviceHandle(),
                                        detail::CudaCsgOp(int(op)), out.deviceHandle(), &error),
                      error);
    out.setLastKernelMs(detail::lastCudaKernelMs(s));
    return out;
}

CudaGrid morphology(const CudaGrid& grid, MorphOp op, const MorphologyOptions& options) {
    if (options.rx < 0 || options.ry < 0 || options.rz < 0)
        fail("morphology radii must be >= 0, got ", options.rx, ", ", options.ry, ", ", options.rz);
    if (grid.empty()) return {};
    CudaGrid out(grid.width(), grid.height(), grid.depth());
    CudaGrid scratch(grid.width(), grid.height(), grid.depth());
    detail::CudaSharedContext& s = detail::cudaSharedContext();
    const std::lock_guard lock(s.mutex);
    const int64_t radii[3] = {options.rx, options.ry, options.rz};
    std::string error;
    detail::checkCuda(s.module->morphologyGrid(s.context, grid.deviceHandle(), detail::CudaMorphOp(int(op)),
                                               radii, detail::CudaMorphBorder(int(options.border)),
                                               out.deviceHandle(), scratch.deviceHandle(), &error),
                      error);
    out.setLastKernelMs(detail::lastCudaKernelMs(s));
    return out;
}

} // namespace voxfx
