// Tiled and sparse voxelization (#23) against the dense path, in one run so the ratios hold:
//   Dense        voxelize(): the whole grid in memory (the path before tiles)
//   Tiles        voxelizeTiles() with a visitor that keeps nothing: the tiling's own cost
//   Sparse       voxelizeSparse(): the tiles into OpenVDB's tree
//   DenseToVdb   voxelize() and writeGrid() of the dense grid to .vdb (what `voxfx voxelize
//                -o x.vdb --dense` does)
//   SparseToVdb  voxelizeSparse() and writeGrid() of the tree (what `voxfx voxelize -o x.vdb` does)
//   WriteSparse  writeGrid() of an already voxelized sparse grid alone
// on bunny00 (75K triangles) and bunny1m (1.2M, bench/bench_meshes.hpp), solid (parity), at the
// resolution in the name. Files go to $TMPDIR (default /tmp).
//
//   ./build/bench_sparse --benchmark_min_time=0.01 --benchmark_repetitions=3
//
// Counters: voxels_per_second (cells of the grid), filled (cells), tree_MiB (OpenVDB memUsage).
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <benchmark/benchmark.h>

#include "bench_meshes.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;

std::string tempVdb() {
    const char* dir = std::getenv("TMPDIR");
    return (std::filesystem::path(dir && *dir ? dir : "/tmp") / "voxfx_bench_sparse.vdb").string();
}

// The frame of `name` at state.range(0), without the dense memory check (the sparse runs never
// build the dense grid).
std::optional<bench::FittedMesh> fitted(benchmark::State& state, const std::string& name) {
    const Mesh* m = bench::mesh(name);
    if (!m) {
        state.SkipWithError("missing data: run scripts/fetch-data.sh");
        return std::nullopt;
    }
    FitOptions fo;
    fo.resolution = state.range(0);
    fo.checkDenseMemory = false;
    return bench::FittedMesh{m, fitFrame(computeBounds(m->view()), fo)};
}

void counters(benchmark::State& state, const Frame& frame, int64_t filled) {
    state.SetItemsProcessed(state.iterations() * frame.width() * frame.height() * frame.depth());
    state.counters["filled"] = double(filled);
}

void Dense(benchmark::State& state, const std::string& name) {
    const auto f = fitted(state, name);
    if (!f) return;
    int64_t filled = 0;
    for (auto _ : state) filled = voxelize(f->mesh->view(), f->frame).bits.count();
    counters(state, f->frame, filled);
}

void Tiles(benchmark::State& state, const std::string& name) {
    const auto f = fitted(state, name);
    if (!f) return;
    std::atomic<int64_t> uniform{0};
    for (auto _ : state)
        voxelizeTiles(f->mesh->view(), f->frame, {}, {}, [&](const GridTile& t) { uniform += t.uniform; });
    counters(state, f->frame, 0);
    state.counters["uniform_bricks"] = double(uniform) / double(state.iterations());
}

void Sparse(benchmark::State& state, const std::string& name) {
    const auto f = fitted(state, name);
    if (!f) return;
    int64_t filled = 0;
    uint64_t bytes = 0;
    for (auto _ : state) {
        const SparseGrid g = voxelizeSparse(f->mesh->view(), f->frame);
        state.PauseTiming();
        filled = g.count();
        bytes = g.memoryBytes();
        state.ResumeTiming();
    }
    counters(state, f->frame, filled);
    state.counters["tree_MiB"] = double(bytes) / double(1 << 20);
}

void DenseToVdb(benchmark::State& state, const std::string& name) {
    const auto f = fitted(state, name);
    if (!f) return;
    for (auto _ : state) writeGrid(voxelize(f->mesh->view(), f->frame), tempVdb());
    counters(state, f->frame, 0);
    std::filesystem::remove(tempVdb());
}

void SparseToVdb(benchmark::State& state, const std::string& name) {
    const auto f = fitted(state, name);
    if (!f) return;
    for (auto _ : state) writeGrid(voxelizeSparse(f->mesh->view(), f->frame), tempVdb());
    counters(state, f->frame, 0);
    state.counters["file_MiB"] = double(std::filesystem::file_size(tempVdb())) / double(1 << 20);
    std::filesystem::remove(tempVdb());
}

void WriteSparse(benchmark::State& state, const std::string& name) {
    const auto f = fitted(state, name);
    if (!f) return;
    const SparseGrid g = voxelizeSparse(f->mesh->view(), f->frame);
    for (auto _ : state) writeGrid(g, tempVdb());
    counters(state, f->frame, g.count());
    state.counters["file_MiB"] = double(std::filesystem::file_size(tempVdb())) / double(1 << 20);
    std::filesystem::remove(tempVdb());
}

void registerAll() {
    for (const char* mesh : {"bunny00", "bunny1m"}) {
        const std::string m = mesh;
        for (int64_t n : {512, 1024}) {
            benchmark::RegisterBenchmark(("Dense/" + m).c_str(), Dense, m)
                ->Arg(n)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark(("Tiles/" + m).c_str(), Tiles, m)
                ->Arg(n)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark(("Sparse/" + m).c_str(), Sparse, m)
                ->Arg(n)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark(("DenseToVdb/" + m).c_str(), DenseToVdb, m)
                ->Arg(n)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark(("SparseToVdb/" + m).c_str(), SparseToVdb, m)
                ->Arg(n)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        }
        benchmark::RegisterBenchmark(("WriteSparse/" + m).c_str(), WriteSparse, m)
            ->Arg(2048)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    }
}

} // namespace

int main(int argc, char** argv) {
    registerAll();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
