// The robust fills on open CGAL meshes (scripts/fetch-data.sh): parity, flood and gwn against the
// exact generalized winding number at every cell centre (brute force, O(triangles) per centre,
// voxfx::windingNumber), and their time.
//
//   ./build/bench_fill --benchmark_filter='FillAgreement/' --benchmark_min_time=0
//   ./build/bench_fill --benchmark_filter='FillTime/.*/128'
//
// FillAgreement/<mesh>/<fill>/<res> counters: agree_pct (cells with the reference's answer, of
// all cells), wrong_pct (cells that differ, as a percentage of the reference's inside cells),
// ref_inside (the reference's inside cells). The reference is computed once per mesh and size,
// outside the timing.
#include <bit>
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_meshes.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;

// Open meshes with an inside (boundary edges from `voxfx info`), smallest first.
const char* const kOpenMeshes[] = {"blob",      "double-torus-3-holes", "pig",   "head",
                                   "mushroom",  "elephant-with-holes",  "holes", "mech-holes-shark",
                                   "lion-head", "ChineseDragon-10kv"};

Frame fillFrame(const Mesh& m, int64_t resolution) {
    FitOptions fo;
    fo.resolution = resolution;
    fo.marginCells = 1;
    return fitFrame(computeBounds(m.view()), fo);
}

// The exact winding number >= 0.5 at every cell centre, by brute force.
const BitGrid& reference(const std::string& name, const Mesh& m, const Frame& f) {
    static std::map<std::pair<std::string, int64_t>, BitGrid> cache;
    const auto key = std::make_pair(name, f.width() * 1000003 + f.height() * 1009 + f.depth());
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    BitGrid g(f.width(), f.height(), f.depth());
    const MeshView mv = m.view();
    parallelFor(0, f.columnCount(), 1, [&](int64_t c0, int64_t c1) {
        for (int64_t c = c0; c < c1; ++c)
            for (int64_t z = 0; z < f.depth(); ++z)
                if (windingNumber(mv, f.cellCenter(c % f.width(), c / f.width(), z)) >= 0.5)
                    g.set(c % f.width(), c / f.width(), z);
    });
    return cache.emplace(key, std::move(g)).first->second;
}

VoxelGrid runFill(const Mesh& m, const Frame& f, Fill fill) {
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Solid;
    vo.fill = fill;
    return voxelize(m.view(), f, vo);
}

// The named mesh (or null, the benchmark skipped: the data is missing).
const Mesh* meshOrSkip(benchmark::State& state, const std::string& name) {
    const Mesh* m = bench::mesh(name);
    if (!m) state.SkipWithError("missing data: run scripts/fetch-data.sh");
    return m;
}

void fillAgreement(benchmark::State& state, const std::string& name, Fill fill) {
    const Mesh* m = meshOrSkip(state, name);
    if (!m) return;
    const Frame f = fillFrame(*m, state.range(0));
    const BitGrid& ref = reference(name, *m, f);
    VoxelGrid g;
    for (auto _ : state) {
        g = runFill(*m, f, fill);
        benchmark::DoNotOptimize(g.bits.words());
    }
    int64_t differ = 0;
    for (int64_t i = 0; i < ref.wordCount(); ++i) differ += std::popcount(ref.words()[i] ^ g.bits.words()[i]);
    const double cells = double(f.width() * f.height() * f.depth());
    const double inside = double(ref.count());
    state.counters["agree_pct"] = 100.0 * (1.0 - double(differ) / cells);
    state.counters["wrong_pct"] = inside > 0 ? 100.0 * double(differ) / inside : 0.0;
    state.counters["ref_inside"] = inside;
    state.SetLabel(name + " " + std::to_string(m->triangleCount()) + " tris");
}

void fillTime(benchmark::State& state, const std::string& name, Fill fill) {
    const Mesh* m = meshOrSkip(state, name);
    if (!m) return;
    const Frame f = fillFrame(*m, state.range(0));
    for (auto _ : state) {
        VoxelGrid g = runFill(*m, f, fill);
        benchmark::DoNotOptimize(g.bits.words());
    }
    state.SetLabel(name + " " + std::to_string(f.width()) + "x" + std::to_string(f.height()) + "x" +
                   std::to_string(f.depth()));
}

struct Register {
    Register() {
        const std::pair<const char*, Fill> fills[] = {
            {"parity", Fill::Parity}, {"flood", Fill::Flood}, {"gwn", Fill::Gwn}};
        for (const char* name : kOpenMeshes)
            for (const auto& [label, fill] : fills) {
                const std::string suffix = std::string(name) + "/" + label;
                benchmark::RegisterBenchmark(("FillAgreement/" + suffix).c_str(),
                                             [=](benchmark::State& s) { fillAgreement(s, name, fill); })
                    ->Arg(32)
                    ->Arg(64)
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime();
                benchmark::RegisterBenchmark(("FillTime/" + suffix).c_str(),
                                             [=](benchmark::State& s) { fillTime(s, name, fill); })
                    ->Arg(64)
                    ->Arg(128)
                    ->Arg(256)
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime();
            }
    }
} registerFillBenchmarks;

} // namespace

BENCHMARK_MAIN();
