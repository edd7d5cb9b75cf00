// Voxelization throughput on real meshes (scripts/fetch-data.sh): every mode at 128..1024, with
// the mesh already in memory, next to the time to write the output grid's bytes twice (the
// memory-bandwidth floor the issue compares large grids against), measured in the same run.
//
//   ./build/bench/bench_voxelize --benchmark_filter='Solid/bunny' --benchmark_repetitions=5
//
// Counters: tri/s (triangles per second), voxels/s (grid cells per second), grid_MiB.
#include <cstring>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_meshes.hpp"
#include "voxelize/fill.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;

using bench::fittedMesh;
using bench::kModes;
using bench::mesh;

void voxelizeBench(benchmark::State& state, const std::string& name, VoxelizeMode mode, Fill fill,
                   RasterPath path = RasterPath::Auto) {
    const auto in = fittedMesh(state, name);
    if (!in) return;
    const Mesh* m = in->mesh;
    const Frame& frame = in->frame;
    VoxelizeOptions vo;
    vo.mode = mode;
    vo.fill = fill;
    vo.rasterPath = path;
    // Parity needs a closed mesh; the dragon is open, so its solid modes use the flood fill.
    int64_t cells = frame.width() * frame.height() * frame.depth();
    for (auto _ : state) {
        VoxelGrid g = voxelize(m->view(), frame, vo);
        benchmark::DoNotOptimize(g.bits.words());
    }
    state.counters["tri/s"] =
        benchmark::Counter(double(m->triangleCount()), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["voxels/s"] =
        benchmark::Counter(double(cells), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["grid_MiB"] =
        double(BitGrid::requiredBytes(frame.width(), frame.height(), frame.depth())) / (1 << 20);
    state.SetLabel(name + " " + std::to_string(m->triangleCount()) + " tris, " +
                   std::to_string(frame.width()) + "x" + std::to_string(frame.height()) + "x" +
                   std::to_string(frame.depth()));
}

// The floor for large grids: allocating the output grid the way voxelize() does (BitGrid: fresh
// pages, huge pages from 2 MiB) and writing all of its bytes twice. Allocating through BitGrid
// rather than malloc keeps the floor honest: malloc would hand back the warm pages of the previous
// iteration for grids under glibc's mmap threshold, which voxelize() never gets.
void writeGridBytesTwice(benchmark::State& state, const std::string& name) {
    const Mesh* m = mesh(name);
    if (!m) {
        state.SkipWithError("missing data");
        return;
    }
    FitOptions fo;
    fo.resolution = state.range(0);
    const Frame f = fitFrame(computeBounds(m->view()), fo);
    const uint64_t bytes = BitGrid::requiredBytes(f.width(), f.height(), f.depth());
    for (auto _ : state) {
        BitGrid g(f.width(), f.height(), f.depth());
        auto* p = reinterpret_cast<unsigned char*>(g.words());
        std::memset(p, 0, bytes);
        benchmark::ClobberMemory();
        std::memset(p, 0xff, bytes);
        benchmark::DoNotOptimize(p);
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(bytes) * 2);
}

// The flood fill alone (detail::floodFillInside on the conservative surface computed once,
// outside the timing): what the "within 3x the write-twice floor" target of open meshes measures.
void floodFillBench(benchmark::State& state, const std::string& name) {
    const auto in = fittedMesh(state, name);
    if (!in) return;
    const Mesh* m = in->mesh;
    const Frame& frame = in->frame;
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Conservative;
    const VoxelGrid walls = voxelize(m->view(), frame, vo);
    for (auto _ : state) {
        BitGrid inside = detail::floodFillInside(walls.bits);
        benchmark::DoNotOptimize(inside.words());
    }
    state.SetLabel(name + " " + std::to_string(frame.width()) + "x" + std::to_string(frame.height()) + "x" +
                   std::to_string(frame.depth()));
}

// CHANG §2 attribute voxelization (table 1: the 871K-triangle dragon in 16.5 / 23.9 / 31.1 ms at
// 128^3 / 256^3 / 512^3 on an HD5850), with the channels of each use: shadows (count + absorption,
// centre coverage, 6 B/voxel), glass (normals + material id, conservative coverage as the glass
// renderer runs it, 16 B/voxel), all channels (centre, 38 B/voxel), and the sparse columns the
// renderer's absorption shadows use (count + absorption of written voxels only). The dense arrays
// are allocated and zeroed in every iteration, as voxelizeAttributes does.
void attributeBench(benchmark::State& state, const std::string& name, const std::string& use) {
    const auto in = fittedMesh(state, name);
    if (!in) return;
    const Mesh* m = in->mesh;
    const Frame& frame = in->frame;
    std::vector<float> absorption(m->triangleCount(), 0.1f);
    std::vector<uint32_t> material(m->triangleCount(), 0);
    const std::vector<AttributeMaterial> table{{1.5f, {0.1f, 0.2f, 0.3f}}};
    AttributeOptions ao;
    ao.triangleMaterial = material;
    ao.materials = table;
    std::span<const float> perTriangle;
    if (use == "Shadows") {
        ao.channels = AttributeChannels::shadows();
        perTriangle = absorption;
    } else if (use == "Glass") {
        ao.channels = AttributeChannels::glass();
        ao.coverage = Coverage::Conservative;
    } else {
        ao.channels = AttributeChannels::all();
        perTriangle = absorption;
    }
    uint64_t bytes = 0;
    for (auto _ : state) {
        if (use == "Sparse") { // what the renderer's absorption shadows build: O(writes) memory
            AttributeColumns c = voxelizeAttributeColumns(m->view(), frame, absorption, ao);
            bytes = c.offsets.size() * sizeof(int64_t) + c.slice.size() * sizeof(uint32_t) +
                    c.count.size() * sizeof(uint16_t) + c.absorption.size() * sizeof(float);
            benchmark::DoNotOptimize(c.frame);
            continue;
        }
        AttributeGrid g = voxelizeAttributes(m->view(), frame, perTriangle, ao);
        bytes = g.bytes();
        benchmark::DoNotOptimize(g.frame);
    }
    state.counters["grid_MiB"] = double(bytes) / (1 << 20);
    state.counters["tri/s"] =
        benchmark::Counter(double(m->triangleCount()), benchmark::Counter::kIsIterationInvariantRate);
    state.SetLabel(name + " " + std::to_string(m->triangleCount()) + " tris, " +
                   std::to_string(frame.width()) + "x" + std::to_string(frame.height()) + "x" +
                   std::to_string(frame.depth()));
}

struct Register {
    Register() {
        const auto& modes = kModes;
        for (const char* name : {"bunny00", "armadillo", "dragon", "dragon1m", "bunny1m"}) {
            const Fill fill = std::string(name).rfind("dragon", 0) == 0 ? Fill::Flood : Fill::Parity;
            for (const auto& [label, mode] : modes) {
                benchmark::RegisterBenchmark((std::string(label) + "/" + name).c_str(),
                                             [=](benchmark::State& s) { voxelizeBench(s, name, mode, fill); })
                    ->Arg(128)
                    ->Arg(256)
                    ->Arg(512)
                    ->Arg(1024)
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime();
            }
            // The rasterizer's two parallel schemes side by side (Auto picks one of them).
            for (const auto& [pathLabel, path] :
                 {std::pair{"Binned", RasterPath::Binned}, std::pair{"Direct", RasterPath::Direct}})
                for (const auto& [label, mode] : {modes[1], modes[2]})
                    benchmark::RegisterBenchmark(
                        (std::string(label) + pathLabel + "/" + name).c_str(),
                        [=](benchmark::State& s) { voxelizeBench(s, name, mode, fill, path); })
                        ->Arg(512)
                        ->Arg(1024)
                        ->Unit(benchmark::kMillisecond)
                        ->UseRealTime();
            benchmark::RegisterBenchmark((std::string("FloodFill/") + name).c_str(),
                                         [=](benchmark::State& s) { floodFillBench(s, name); })
                ->Arg(256)
                ->Arg(512)
                ->Arg(1024)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark((std::string("WriteGridBytesTwice/") + name).c_str(),
                                         [=](benchmark::State& s) { writeGridBytesTwice(s, name); })
                ->Arg(128)
                ->Arg(256)
                ->Arg(512)
                ->Arg(1024)
                ->Arg(2048)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        }
        for (const char* name : {"dragon", "dragon1m"})
            for (const char* use : {"Shadows", "Sparse", "Glass", "All"})
                benchmark::RegisterBenchmark((std::string("Attribute") + use + "/" + name).c_str(),
                                             [=](benchmark::State& s) { attributeBench(s, name, use); })
                    ->Arg(128)
                    ->Arg(256)
                    ->Arg(512)
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime();
        // Large grids (a 2048^3 slicemap of the bunny is 780 MiB): solid and conservative only.
        for (const auto& [label, mode] :
             {std::pair{"Solid", VoxelizeMode::Solid}, std::pair{"Conservative", VoxelizeMode::Conservative}})
            benchmark::RegisterBenchmark(
                (std::string(label) + "/bunny00").c_str(),
                [=](benchmark::State& s) { voxelizeBench(s, "bunny00", mode, Fill::Parity); })
                ->Arg(2048)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
    }
} registerAll;

} // namespace

BENCHMARK_MAIN();
