// Grid file writing speed: every format of grid_io.hpp on a 512^3 grid, next to fwrite of the
// same number of bytes to the same folder (the I/O floor), so the ratio can be read off the
// bytes_per_second columns. Grids: "sphere", an analytic ball filling 49% of the cube, and
// "armadillo", the solid voxelization of data/meshes/armadillo.off (scripts/fetch-data.sh) at
// resolution 512 (skipped when the data is missing). Files go to $TMPDIR (default /tmp).
//
//   ./build/bench/bench_grid_io --benchmark_filter=sphere --benchmark_repetitions=3
//
// Counters: bytes_per_second (file bytes), items_per_second (voxels), file_MiB.
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <unistd.h>

#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;
namespace fs = std::filesystem;

constexpr int64_t kN = 512;

// Ball of radius 0.49 * N centred in an N^3 grid over [0, 1]^3 (4/3 pi 0.49^3 = 49% filled),
// built column by column from exact integer tests.
VoxelGrid sphereGrid() {
    VoxelGrid g{Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, kN, kN, kN), BitGrid(kN, kN, kN)};
    const double c = 0.5 * double(kN), r = 0.49 * double(kN);
    for (int64_t y = 0; y < kN; ++y)
        for (int64_t x = 0; x < kN; ++x)
            for (int64_t z = 0; z < kN; ++z) {
                const double dx = double(x) + 0.5 - c, dy = double(y) + 0.5 - c, dz = double(z) + 0.5 - c;
                if (dx * dx + dy * dy + dz * dz <= r * r) g.bits.set(x, y, z);
            }
    return g;
}

const VoxelGrid* grid(const std::string& name) {
    static std::map<std::string, std::unique_ptr<VoxelGrid>> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second.get();
    std::unique_ptr<VoxelGrid> g;
    if (name == "sphere") {
        g = std::make_unique<VoxelGrid>(sphereGrid());
    } else {
        const std::string path = std::string(VOXFX_DATA_DIR) + "/meshes/" + name + ".off";
        if (fs::exists(path)) {
            const Mesh mesh = loadMesh(path);
            FitOptions fit;
            fit.resolution = kN;
            g = std::make_unique<VoxelGrid>(voxelize(mesh.view(), fitFrame(computeBounds(mesh.view()), fit)));
        }
    }
    return cache.emplace(name, std::move(g)).first->second.get();
}

std::string benchDir() {
    static const fs::path dir =
        fs::temp_directory_path() / ("voxfx-bench-grid-io-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir.string();
}

void finish(benchmark::State& state, const VoxelGrid& g, uint64_t bytes) {
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(bytes));
    state.SetItemsProcessed(int64_t(state.iterations()) * g.frame.columnCount() * g.frame.depth());
    state.counters["file_MiB"] = double(bytes) / double(1 << 20);
}

void BM_Write(benchmark::State& state, const std::string& gridName, const std::string& ext, bool vdbFloat) {
    const VoxelGrid* g = grid(gridName);
    if (!g) return state.SkipWithError("missing data/meshes (run scripts/fetch-data.sh)");
    const std::string path = benchDir() + "/" + gridName + (vdbFloat ? "_float" : "") + "." + ext;
    GridWriteOptions o;
    o.vdbFloat = vdbFloat;
    for (auto _ : state) writeGrid(*g, path, o);
    finish(state, *g, fs::file_size(path));
    fs::remove(path);
}

// fwrite of as many bytes as the format's file has, into the same folder.
void BM_FwriteSameBytes(benchmark::State& state, const std::string& gridName, const std::string& ext,
                        bool vdbFloat) {
    const VoxelGrid* g = grid(gridName);
    if (!g) return state.SkipWithError("missing data/meshes (run scripts/fetch-data.sh)");
    const std::string path = benchDir() + "/" + gridName + "_raw." + ext;
    GridWriteOptions o;
    o.vdbFloat = vdbFloat;
    writeGrid(*g, path, o);
    const uint64_t bytes = fs::file_size(path);
    const std::vector<char> data(bytes, 'v');
    for (auto _ : state) {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f || std::fwrite(data.data(), 1, data.size(), f) != data.size() || std::fclose(f) != 0)
            return state.SkipWithError("fwrite failed");
    }
    finish(state, *g, bytes);
    fs::remove(path);
}

// The .vdb writer fills leaf masks from whole words; this is the same grid built with one
// accessor setValueOn per filled voxel, then written the same way.
void BM_VdbPerVoxelSetValueOn(benchmark::State& state, const std::string& gridName) {
    const VoxelGrid* src = grid(gridName);
    if (!src) return state.SkipWithError("missing data/meshes (run scripts/fetch-data.sh)");
    openvdb::initialize();
    const VoxelGrid g = reslice(*src, Axis::Z);
    const std::string path = benchDir() + "/" + gridName + "_pervoxel.vdb";
    for (auto _ : state) {
        auto vdb = openvdb::BoolGrid::create(false);
        auto acc = vdb->getAccessor();
        for (int64_t y = 0; y < g.bits.height(); ++y)
            for (int64_t x = 0; x < g.bits.width(); ++x)
                for (int64_t z = 0; z < g.bits.depth(); ++z)
                    if (g.bits.get(x, y, z)) acc.setValueOn(openvdb::Coord(int(x), int(y), int(z)), true);
        vdb->tree().prune();
        vdb->setName("voxels");
        openvdb::io::File(path).write({vdb});
    }
    finish(state, g, fs::file_size(path));
    fs::remove(path);
}

void registerAll() {
    for (const std::string gridName : {"sphere", "armadillo"}) {
        for (const auto& [ext, asFloat] : std::vector<std::pair<std::string, bool>>{{"binvox", false},
                                                                                    {"nrrd", false},
                                                                                    {"vdb", false},
                                                                                    {"vdb", true},
                                                                                    {"ply", false},
                                                                                    {"obj", false}}) {
            const std::string label = ext + (asFloat ? "_float" : "");
            benchmark::RegisterBenchmark(("Write/" + label + "/" + gridName).c_str(), BM_Write, gridName, ext,
                                         asFloat)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark(("Fwrite/" + label + "/" + gridName).c_str(), BM_FwriteSameBytes,
                                         gridName, ext, asFloat)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        }
        benchmark::RegisterBenchmark(("VdbPerVoxelSetValueOn/" + gridName).c_str(), BM_VdbPerVoxelSetValueOn,
                                     gridName)
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
    std::error_code ec;
    fs::remove_all(benchDir(), ec);
    return 0;
}
