// GI08's comparison (Eisemann & Décoret 2008, fig. 9 and §9; CHANG's "Grid" column): single-pass
// solid voxelization against the slice-by-slice method it improves on, on the CGAL meshes at
// 128^3 - 1024^3, in one run, so that the ratio is like for like.
//
// The baseline is the classic one rasterization pass per slice (GI08's reference [5], Crane et
// al., GPU Gems 3 ch. 30, after Fang & Chen 2000): for slice s, render the whole mesh with a clip
// plane at the slice's centre into a one-bit stencil that every fragment in front of the plane
// flips; the stencil then holds the parity of the surfaces between the eye and the slice, which
// is the slice's inside bits. Written for this benchmark, not the library: it calls the library's
// own rasterizer once per slice (same fragments, same tie rule, same tiling and threads), so the
// difference measured is D passes against one. Its grid is checked against voxelize()'s once,
// outside the timing (the benchmark fails when they differ).
//
//   ./build/bench_slice_by_slice --benchmark_filter='/bunny00/(128|256)/' --benchmark_min_time=0.05
//
// Counters: passes (rasterization passes per grid), tri/s.
#include <cstring>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_meshes.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;
using bench::fittedMesh;

// Flips stencil[column] for every centre fragment in front of the clip plane at frame depth
// `plane` (orthographic: slice units, slice s centred at s + 0.5). Each tile owns its rows.
struct StencilConsumer {
    int64_t width;
    double plane;
    uint8_t* stencil;
    struct Sink {
        int64_t width;
        double plane;
        uint8_t* stencil;
        void fragment(int64_t x, int64_t y, double depth, uint32_t, bool) {
            if (depth < plane) stencil[y * width + x] ^= 1;
        }
        void finish() {}
    };
    Sink tile(const Tile&) const { return {width, plane, stencil}; }
};

// One rasterization pass per slice into the stencil, then the stencil into the slice's bits.
BitGrid sliceBySlice(const MeshView& mesh, const Frame& frame) {
    const int64_t W = frame.width(), H = frame.height(), D = frame.depth();
    BitGrid grid(W, H, D);
    std::vector<uint8_t> stencil(std::size_t(W * H));
    RasterOptions ro;
    ro.path = RasterPath::Binned;
    for (int64_t s = 0; s < D; ++s) {
        std::memset(stencil.data(), 0, stencil.size());
        StencilConsumer c{W, double(s) + 0.5, stencil.data()};
        rasterize<Coverage::Center>(frame, mesh, ro, c);
        const uint64_t bit = uint64_t(1) << (s & 63);
        parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
            for (int64_t y = y0; y < y1; ++y)
                for (int64_t x = 0; x < W; ++x)
                    if (stencil[std::size_t(y * W + x)]) grid.column(x, y)[s >> 6] |= bit;
        });
    }
    return grid;
}

bool sameBits(const BitGrid& a, const BitGrid& b) {
    return a.wordCount() == b.wordCount() &&
           std::memcmp(a.words(), b.words(), std::size_t(a.wordCount()) * sizeof(uint64_t)) == 0;
}

void solidBench(benchmark::State& state, const std::string& name, bool baseline) {
    const auto in = fittedMesh(state, name);
    if (!in) return;
    const MeshView m = in->mesh->view();
    const Frame& frame = in->frame;
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Solid;
    vo.fill = Fill::Parity;
    if (baseline && !sameBits(sliceBySlice(m, frame), voxelize(m, frame, vo).bits)) {
        state.SkipWithError("the slice-by-slice grid differs from voxelize()'s");
        return;
    }
    for (auto _ : state) {
        if (baseline) {
            BitGrid g = sliceBySlice(m, frame);
            benchmark::DoNotOptimize(g.words());
        } else {
            VoxelGrid g = voxelize(m, frame, vo);
            benchmark::DoNotOptimize(g.bits.words());
        }
    }
    state.counters["passes"] = baseline ? double(frame.depth()) : 1.0;
    state.counters["tri/s"] =
        benchmark::Counter(double(m.triangleCount), benchmark::Counter::kIsIterationInvariantRate);
    state.SetLabel(name + " " + std::to_string(m.triangleCount) + " tris, " + std::to_string(frame.width()) +
                   "x" + std::to_string(frame.height()) + "x" + std::to_string(frame.depth()));
}

struct Register {
    Register() {
        // cube: GI08 §9's worst case for the single pass (12 triangles); the others are closed
        // meshes of the CGAL data from 5,000 to 75,000 triangles.
        for (const char* name : {"cube", "knot1", "elephant", "armadillo", "bunny00"})
            for (const bool baseline : {false, true})
                benchmark::RegisterBenchmark(
                    (std::string(baseline ? "SliceBySlice/" : "SinglePass/") + name).c_str(),
                    [=](benchmark::State& s) { solidBench(s, name, baseline); })
                    ->RangeMultiplier(2)
                    ->Range(128, 1024)
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime();
    }
} registerAll;

} // namespace

BENCHMARK_MAIN();
