// voxfx — the casters of a scene split by how they shadow (render/shadow_casters.hpp).
#include "render/shadow_casters.hpp"

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

} // namespace voxfx::detail
