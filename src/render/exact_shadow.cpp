// voxfx — exact shadows through partial occluders: every caster triangle between a point and the
// light multiplies the light by its crossing transmittance (Embree finds them in order).
#include <algorithm>

#include "voxfx/glass.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx {

ExactShadow::ExactShadow(const MeshView& casters, std::vector<Vec3f> triangleTransmittance)
    : transmittance_(std::move(triangleTransmittance)) {
    validateMesh(casters, "shadow casters");
    if (transmittance_.size() != casters.triangleCount)
        fail("exact shadows: ", transmittance_.size(), " transmittances for ", casters.triangleCount,
             " triangles");
    mesh_.positions.resize(casters.vertexCount);
    for (size_t i = 0; i < casters.vertexCount; ++i) mesh_.positions[i] = Vec3f(casters.vertex(i));
    mesh_.indices.assign(casters.indices, casters.indices + 3 * casters.triangleCount);
    const Box3d box = computeBounds(casters);
    epsilon_ = box.empty() ? 1e-6 : std::max(1e-9, 1e-5 * length(box.extent()));
    tracer_ = std::make_shared<const TriangleTracer>(mesh_.view());
}

Vec3f ExactShadow::transmittance(const Vec3d& p, const Vec3d& dir, double distance) const {
    Vec3f v{1, 1, 1};
    Vec3d o = p;
    double left = distance;
    // Each crossing moves the origin to the hit; epsilon steps over the triangle just crossed.
    for (int crossings = 0; crossings < 100000; ++crossings) {
        const TriangleTracer::Hit h = tracer_->intersect(o, dir, epsilon_, left);
        if (!h.hit) break;
        v = v * transmittance_[h.triangle];
        if (std::max({v.x, v.y, v.z}) <= 0) break;
        o = o + dir * h.t;
        left -= h.t;
    }
    return v;
}

} // namespace voxfx
