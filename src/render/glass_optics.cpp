// voxfx — glass optics in closed form (Snell, Fresnel, Beer–Lambert), the Embree-backed triangle
// tracer and the image error used to compare the glass methods with the exact reference.
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/module_loader.hpp"
#include "render/embree_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"

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

const char* toString(GlassKind k) { return enumName(k, kGlassKindNames); }

GlassKind parseGlassKind(const std::string& name) {
    return parseEnum<GlassKind>(name, "glass method", kGlassKindNames);
}

GlassKind defaultGlassKind(const Scene& scene) {
    for (const SceneMesh& m : scene.meshes)
        if (m.material < scene.materials.size() && scene.materials[m.material].isGlass())
            return GlassKind::Exact;
    return GlassKind::None;
}

bool refractDirection(const Vec3d& d, const Vec3d& n, double eta, Vec3d& out) {
    const double cosI = -dot(d, n);
    const double sin2T = eta * eta * std::max(0.0, 1 - cosI * cosI);
    if (sin2T > 1) return false;
    const double cosT = std::sqrt(1 - sin2T);
    out = normalize(d * eta + n * (eta * cosI - cosT));
    return true;
}

double fresnelDielectric(double cosI, double etaI, double etaT) {
    cosI = std::clamp(cosI, 0.0, 1.0);
    const double sinT = etaI / etaT * std::sqrt(std::max(0.0, 1 - cosI * cosI));
    if (sinT >= 1) return 1;
    const double cosT = std::sqrt(std::max(0.0, 1 - sinT * sinT));
    const double rs = (etaI * cosI - etaT * cosT) / (etaI * cosI + etaT * cosT);
    const double rp = (etaT * cosI - etaI * cosT) / (etaT * cosI + etaI * cosT);
    return 0.5 * (rs * rs + rp * rp);
}

Vec3f attenuationCoefficient(const Material& m) {
    if (!std::isfinite(m.attenuationDistance) || !(m.attenuationDistance > 0)) return {};
    Vec3f s;
    for (int c = 0; c < 3; ++c)
        s[c] = -std::log(std::clamp(m.attenuationColor[c], 1e-6f, 1.0f)) / m.attenuationDistance;
    return s;
}

Vec3f beerLambert(const Vec3f& sigma, double length) {
    return {float(std::exp(-double(sigma.x) * length)), float(std::exp(-double(sigma.y) * length)),
            float(std::exp(-double(sigma.z) * length))};
}

struct TriangleTracer::Impl {
    const detail::EmbreeModule* module = nullptr;
    void* scene = nullptr;
};

TriangleTracer::TriangleTracer(const MeshView& mesh) : impl_(std::make_unique<Impl>()) {
    validateMesh(mesh, "mesh");
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

ImageError imageError(const Image& test, const Image& reference, const std::vector<uint8_t>& mask) {
    if (test.width != reference.width || test.height != reference.height ||
        mask.size() != reference.pixels.size())
        fail("image error: the images and the mask differ in size");
    ImageError e;
    double sumAbs = 0, sumSq = 0;
    for (size_t i = 0; i < mask.size(); ++i) {
        if (!mask[i]) continue;
        ++e.pixels;
        for (int c = 0; c < 3; ++c) {
            const double a = std::clamp(double(test.pixels[i][c]), 0.0, 1.0);
            const double b = std::clamp(double(reference.pixels[i][c]), 0.0, 1.0);
            sumAbs += std::abs(a - b);
            sumSq += (a - b) * (a - b);
        }
    }
    if (e.pixels == 0) return e;
    const double n = 3.0 * double(e.pixels);
    e.mae = sumAbs / n;
    e.psnr = sumSq > 0 ? 10 * std::log10(1.0 / (sumSq / n)) : std::numeric_limits<double>::infinity();
    return e;
}

} // namespace voxfx
