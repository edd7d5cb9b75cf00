// voxfx — what the passes of one frame share (internal): the inputs, what each pass leaves for the
// next, and the result (render/renderer.cpp runs the passes in order over it).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "render/render_cache.hpp"
#include "voxfx/ambient_occlusion.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx::detail {

class SurfaceShader;
class CellOcclusion; // render/screen_space_ao.hpp

struct FrameState {
    const Scene& scene; ///< as given: its meshes, materials and volumes
    /// The lights that light and shadow it: the scene's, or the default sun when it has none.
    std::span<const Light> lights;
    const Camera& camera;
    const RenderOptions& options;
    /// The given environment, else the procedural sky or the flat background (RenderOptions::sky):
    /// never null.
    const Environment* environment;
    int64_t width, height; ///< samples (supersampled image, times `adaptive`)
    /// Adaptive anti-aliasing: the G-buffer has adaptive x adaptive samples per supersampled pixel
    /// (a cell); 1 when off.
    int adaptive;
    /// What earlier frames built, with their keys; the members below live in it.
    RenderCacheData& cache;
    uint64_t meshesKey, materialsKey; ///< content keys of scene.meshes and scene.materials
    /// Per cell (row-major, y up, (width / adaptive) x (height / adaptive)): 1 where every sample
    /// is shaded; elsewhere only the cell's representative sample (adaptive / 2, adaptive / 2) is,
    /// and copied to the others. Empty when adaptive is 1.
    std::vector<uint8_t>& refined;
    SceneGeometry& geometry;
    std::vector<TriangleBasis>& triangleBases; ///< of `geometry` (render/shading.hpp)
    GBuffer& gbuffer;
    std::vector<std::shared_ptr<LightShadow>> shadows; ///< one per light (kept in the cache)
    /// The ambient light's occlusion field (RenderOptions::ambientOcclusion field); null otherwise.
    std::shared_ptr<const AmbientOcclusion> occlusion;
    /// Screen-space ambient occlusion (RenderOptions::ambientOcclusion screen): the ambient light's
    /// visibility per cell (row-major, y up, as `refined`); empty otherwise.
    std::vector<float>& screenOcclusion;
    /// The shading of surface points (render/shading.hpp), built by the shading pass for it and the
    /// passes after it.
    std::shared_ptr<const SurfaceShader> shader;
    std::vector<Vec3f>& shaded;         ///< linear radiance per sample, row-major, y up
    std::vector<uint8_t>& glassSamples; ///< per sample: 1 where it shows glass (empty without glass)
    RenderResult& result;
    /// Set by a pass that reused what an earlier frame built (PassTime::cached).
    bool cachedPass = false;
    /// RenderOptions::exposure is 0 (automatic): `options` holds exposure 1, the resolve pass scales.
    bool autoExposure = false;
    /// Screen-space occlusion before its upsample to the cells, which the shading pass does where it
    /// has each cell's surface point (filling screenOcclusion); null otherwise.
    std::shared_ptr<const CellOcclusion> cellOcclusion = nullptr;
    /// Per light, the key its shadow is kept under in cache.shadows (what it was built from; the
    /// shadow pass sets it with `shadows`).
    std::vector<uint64_t> shadowKeys = {};
};

} // namespace voxfx::detail
