// voxfx scene-info SCENE — what the loader understood: meshes, materials, lights, cameras, settings.
#include <iostream>

#include "cli_common.hpp"
#include "voxfx/scene.hpp"

namespace voxfx::cli {
namespace {

std::string vec(const Vec3d& v) { return "(" + fmt(v.x, 4) + ", " + fmt(v.y, 4) + ", " + fmt(v.z, 4) + ")"; }
std::string vec(const Vec3f& v) { return vec(Vec3d(v)); }
std::string degrees(double radians) { return fmt(radians * 180 / M_PI, 4) + " deg"; }

int runSceneInfo(const std::string& path) {
    const Scene scene = loadScene(path);
    std::cout << path << ": " << scene.meshes.size() << " meshes, "
              << withCommas(int64_t(scene.triangleCount())) << " triangles, " << scene.materials.size()
              << " materials, " << scene.lights.size() << " lights, " << scene.cameras.size() << " cameras\n";
    std::cout << "bounds " << boxString(scene.bounds()) << "\n";
    std::cout << "materials:\n";
    for (std::size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        std::cout << "  [" << i << "] '" << m.name << "' base colour " << vec(m.baseColor) << ", opacity "
                  << fmt(m.opacity) << ", transmission " << fmt(m.transmission) << ", ior " << fmt(m.ior);
        if (m.thickness > 0 || std::isfinite(m.attenuationDistance))
            std::cout << ", volume thickness " << fmt(m.thickness) << " attenuation "
                      << vec(m.attenuationColor) << " over " << fmt(m.attenuationDistance);
        std::cout << (m.doubleSided ? ", double-sided" : "") << " -> "
                  << (m.isOpaque()
                          ? std::string("opaque")
                          : "partial occluder, passes " + vec(m.crossingTransmittance()) + " per crossing")
                  << (m.blend ? ", seen through (blend)" : "") << "\n";
    }
    std::cout << "meshes:\n";
    for (const SceneMesh& m : scene.meshes)
        std::cout << "  '" << m.name << "': " << withCommas(int64_t(m.mesh.triangleCount()))
                  << " triangles, material " << m.material << (m.normals.empty() ? "" : ", normals")
                  << (m.castsShadow ? "" : ", receives only") << ", bounds "
                  << boxString(computeBounds(m.mesh.view())) << "\n";
    std::cout << "lights:\n";
    for (const Light& l : scene.lights) {
        std::cout << "  '" << l.name << "' " << toString(l.type);
        if (l.type != LightType::Directional) std::cout << " at " << vec(l.position);
        if (l.type != LightType::Point) std::cout << " direction " << vec(l.direction);
        std::cout << ", colour " << vec(l.color) << ", intensity " << fmt(l.intensity);
        if (l.type == LightType::Spot)
            std::cout << ", cone " << degrees(l.innerConeAngle) << " .. " << degrees(l.outerConeAngle);
        if (l.range > 0) std::cout << ", range " << fmt(l.range);
        std::cout << "\n";
    }
    std::cout << "cameras:\n";
    for (const Camera& c : scene.cameras)
        std::cout << "  '" << c.name << "' at " << vec(c.position) << " looking at " << vec(c.target)
                  << ", up " << vec(c.up) << ", fov y " << degrees(c.fovY) << ", near " << fmt(c.nearDepth)
                  << "\n";
    const SceneSettings& s = scene.settings;
    std::string settings;
    for (const auto& [name, value] : s.render)
        settings += (settings.empty() ? "" : ", ") + name + " " + formatOption(value);
    if (!s.environmentMap.empty())
        settings += (settings.empty() ? "" : ", ") + std::string("environment map ") + s.environmentMap;
    if (!settings.empty()) std::cout << "settings: " << settings << "\n";
    for (const std::string& w : scene.warnings) std::cout << "note: " << w << "\n";
    return 0;
}

const Command kSceneInfo{
    "scene-info", "Print what a scene file holds (meshes, materials, lights, cameras)", [](CLI::App& app) {
        auto path = std::make_shared<std::string>();
        app.add_option("SCENE", *path, "Scene: .gltf .glb .json, or a mesh file")->required();
        return std::function<int()>([path] { return runSceneInfo(*path); });
    }};

} // namespace
} // namespace voxfx::cli
