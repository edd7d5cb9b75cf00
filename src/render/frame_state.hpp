// voxfx — what the passes of one frame share (internal): the inputs, what each pass leaves for the
// next, and the result (render/renderer.cpp runs the passes in order over it).
#pragma once

#include <cstdint>
#include <vector>

#include "voxfx/ambient_occlusion.hpp"
#include "voxfx/render.hpp"

namespace voxfx::detail {

struct FrameState {
    const Scene& scene; ///< as given: the G-buffer draws its meshes
    const Scene& lit;   ///< the scene lit and shadowed: with the default sun when it has no lights
    const Camera& camera;
    const RenderOptions& options;
    /// The given environment, else the procedural sky or the flat background (RenderOptions::sky):
    /// never null.
    const Environment* environment;
    int64_t width, height; ///< samples (supersampled image, times `adaptive`)
    /// Adaptive anti-aliasing: the G-buffer has adaptive x adaptive samples per supersampled pixel
    /// (a cell); 1 when off.
    int adaptive;
    /// Per cell (row-major, y up, (width / adaptive) x (height / adaptive)): 1 where every sample
    /// is shaded; elsewhere only the cell's representative sample (adaptive / 2, adaptive / 2) is,
    /// and copied to the others. Empty when adaptive is 1.
    std::vector<uint8_t> refined;
    SceneGeometry geometry;
    GBuffer gbuffer;
    std::vector<LightShadow> shadows; ///< one per light of `lit`
    /// The ambient light's occlusion (no field, so visibility 1 everywhere, when off).
    AmbientOcclusion occlusion;
    std::vector<Vec3f> shaded;         ///< linear radiance per sample, row-major, y up
    std::vector<uint8_t> glassSamples; ///< per sample: 1 where it shows glass (empty without glass)
    RenderResult& result;
};

} // namespace voxfx::detail
