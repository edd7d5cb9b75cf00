// Deep shadow maps (Bornik et al. 2012): building and ε-compressing a 512 x 512 map of random
// visibility functions, in both storages, for ε = 0.01, 0.05, 0.1, 0.2 (the paper's table 4).
//
//   ./build/bench/bench_dsm --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Each texel's ray meets 0..8 surfaces (opacity 0.1..0.9, one in ten opaque) and 0..2 smoke-like
// volume segments (extinction varying per sample, a sample every 0.25 depth units) in depths
// [0, 100], seeded by the texel, fed to the builder in depth order as a ray caster would.
// Counters: nodes_mean and nodes_max per texel, bytes held, and for the fixed storage (sized, as
// in the paper, by the worst texel of the same ε) the bytes of that layout; chunked bytes include
// the per-texel heads.
#include <algorithm>
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "voxfx/dsm.hpp"
#include "voxfx/parallel.hpp"

namespace {

using namespace voxfx;

constexpr int64_t kSize = 512;

// SplitMix64: seeding per texel costs nothing (a Mersenne twister's seeding dominated the texel).
struct SplitMix {
    uint64_t s;
    uint64_t operator()() {
        uint64_t z = (s += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
};

void randomRay(int64_t x, int64_t y, VisibilityBuilder& b) {
    SplitMix rng{uint64_t(x) * 73856093u ^ uint64_t(y) * 19349663u};
    const auto unit = [&](SplitMix& r) { return double(r() >> 11) * 0x1.0p-53; };
    struct Ev {
        double z0, z1, alpha;
        bool volume;
    };
    thread_local std::vector<Ev> ev;
    ev.clear();
    for (int i = int(rng() % 9); i > 0; --i) {
        const double a = unit(rng) < 0.1 ? 1.0 : 0.1 + 0.8 * unit(rng);
        ev.push_back({unit(rng) * 100, 0, a, false});
    }
    // Volume segments in disjoint thirds of the depth range.
    for (int i = 0; i < 3; ++i)
        if (unit(rng) < 0.3) {
            const double z0 = 33.3 * i + unit(rng) * 10, z1 = z0 + 5 + unit(rng) * 15;
            ev.push_back({z0, z1, 0, true});
        }
    std::sort(ev.begin(), ev.end(), [](const Ev& a, const Ev& c) { return a.z0 < c.z0; });
    // Surfaces inside a segment are applied where the marching reaches them.
    size_t s = 0;
    for (const Ev& e : ev) {
        if (!e.volume) continue;
        for (; s < ev.size() && ev[s].z0 < e.z0; ++s)
            if (!ev[s].volume) b.surface(ev[s].z0, ev[s].alpha);
        b.volumeBegin(e.z0);
        const double base = 0.02 + 0.1 * unit(rng), phase = unit(rng) * 6.28;
        for (double z = e.z0 + 0.25; z <= e.z1; z += 0.25) {
            for (; s < ev.size() && ev[s].z0 < z; ++s)
                if (!ev[s].volume) b.surface(ev[s].z0, ev[s].alpha);
            b.volumeSample(z, base * (1 + 0.8 * std::sin(z * 0.7 + phase)), 0.25);
        }
    }
    for (; s < ev.size(); ++s)
        if (!ev[s].volume) b.surface(ev[s].z0, ev[s].alpha);
}

void report(benchmark::State& state, const DsmStats& s) {
    state.counters["nodes_mean"] = s.meanNodes();
    state.counters["nodes_max"] = double(s.maxNodes);
    state.counters["bytes"] = double(s.bytes);
    state.counters["overflow"] = double(s.overflowTexels);
    state.counters["max_eps"] = s.maxEpsilon;
    state.SetItemsProcessed(state.iterations() * kSize * kSize);
}

void BM_DsmChunked(benchmark::State& state) {
    const double eps = double(state.range(0)) / 100.0;
    DsmStats stats;
    for (auto _ : state) {
        const DsmChunked m = DsmChunked::build(kSize, kSize, randomRay, eps);
        stats = m.stats();
        benchmark::DoNotOptimize(m.view().chunks);
    }
    report(state, stats);
}

// One thread, to compare with BM_DsmRaysOnly (the event generation alone, also one thread): the
// difference is the cost of building, compressing and storing.
void BM_DsmChunkedOneThread(benchmark::State& state) {
    const double eps = double(state.range(0)) / 100.0;
    DsmStats stats;
    withThreads(1, [&] {
        for (auto _ : state) {
            const DsmChunked m = DsmChunked::build(kSize, kSize, randomRay, eps);
            stats = m.stats();
            benchmark::DoNotOptimize(m.view().chunks);
        }
    });
    report(state, stats);
}

// The synthetic rays alone: events generated and fed to a builder that keeps the exact function
// in a reused buffer (no compression, no map).
void BM_DsmRaysOnly(benchmark::State& state) {
    std::vector<DsmNode> out;
    for (auto _ : state)
        for (int64_t y = 0; y < kSize; ++y)
            for (int64_t x = 0; x < kSize; ++x) {
                out.clear();
                VisibilityBuilder b(-1, out);
                randomRay(x, y, b);
                b.finish();
                benchmark::DoNotOptimize(out.data());
            }
    state.SetItemsProcessed(state.iterations() * kSize * kSize);
}

void BM_DsmFixed(benchmark::State& state) {
    const double eps = double(state.range(0)) / 100.0;
    DsmBuildOptions o;
    o.epsilon = eps;
    // Sized by the worst texel, as the paper's fixed layout must be.
    o.fixedNodes =
        int32_t(std::max<int64_t>(2, DsmChunked::build(kSize, kSize, randomRay, eps).stats().maxNodes));
    DsmStats stats;
    for (auto _ : state) {
        const DsmFixed m = DsmFixed::build(kSize, kSize, randomRay, o);
        stats = m.stats();
        benchmark::DoNotOptimize(m.view().nodes);
    }
    report(state, stats);
}

// Fixed storage capped at 8 nodes per texel: texels that need more are rebuilt with a larger ε
// (overflow counts them, max_eps is the largest ε used).
void BM_DsmFixedCapped(benchmark::State& state) {
    DsmBuildOptions o;
    o.epsilon = double(state.range(0)) / 100.0;
    o.fixedNodes = 8;
    DsmStats stats;
    for (auto _ : state) {
        const DsmFixed m = DsmFixed::build(kSize, kSize, randomRay, o);
        stats = m.stats();
        benchmark::DoNotOptimize(m.view().nodes);
    }
    report(state, stats);
}

// The uncompressed function's node count for reference (ε < 0: exact).
void BM_DsmUncompressedNodes(benchmark::State& state) {
    int64_t nodes = 0, maxNodes = 0;
    for (auto _ : state) {
        nodes = maxNodes = 0;
        std::vector<DsmNode> out;
        for (int64_t y = 0; y < kSize; y += 4)
            for (int64_t x = 0; x < kSize; x += 4) {
                out.clear();
                VisibilityBuilder b(-1, out);
                randomRay(x, y, b);
                b.finish();
                nodes += int64_t(out.size());
                maxNodes = std::max(maxNodes, int64_t(out.size()));
            }
    }
    state.counters["nodes_mean"] = double(nodes) / double((kSize / 4) * (kSize / 4));
    state.counters["nodes_max"] = double(maxNodes);
}

BENCHMARK(BM_DsmChunked)->Arg(1)->Arg(5)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DsmChunkedOneThread)
    ->Arg(1)
    ->Arg(5)
    ->Arg(10)
    ->Arg(20)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_DsmRaysOnly)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DsmFixed)->Arg(1)->Arg(5)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DsmFixedCapped)->Arg(1)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DsmUncompressedNodes)->Iterations(1)->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
