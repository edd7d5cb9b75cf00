// voxfx — file names: the one place that lowercases a file's extension to pick its format (the
// library's readers and writers and the command line use it alike).
// Thread-safety: pure functions; use from any thread.
#pragma once

#include <algorithm>
#include <filesystem>
#include <string>

namespace voxfx {

/// The extension of `path` with its dot, ASCII-lowercased: "mesh.PLY" -> ".ply",
/// "a.tar.GZ" -> ".gz", "noext" -> "", ".hidden" -> "".
inline std::string fileExtension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; });
    return ext;
}

} // namespace voxfx
