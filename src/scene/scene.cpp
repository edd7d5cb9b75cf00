// voxfx — the scene model: materials, validation and the default camera. Reading and writing
// scene files lives in io/scene_io.cpp (voxfx/scene_io.hpp).
#include "voxfx/scene.hpp"

#include <algorithm>
#include <cmath>

namespace voxfx {

using detail::concat;

const char* toString(LightType t) { return enumName(t, kLightTypeNames); }

Vec3f Material::crossingTransmittance() const {
    const float a = std::clamp(opacity, 0.0f, 1.0f), t = std::clamp(transmission, 0.0f, 1.0f);
    Vec3f out;
    for (int c = 0; c < 3; ++c)
        out[c] = std::clamp((1 - a) + a * t * std::clamp(baseColor[c], 0.0f, 1.0f), 0.0f, 1.0f);
    return out;
}

Vec3f attenuationCoefficient(const Material& m) {
    if (!std::isfinite(m.attenuationDistance) || !(m.attenuationDistance > 0)) return {};
    Vec3f s;
    for (int c = 0; c < 3; ++c)
        s[c] = -std::log(std::clamp(m.attenuationColor[c], 1e-6f, 1.0f)) / m.attenuationDistance;
    return s;
}

bool Material::isGlass() const { return transmission > 0 && opacity >= 1; }
bool Material::isTranslucent() const {
    return diffuseTransmission > 0 && !isGlass() && opacity >= 1 && !blend;
}

Vec3f beerLambert(const Vec3f& sigma, double length) {
    Vec3f out;
    for (int c = 0; c < 3; ++c) out[c] = float(std::exp(-double(sigma[c]) * length));
    return out;
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

Vec3f Material::shadowCrossingTransmittance() const {
    const Vec3f tint = crossingTransmittance();
    if (!isGlass()) return tint;
    const double n = std::max(1.0f, ior), f0 = ((n - 1) / (n + 1)) * ((n - 1) / (n + 1));
    Vec3f out;
    for (int c = 0; c < 3; ++c) out[c] = float(std::sqrt(double(tint[c])) * (1 - f0));
    return out;
}

Vec3f Material::shadowAttenuationCoefficient() const {
    return isGlass() ? attenuationCoefficient(*this) : Vec3f{0, 0, 0};
}

bool Material::isOpaque() const {
    const Vec3f t = crossingTransmittance();
    return t.x <= 0 && t.y <= 0 && t.z <= 0;
}

uint32_t Scene::addMaterial(const Material& m) {
    materials.push_back(m);
    return uint32_t(materials.size() - 1);
}

Box3d Scene::bounds(bool castersOnly) const {
    Box3d b;
    for (const SceneMesh& m : meshes)
        if (!castersOnly || m.castsShadow) b.extend(computeBounds(m.mesh.view()));
    return b;
}

std::size_t Scene::triangleCount() const {
    std::size_t n = 0;
    for (const SceneMesh& m : meshes) n += m.mesh.triangleCount();
    return n;
}

void Scene::validate() const {
    const std::string in = source.empty() ? std::string("scene") : source;
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        const SceneMesh& m = meshes[i];
        const std::string where = concat(in, ": mesh '", m.name, "'");
        if (m.material >= materials.size())
            fail(where, ": material ", m.material, " does not exist (", materials.size(), " materials)");
        validateMesh(m.mesh.view(), where);
        if (!m.normals.empty() && m.normals.size() != m.mesh.positions.size())
            fail(where, ": ", m.normals.size(), " normals for ", m.mesh.positions.size(), " vertices");
    }
    for (const Material& m : materials) {
        const std::string where = concat(in, ": material '", m.name, "'");
        if (!isFinite(m.baseColor) || !(m.opacity >= 0 && m.opacity <= 1) ||
            !(m.transmission >= 0 && m.transmission <= 1))
            fail(where, ": base colour must be finite and opacity, transmission in [0, 1]");
        if (!(m.diffuseTransmission >= 0 && m.diffuseTransmission <= 1) ||
            !isFinite(m.diffuseTransmissionColor))
            fail(where, ": diffuse transmission must lie in [0, 1] with a finite colour, got ",
                 m.diffuseTransmission);
        if (m.diffuseTransmission > 0 && !(m.attenuationDistance > 0))
            fail(where,
                 ": attenuation distance of a translucent material must be > 0 (infinite: no "
                 "attenuation), got ",
                 m.attenuationDistance);
        if (m.diffuseTransmission > 0 && !(isFinite(m.attenuationColor) && m.attenuationColor.x >= 0 &&
                                           m.attenuationColor.y >= 0 && m.attenuationColor.z >= 0))
            fail(where, ": attenuation colour of a translucent material must be finite and >= 0");
        if (!(m.ior >= 1) || !std::isfinite(m.ior))
            fail(where, ": index of refraction must be >= 1, got ", m.ior);
        if (!(m.shininess >= 0) || !std::isfinite(m.shininess) || !std::isfinite(m.specular))
            fail(where, ": shininess and specular must be finite, shininess >= 0");
    }
    for (const Light& l : lights) {
        const std::string where = concat(in, ": light '", l.name, "' (", toString(l.type), ")");
        if (!(l.intensity >= 0) || !std::isfinite(l.intensity))
            fail(where, ": intensity must be finite and >= 0, got ", l.intensity);
        if (!isFinite(l.color)) fail(where, ": colour is not finite");
        if (l.type != LightType::Point) {
            if (!isFinite(l.direction) || !(length(l.direction) > 1e-12))
                fail(where,
                     " has no direction (zero or non-finite; in glTF the node's -Z axis is the direction)");
        }
        if (l.type != LightType::Directional && !isFinite(l.position))
            fail(where, ": position is not finite");
        if (l.type == LightType::Spot && !(l.outerConeAngle > 0 && l.outerConeAngle <= M_PI / 2 + 1e-9 &&
                                           l.innerConeAngle >= 0 && l.innerConeAngle <= l.outerConeAngle))
            fail(where, ": cone angles need 0 <= inner <= outer <= pi/2 and outer > 0, got inner ",
                 l.innerConeAngle, ", outer ", l.outerConeAngle);
    }
    for (const Camera& c : cameras) {
        const std::string where = concat(in, ": camera '", c.name, "'");
        if (!isFinite(c.position) || !isFinite(c.target) || !isFinite(c.up)) fail(where, ": not finite");
        if (!(length(c.target - c.position) > 0)) fail(where, ": position equals target (no view direction)");
        if (!(length(cross(c.target - c.position, c.up)) > 0))
            fail(where, ": up is parallel to the view direction");
        if (!(c.fovY > 0 && c.fovY < M_PI))
            fail(where, ": vertical field of view must lie in (0, pi), got ", c.fovY);
        if (!(c.nearDepth > 0) || !std::isfinite(c.nearDepth))
            fail(where, ": near must be > 0, got ", c.nearDepth);
    }
}

Camera defaultCamera(const Scene& scene, double aspect) {
    Camera c;
    const Box3d b = scene.bounds();
    if (b.empty()) return c;
    const double radius = 0.5 * length(b.extent());
    c.fovY = 45.0 * M_PI / 180.0;
    const double fit = std::min(c.fovY, 2 * std::atan(std::tan(c.fovY / 2) * std::max(aspect, 1e-3)));
    const double distance = radius / std::sin(fit / 2);
    c.target = b.center();
    c.position = c.target + normalize(Vec3d{0.35, 0.45, 1.0}) * distance;
    c.up = {0, 1, 0};
    c.nearDepth = std::max(1e-4 * distance, distance - 2 * radius) * 0.5;
    c.farDepth = distance + 2 * radius;
    c.name = "default";
    return c;
}

Camera sceneCamera(const Scene& scene, int index, double aspect) {
    if (scene.cameras.empty()) {
        if (index != 0) fail(scene.source, ": the scene has no cameras (camera ", index, ")");
        return defaultCamera(scene, aspect);
    }
    if (index < 0 || std::size_t(index) >= scene.cameras.size())
        fail("camera ", index, ": the scene has ", scene.cameras.size(), " cameras (0 .. ",
             scene.cameras.size() - 1, ")");
    return scene.cameras[std::size_t(index)];
}

} // namespace voxfx
