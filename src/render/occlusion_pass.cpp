// voxfx — the renderer's ambient occlusion pass (render/frame_passes.hpp): the policy of which
// occlusion the ambient light gets and what of it the cache keeps.
#include <memory>
#include <vector>

#include "render/frame_passes.hpp"
#include "render/render_cache.hpp"
#include "render/screen_space_ao.hpp"
#include "render/shading.hpp"
#include "voxfx/ambient_occlusion.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/render.hpp"

namespace voxfx::detail {

namespace {

// Screen-space occlusion per cell of the G-buffer (adaptive x adaptive samples), of the sample the
// shading pass shades there, read from the G-buffer itself (no gather of surface points): all but the
// upsample to the cells, which the shading pass does where it has each cell's surface point
// (f.cellOcclusion; it fills f.screenOcclusion).
void screenOcclusion(FrameState& f, const FieldOcclusionSetup& setup) {
    const int a = f.adaptive;
    std::vector<uint8_t>& opaque = f.cache.screen.opaque;
    opaqueMaterials(f.scene, opaque);
    f.screenOcclusion.resize(size_t((f.width / a) * (f.height / a)));
    ScreenSpaceOcclusionOptions so;
    so.radius = setup.radius;
    so.flatMeshes = setup.flatMeshes; // kept in the cache with the setup
    f.cellOcclusion = std::make_shared<const CellOcclusion>(f.gbuffer, f.geometry, f.triangleBases, opaque, a,
                                                            so, f.cache.screen.scratch, f.cache.triangleTags);
}

} // namespace

// The ambient light's occlusion (RenderOptions::ambientOcclusion): its setup (opaque triangles,
// region, radius) and, for the field method, the field, both kept in the cache; for the screen
// method, GTAO over the G-buffer's cells (one sample each: the one the shading pass shades), the
// upsample left to the shading pass.
void occlusionPass(FrameState& f, Progress* progress) {
    const RenderOptions& o = f.options;
    const bool ambientLight = o.skyLight > 0 || o.ambient.x > 0 || o.ambient.y > 0 || o.ambient.z > 0;
    if (o.ambientOcclusion == Occlusion::Off || !ambientLight) return;
    Hasher key;
    key.value(f.meshesKey), key.value(f.materialsKey), key.value(o.creaseAngle);
    key.value(o.occlusionRadius), key.value(o.occlusionResolution);
    std::shared_ptr<const FieldOcclusionSetup> setup = f.cache.occlusionSetup.find(key.get());
    const bool setupCached = setup != nullptr;
    if (!setup) {
        setup = std::make_shared<const FieldOcclusionSetup>(fieldOcclusionSetup(
            f.geometry, f.scene.materials, f.scene.meshes.size(), o.occlusionRadius, o.occlusionResolution));
        f.cache.occlusionSetup.insert(key.get(), setup);
    }
    if (!(setup->radius > 0)) { // nothing occludes
        f.cachedPass = setupCached;
        return;
    }
    if (o.ambientOcclusion == Occlusion::Screen) {
        screenOcclusion(f, *setup);
        return;
    }
    f.occlusion = f.cache.occlusion.find(key.get());
    if (f.occlusion) {
        f.cachedPass = true;
        return;
    }
    const SceneGeometry& g = f.geometry;
    AmbientOcclusionOptions ao;
    ao.radius = setup->radius;
    ao.resolution = setup->resolution;
    ao.threads = o.threads;
    ao.progress = progress;
    MeshView view;
    view.positions = &g.mesh.positions[0].x;
    view.vertexCount = g.mesh.positions.size();
    view.indices = setup->indices.data();
    view.triangleCount = setup->indices.size() / 3;
    f.occlusion = std::make_shared<const AmbientOcclusion>(view, setup->region, ao);
    f.cache.occlusion.insert(key.get(), f.occlusion);
}

} // namespace voxfx::detail
