// voxfx — replays files through every fuzz target without libFuzzer (the test build's
// voxfx_fuzz_replay, a fast ctest test, also under the sanitizer pass of scripts/test.sh):
//
//   voxfx_fuzz_replay ROOT...     feeds each file of ROOT/<target>/ to <target>, for every target
//
// A target that finds no file in any root is an error (its seed corpus went missing). A finding
// aborts (sanitizers, require()) or escapes as an exception, which fails the test.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>

#include "fuzz_target.hpp"

int main(int argc, char** argv) {
    namespace fs = std::filesystem;
    voxfx::fuzz::applyMemoryBudget(); // as the libFuzzer programs run
    int missing = 0;
    for (const voxfx::fuzz::Target& target : voxfx::fuzz::targets()) {
        std::vector<fs::path> files;
        for (int a = 1; a < argc; ++a) {
            const fs::path dir = fs::path(argv[a]) / target.name;
            std::error_code ec;
            if (!fs::is_directory(dir, ec)) continue;
            for (const auto& entry : fs::directory_iterator(dir))
                if (entry.is_regular_file()) files.push_back(entry.path());
        }
        std::sort(files.begin(), files.end());
        for (const fs::path& file : files) {
            std::ifstream in(file, std::ios::binary);
            const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                             std::istreambuf_iterator<char>());
            try {
                target.run(bytes);
            } catch (const std::exception& e) {
                std::cerr << target.name << ": " << file.string() << ": escaped exception: " << e.what()
                          << "\n";
                return 1;
            }
        }
        std::cout << target.name << ": " << files.size() << " files\n";
        if (files.empty()) {
            std::cerr << target.name << ": no file in any of the given folders\n";
            ++missing;
        }
    }
    return missing ? 1 : 0;
}
