// voxfx — the demo scenes that read mesh files (bunny, cgal): the files are read here, the scenes
// are built by render/demo_scenes.cpp from the meshes.
#include <filesystem>

#include "render/demo_scenes.hpp"
#include "voxfx/demo.hpp"
#include "voxfx/mesh_io.hpp"

namespace voxfx {

namespace {

// The meshes of `folder`: a missing file is nullopt, an unreadable one throws (loadMesh).
detail::DemoMeshes meshFolder(const std::string& folder) {
    return {folder, [folder](const std::string& file) -> std::optional<Mesh> {
                const std::string path = (std::filesystem::path(folder) / file).string();
                if (!std::filesystem::exists(path)) return std::nullopt;
                return loadMesh(path);
            }};
}

} // namespace

Scene makeBunnyScene(const std::string& meshesDir, int leaves, uint64_t seed) {
    return detail::makeBunnyScene(meshFolder(meshesDir), leaves, seed);
}

Scene makeCgalScene(const std::string& meshesDir, int leaves, uint64_t seed) {
    return detail::makeCgalScene(meshFolder(meshesDir), leaves, seed);
}

Scene makeGlassScene(const std::string& meshesDir) { return detail::makeGlassScene(meshFolder(meshesDir)); }

Scene makeDemoScene(const std::string& name, const std::string& meshesDir) {
    if (name == "tree") return makeTreeScene();
    if (name == "bunny") return makeBunnyScene(meshesDir);
    if (name == "cgal") return makeCgalScene(meshesDir);
    if (name == "glass") return makeGlassScene(meshesDir);
    fail("unknown demo scene '", name, "' (allowed: tree, bunny, cgal, glass)");
}

} // namespace voxfx
