// Mesh input throughput: loadMesh in MB/s of file per format, and analyzeTopology in triangles/s.
//
// The fetched bunny00.off (2.6 MB, 75k triangles) and pig.stl (binary, 0.8 MB) are read as they
// are; the bunny is also written once into every other format (OBJ, PLY ascii/binary, STL
// ascii/binary, GLB) in a temporary folder, so that all formats are timed on the same geometry.
//   build-*/bench/bench_mesh_io --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <unistd.h>

#include "voxfx/mesh.hpp"
#include "voxfx/mesh_io.hpp"

namespace {

namespace fs = std::filesystem;
using voxfx::Mesh;

template <class T> void append(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    s.append(b, sizeof(T));
}

// Shortest round-trip text of a float.
void appendFloat(std::string& s, float v) {
    char b[32];
    s.append(b, std::to_chars(b, b + sizeof b, v).ptr);
}

std::string toObj(const Mesh& m) {
    std::string s;
    for (const auto& p : m.positions) {
        s += "v ";
        appendFloat(s, p.x);
        s += ' ';
        appendFloat(s, p.y);
        s += ' ';
        appendFloat(s, p.z);
        s += '\n';
    }
    for (std::size_t i = 0; i < m.indices.size(); i += 3)
        s += "f " + std::to_string(m.indices[i] + 1) + ' ' + std::to_string(m.indices[i + 1] + 1) + ' ' +
             std::to_string(m.indices[i + 2] + 1) + '\n';
    return s;
}

std::string toPly(const Mesh& m, bool binary) {
    std::string s = std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") +
                    " 1.0\nelement vertex " + std::to_string(m.positions.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(m.triangleCount()) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& p : m.positions) {
        if (binary) {
            append(s, p.x);
            append(s, p.y);
            append(s, p.z);
            continue;
        }
        appendFloat(s, p.x);
        s += ' ';
        appendFloat(s, p.y);
        s += ' ';
        appendFloat(s, p.z);
        s += '\n';
    }
    for (std::size_t i = 0; i < m.indices.size(); i += 3) {
        if (binary) {
            append<uint8_t>(s, 3);
            for (int c = 0; c < 3; ++c) append<int32_t>(s, int32_t(m.indices[i + c]));
            continue;
        }
        s += "3 " + std::to_string(m.indices[i]) + ' ' + std::to_string(m.indices[i + 1]) + ' ' +
             std::to_string(m.indices[i + 2]) + '\n';
    }
    return s;
}

std::string toStl(const Mesh& m, bool binary) {
    std::string s;
    if (binary) {
        s.resize(80, ' ');
        append<uint32_t>(s, uint32_t(m.triangleCount()));
    } else {
        s = "solid bunny\n";
    }
    for (std::size_t i = 0; i < m.indices.size(); i += 3) {
        if (binary) {
            for (int k = 0; k < 3; ++k) append(s, 0.0f);
            for (int c = 0; c < 3; ++c) {
                const auto& p = m.positions[m.indices[i + c]];
                append(s, p.x);
                append(s, p.y);
                append(s, p.z);
            }
            append<uint16_t>(s, 0);
            continue;
        }
        s += "facet normal 0 0 0\n outer loop\n";
        for (int c = 0; c < 3; ++c) {
            const auto& p = m.positions[m.indices[i + c]];
            s += "  vertex ";
            appendFloat(s, p.x);
            s += ' ';
            appendFloat(s, p.y);
            s += ' ';
            appendFloat(s, p.z);
            s += '\n';
        }
        s += " endloop\nendfacet\n";
    }
    if (!binary) s += "endsolid bunny\n";
    return s;
}

std::string toGlb(const Mesh& m) {
    std::string bin;
    for (const auto& p : m.positions) {
        append(bin, p.x);
        append(bin, p.y);
        append(bin, p.z);
    }
    const std::size_t positionBytes = bin.size();
    for (uint32_t i : m.indices) append(bin, i);
    const voxfx::Box3d box = voxfx::computeBounds(m.view());
    std::string json =
        R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
        R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"buffers":[{"byteLength":)" +
        std::to_string(bin.size()) + R"(}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":)" +
        std::to_string(positionBytes) + R"(},{"buffer":0,"byteOffset":)" + std::to_string(positionBytes) +
        R"(,"byteLength":)" + std::to_string(bin.size() - positionBytes) +
        R"(}],"accessors":[{"bufferView":0,"componentType":5126,"count":)" +
        std::to_string(m.positions.size()) + R"(,"type":"VEC3","min":[)" + std::to_string(box.lo.x) + "," +
        std::to_string(box.lo.y) + "," + std::to_string(box.lo.z) + R"(],"max":[)" +
        std::to_string(box.hi.x) + "," + std::to_string(box.hi.y) + "," + std::to_string(box.hi.z) +
        R"(]},{"bufferView":1,"componentType":5125,"count":)" + std::to_string(m.indices.size()) +
        R"(,"type":"SCALAR"}]})";
    json.resize((json.size() + 3) / 4 * 4, ' ');
    std::string s = "glTF";
    append<uint32_t>(s, 2);
    append<uint32_t>(s, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
    append<uint32_t>(s, uint32_t(json.size()));
    s += "JSON" + json;
    append<uint32_t>(s, uint32_t(bin.size()));
    s += std::string("BIN\0", 4) + bin;
    return s;
}

// The benchmark inputs: fetched files and the bunny converted once per run.
struct Inputs {
    fs::path dir;
    std::vector<std::pair<std::string, std::string>> files; // benchmark name, path

    Inputs() {
        const fs::path data = fs::path(VOXFX_DATA_DIR) / "meshes";
        const fs::path bunny = data / "bunny00.off";
        if (!fs::exists(bunny)) return;
        files.emplace_back("off/bunny00", bunny.string());
        if (fs::exists(data / "pig.stl")) files.emplace_back("stl_binary/pig", (data / "pig.stl").string());
        dir = fs::temp_directory_path() / ("voxfx-bench-mesh-io-" + std::to_string(::getpid()));
        fs::create_directories(dir);
        const Mesh m = voxfx::loadMesh(bunny.string());
        const std::pair<const char*, std::string> converted[] = {{"bunny00.obj", toObj(m)},
                                                                 {"bunny00-ascii.ply", toPly(m, false)},
                                                                 {"bunny00-binary.ply", toPly(m, true)},
                                                                 {"bunny00-ascii.stl", toStl(m, false)},
                                                                 {"bunny00-binary.stl", toStl(m, true)},
                                                                 {"bunny00.glb", toGlb(m)}};
        const char* names[] = {"obj/bunny00",       "ply_ascii/bunny00",  "ply_binary/bunny00",
                               "stl_ascii/bunny00", "stl_binary/bunny00", "glb/bunny00"};
        for (std::size_t i = 0; i < std::size(converted); ++i) {
            const fs::path path = dir / converted[i].first;
            std::ofstream(path, std::ios::binary)
                .write(converted[i].second.data(), std::streamsize(converted[i].second.size()));
            files.emplace_back(names[i], path.string());
        }
    }
    ~Inputs() {
        std::error_code ec;
        if (!dir.empty()) fs::remove_all(dir, ec);
    }
};

void loadFile(benchmark::State& state, const std::string& path) {
    voxfx::MeshLoadReport report;
    for (auto _ : state) {
        Mesh m = voxfx::loadMesh(path, &report);
        benchmark::DoNotOptimize(m.indices.data());
    }
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(report.fileBytes));
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(report.inputTriangles));
    state.counters["MB"] = double(report.fileBytes) / 1e6;
    state.counters["triangles"] = double(report.inputTriangles);
}

// A closed torus of n x m quads (2 n m triangles), with vertices shuffled by a fixed stride so
// that edge keys are not already sorted.
Mesh torus(int n, int m) {
    Mesh mesh;
    const double pi = 3.14159265358979323846;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            const double u = 2 * pi * i / n, v = 2 * pi * j / m;
            mesh.positions.push_back({float((3 + std::cos(v)) * std::cos(u)),
                                      float((3 + std::cos(v)) * std::sin(u)), float(std::sin(v))});
        }
    auto id = [&](int i, int j) { return uint32_t(((i % n) * m + (j % m))); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j)
            mesh.indices.insert(mesh.indices.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j),
                                                     id(i + 1, j + 1), id(i, j + 1)});
    return mesh;
}

void BM_AnalyzeTopology(benchmark::State& state) {
    const Mesh mesh = torus(int(state.range(0)), 500);
    for (auto _ : state) benchmark::DoNotOptimize(voxfx::analyzeTopology(mesh.view()));
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh.triangleCount()));
    state.counters["triangles"] = double(mesh.triangleCount());
}
BENCHMARK(BM_AnalyzeTopology)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_RemoveDegenerateTriangles(benchmark::State& state) {
    const Mesh mesh = torus(1000, 500);
    for (auto _ : state) {
        state.PauseTiming();
        Mesh copy = mesh;
        state.ResumeTiming();
        benchmark::DoNotOptimize(voxfx::removeDegenerateTriangles(copy));
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh.triangleCount()));
}
BENCHMARK(BM_RemoveDegenerateTriangles)->Unit(benchmark::kMillisecond);

} // namespace

int main(int argc, char** argv) {
    const Inputs inputs;
    if (inputs.files.empty())
        std::fprintf(stderr, "no data: run scripts/fetch-data.sh for the load benchmarks\n");
    for (const auto& [name, path] : inputs.files)
        benchmark::RegisterBenchmark(("BM_LoadMesh/" + name).c_str(), loadFile, path)
            ->Unit(benchmark::kMillisecond);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
