// voxfx — a light's deep-shadow visibility cached on a volume's lattice (render/volume_light_grid.hpp).
#include "render/volume_light_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/parallel.hpp"

namespace voxfx::detail {

LightVisibilityGrid LightVisibilityGrid::build(const Volume& volume, const DeepShadow& shadow,
                                               const Light& light, const LightCone& cone, double step,
                                               const EmptySpace* skip, double reach,
                                               const OwnTransmittance* own) {
    LightVisibilityGrid g;
    g.place_ = volume.view();
    g.place_.values = nullptr;
    if (g.place_.nx <= 0 || g.place_.ny <= 0 || g.place_.nz <= 0) return {};
    const int64_t vx = g.place_.nx, vy = g.place_.ny, vz = g.place_.nz;
    const int64_t nx = vx + 1, ny = vy + 1, nz = vz + 1;
    // Which nodes the march can read: those of voxels in bricks within r bricks of one that is not
    // empty, r covering the reach and a voxel diagonal (a lit piece lies within `reach` of a point
    // in such a brick; the corners of its voxel within a diagonal of it).
    std::vector<uint8_t> wanted;
    if (skip) {
        const int64_t B = EmptySpace::kBrick;
        const int64_t bx = (vx + B - 1) / B, by = (vy + B - 1) / B, bz = (vz + B - 1) / B;
        const Vec3d h = volume.spacing();
        const int64_t r = int64_t(std::ceil((reach / std::min({h.x, h.y, h.z}) + 2) / double(B)));
        std::vector<uint8_t> matter(std::size_t(bx * by * bz), 0);
        for (int64_t k = 0; k < bz; ++k)
            for (int64_t j = 0; j < by; ++j)
                for (int64_t i = 0; i < bx; ++i)
                    matter[std::size_t(i + bx * (j + by * k))] = !skip->empty(volume.worldFromVoxel(
                        {double(i * B) + 0.5, double(j * B) + 0.5, double(k * B) + 0.5}));
        std::vector<uint8_t> near(matter.size(), 0); // dilated by r bricks, diagonals included
        for (int64_t k = 0; k < bz; ++k)
            for (int64_t j = 0; j < by; ++j)
                for (int64_t i = 0; i < bx; ++i) {
                    if (!matter[std::size_t(i + bx * (j + by * k))]) continue;
                    for (int64_t c = std::max<int64_t>(0, k - r); c <= std::min(bz - 1, k + r); ++c)
                        for (int64_t b = std::max<int64_t>(0, j - r); b <= std::min(by - 1, j + r); ++b)
                            for (int64_t a = std::max<int64_t>(0, i - r); a <= std::min(bx - 1, i + r); ++a)
                                near[std::size_t(a + bx * (b + by * c))] = 1;
                }
        // A node is wanted when a voxel it is a corner of lies in a brick near matter.
        wanted.assign(std::size_t(nx * ny * nz), 0);
        for (int64_t k = 0; k < vz; ++k)
            for (int64_t j = 0; j < vy; ++j)
                for (int64_t i = 0; i < vx; ++i) {
                    if (!near[std::size_t(i / B + bx * (j / B + by * (k / B)))]) continue;
                    for (int c = 0; c < 8; ++c)
                        wanted[std::size_t((i + (c & 1)) +
                                           nx * ((j + ((c >> 1) & 1)) + ny * (k + (c >> 2))))] = 1;
                }
    }
    const float nan = std::numeric_limits<float>::quiet_NaN();
    g.nodes_.assign(std::size_t(nx * ny * nz), Node{{nan, nan, nan, nan}});
    if (own) g.lit_.assign(g.nodes_.size(), Node{{nan, nan, nan, nan}});
    parallelFor(0, nz, 1, [&](int64_t k0, int64_t k1) {
        for (int64_t k = k0; k < k1; ++k)
            for (int64_t j = 0; j < ny; ++j)
                for (int64_t i = 0; i < nx; ++i) {
                    const std::size_t n = std::size_t(i + nx * (j + ny * k));
                    if (!wanted.empty() && !wanted[n]) continue;
                    const Vec3d c = volume.worldFromVoxel({double(i), double(j), double(k)});
                    Vec3d toLight;
                    const Vec3f e = lightIrradiance(light, cone, c, toLight);
                    double texel = 0;
                    const Vec3f v = shadow.visibility(c + toLight * step, toLight, texel);
                    g.nodes_[n] = {{v.x, v.y, v.z, float(texel)}};
                    if (own) {
                        const double t = (*own)(c, toLight, texel);
                        const Vec3f l = e * v * float(t);
                        g.lit_[n] = {{l.x, l.y, l.z, float(t)}};
                    }
                }
    });
    g.filled_ = wanted.empty() ? nx * ny * nz : int64_t(std::count(wanted.begin(), wanted.end(), uint8_t(1)));
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
