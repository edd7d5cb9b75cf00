// voxfx — nearest-hit ray queries on triangles through the voxfx_embree module (Embree 3): the
// module table, loaded on first use, and TriangleTracer (voxfx/triangle_tracer.hpp).
#include "voxfx/triangle_tracer.hpp"

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "core/module_loader.hpp"
#include "render/embree_api.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

namespace detail {
const EmbreeModule& embreeModule() {
    static const EmbreeModule& table = []() -> const EmbreeModule& {
        const auto* t = static_cast<const EmbreeModule*>(
            loadModule("embree", kEmbreeModuleAbi, "for the exact glass and shadow reference (Embree)"));
        if (t->abi != kEmbreeModuleAbi || t->size != sizeof(EmbreeModule))
            fail(
                "module voxfx_embree.so is from another voxfx build (its table does not match this library)");
        return *t;
    }();
    return table;
}
} // namespace detail

struct TriangleTracer::Impl {
    const detail::EmbreeModule* module = nullptr;
    void* scene = nullptr;
};

TriangleTracer::TriangleTracer(const MeshView& mesh) : impl_(std::make_unique<Impl>()) {
    validateMesh(mesh, "mesh");
    mesh_.positions.resize(mesh.vertexCount);
    for (size_t i = 0; i < mesh.vertexCount; ++i) mesh_.positions[i] = Vec3f(mesh.vertex(i));
    mesh_.indices.assign(mesh.indices, mesh.indices + 3 * mesh.triangleCount);
    const Box3d box = computeBounds(mesh);
    epsilon_ = box.empty() ? 1e-6 : std::max(1e-9, 1e-5 * length(box.extent()));
    impl_->module = &detail::embreeModule();
    std::vector<float> positions(mesh.vertexCount * 3);
    for (size_t i = 0; i < mesh.vertexCount; ++i) {
        const Vec3d p = mesh.vertex(uint32_t(i));
        positions[3 * i] = float(p.x);
        positions[3 * i + 1] = float(p.y);
        positions[3 * i + 2] = float(p.z);
    }
    std::vector<uint32_t> indices(mesh.triangleCount * 3);
    for (size_t t = 0; t < mesh.triangleCount; ++t)
        for (int k = 0; k < 3; ++k) indices[3 * t + size_t(k)] = mesh.index(t, k);
    std::string error;
    impl_->scene = impl_->module->createScene(positions.data(), mesh.vertexCount, indices.data(),
                                              mesh.triangleCount, &error);
    if (!impl_->scene) fail("exact tracer: ", error);
}

TriangleTracer::~TriangleTracer() {
    if (impl_ && impl_->scene) impl_->module->releaseScene(impl_->scene);
}

TriangleTracer::Hit TriangleTracer::intersect(const Vec3d& origin, const Vec3d& dir, double tNear,
                                              double tFar) const {
    Hit h;
    const float o[3] = {float(origin.x), float(origin.y), float(origin.z)};
    const float d[3] = {float(dir.x), float(dir.y), float(dir.z)};
    float t = 0, u = 0, v = 0;
    uint32_t tri = 0;
    const float far = tFar > double(std::numeric_limits<float>::max())
                          ? std::numeric_limits<float>::infinity()
                          : float(tFar);
    if (!impl_->module->intersect(impl_->scene, o, d, float(tNear), far, &t, &tri, &u, &v)) return h;
    h.hit = true;
    h.t = t;
    h.triangle = tri;
    h.u = u;
    h.v = v;
    return h;
}

} // namespace voxfx
