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

// Screen-space occlusion per cell of the G-buffer (adaptive x adaptive samples), from the sample the
// shading pass shades for it: its surface point and whether it occludes (opaque), then GTAO over
// the cells in the camera's frame at the cells' resolution, into f.screenOcclusion.
void screenOcclusion(FrameState& f, double radius) {
    const int a = f.adaptive;
    const int64_t cw = f.width / a, ch = f.height / a;
    RenderCacheData::ScreenOcclusion& c = f.cache.screen;
    c.position.resize(size_t(cw * ch));
    c.normal.resize(size_t(cw * ch));
    c.covered.resize(size_t(cw * ch));
    c.occluder.resize(size_t(cw * ch));
    std::vector<uint8_t> opaque(f.scene.materials.size());
    for (std::size_t m = 0; m < opaque.size(); ++m) opaque[m] = f.scene.materials[m].isOpaque();
    parallelFor(0, ch, 8, [&](int64_t y0, int64_t y1) {
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                const auto i = size_t(cy * cw + cx);
                SurfacePoint s;
                const bool hit = surfaceFromBasis(f.gbuffer, f.geometry, f.triangleBases, cx * a + a / 2,
                                                  cy * a + a / 2, s);
                c.covered[i] = hit;
                c.occluder[i] = hit && s.material < opaque.size() && opaque[s.material];
                if (!hit) continue;
                c.position[i] = Vec3f(s.position);
                c.normal[i] = Vec3f(s.normal);
            }
    });
    f.screenOcclusion.resize(size_t(cw * ch));
    ScreenSpaceOcclusionOptions so;
    so.radius = radius;
    screenSpaceOcclusion(cameraFrame(f.camera, cw, ch), cw, ch, c.position, c.normal, c.covered, so,
                         c.occluder, f.screenOcclusion, c.scratch);
}

} // namespace

// The ambient light's occlusion (RenderOptions::ambientOcclusion): its setup (opaque triangles,
// region, radius) and, for the field method, the field, both kept in the cache; for the screen
// method, GTAO over the G-buffer's cells (one sample each: the one the shading pass shades).
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
        screenOcclusion(f, setup->radius);
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
