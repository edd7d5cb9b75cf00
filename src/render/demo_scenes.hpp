// voxfx — the demo scenes that need mesh files, built from meshes handed in (internal): the
// render layer does no file I/O; io/demo_io.cpp reads the files and calls these.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "voxfx/demo.hpp"
#include "voxfx/mesh.hpp"

namespace voxfx::detail {

/// Where a demo's meshes come from: `mesh(file)` gives the mesh of a file name such as
/// "bunny00.off" (nullopt when there is none; it may throw voxfx::Error for an unreadable one),
/// and `folder` names the place for messages.
struct DemoMeshes {
    std::string folder;
    std::function<std::optional<Mesh>(const std::string& file)> mesh;
};

Scene makeBunnyScene(const DemoMeshes& meshes, int leaves, uint64_t seed);
Scene makeCgalScene(const DemoMeshes& meshes, int leaves, uint64_t seed);
Scene makeGlassScene(const DemoMeshes& meshes);

/// Appends the axis-aligned box [lo, hi] to m: 8 corners, 12 outward-facing triangles.
void appendBox(Mesh& m, const Vec3d& lo, const Vec3d& hi);

} // namespace voxfx::detail
