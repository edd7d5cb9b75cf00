// The benchmarks' meshes, by name, and the frame fitted to one at a benchmark's resolution
// (bench_voxelize, bench_cuda).
//   CGAL data: data/meshes/<name>.off ("dragon" is ChineseDragon-10kv); $VOXFX_DATA_DIR
//              overrides the data folder, as in the tests.
//   bunny1m:   bunny00 midpoint-subdivided twice (1,206,528 triangles, closed);
//   dragon1m:  the Chinese dragon subdivided three times (1,279,616 triangles, open).
//              Read from data/dense/<name>.off, which bench/dense-meshes.sh makes (and
//              bench/cli_bench.sh needs; $VOXFX_DENSE_DIR overrides the folder), when it is there;
//              else subdivided here in memory the same way (midpoints in float rather than from the
//              file's decimal text), so that a machine with only the CGAL data can run them.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>

#include <benchmark/benchmark.h>

#include "voxfx/voxfx.hpp"

namespace voxfx::bench {

/// The voxelization modes with the benchmarks' names for them.
inline constexpr std::pair<const char*, VoxelizeMode> kModes[] = {
    {"Surface", VoxelizeMode::Surface},
    {"Conservative", VoxelizeMode::Conservative},
    {"Solid", VoxelizeMode::Solid},
    {"SolidConservative", VoxelizeMode::SolidConservative},
    {"Interior", VoxelizeMode::Interior}};

/// Every triangle into four at its edges' midpoints (shared midpoints made once), as
/// bench/subdivide_off.awk does.
inline Mesh subdivideMidpoints(const Mesh& in) {
    Mesh out;
    out.positions = in.positions;
    std::unordered_map<uint64_t, uint32_t> mid;
    auto midpoint = [&](uint32_t p, uint32_t q) {
        const uint64_t key = p < q ? (uint64_t(p) << 32 | q) : (uint64_t(q) << 32 | p);
        const auto [it, added] = mid.emplace(key, uint32_t(out.positions.size()));
        if (added) {
            const Vec3f a = out.positions[p], b = out.positions[q];
            out.positions.push_back(Vec3f((Vec3d(a) + Vec3d(b)) * 0.5));
        }
        return it->second;
    };
    for (std::size_t t = 0; t < in.triangleCount(); ++t) {
        const uint32_t a = in.indices[3 * t], b = in.indices[3 * t + 1], c = in.indices[3 * t + 2];
        const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
        for (uint32_t v : {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca}) out.indices.push_back(v);
    }
    return out;
}

inline std::string dataFolder() {
    const char* env = std::getenv("VOXFX_DATA_DIR");
    return env && *env ? std::string(env) : std::string(VOXFX_DATA_DIR);
}

/// The mesh called `name` (loaded once per process), or null when its data is missing.
inline const Mesh* mesh(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Mesh>> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second.get();
    const bool dense = name == "bunny1m" || name == "dragon1m";
    if (dense) {
        const char* denseDir = std::getenv("VOXFX_DENSE_DIR");
        const std::string file =
            (denseDir ? std::string(denseDir) : dataFolder() + "/dense") + "/" + name + ".off";
        if (std::filesystem::exists(file))
            return cache.emplace(name, std::make_unique<Mesh>(loadMesh(file))).first->second.get();
    }
    const std::string base = name == "bunny1m"                        ? "bunny00"
                             : name == "dragon" || name == "dragon1m" ? "ChineseDragon-10kv"
                                                                      : name;
    const std::string file = dataFolder() + "/meshes/" + base + ".off";
    if (!std::filesystem::exists(file)) return nullptr;
    auto m = std::make_unique<Mesh>(loadMesh(file));
    for (int round = 0, rounds = name == "bunny1m" ? 2 : name == "dragon1m" ? 3 : 0; round < rounds; ++round)
        *m = subdivideMidpoints(*m);
    return cache.emplace(name, std::move(m)).first->second.get();
}

/// The preamble of the benchmarks over one mesh: the mesh `name` and a frame fitted to its bounds
/// at resolution state.range(0); nothing, with the benchmark marked skipped, when its data is
/// missing.
struct FittedMesh {
    const Mesh* mesh;
    Frame frame;
};

inline std::optional<FittedMesh> fittedMesh(benchmark::State& state, const std::string& name) {
    const Mesh* m = mesh(name);
    if (!m) {
        state.SkipWithError("missing data: run scripts/fetch-data.sh");
        return std::nullopt;
    }
    FitOptions fo;
    fo.resolution = state.range(0);
    return FittedMesh{m, fitFrame(computeBounds(m->view()), fo)};
}

} // namespace voxfx::bench
