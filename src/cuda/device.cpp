// voxfx — the CUDA back end as the library sees it: probing, and a voxelizer over the module.
#include "voxfx/device.hpp"

#include <cmath>
#include <cstdio>
#include <mutex>
#include <utility>

#include "core/module_loader.hpp"
#include "cuda/cuda_api.hpp"
#include "cuda/cuda_context.hpp"
#include "voxfx/error.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

namespace {

#ifdef VOXFX_HAS_CUDA_MODULE
constexpr bool kBuilt = true;
#else
constexpr bool kBuilt = false;
#endif

const detail::CudaModule& cudaModule() {
    const auto* t = static_cast<const detail::CudaModule*>(
        detail::loadModule("cuda", detail::kCudaModuleAbi, "for the CUDA back end"));
    if (t->abi != detail::kCudaModuleAbi || t->size != sizeof(detail::CudaModule))
        fail("module voxfx_cuda.so is from another voxfx build (its table does not match this library)");
    return *t;
}

CudaStatus probe() {
    CudaStatus s;
    s.built = kBuilt;
    if (!kBuilt) {
        s.reason = "this voxfx was built without CUDA (nvcc was not found when it was configured)";
        return s;
    }
    const detail::CudaModule* m = nullptr;
    try {
        m = &cudaModule();
    } catch (const Error& e) {
        s.reason = e.what();
        return s;
    }
    detail::CudaDeviceInfo info;
    std::string why;
    if (!m->probe(&info, &why)) {
        s.reason = why;
        return s;
    }
    char text[400];
    std::snprintf(text, sizeof(text), "%s (compute %d.%d, %.1f GiB)", info.name, info.computeMajor,
                  info.computeMinor, double(info.memoryBytes) / double(uint64_t(1) << 30));
    s.available = true;
    s.device = text;
    return s;
}

using detail::checkCuda;

/// A new context on the first device, and the module it belongs to; voxfx::Error with the reason
/// when no GPU can be used.
void* newContext(const detail::CudaModule*& module) {
    const CudaStatus& s = cudaStatus();
    if (!s.available) fail("the CUDA back end cannot run here: ", s.reason);
    module = &cudaModule();
    std::string error;
    void* context = module->createContext(&error);
    checkCuda(context != nullptr, error);
    return context;
}

} // namespace

namespace detail {

void checkCuda(bool ok, const std::string& error) {
    if (!ok) fail("CUDA: ", error);
}

CudaSharedContext& cudaSharedContext() {
    static CudaSharedContext* shared = [] {
        const CudaModule* module = nullptr;
        void* context = newContext(module);
        // Lives as long as the process: grids may outlive main's locals.
        auto* c = new CudaSharedContext;
        c->module = module;
        c->context = context;
        return c;
    }();
    return *shared;
}

double lastCudaKernelMs(CudaSharedContext& s) {
    CudaTimings t;
    s.module->timings(s.context, &t);
    return t.kernelMs;
}

} // namespace detail

const char* toString(Device d) { return enumName(d, kDeviceNames); }

Device parseDevice(const std::string& name) { return parseEnum<Device>(name, "device", kDeviceNames); }

const CudaStatus& cudaStatus() {
    static const CudaStatus status = probe();
    return status;
}

struct CudaVoxelizer::Impl {
    const detail::CudaModule* module = nullptr;
    void* context = nullptr;
    int64_t width = 0, height = 0, depth = 0;
    bool haveMesh = false, haveGrid = false;
    Mesh host; // the mesh's copy for the eye's clearance in perspective frames (clipDepthOf)
};

CudaVoxelizer::CudaVoxelizer() : impl_(std::make_unique<Impl>()) {
    impl_->context = newContext(impl_->module);
}

CudaVoxelizer::~CudaVoxelizer() {
    if (impl_ && impl_->context) impl_->module->destroyContext(impl_->context);
}

void CudaVoxelizer::setMesh(const MeshView& mesh) {
    validateMesh(mesh, "mesh");
    detail::CudaMesh m;
    m.positions = mesh.positions;
    m.vertexCount = mesh.vertexCount;
    m.positionStride = mesh.positionStride;
    m.indices = mesh.indices;
    m.triangleCount = mesh.triangleCount;
    std::string error;
    checkCuda(impl_->module->setMesh(impl_->context, m, &error), error);
    impl_->host.positions.resize(mesh.vertexCount);
    for (std::size_t i = 0; i < mesh.vertexCount; ++i) impl_->host.positions[i] = Vec3f(mesh.vertex(i));
    impl_->host.indices.assign(mesh.indices, mesh.indices + 3 * mesh.triangleCount);
    impl_->haveMesh = true;
    impl_->haveGrid = false;
}

// VoxelizeMode crosses the module boundary as CudaMode: the values must agree.
static_assert(int(VoxelizeMode::Surface) == int(detail::CudaMode::Surface) &&
              int(VoxelizeMode::Conservative) == int(detail::CudaMode::Conservative) &&
              int(VoxelizeMode::Solid) == int(detail::CudaMode::Solid) &&
              int(VoxelizeMode::SolidConservative) == int(detail::CudaMode::SolidConservative) &&
              int(VoxelizeMode::Interior) == int(detail::CudaMode::Interior));

void CudaVoxelizer::voxelize(const Frame& frame, VoxelizeMode mode) {
    if (!impl_->haveMesh) fail("CudaVoxelizer::voxelize: no mesh (call setMesh first)");
    // Clipped as the CPU clips the passes of this mode (voxelize.cpp's passOptions).
    const double clipDepth = detail::clipDepthOf(frame, impl_->host.view(), needsFill(mode));
    std::string error;
    impl_->haveGrid = false;
    checkCuda(
        impl_->module->voxelize(impl_->context, frame.view(), clipDepth, detail::CudaMode(int(mode)), &error),
        error);
    impl_->width = frame.width();
    impl_->height = frame.height();
    impl_->depth = frame.depth();
    impl_->haveGrid = true;
}

BitGrid CudaVoxelizer::download() {
    if (!impl_->haveGrid) fail("CudaVoxelizer::download: nothing voxelized yet");
    BitGrid grid(impl_->width, impl_->height, impl_->depth);
    std::string error;
    checkCuda(impl_->module->download(impl_->context, grid.words(), grid.wordCount(), &error), error);
    return grid;
}

int64_t CudaVoxelizer::count() {
    if (!impl_->haveGrid) fail("CudaVoxelizer::count: nothing voxelized yet");
    int64_t n = 0;
    std::string error;
    checkCuda(impl_->module->count(impl_->context, &n, &error), error);
    return n;
}

CudaGrid CudaVoxelizer::grid() {
    if (!impl_->haveGrid) fail("CudaVoxelizer::grid: nothing voxelized yet");
    CudaGrid g(impl_->width, impl_->height, impl_->depth);
    std::string error;
    checkCuda(impl_->module->copyVoxelized(impl_->context, g.deviceHandle(), &error), error);
    return g;
}

DeviceTimings CudaVoxelizer::timings() const {
    detail::CudaTimings t;
    impl_->module->timings(impl_->context, &t);
    return {t.uploadMs, t.kernelMs, t.downloadMs};
}

CudaGrid::CudaGrid() = default;

CudaGrid::CudaGrid(int64_t w, int64_t h, int64_t d) : w_(w), h_(h), d_(d) {
    if (w <= 0 || h <= 0 || d <= 0) fail("a grid needs positive dimensions, got ", w, " x ", h, " x ", d);
    detail::CudaSharedContext& s = detail::cudaSharedContext();
    const std::lock_guard lock(s.mutex);
    std::string error;
    handle_ = s.module->createGrid(s.context, w, h, d, &error);
    if (!handle_) fail("CUDA: ", error);
}

CudaGrid::CudaGrid(const BitGrid& grid) : CudaGrid(grid.width(), grid.height(), grid.depth()) {
    detail::CudaSharedContext& s = detail::cudaSharedContext();
    const std::lock_guard lock(s.mutex);
    std::string error;
    checkCuda(s.module->uploadGrid(s.context, handle_, grid.words(), &error), error);
}

CudaGrid::~CudaGrid() {
    if (handle_) detail::cudaSharedContext().module->destroyGrid(handle_);
}

CudaGrid::CudaGrid(CudaGrid&& o) noexcept
    : handle_(std::exchange(o.handle_, nullptr)), w_(o.w_), h_(o.h_), d_(o.d_), kernelMs_(o.kernelMs_) {}

CudaGrid& CudaGrid::operator=(CudaGrid&& o) noexcept {
    if (this != &o) {
        if (handle_) detail::cudaSharedContext().module->destroyGrid(handle_);
        handle_ = std::exchange(o.handle_, nullptr);
        w_ = o.w_;
        h_ = o.h_;
        d_ = o.d_;
        kernelMs_ = o.kernelMs_;
    }
    return *this;
}

BitGrid CudaGrid::download() const {
    if (!handle_) return {};
    BitGrid grid(w_, h_, d_);
    detail::CudaSharedContext& s = detail::cudaSharedContext();
    const std::lock_guard lock(s.mutex);
    std::string error;
    checkCuda(s.module->downloadGrid(s.context, handle_, grid.words(), &error), error);
    return grid;
}

int64_t CudaGrid::count() const {
    if (!handle_) return 0;
    detail::CudaSharedContext& s = detail::cudaSharedContext();
    const std::lock_guard lock(s.mutex);
    int64_t n = 0;
    std::string error;
    checkCuda(s.module->countGrid(s.context, handle_, &n, &error), error);
    return n;
}

} // namespace voxfx
