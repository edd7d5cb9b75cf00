// voxfx — the scratch folder of the fuzz targets that read through a path.
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "fuzz_target.hpp"

namespace voxfx::fuzz {

namespace {
struct ScratchDir {
    std::filesystem::path dir;
    ScratchDir() {
        dir = std::filesystem::temp_directory_path() / ("voxfx-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir);
    }
    ~ScratchDir() {
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
};
} // namespace

std::string scratchPath(const char* fileName) {
    static ScratchDir scratch;
    return (scratch.dir / fileName).string();
}

void writeFile(const std::string& path, std::span<const uint8_t> data) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
    if (!out) {
        std::fprintf(stderr, "voxfx fuzz: cannot write %s\n", path.c_str());
        std::abort();
    }
}

} // namespace voxfx::fuzz
