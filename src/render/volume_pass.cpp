// voxfx — volume ray casting over fragment lists, composited over the shaded G-buffer
// (render/volume_pass.hpp).
#include "render/volume_pass.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "render/shading.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx::detail {

int64_t compositeVolumes(const GBuffer& gbuffer, const Scene& scene, const std::vector<LightShadow>& shadows,
                         const RenderOptions& options, std::vector<Vec3f>& shaded, Progress* progress) {
    if (!scene.volumeScene) return 0;
    const VolumeScene& vs = *scene.volumeScene;
    bool anyVolume = false;
    double spacing = std::numeric_limits<double>::infinity();
    for (const VolumeSceneObject& o : vs.objects)
        if (o.kind == ObjectKind::Volume) {
            anyVolume = true;
            const Vec3d s = vs.volumes[std::size_t(o.volume)]->spacing();
            spacing = std::min({spacing, s.x, s.y, s.z});
        }
    if (!anyVolume) return 0;
    const double step = spacing * options.volumeStep;
    const FlatLeaves flat = flattenLeaves(vs, false);
    const Frame& f = gbuffer.frame;
    const FragmentLists lists = FragmentLists::build(f, flat.mesh.view(), progress);
    const int64_t W = f.width(), H = f.height();
    std::atomic<int64_t> samples{0};
    parallelFor(0, H, 4, [&](int64_t y0, int64_t y1) {
        SegmentWalker walker(vs, flat.triangleLeaf);
        int64_t local = 0;
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto col = lists.column(x, y);
                if (col.empty()) continue;
                const std::size_t pixel = std::size_t(y * W + x);
                const double zMax = gbuffer.triangle[pixel] != GBuffer::kNone
                                        ? double(gbuffer.depth[pixel])
                                        : std::numeric_limits<double>::infinity();
                const Vec3d eye = f.eye();
                const Vec3d perDepth = f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye;
                const double lengthPerDepth = length(perDepth);
                Vec3f color{0, 0, 0};
                double transmittance = 1;
                walker.walk(
                    col, [](double, std::size_t, bool) { return true; },
                    [&](double z0, double z1, std::span<const uint8_t> inside) {
                        if (z0 >= zMax) return false;
                        z1 = std::min(z1, zMax);
                        const double worldLength = (z1 - z0) * lengthPerDepth;
                        const int64_t n = std::max<int64_t>(1, int64_t(std::ceil(worldLength / step)));
                        const double dz = (z1 - z0) / double(n), dl = worldLength / double(n);
                        for (int64_t k = 0; k < n; ++k) {
                            const Vec3d p = eye + perDepth * (z0 + (double(k) + 0.5) * dz);
                            for (std::size_t o = 0; o < inside.size(); ++o) {
                                const VolumeSceneObject& obj = vs.objects[o];
                                if (!inside[o] || obj.kind != ObjectKind::Volume) continue;
                                const Rgba c = obj.transfer(vs.volumes[std::size_t(obj.volume)]->sample(p));
                                ++local;
                                if (c.a <= 0) continue;
                                const double a = 1.0 - std::pow(1.0 - std::min(double(c.a), 1.0 - 1e-7),
                                                                dl / obj.opacityLength);
                                Vec3f light = options.ambient;
                                for (std::size_t l = 0; l < scene.lights.size(); ++l) {
                                    Vec3d toLight;
                                    const Vec3f e = lightIrradiance(scene.lights[l], p, toLight);
                                    if (e.x <= 0 && e.y <= 0 && e.z <= 0) continue;
                                    const Vec3f vis = l < shadows.size() ? shadows[l].visibility(p, {0, 0, 0})
                                                                         : Vec3f{1, 1, 1};
                                    light += e * vis * float(1.0 / M_PI);
                                }
                                color += Vec3f{c.r, c.g, c.b} * light * float(a * transmittance);
                                transmittance *= 1.0 - a;
                            }
                            if (transmittance < 1e-3) return false;
                        }
                        return true;
                    });
                if (transmittance < 1.0)
                    shaded[pixel] = color * options.exposure + shaded[pixel] * float(transmittance);
            }
        samples += local;
    });
    return samples.load();
}

} // namespace voxfx::detail
