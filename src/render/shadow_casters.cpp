// voxfx — the casters of a scene split by how they shadow (render/shadow_casters.hpp).
#include "render/shadow_casters.hpp"

#include <algorithm>
#include <cmath>

namespace voxfx::detail {

namespace {

void append(Mesh& to, const Mesh& from) {
    const auto base = uint32_t(to.positions.size());
    to.positions.insert(to.positions.end(), from.positions.begin(), from.positions.end());
    for (const uint32_t i : from.indices) to.indices.push_back(base + i);
}

} // namespace

CasterSets collectCasters(const Scene& scene) {
    CasterSets s;
    for (const SceneMesh& m : scene.meshes) {
        if (!m.castsShadow) continue;
        const Material& mat = scene.materials[m.material];
        append(s.all, m.mesh);
        s.allMaterialIndex.insert(s.allMaterialIndex.end(), m.mesh.triangleCount(), m.material);
        if (mat.isOpaque()) {
            append(s.opaque, m.mesh);
        } else {
            const Vec3f t = mat.shadowCrossingTransmittance(), sigma = mat.shadowAttenuationCoefficient();
            append(s.partial[{t.x, t.y, t.z, sigma.x, sigma.y, sigma.z}], m.mesh);
        }
    }
    return s;
}

float glassCrossingFresnelDepth(const Mesh& mesh, std::size_t t, const Light& light, double ior, float cap) {
    const Vec3d a(mesh.positions[mesh.indices[3 * t]]), b(mesh.positions[mesh.indices[3 * t + 1]]),
        c(mesh.positions[mesh.indices[3 * t + 2]]);
    const Vec3d n = cross(b - a, c - a);
    const Vec3d toLight =
        light.type == LightType::Directional ? -light.direction : light.position - (a + b + c) * (1.0 / 3);
    const double nl = length(n) * length(toLight);
    const double cosine = nl > 0 ? std::min(1.0, std::abs(dot(n, toLight)) / nl) : 1.0;
    const double pass = 1 - fresnelDielectric(cosine, 1.0, std::max(1.0, ior));
    return std::min(cap, float(-std::log(std::max(pass, 1e-30))));
}

} // namespace voxfx::detail
