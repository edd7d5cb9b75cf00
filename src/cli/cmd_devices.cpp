// voxfx devices — where voxelization can run: the CPU's threads and the CUDA back end's device.
#include <iostream>
#include <thread>

#include "cli_common.hpp"

namespace voxfx::cli {
namespace {

int runDevices() {
    std::cout << "cpu:   " << std::thread::hardware_concurrency() << " hardware threads\n";
    const CudaStatus& s = cudaStatus();
    if (s.available)
        std::cout << "cuda:  " << s.device << " (voxelize --device cuda)\n";
    else
        std::cout << "cuda:  not usable: " << s.reason << "\n";
    return 0;
}

const Command kDevices{"devices", "Show where voxelization can run (CPU threads, CUDA device)",
                       [](CLI::App&) { return std::function<int()>([] { return runDevices(); }); }};

} // namespace
} // namespace voxfx::cli
