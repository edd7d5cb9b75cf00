// A long-running process (the batch command, the Python module) that reads bad files one after
// another must not grow: every failed read releases what it allocated. Measured as the live heap
// (glibc's mallinfo2, or AddressSanitizer's own count under the sanitizers, whose quarantine
// makes the resident size meaningless) after warm-up rounds and after many more.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <malloc.h>

#if defined(__SANITIZE_ADDRESS__)
#define VOXFX_HOSTILE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VOXFX_HOSTILE_ASAN 1
#endif
#endif
#ifdef VOXFX_HOSTILE_ASAN
// From the sanitizer runtime (GCC ships no sanitizer/allocator_interface.h to declare it).
extern "C" std::size_t __sanitizer_get_current_allocated_bytes();
#endif

#include "test_util.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/error.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx {
namespace {

using test::TempDir;

uint64_t memoryLiveHeapBytes() {
#ifdef VOXFX_HOSTILE_ASAN
    return __sanitizer_get_current_allocated_bytes();
#else
    return mallinfo2().uordblks;
#endif
}

TEST(HostileMemoryTest, ReadingBadFilesOverAndOverKeepsTheHeapFlat) {
    TempDir dir;
    // One bad file per reader: truncated, lying about sizes, or corrupt in the middle.
    std::vector<std::function<void()>> reads;
    auto bad = [&](const std::string& name, const std::string& bytes, auto read) {
        const std::string path = test::writeFile(dir.file(name), bytes);
        reads.push_back([path, read] { read(path); });
    };
    const auto mesh = [](const std::string& p) { loadMesh(p); };
    const auto grid = [](const std::string& p) { readGrid(p); };
    const auto volume = [](const std::string& p) { loadVolume(p); };
    bad("a.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 9\n", mesh);
    bad("b.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n3 0 1\n",
        mesh);
    bad("c.stl", "solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\n",
        mesh);
    bad("d.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n", mesh);
    bad("e.binvox", std::string("#binvox 1\ndim 8 8 8\ndata\n") + "\x01\xff\x00\x02", grid);
    bad("f.nrrd",
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n" + std::string(60, '\1'), grid);
    bad("g.nrrd",
        "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: gzip\n\nnot gzip",
        volume);
    bad("h.json", R"({"file": "missing.raw", "dims": [2, 2, 2], "type": "uint8"})", volume);
    bad("i.json", R"({"meshes": [{"file": "a.off"}], "lights": [{"type": "spot"}]})",
        [](const std::string& p) { loadScene(p); });
    reads.push_back([] { parseCsgExpression("union(a.off, intersection(b.off, \"c"); });
    // .vdb: a real file with mutations and truncations that stop OpenVDB at various depths.
    const std::string vdbPath = dir.file("ok.vdb");
    writeGrid(test::randomVoxelGrid(Box3d{{0, 0, 0}, {1, 1, 1}}, Axis::Z, {20, 20, 20}, 0.3, 3), vdbPath,
              GridWriteOptions{true, "voxels"});
    const std::string vdb = test::readFileBytes(vdbPath);
    for (const std::size_t cut : {vdb.size() / 3, vdb.size() / 2, vdb.size() - 5})
        bad("cut" + std::to_string(cut) + ".vdb", vdb.substr(0, cut), grid);
    for (const std::size_t at : {vdb.size() / 4, vdb.size() / 2, 3 * vdb.size() / 4}) {
        std::string m = vdb;
        m[at] = char(~m[at]);
        bad("flip" + std::to_string(at) + ".vdb", m, [](const std::string& p) {
            try {
                readGrid(p);
            } catch (const Error&) {}
        });
    }

    int errors = 0;
    auto round = [&] {
        for (const auto& read : reads) {
            try {
                read();
            } catch (const Error&) { ++errors; }
        }
    };
    for (int i = 0; i < 3; ++i) round(); // warm-up: OpenVDB's registries, the module, TBB's pools
    const uint64_t before = memoryLiveHeapBytes();
    constexpr int kRounds = 40;
    for (int i = 0; i < kRounds; ++i) round();
    const uint64_t after = memoryLiveHeapBytes();
    EXPECT_GT(errors, 0);
    // A leak of even 100 bytes per bad file would grow the heap by 100 * files * rounds.
    const int64_t growth = int64_t(after) - int64_t(before);
    const int64_t leakFloor = 100 * int64_t(reads.size()) * kRounds;
    EXPECT_LT(growth, leakFloor) << "live heap " << before << " -> " << after << " bytes over " << kRounds
                                 << " rounds of " << reads.size() << " bad files";
}

} // namespace
} // namespace voxfx
