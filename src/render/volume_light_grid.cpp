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

GradientGrid::GradientGrid(const Volume& volume) {
    place_ = volume.view();
    place_.values = nullptr;
    const VolumeView v = volume.view();
    const int64_t nx = v.nx, ny = v.ny, nz = v.nz;
    if (nx < 4 || ny < 4 || nz < 4 || v.values == nullptr) return; // no interior cell to read
    nodes_.assign(std::size_t(nx * ny * nz), Vec3f{0, 0, 0});
    parallelFor(1, nz - 1, 4, [&](int64_t k0, int64_t k1) {
        for (int64_t k = k0; k < k1; ++k)
            for (int64_t j = 1; j + 1 < ny; ++j)
                for (int64_t i = 1; i + 1 < nx; ++i) {
                    // gradient()'s arithmetic at the centre: (f(c + 1) - f(c - 1)) / (2 spacing) per axis.
                    const double d[3] = {
                        (double(v.at(i + 1, j, k)) - double(v.at(i - 1, j, k))) / (2 * v.spacing.x),
                        (double(v.at(i, j + 1, k)) - double(v.at(i, j - 1, k))) / (2 * v.spacing.y),
                        (double(v.at(i, j, k + 1)) - double(v.at(i, j, k - 1))) / (2 * v.spacing.z)};
                    const Vec3d g = v.axes[0] * d[0] + v.axes[1] * d[1] + v.axes[2] * d[2];
                    nodes_[std::size_t(i + nx * (j + ny * k))] = Vec3f(g);
                }
    });
}

Vec3i LightVisibilityGrid::nodeCounts() const {
    if (nodes_.empty()) return {0, 0, 0};
    return {place_.nx + 1, place_.ny + 1, place_.nz + 1};
}

} // namespace voxfx::detail
