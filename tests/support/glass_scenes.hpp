// voxfx tests — what the glass tests share: the index and ray directions of the closed-form cases,
// the glass ball over a grey ground, and the green glass cube standing on it (how many pixels of its
// top show the environment through the glass).
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>

#include "support/ground_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/environment.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/render.hpp"

namespace voxfx::test {

constexpr double kGlassIor = 1.5;

/// A unit direction into -z, tilted by `angle` towards +x.
inline Vec3d glassDirAt(double angle) { return {std::sin(angle), 0, -std::cos(angle)}; }

/// A glass ball (radius 0.7 at (0, 0.8, 0): transmission 1, ior 1.5, attenuation (0.5, 0.9, 0.6)
/// after 1) on the grey ground (greyGroundScene): material 1, mesh 1; and a camera on it.
inline Scene glassTestScene() {
    Scene s = greyGroundScene();
    Material glass;
    glass.transmission = 1;
    glass.ior = 1.5f;
    glass.attenuationColor = {0.5f, 0.9f, 0.6f};
    glass.attenuationDistance = 1;
    SceneMesh ball;
    ball.mesh = makeUvSphere({0, 0.8, 0}, 0.7, 48, 96);
    ball.material = s.addMaterial(glass);
    s.meshes.push_back(ball);
    Camera cam;
    cam.position = {0, 1.5, 4};
    cam.target = {0, 0.6, 0};
    cam.fovY = 0.6;
    s.cameras.push_back(cam);
    return s;
}

// The top pixels of a green glass cube standing on the ground in a magenta environment, and how
// many of them show the environment (magenta over green) through the glass.
struct TopPixels {
    int64_t top = 0, sky = 0;
};
inline TopPixels glassCubeOnTheGround(const GlassOptions& method) {
    Scene s = glassTestScene(); // the ground, and the ball (mesh 1) made a cube
    s.meshes[1].mesh = makeBox({-0.5, 0, -0.5}, {0.5, 1, 0.5});
    Light sun;
    sun.direction = normalize(Vec3d{0.2, -1, 0.1});
    s.lights.push_back(sun);
    Camera cam = s.cameras[0]; // from higher up: the top fills the view
    cam.position = {0.3, 3, 2};
    cam.target = {0, 0.4, 0};
    RenderOptions o;
    o.width = 96;
    o.height = 72;
    o.shadow = shadowOptionsNamed("none");
    o.glass = method;
    Image magenta(4, 2);
    for (Vec3f& p : magenta.pixels) p = {1, 0, 1};
    o.environment = std::make_shared<const Environment>(magenta);
    o.skyLight = 0; // what the glass sees, not the magenta ambient on its surface
    const RenderResult r = render(s, cam, o);
    const SceneGeometry geo = flattenScene(s);
    const GBuffer g = renderGBuffer(geo, cameraFrame(cam, o.width, o.height));
    TopPixels out;
    for (int64_t y = 0; y < o.height; ++y)
        for (int64_t x = 0; x < o.width; ++x) {
            const uint32_t t = g.triangle[size_t(y * o.width + x)];
            if (t == GBuffer::kNone || geo.triangleMesh[t] != 1) continue;
            bool onTop = true;
            for (int k = 0; k < 3; ++k)
                onTop = onTop && geo.mesh.positions[geo.mesh.indices[3 * t + k]].y == 1;
            if (!onTop) continue;
            ++out.top;
            const Vec3f& p = r.image.at(x, o.height - 1 - y);
            out.sky += p.y < 0.5f * p.x;
        }
    return out;
}

} // namespace voxfx::test
