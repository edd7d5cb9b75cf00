// voxfx — what the passes of one frame share (internal): the inputs, what each pass leaves for the
// next, and the result (render/renderer.cpp runs the passes in order over it).
#pragma once

#include <cstdint>
#include <vector>

#include "voxfx/render.hpp"

namespace voxfx::detail {

struct FrameState {
    const Scene& scene; ///< as given: the G-buffer draws its meshes
    const Scene& lit;   ///< the scene lit and shadowed: with the default sun when it has no lights
    const Camera& camera;
    /// The options, with the environment's average as ambient when the default sun lights the scene.
    const RenderOptions& options;
    /// The given environment, or the procedural sky where glass or the default sun needs one; null
    /// otherwise.
    const Environment* environment;
    int64_t width, height; ///< samples (supersampled image)
    SceneGeometry geometry;
    GBuffer gbuffer;
    std::vector<LightShadow> shadows;  ///< one per light of `lit`
    std::vector<Vec3f> shaded;         ///< linear radiance per sample, row-major, y up
    std::vector<uint8_t> glassSamples; ///< per sample: 1 where it shows glass (empty without glass)
    RenderResult& result;
};

} // namespace voxfx::detail
