// voxfx — loading the optional modules (internal): dlopen() on first use, one search path.
//
// A module named N is the file voxfx_N.so exporting `extern "C" const void* voxfx_module_N(uint32_t abi)`.
// It is searched, in order, in: each directory of $VOXFX_MODULE_PATH (colon-separated); the
// directory of the binary that holds this loader (the executable for a static library, libvoxfx.so
// for a shared one); ../lib/voxfx relative to that directory; the install directory fixed when the
// library was configured (<libdir>/voxfx).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace voxfx::detail {

/// The directories searched for modules, in order.
std::vector<std::string> moduleSearchPath();

/// The table module `name` returns for `abi`; loaded once per process and cached. Thread-safe.
/// Throws voxfx::Error when no directory holds the file, when it cannot be loaded, or when it
/// answers no table for this ABI; `purpose` says what the module was needed for.
const void* loadModule(const char* name, uint32_t abi, const char* purpose);

/// Starts loadModule(name, abi) on a background thread and returns at once, so that a later
/// loadModule() of it finds it loaded or waits for the load under way (OpenVDB's module takes
/// ~40 ms to load: a command that knows it will write a .vdb starts it before its other work).
/// Errors are not reported here: the later loadModule() meets them again and reports them with
/// its purpose. The thread is joined at exit.
void prefetchModule(const char* name, uint32_t abi);

} // namespace voxfx::detail
