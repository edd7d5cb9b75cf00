// The voxelize step alone, for profilers (#39): not a Google Benchmark, a fixed number of calls
// of voxelize() as `voxfx voxelize` runs it (solid, --fill auto, the mesh already in memory), so
// that instruction counts and page faults per call can be read off exactly:
//
//   build/bench_step_profile MESH.off RES CALLS THREADS
//   valgrind --tool=callgrind --toggle-collect='voxfx::voxelize(*'
//       build/bench_step_profile data/meshes/bunny00.off 512 1 1   # the step's instructions, 1 thread
//   perf stat -e page-faults build/bench_step_profile data/meshes/bunny00.off 512 21 2
//                                                            # minus the run with CALLS 1: 20 calls
// Prints the wall time of each call.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#include "voxfx/voxfx.hpp"

int main(int argc, char** argv) {
    using namespace voxfx;
    if (argc != 5) {
        std::fprintf(stderr, "usage: %s MESH RES CALLS THREADS\n", argv[0]);
        return 2;
    }
    try {
        const Mesh mesh = loadMesh(argv[1]);
        FitOptions fo;
        fo.resolution = std::atoi(argv[2]);
        const Frame frame = fitFrame(computeBounds(mesh.view()), fo);
        VoxelizeOptions vo; // solid (the library's default) and --fill auto (the command's)
        vo.fill = Fill::Auto;
        vo.threads = std::atoi(argv[4]);
        const int calls = std::atoi(argv[3]);
        VoxelGrid last;
        for (int i = 0; i < calls; ++i) {
            const auto t0 = std::chrono::steady_clock::now();
            VoxelGrid g = voxelize(mesh.view(), frame, vo);
            const double ms =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            last = std::move(g);
            std::printf("call %d: %.2f ms\n", i, ms);
        }
        std::printf("%lld filled voxels\n", static_cast<long long>(last.bits.count()));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
