// voxfx — exact shadows through partial occluders: every caster triangle between a point and the
// light multiplies the light by its crossing transmittance (Embree finds them in order); glass
// multiplies by the Fresnel-transmitted fraction at each crossing, its tint where the ray enters and
// Beer–Lambert over the length inside (voxfx/exact_shadow.hpp).
#include "voxfx/exact_shadow.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/shadow_casters.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/text.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {

ExactShadow::ExactShadow(const MeshView& casters, std::vector<Vec3f> triangleTransmittance,
                         std::vector<uint32_t> triangleGlass, std::vector<Glass> glass)
    : transmittance_(std::move(triangleTransmittance)), triangleGlass_(std::move(triangleGlass)),
      glass_(std::move(glass)) {
    validateMesh(casters, "shadow casters");
    if (transmittance_.size() != casters.triangleCount)
        fail("exact shadows: ", transmittance_.size(), " transmittances for ", casters.triangleCount,
             " triangles");
    if (!triangleGlass_.empty() && triangleGlass_.size() != casters.triangleCount)
        fail("exact shadows: ", triangleGlass_.size(), " glass indices for ", casters.triangleCount,
             " triangles");
    for (const uint32_t g : triangleGlass_)
        if (g != kNotGlass && g >= glass_.size())
            fail("exact shadows: glass index ", g, " outside the table of ", glass_.size());
    for (const Glass& g : glass_)
        if (!(g.ior >= 1 && std::isfinite(g.ior))) fail("exact shadows: glass ior must be >= 1, got ", g.ior);
    tracer_ = std::make_shared<const TriangleTracer>(casters);
}

ExactShadow ExactShadow::fromMaterials(const MeshView& casters, std::span<const uint32_t> triangleMaterial,
                                       std::span<const Material> materials) {
    if (triangleMaterial.size() != casters.triangleCount)
        fail("exact shadows: ", triangleMaterial.size(), " materials for ", casters.triangleCount,
             " triangles");
    std::vector<uint32_t> glassOf(materials.size(), kNotGlass);
    std::vector<Glass> glass;
    for (size_t m = 0; m < materials.size(); ++m)
        if (materials[m].isGlass()) {
            glassOf[m] = uint32_t(glass.size());
            glass.push_back({std::max(1.0f, materials[m].ior), attenuationCoefficient(materials[m]),
                             materials[m].crossingTransmittance()});
        }
    std::vector<Vec3f> perTriangle(casters.triangleCount);
    std::vector<uint32_t> triangleGlass;
    if (!glass.empty()) triangleGlass.resize(casters.triangleCount);
    for (size_t t = 0; t < casters.triangleCount; ++t) {
        const uint32_t m = triangleMaterial[t];
        if (m >= materials.size()) fail("exact shadows: material ", m, " out of range");
        perTriangle[t] = materials[m].crossingTransmittance();
        if (!glass.empty()) triangleGlass[t] = glassOf[m];
    }
    return ExactShadow(casters, std::move(perTriangle), std::move(triangleGlass), std::move(glass));
}

Vec3f ExactShadow::transmittance(const Vec3d& p, const Vec3d& dir, double distance) const {
    const Mesh& mesh = tracer_->mesh();
    const double epsilon = tracer_->epsilon();
    Vec3f v{1, 1, 1};
    Vec3d o = p;
    double left = distance, travelled = 0;
    // Glass volumes the ray is inside: which one and where it entered (nested objects stack). One
    // stack per thread, reused: this runs once per shadow ray, and a fresh vector would allocate
    // on every ray that enters glass.
    struct Inside {
        uint32_t glass;
        double t;
    };
    thread_local std::vector<Inside> inside;
    inside.clear();
    // Each crossing moves the origin to the hit; epsilon steps over the triangle just crossed.
    for (int crossings = 0; crossings < 100000; ++crossings) {
        const TriangleTracer::Hit h = tracer_->intersect(o, dir, epsilon, left);
        if (!h.hit) break;
        const uint32_t g = triangleGlass_.empty() ? kNotGlass : triangleGlass_[h.triangle];
        const double tHit = travelled + h.t;
        if (g == kNotGlass) {
            v = v * transmittance_[h.triangle];
        } else {
            const Glass& glass = glass_[g];
            const Vec3d a = Vec3d(mesh.positions[mesh.indices[3 * size_t(h.triangle)]]);
            const Vec3d b = Vec3d(mesh.positions[mesh.indices[3 * size_t(h.triangle) + 1]]);
            const Vec3d c = Vec3d(mesh.positions[mesh.indices[3 * size_t(h.triangle) + 2]]);
            const Vec3d n = normalize(cross(b - a, c - a));
            const double cosine = dot(dir, n);
            v = v * float(1 - fresnelDielectric(std::min(1.0, std::abs(cosine)), 1.0, glass.ior));
            if (cosine < 0) { // a front face: the ray enters
                v = v * glass.tint;
                inside.push_back({g, tHit});
            } else { // leaves: Beer–Lambert since it entered (or since p, which was inside)
                double entered = 0;
                for (size_t i = inside.size(); i-- > 0;)
                    if (inside[i].glass == g) {
                        entered = inside[i].t;
                        inside.erase(inside.begin() + std::ptrdiff_t(i));
                        break;
                    }
                v = v * beerLambert(glass.sigma, tHit - entered);
            }
        }
        if (std::max({v.x, v.y, v.z}) <= 0) return v;
        o = o + dir * h.t;
        left -= h.t;
        travelled = tHit;
    }
    // A light inside glass: attenuated up to the light.
    if (std::isfinite(distance))
        for (const Inside& i : inside) v = v * beerLambert(glass_[i.glass].sigma, distance - i.t);
    return v;
}

std::span<const OptionField<ExactShadowOptions>> ExactShadowOptions::fields() { return {}; }

ExactShadow::Stats& ExactShadow::Stats::operator+=(const Stats& o) {
    triangles += o.triangles;
    return *this;
}

std::string ExactShadow::Stats::summary() const {
    return countText(triangles) + " caster triangles traced (Embree)";
}

ExactShadow ExactShadow::build(const Scene& scene, const Light& light, const ExactShadowOptions&, Progress*) {
    const detail::CasterSets casters = detail::collectCasters(scene);
    if (casters.all.indices.empty()) return {};
    ExactShadow out = fromMaterials(casters.all.view(), casters.allMaterialIndex, scene.materials);
    out.light_ = light;
    return out;
}

Vec3f ExactShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    if (!tracer_) return {1, 1, 1};
    // Towards the light from p, offset along n against self-intersection.
    Vec3d l;
    double distance = std::numeric_limits<double>::infinity();
    if (light_.type == LightType::Directional) {
        l = -normalize(light_.direction);
    } else {
        l = light_.position - p;
        distance = length(l);
        l = l / std::max(distance, 1e-300);
    }
    const Vec3d o = p + n * (tracer_->epsilon() * 10);
    return transmittance(o, l, distance);
}

ExactShadow::Stats ExactShadow::stats() const {
    return {tracer_ ? int64_t(tracer_->mesh().triangleCount()) : 0};
}

double ExactShadow::epsilon() const { return tracer_ ? tracer_->epsilon() : 1e-6; }

} // namespace voxfx
