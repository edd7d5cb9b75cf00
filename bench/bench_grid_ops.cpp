// Bit-grid operations (GI08 §6-7) at 512^3 and 1024^3, as grid bytes processed per second, next
// to a plain memory copy of the same bytes measured in the same run (the bandwidth floor the
// issue compares against). The grid is the Stanford bunny (scripts/fetch-data.sh) voxelized as a
// solid into an N^3 cube; a random grid stands in when the data is missing.
//
//   ./build/bench/bench_grid_ops --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// bytes_per_second counts the bytes of one input grid (N^3 / 8) per iteration for every grid
// operation and for the copies, so the rates compare directly. Like with like: BM_Memcpy copies
// into a destination faulted in beforehand, and so do the operations writing into caller-owned
// outputs (each runs once before timing); the *Allocating rows and BM_GridCopy include the
// allocation and first-touch page faults of a fresh result. The machine may be shared: compare
// ratios to BM_Memcpy from the same run, not absolute times. Particles report particle steps
// per second (items) and whole steps per second (steps/s) for 10^6 particles.
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "voxfx/csg.hpp"
#include "voxfx/density.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/particles.hpp"
#include "voxfx/surface_mesh.hpp"
#include "voxfx/voxelize.hpp"

namespace {

using namespace voxfx;

// The bunny in an N^3 cube of cells around its bounds (cached per N), or a random grid.
const VoxelGrid& grid(int64_t n) {
    static std::map<int64_t, std::unique_ptr<VoxelGrid>> cache;
    auto it = cache.find(n);
    if (it != cache.end()) return *it->second;
    const std::string path = std::string(VOXFX_DATA_DIR) + "/meshes/bunny00.off";
    std::unique_ptr<VoxelGrid> g;
    if (std::filesystem::exists(path)) {
        const Mesh m = loadMesh(path);
        const Box3d b = computeBounds(m.view());
        const Vec3d c = b.center(), e = b.extent();
        const double half = 0.51 * std::max({e.x, e.y, e.z});
        const Frame f =
            Frame::orthographic({c - Vec3d{half, half, half}, c + Vec3d{half, half, half}}, Axis::Z, n, n, n);
        g = std::make_unique<VoxelGrid>(voxelize(m.view(), f));
    } else {
        g = std::make_unique<VoxelGrid>(
            VoxelGrid{Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, n, n, n), BitGrid(n, n, n)});
        std::mt19937_64 rng(1);
        for (int64_t i = 0; i < g->bits.wordCount(); ++i) g->bits.words()[i] = rng() & rng();
    }
    return *cache.emplace(n, std::move(g)).first->second;
}

// A second operand of the same size with different content: the bunny re-sliced along x, its
// bits read as a z-sliced grid.
const BitGrid& other(int64_t n) {
    static std::map<int64_t, std::unique_ptr<BitGrid>> cache;
    auto it = cache.find(n);
    if (it != cache.end()) return *it->second;
    return *cache.emplace(n, std::make_unique<BitGrid>(reslice(grid(n), Axis::X).bits)).first->second;
}

void setBytes(benchmark::State& state, const BitGrid& g) {
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(g.byteCount()));
    state.counters["grid_MiB"] = double(g.byteCount()) / (1 << 20);
}

void BM_Memcpy(benchmark::State& state) {
    const BitGrid& g = grid(state.range(0)).bits;
    BitGrid dst(g.width(), g.height(), g.depth());
    std::memcpy(dst.words(), g.words(), g.byteCount()); // fault the pages in once
    for (auto _ : state) {
        std::memcpy(dst.words(), g.words(), g.byteCount());
        benchmark::ClobberMemory();
    }
    setBytes(state, g);
}

void BM_MemcpyParallel(benchmark::State& state) {
    // The same copy split over all threads in fixed chunks, as the grid operations run: the
    // stricter reference where one thread does not saturate memory.
    const BitGrid& g = grid(state.range(0)).bits;
    BitGrid dst(g.width(), g.height(), g.depth());
    std::memcpy(dst.words(), g.words(), g.byteCount()); // fault the pages in once
    for (auto _ : state) {
        parallelFor(0, g.wordCount(), int64_t(1) << 15, [&](int64_t b, int64_t e) {
            std::memcpy(dst.words() + b, g.words() + b, size_t(e - b) * 8);
        });
        benchmark::ClobberMemory();
    }
    setBytes(state, g);
}

void BM_GridCopy(benchmark::State& state) {
    // Allocation (fresh zero pages) plus copy: what an operation returning a new grid pays.
    const BitGrid& g = grid(state.range(0)).bits;
    for (auto _ : state) {
        BitGrid copy(g);
        benchmark::DoNotOptimize(copy.words());
    }
    setBytes(state, g);
}

void BM_Density(benchmark::State& state) {
    // Into a caller-owned density grid (level 1 reuses it; higher levels allocate their steps).
    const BitGrid& g = grid(state.range(0)).bits;
    DensityOptions o;
    o.level = int(state.range(1));
    DensityGrid d;
    computeDensity(g, d, o); // allocate and fault the output in once, as BM_Memcpy does
    for (auto _ : state) {
        computeDensity(g, d, o);
        benchmark::DoNotOptimize(d.words());
    }
    setBytes(state, g);
}

void BM_CsgUnion(benchmark::State& state) {
    // Into a caller-owned, already faulted-in grid (like BM_Memcpy's destination): two grids
    // read, one written, so three grids of traffic against the copy's two.
    const BitGrid &a = grid(state.range(0)).bits, &b = other(state.range(0));
    BitGrid r;
    csg(a, b, CsgOp::Union, r);
    for (auto _ : state) {
        csg(a, b, CsgOp::Union, r);
        benchmark::DoNotOptimize(r.words());
    }
    setBytes(state, a);
}

void BM_CsgUnionAllocating(benchmark::State& state) {
    // The value-returning form: a fresh grid per call, its first-touch page faults included.
    const BitGrid &a = grid(state.range(0)).bits, &b = other(state.range(0));
    for (auto _ : state) {
        BitGrid r = csg(a, b, CsgOp::Union);
        benchmark::DoNotOptimize(r.words());
    }
    setBytes(state, a);
}

void BM_CsgDifferenceInPlace(benchmark::State& state) {
    BitGrid a = grid(state.range(0)).bits;
    const BitGrid& b = other(state.range(0));
    for (auto _ : state) {
        csgInPlace(a, b, CsgOp::Difference);
        benchmark::ClobberMemory();
    }
    setBytes(state, a);
}

// Arguments: N, radius along x and y, radius along depth.
MorphologyOptions morphOptions(const benchmark::State& state) {
    MorphologyOptions o;
    o.rx = o.ry = state.range(1);
    o.rz = state.range(2);
    return o;
}

void BM_Morphology(benchmark::State& state) {
    // Dilation into caller-owned grids (the scratch grid holds the x/depth pass when y runs too).
    const BitGrid& g = grid(state.range(0)).bits;
    const MorphologyOptions o = morphOptions(state);
    BitGrid r, scratch;
    morphology(g, MorphOp::Dilate, o, r, scratch); // allocate and fault the outputs in once
    for (auto _ : state) {
        morphology(g, MorphOp::Dilate, o, r, scratch);
        benchmark::DoNotOptimize(r.words());
    }
    setBytes(state, g);
}

void BM_MorphologyAllocating(benchmark::State& state) {
    // The value-returning form: two fresh grids per call when y runs.
    const BitGrid& g = grid(state.range(0)).bits;
    const MorphologyOptions o = morphOptions(state);
    for (auto _ : state) {
        BitGrid r = dilate(g, o);
        benchmark::DoNotOptimize(r.words());
    }
    setBytes(state, g);
}

void BM_Count(benchmark::State& state) {
    const VoxelGrid& g = grid(state.range(0));
    for (auto _ : state) benchmark::DoNotOptimize(filledVolume(g));
    setBytes(state, g.bits);
}

void BM_ColumnRange(benchmark::State& state) {
    // Random columns and slice ranges, as the shadow lookups issue them.
    const BitGrid& g = grid(state.range(0)).bits;
    const int64_t n = state.range(0);
    std::mt19937_64 rng(2);
    std::vector<int64_t> q(4096 * 4);
    for (size_t i = 0; i < q.size(); i += 4) {
        q[i] = int64_t(rng() % uint64_t(n));
        q[i + 1] = int64_t(rng() % uint64_t(n));
        const int64_t s0 = int64_t(rng() % uint64_t(n)), s1 = int64_t(rng() % uint64_t(n));
        q[i + 2] = std::min(s0, s1);
        q[i + 3] = std::max(s0, s1);
    }
    int64_t sum = 0;
    for (auto _ : state)
        for (size_t i = 0; i < q.size(); i += 4)
            sum += countColumnRange(g, q[i], q[i + 1], q[i + 2], q[i + 3]);
    benchmark::DoNotOptimize(sum);
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(q.size() / 4));
}

void BM_TraceSegment(benchmark::State& state) {
    // Random segments between points on two opposite faces of the grid: ~1.5 N cells each.
    const BitGrid& g = grid(state.range(0)).bits;
    const double n = double(state.range(0));
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0, n);
    std::vector<Vec3d> ends;
    for (int i = 0; i < 1024; ++i) {
        ends.push_back({u(rng), u(rng), 0});
        ends.push_back({u(rng), u(rng), n});
    }
    int64_t cells = 0;
    double len = 0;
    for (auto _ : state)
        for (size_t i = 0; i < ends.size(); i += 2) {
            const SegmentHits h = traceSegmentGrid(g, ends[i], ends[i + 1]);
            cells += h.cellsVisited;
            len += h.filledLength;
        }
    benchmark::DoNotOptimize(len);
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(ends.size() / 2));
    state.counters["cells/s"] = benchmark::Counter(double(cells), benchmark::Counter::kIsRate);
}

void BM_MarchingCubes(benchmark::State& state) {
    const VoxelGrid& g = grid(state.range(0));
    const DensityGrid d = computeDensity(g.bits);
    size_t tris = 0;
    for (auto _ : state) tris = extractSurface(d, g.frame).triangleCount();
    state.counters["triangles"] = double(tris);
    setBytes(state, g.bits);
}

void BM_Particles(benchmark::State& state) {
    // 10^6 particles dropped on the bunny (512^3) in a closed box; 60 steps first so that the
    // timed steps mix falling, bouncing and resting particles.
    const VoxelGrid& g = grid(state.range(0));
    static std::map<int64_t, std::unique_ptr<ParticleCollider>> colliders;
    auto& c = colliders[state.range(0)];
    if (!c) c = std::make_unique<ParticleCollider>(g);
    Particles ps = emitParticles(*c, 1000000, {}, 1);
    ParticleOptions o;
    o.gravity = {0, 0, -2.0 * g.frame.box().extent().z}; // falls its height in about a second
    o.dt = 1.0 / 60;
    o.boxWalls = true;
    for (int i = 0; i < 60; ++i) stepParticles(ps, *c, o);
    sortParticles(ps, *c); // as an application would now and then, to keep grid reads coherent
    int64_t bounces = 0;
    for (auto _ : state) bounces += stepParticles(ps, *c, o).bounces;
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(ps.size()));
    state.counters["steps/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["bounce_frac"] = double(bounces) / double(state.iterations()) / double(ps.size());
}

} // namespace

BENCHMARK(BM_Memcpy)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MemcpyParallel)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GridCopy)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Density)
    ->Args({512, 1})
    ->Args({1024, 1})
    ->Args({1024, 3})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_CsgUnion)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CsgUnionAllocating)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CsgDifferenceInPlace)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
// Arguments: N, radius along x and y, radius along depth.
BENCHMARK(BM_Morphology)
    ->Args({512, 0, 1})
    ->Args({1024, 0, 1})
    ->Args({512, 0, 8})
    ->Args({1024, 0, 8})
    ->Args({1024, 0, 100})
    ->Args({512, 1, 1})
    ->Args({1024, 1, 1})
    ->Args({1024, 4, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_MorphologyAllocating)
    ->Args({1024, 0, 1})
    ->Args({1024, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Count)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ColumnRange)->Arg(512)->Arg(1024)->UseRealTime();
BENCHMARK(BM_TraceSegment)->Arg(512)->Arg(1024)->UseRealTime();
BENCHMARK(BM_MarchingCubes)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Particles)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
