#include "core/module_loader.hpp"

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

#include <dlfcn.h>

#include "voxfx/error.hpp"

#ifndef VOXFX_INSTALL_MODULE_DIR
#define VOXFX_INSTALL_MODULE_DIR ""
#endif

namespace voxfx::detail {

namespace {

namespace fs = std::filesystem;

// The modules loaded so far (their tables), and the prefetch threads, which are joined at exit
// before the map goes (they are destroyed in the reverse order of these definitions).
std::mutex gLoadedMutex;
std::map<std::string, const void*> gLoaded;

struct PrefetchThreads {
    std::mutex mutex;
    std::vector<std::thread> threads;
    std::set<std::string> started; ///< one thread per module, however often it is prefetched
    ~PrefetchThreads() {
        for (std::thread& t : threads) t.join();
    }
} gPrefetch;

// The directory of the binary holding this function: dladdr names the shared library, or for the
// main program whatever argv[0] was, so the executable is read from /proc/self/exe instead.
std::string loaderDirectory() {
    Dl_info info{};
    std::string file;
    // glibc reports the main program as argv[0] (program_invocation_name): maybe relative, maybe
    // a bare name found through PATH.
    if (dladdr(reinterpret_cast<void*>(&loaderDirectory), &info) && info.dli_fname && info.dli_fname[0] &&
        std::string_view(info.dli_fname) != program_invocation_name)
        file = info.dli_fname;
    std::error_code ec;
    if (file.empty()) file = fs::read_symlink("/proc/self/exe", ec).string();
    if (file.empty()) return {};
    const fs::path canonical = fs::weakly_canonical(fs::absolute(file, ec), ec);
    return (ec ? fs::path(file) : canonical).parent_path().string();
}

} // namespace

std::vector<std::string> moduleSearchPath() {
    std::vector<std::string> dirs;
    if (const char* env = std::getenv("VOXFX_MODULE_PATH")) {
        std::string s = env;
        std::size_t start = 0;
        while (start <= s.size()) {
            const std::size_t colon = s.find(':', start);
            const std::string dir =
                s.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
            if (!dir.empty()) dirs.push_back(dir);
            if (colon == std::string::npos) break;
            start = colon + 1;
        }
    }
    const std::string here = loaderDirectory();
    if (!here.empty()) {
        dirs.push_back(here);
        dirs.push_back((fs::path(here) / ".." / "lib" / "voxfx").lexically_normal().string());
    }
    if (VOXFX_INSTALL_MODULE_DIR[0]) dirs.push_back(VOXFX_INSTALL_MODULE_DIR);
    return dirs;
}

const void* loadModule(const char* name, uint32_t abi, const char* purpose) {
    const std::lock_guard lock(gLoadedMutex);
    const auto it = gLoaded.find(name);
    if (it != gLoaded.end()) return it->second;

    const std::string file = concat("voxfx_", name, ".so"), entry = concat("voxfx_module_", name);
    const std::vector<std::string> dirs = moduleSearchPath();
    std::string searched;
    for (const std::string& dir : dirs) {
        const fs::path candidate = fs::path(dir) / file;
        std::error_code ec;
        if (!fs::is_regular_file(candidate, ec)) {
            searched += (searched.empty() ? "" : ", ") + dir;
            continue;
        }
        void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* why = dlerror();
            fail("cannot load module '", candidate.string(), "' (needed ", purpose,
                 "): ", why ? why : "dlopen failed");
        }
        using Entry = const void* (*)(uint32_t);
        const auto fn = reinterpret_cast<Entry>(dlsym(handle, entry.c_str()));
        if (!fn) fail("module '", candidate.string(), "' has no entry '", entry, "' (needed ", purpose, ")");
        const void* table = fn(abi);
        if (!table)
            fail("module '", candidate.string(), "' does not speak this library's interface version ", abi,
                 " (needed ", purpose, "; it is from another voxfx build)");
        gLoaded.emplace(name, table);
        return table;
    }
    fail("module ", file, " (needed ", purpose,
         ") was not found; searched: ", searched.empty() ? std::string("no directories") : searched,
         " (set VOXFX_MODULE_PATH to the directory that holds it)");
}

void prefetchModule(const char* name, uint32_t abi) {
    // Not gLoadedMutex: a load under way holds it for its whole dlopen(), and this returns at once.
    const std::lock_guard lock(gPrefetch.mutex);
    if (!gPrefetch.started.insert(name).second) return; // prefetched before: loaded or being loaded
    gPrefetch.threads.emplace_back([module = std::string(name), abi] {
        try {
            loadModule(module.c_str(), abi, "ahead of use");
        } catch (...) { // reported by the call that needs the module
        }
    });
}

} // namespace voxfx::detail
