// voxfx — the translucency pass: GI08 §7 for the camera (see translucency_pass.hpp). The translucent
// meshes are voxelized as a solid in the camera's own frame (viewMatterBehind), the solid cells
// between each visible translucent surface and the opaque surface behind it counted into a length,
// and the light from behind attenuated by Beer-Lambert over it: thin parts show what lies behind,
// thick parts are dark.
#include "render/translucency_pass.hpp"

#include <cmath>
#include <limits>

#include "render/antialias.hpp"
#include "render/shading.hpp"
#include "voxfx/translucency_shadow.hpp"

namespace voxfx::detail {

void compositeTranslucency(FrameState& f) {
    const std::vector<Material>& materials = f.scene.materials;
    std::vector<uint8_t> translucent(materials.size(), 0);
    bool anyMaterial = false;
    for (std::size_t i = 0; i < materials.size(); ++i)
        anyMaterial |= (translucent[i] = materials[i].isTranslucent()) != 0;
    if (!anyMaterial) return;
    const SceneGeometry& g = f.geometry;
    const GBuffer& gb = f.gbuffer;
    const int64_t W = f.width, H = f.height;
    // The samples the passes shade that show a translucent surface: their depth, the rest none.
    const float none = std::numeric_limits<float>::infinity();
    std::vector<float> front(gb.depth.size(), none);
    bool anySample = false;
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const auto i = size_t(y * W + x);
            const uint32_t t = gb.triangle[i];
            if (t == GBuffer::kNone || !translucent[g.triangleMaterial[t]] || !shadedSample(f, x, y))
                continue;
            front[i] = gb.depth[i];
            anySample = true;
        }
    if (!anySample) return;
    // What lies behind: the G-buffer of the scene without the translucent meshes (their triangles
    // collapsed to a point, so the triangle numbers and surfaceAt stay valid).
    SceneGeometry behind = g;
    std::vector<uint32_t> solid;
    for (std::size_t t = 0; t < g.drawnTriangles; ++t) {
        if (!translucent[g.triangleMaterial[t]]) continue;
        for (int k = 0; k < 3; ++k) solid.push_back(g.mesh.indices[3 * t + k]);
        behind.mesh.indices[3 * t + 1] = behind.mesh.indices[3 * t + 2] = behind.mesh.indices[3 * t];
    }
    const GBuffer back = renderGBuffer(behind, gb.frame);
    MeshView solids;
    solids.positions = &g.mesh.positions[0].x;
    solids.vertexCount = g.mesh.positions.size();
    solids.indices = solid.data();
    solids.triangleCount = solid.size() / 3;
    // One column per output pixel: the samples of a pixel share its centre ray's cells (each from
    // its own depths), so supersampling does not multiply the grid.
    const int64_t k = W / f.options.width;
    const ViewMatter matter = ViewMatter::build(cameraFrame(f.camera, f.options.width, f.options.height),
                                                solids, Fill::Auto, f.options.translucencySlices);
    const Vec3d eye = gb.frame.eye();
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto i = size_t(y * W + x);
                if (!std::isfinite(front[i])) continue;
                const Material& m = materials[g.triangleMaterial[gb.triangle[i]]];
                SurfacePoint s;
                const Vec3f light =
                    surfaceAt(back, behind, x, y, s)
                        ? shadePoint(f, s, eye)
                        : f.environment->lookup(
                              gb.frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye) *
                              f.options.exposure;
                const double L = matter.between(x / k, y / k, double(front[i]), double(back.depth[i]));
                f.shaded[i] += light * beerLambert(attenuationCoefficient(m), L) * m.diffuseTransmission;
            }
    });
}

} // namespace voxfx::detail
