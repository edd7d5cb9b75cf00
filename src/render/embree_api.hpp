// voxfx — the interface of the voxfx_embree module (internal to render/): Embree 3 ray queries on
// triangles for the exact glass and shadow reference. Embree costs about 8 ms of dynamic loading per
// process (measured: a program linking libembree3 against an empty one, 50 runs), so, like
// OpenVDB, Assimp and OpenEXR (io/module_api.hpp), it is loaded by core/module_loader on first use.
// The module uses no voxfx symbol; functions report errors through *error instead of throwing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace voxfx::detail {

/// Bump when the table changes.
inline constexpr uint32_t kEmbreeModuleAbi = 1;

struct EmbreeModule {
    uint32_t abi;
    uint32_t size; ///< sizeof(EmbreeModule) as the module was built
    /// A committed scene over `triangleCount` triangles (3 indices each) of `vertexCount` vertices
    /// (x, y, z floats), or null with *error set.
    void* (*createScene)(const float* positions, std::size_t vertexCount, const uint32_t* indices,
                         std::size_t triangleCount, std::string* error);
    void (*releaseScene)(void* scene);
    /// Nearest hit with t in (tNear, tFar): true and *t, *triangle, *u, *v set; false when none.
    /// Thread-safe on one scene.
    bool (*intersect)(const void* scene, const float origin[3], const float dir[3], float tNear, float tFar,
                      float* t, uint32_t* triangle, float* u, float* v);
};

/// The loaded module (on first call; voxfx::Error naming where it was searched when missing).
const EmbreeModule& embreeModule();

} // namespace voxfx::detail
