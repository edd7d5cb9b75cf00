// The CUDA back end's voxelization (voxfx/device.hpp) on real meshes at 512^3..2048^3, timed with
// CUDA events, next to the CPU path on the same machine for a few of the same cases.
//
//   ./build/bench_cuda --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Gpu/<mode>/<mesh>/<N>: the reported time is the kernels' (CUDA events around the grid's
// clearing, vertex transform, rasterization, prefix pass and combine; the mesh already on the
// GPU), set as manual time. Counters: upload_ms (the mesh, host to device) and download_ms (the
// grid, device to host), measured once per benchmark; Mtri/s. Cpu/<mode>/<mesh>/<N>: voxfx::voxelize
// on every core, wall time. Without a usable GPU the Gpu rows are skipped with the reason.
//
// The meshes are bench_meshes.hpp's: bunny1m is bunny00 subdivided twice at the midpoints
// (1,206,528 triangles), built in memory when data/dense/ does not hold it.
#include <chrono>
#include <memory>
#include <string>

#include <benchmark/benchmark.h>

#include "bench_meshes.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;

using bench::fittedMesh;
using bench::kModes;

/// One voxelizer for the whole run: the mesh is uploaded when it changes.
CudaVoxelizer* gpuFor(const Mesh* m) {
    static std::unique_ptr<CudaVoxelizer> gpu;
    static const Mesh* current = nullptr;
    if (!gpu) gpu = std::make_unique<CudaVoxelizer>();
    if (current != m) {
        gpu->setMesh(m->view());
        current = m;
    }
    return gpu.get();
}

void gpuBench(benchmark::State& state, const std::string& name, VoxelizeMode mode) {
    if (!cudaStatus().available) {
        state.SkipWithError(("no usable GPU: " + cudaStatus().reason).c_str());
        return;
    }
    const auto in = fittedMesh(state, name);
    if (!in) return;
    const Mesh* m = in->mesh;
    const Frame& frame = in->frame;
    CudaVoxelizer* gpu = gpuFor(m);
    for (auto _ : state) {
        gpu->voxelize(frame, mode);
        state.SetIterationTime(gpu->timings().kernelMs * 1e-3);
    }
    const double uploadMs = [&] {
        gpu->setMesh(m->view()); // timed again here, so that every row reports it
        return gpu->timings().uploadMs;
    }();
    gpu->voxelize(frame, mode);
    const BitGrid grid = gpu->download();
    benchmark::DoNotOptimize(grid.words());
    state.counters["upload_ms"] = uploadMs;
    state.counters["download_ms"] = gpu->timings().downloadMs;
    state.counters["Mtri/s"] =
        benchmark::Counter(double(m->triangleCount()) * 1e-6, benchmark::Counter::kIsRate);
    state.SetLabel(cudaStatus().device);
}

void cpuBench(benchmark::State& state, const std::string& name, VoxelizeMode mode) {
    const auto in = fittedMesh(state, name);
    if (!in) return;
    const Mesh* m = in->mesh;
    const Frame& frame = in->frame;
    VoxelizeOptions o;
    o.mode = mode;
    for (auto _ : state) benchmark::DoNotOptimize(voxelize(m->view(), frame, o).bits.words());
    state.counters["Mtri/s"] =
        benchmark::Counter(double(m->triangleCount()) * 1e-6, benchmark::Counter::kIsRate);
}

/// The toolkit's operations on the solid and conservative grids of a mesh, on the GPU (grids kept
/// there; kernel time from CUDA events, or wall time for the count, which returns a number to
/// the host) or on the CPU (every core).
enum class Op { Dilate, Close, Difference, Count };

void opBench(benchmark::State& state, const std::string& name, Op op, bool gpu) {
    if (gpu && !cudaStatus().available) {
        state.SkipWithError(("no usable GPU: " + cudaStatus().reason).c_str());
        return;
    }
    const auto in = fittedMesh(state, name);
    if (!in) return;
    const Mesh* m = in->mesh;
    const Frame& frame = in->frame;
    MorphologyOptions mo;
    mo.rx = mo.ry = mo.rz = 1;
    if (gpu) {
        CudaVoxelizer* v = gpuFor(m);
        v->voxelize(frame, VoxelizeMode::Solid);
        const CudaGrid solid = v->grid();
        v->voxelize(frame, VoxelizeMode::Conservative);
        const CudaGrid shell = v->grid();
        for (auto _ : state) {
            const auto t0 = std::chrono::steady_clock::now();
            switch (op) {
            case Op::Dilate:
                state.SetIterationTime(morphology(solid, MorphOp::Dilate, mo).lastKernelMs() * 1e-3);
                break;
            case Op::Close:
                state.SetIterationTime(morphology(solid, MorphOp::Close, mo).lastKernelMs() * 1e-3);
                break;
            case Op::Difference:
                state.SetIterationTime(csg(solid, shell, CsgOp::Difference).lastKernelMs() * 1e-3);
                break;
            case Op::Count:
                benchmark::DoNotOptimize(solid.count());
                state.SetIterationTime(
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
                break;
            }
        }
    } else {
        VoxelizeOptions vo;
        vo.mode = VoxelizeMode::Solid;
        const BitGrid solid = voxelize(m->view(), frame, vo).bits;
        vo.mode = VoxelizeMode::Conservative;
        const BitGrid shell = voxelize(m->view(), frame, vo).bits;
        BitGrid out, scratch;
        for (auto _ : state) {
            const auto t0 = std::chrono::steady_clock::now();
            switch (op) {
            case Op::Dilate:
                morphology(solid, MorphOp::Dilate, mo, out, scratch);
                break;
            case Op::Close:
                morphology(solid, MorphOp::Close, mo, out, scratch);
                break;
            case Op::Difference:
                csg(solid, shell, CsgOp::Difference, out);
                break;
            case Op::Count:
                benchmark::DoNotOptimize(solid.count());
                break;
            }
            state.SetIterationTime(
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        }
    }
}

const struct Register {
    Register() {
        const auto& modes = kModes;
        for (const char* name : {"bunny00", "armadillo", "dragon", "elephant", "bunny1m"})
            for (const auto& [modeName, mode] : modes)
                benchmark::RegisterBenchmark(
                    (std::string("Gpu/") + modeName + "/" + name).c_str(),
                    [name = std::string(name), mode = mode](benchmark::State& s) { gpuBench(s, name, mode); })
                    ->Arg(512)
                    ->Arg(1024)
                    ->Arg(2048)
                    ->UseManualTime()
                    ->Unit(benchmark::kMillisecond);
        // The CPU on the same machine, for ratios taken in one run.
        for (const char* name : {"bunny00", "bunny1m"})
            for (const auto& [modeName, mode] : {modes[1], modes[2]})
                benchmark::RegisterBenchmark(
                    (std::string("Cpu/") + modeName + "/" + name).c_str(),
                    [name = std::string(name), mode = mode](benchmark::State& s) { cpuBench(s, name, mode); })
                    ->Arg(512)
                    ->Arg(1024)
                    ->UseRealTime()
                    ->Unit(benchmark::kMillisecond);
        // The toolkit's operations, GPU and CPU, on the same grids.
        const std::pair<const char*, Op> ops[] = {{"Dilate1", Op::Dilate},
                                                  {"Close1", Op::Close},
                                                  {"Difference", Op::Difference},
                                                  {"Count", Op::Count}};
        for (const auto& [opName, op] : ops)
            for (bool gpu : {true, false})
                benchmark::RegisterBenchmark(
                    (std::string(gpu ? "GpuOp/" : "CpuOp/") + opName + "/bunny00").c_str(),
                    [op = op, gpu](benchmark::State& s) { opBench(s, "bunny00", op, gpu); })
                    ->Arg(512)
                    ->Arg(1024)
                    ->UseManualTime()
                    ->Unit(benchmark::kMillisecond);
    }
} kRegister;

} // namespace

BENCHMARK_MAIN();
