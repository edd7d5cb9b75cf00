// The benchmark guard of the voxelize step (#39): voxfx against the exact CGAL oracle of the tests
// (tests/cgal_oracle.hpp, oracleSolid: one thread, CGAL's exact predicates), and against the floor
// of writing the grid's words once (a fresh BitGrid, as voxelize() allocates it, and one memset of
// all its bytes), all three measured in the same run, so that a regression shows as a ratio in the
// next figures recorded.
//
//   ./build/bench/bench_oracle --benchmark_filter='Step' --benchmark_repetitions=1
//
// Step/<mesh>/<res>: the voxelize step as `voxfx voxelize` runs it (solid, --fill auto, the mesh
// already in memory). Counters, each a median of the run's own timings:
//   voxfx_ms, oracle_ms, floor_ms   the voxelize step, oracleSolid on the same frame, the memset
//   x_oracle                        oracle_ms / voxfx_ms (the goal of #39: >= 8)
//   x_floor                         voxfx_ms / floor_ms (how far the step is from the floor)
//   lean_ms, x_lean                 the lean exact oracle (oracleSolidBits: the same cells as
//                                   oracleSolid, one thread, bits, the crossing's centre guessed
//                                   and confirmed by two orientation_3) and lean_ms / voxfx_ms
// Whole/<mesh>/<res>: the whole command to .binvox (load the .off, fit, voxelize, write), against
// the oracle's whole command (CGAL's reader, oracleSolid, a plain run-length binvox writer).
// Counters as above (x_oracle: the goal of #39 is >= 3 for armadillo 512).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_meshes.hpp"
#include "cgal_oracle.hpp"
#include "cgal_oracle_bits.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;
using Clock = std::chrono::steady_clock;

double msOf(const std::function<void()>& f) {
    const auto t0 = Clock::now();
    f();
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double medianOf(int runs, const std::function<void()>& f) {
    std::vector<double> ms;
    for (int i = 0; i < runs; ++i) ms.push_back(msOf(f));
    return median(ms);
}

// The oracle's solid grid on voxfx's frame (its cell geometry only).
test::SolidOracle oracleOn(const Mesh& m, const Frame& frame) {
    return test::oracleSolid(m.view(), test::CellGeometry::of(VoxelGrid{frame, {}}));
}

// The floor: a fresh grid of the frame's words, as voxelize() allocates it, written once.
double floorMs(const Frame& f) {
    return medianOf(5, [&] {
        BitGrid g(f.width(), f.height(), f.depth());
        std::memset(static_cast<void*>(g.words()), 0xff, size_t(g.wordCount()) * sizeof(uint64_t));
        benchmark::DoNotOptimize(g.words());
        benchmark::ClobberMemory();
    });
}

void report(benchmark::State& state, const std::vector<double>& voxfx, double oracle, double floor) {
    const double v = median(voxfx);
    state.counters["voxfx_ms"] = v;
    state.counters["oracle_ms"] = oracle;
    state.counters["floor_ms"] = floor;
    state.counters["x_oracle"] = oracle / v;
    state.counters["x_floor"] = v / floor;
}

void stepBench(benchmark::State& state, const std::string& name) {
    const auto in = bench::fittedMesh(state, name);
    if (!in) return;
    const Mesh& m = *in->mesh;
    VoxelizeOptions vo;   // solid (the library's default) and --fill auto (the command's: the
    vo.fill = Fill::Auto; // library's default is parity, without the closed-mesh check)
    std::vector<double> ms;
    for (auto _ : state) {
        const auto t0 = Clock::now();
        VoxelGrid g = voxelize(m.view(), in->frame, vo);
        benchmark::DoNotOptimize(g.bits.words());
        ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    const double oracle = medianOf(3, [&] { benchmark::DoNotOptimize(oracleOn(m, in->frame).crossings); });
    const test::CellGeometry geometry = test::CellGeometry::of(VoxelGrid{in->frame, {}});
    const double lean =
        medianOf(5, [&] { benchmark::DoNotOptimize(test::oracleSolidBits(m.view(), geometry).crossings); });
    report(state, ms, oracle, floorMs(in->frame));
    state.counters["lean_ms"] = lean;
    state.counters["x_lean"] = lean / median(ms);
    state.SetLabel(name + " " + std::to_string(m.triangleCount()) + " tris, " +
                   std::to_string(in->frame.width()) + "x" + std::to_string(in->frame.height()) + "x" +
                   std::to_string(in->frame.depth()));
}

// The oracle's writer: binvox's (value, count) pairs from its world grid, voxel by voxel in
// binvox's order (x slowest, then z, y fastest), header as read_binvox.cc expects.
void writeOracleBinvox(const test::WorldGrid& g, const Frame& frame, const std::string& path) {
    std::ofstream out(path, std::ios::binary);
    const Box3d& box = frame.box();
    const Vec3d ext = box.extent();
    out << "#binvox 1\ndim " << g.dims.x << ' ' << g.dims.z << ' ' << g.dims.y << "\ntranslate " << box.lo.x
        << ' ' << box.lo.y << ' ' << box.lo.z << "\nscale " << std::max({ext.x, ext.y, ext.z}) << "\ndata\n";
    std::vector<char> bytes;
    int value = -1, count = 0;
    for (int64_t i = 0; i < g.dims.x; ++i)
        for (int64_t k = 0; k < g.dims.z; ++k)
            for (int64_t j = 0; j < g.dims.y; ++j) {
                const int v = g.at(i, j, k);
                if (v == value && count < 255) {
                    ++count;
                    continue;
                }
                if (count > 0) bytes.insert(bytes.end(), {char(value), char(count)});
                value = v;
                count = 1;
            }
    if (count > 0) bytes.insert(bytes.end(), {char(value), char(count)});
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

void wholeBench(benchmark::State& state, const std::string& name) {
    const std::string file = bench::dataFolder() + "/meshes/" + name + ".off";
    if (!std::filesystem::exists(file)) {
        state.SkipWithError("missing data: run scripts/fetch-data.sh");
        return;
    }
    const std::string out =
        (std::filesystem::temp_directory_path() / ("bench_oracle_" + name + ".binvox")).string();
    FitOptions fo;
    fo.resolution = state.range(0);
    VoxelizeOptions vo; // as the command runs it: --fill auto
    vo.fill = Fill::Auto;
    std::vector<double> ms;
    for (auto _ : state) {
        const auto t0 = Clock::now();
        const Mesh m = loadMesh(file);
        const Frame frame = fitFrame(computeBounds(m.view()), fo);
        writeGrid(voxelize(m.view(), frame, vo), out);
        ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    const double oracle = medianOf(3, [&] {
        const Mesh m = test::meshOfSoup(test::readWithCgal(file));
        const Frame frame = fitFrame(computeBounds(m.view()), fo);
        writeOracleBinvox(oracleOn(m, frame).inside, frame, out + ".oracle");
    });
    std::filesystem::remove(out);
    std::filesystem::remove(out + ".oracle");
    const Mesh m = loadMesh(file);
    report(state, ms, oracle, floorMs(fitFrame(computeBounds(m.view()), fo)));
    state.SetLabel(name + " -> .binvox, " + std::to_string(m.triangleCount()) + " tris");
}

struct Register {
    Register() {
        for (const char* name : {"bunny00", "armadillo"}) {
            benchmark::RegisterBenchmark((std::string("Step/") + name).c_str(),
                                         [=](benchmark::State& s) { stepBench(s, name); })
                ->Arg(512)
                ->Arg(1024)
                ->Iterations(7)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark((std::string("Whole/") + name).c_str(),
                                         [=](benchmark::State& s) { wholeBench(s, name); })
                ->Arg(512)
                ->Iterations(5)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        }
    }
} registerAll;

} // namespace

BENCHMARK_MAIN();
