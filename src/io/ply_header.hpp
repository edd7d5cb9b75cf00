// voxfx — the one writer of PLY headers (internal): every binary PLY the library writes (voxel
// meshes, marching-cubes surfaces, particles) starts with the header written here.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <ostream>
#include <string_view>

namespace voxfx::detail {

/// An element of a PLY header: its name, its count and its properties ("float x",
/// "list uchar int vertex_indices", ...).
struct PlyElement {
    std::string_view name;
    int64_t count;
    std::initializer_list<std::string_view> properties;
};

/// Writes "ply", binary little-endian format 1.0, one comment line (none when empty), the
/// elements in order and "end_header". The body that follows is the caller's (little-endian
/// hosts only: x86-64, aarch64).
inline void writePlyHeader(std::ostream& out, std::string_view comment,
                           std::initializer_list<PlyElement> elements) {
    out << "ply\nformat binary_little_endian 1.0\n";
    if (!comment.empty()) out << "comment " << comment << "\n";
    for (const PlyElement& e : elements) {
        out << "element " << e.name << " " << e.count << "\n";
        for (const std::string_view p : e.properties) out << "property " << p << "\n";
    }
    out << "end_header\n";
}

} // namespace voxfx::detail
