// voxfx tests — the ground scenes several test files build their cases on.
#pragma once

#include "test_util.hpp"
#include "voxfx/scene.hpp"

namespace voxfx::test {

/// A ground quad 8 x 8 at y = 0 (albedo 0.5, no specular, casting no shadow) lit straight from
/// above with irradiance 2, and a camera looking down at it from (0, 5, 5).
inline Scene sunlitGroundScene() {
    Scene s;
    Material ground;
    ground.name = "ground";
    ground.baseColor = {0.5f, 0.5f, 0.5f};
    ground.specular = 0;
    SceneMesh g;
    g.name = "Ground";
    appendQuad(g.mesh, {0, 0, 0}, {0, 0, 4}, {4, 0, 0}); // counter-clockwise from above
    g.material = s.addMaterial(ground);
    g.castsShadow = false;
    s.meshes.push_back(g);
    Light sun;
    sun.name = "sun";
    sun.direction = {0, -1, 0};
    sun.intensity = 2;
    s.lights.push_back(sun);
    Camera c;
    c.position = {0, 5, 5};
    c.target = {0, 0, 0};
    c.fovY = 0.7;
    s.cameras.push_back(c);
    return s;
}

/// A scene holding a grey ground (6 x 6 at y = 0, albedo 0.6, no specular, casting no shadow) and
/// nothing else: material 0, mesh 0.
inline Scene greyGroundScene() {
    Scene s;
    Material ground;
    ground.baseColor = {0.6f, 0.6f, 0.6f};
    ground.specular = 0;
    SceneMesh floor;
    appendQuad(floor.mesh, {0, 0, 0}, {0, 0, 3}, {3, 0, 0});
    floor.material = s.addMaterial(ground);
    floor.castsShadow = false;
    s.meshes.push_back(floor);
    return s;
}

} // namespace voxfx::test
