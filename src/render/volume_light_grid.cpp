// voxfx — a light's deep-shadow visibility cached on a volume's lattice (render/volume_light_grid.hpp).
#include "render/volume_light_grid.hpp"

#include "voxfx/parallel.hpp"

namespace voxfx::detail {

LightVisibilityGrid LightVisibilityGrid::build(const Volume& volume, const DeepShadow& shadow,
                                               const Light& light, const LightCone& cone, double step) {
    LightVisibilityGrid g;
    g.place_ = volume.view();
    g.place_.values = nullptr;
    const int64_t nx = g.place_.nx + 1, ny = g.place_.ny + 1, nz = g.place_.nz + 1;
    if (g.place_.nx <= 0 || g.place_.ny <= 0 || g.place_.nz <= 0) return {};
    g.nodes_.resize(std::size_t(nx * ny * nz));
    parallelFor(0, nz, 1, [&](int64_t k0, int64_t k1) {
        for (int64_t k = k0; k < k1; ++k)
            for (int64_t j = 0; j < ny; ++j)
                for (int64_t i = 0; i < nx; ++i) {
                    const Vec3d c = volume.worldFromVoxel({double(i), double(j), double(k)});
                    Vec3d toLight;
                    lightIrradiance(light, cone, c, toLight);
                    double texel = 0;
                    const Vec3f v = shadow.visibility(c + toLight * step, toLight, texel);
                    g.nodes_[std::size_t(i + nx * (j + ny * k))] = {{v.x, v.y, v.z, float(texel)}};
                }
    });
    return g;
}

Vec3i LightVisibilityGrid::nodeCounts() const {
    if (nodes_.empty()) return {0, 0, 0};
    return {place_.nx + 1, place_.ny + 1, place_.nz + 1};
}

} // namespace voxfx::detail
