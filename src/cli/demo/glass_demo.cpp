// voxfx — the glass demo scene: a glass bunny, a self-occluding glass torus knot, a block of two
// coloured glasses and a ruby bunny inside a clear glass ball (CHANG fig. 3's angel in a ball: glass
// of several materials, nested) over a checkered ground, no lights (the default sun and sky light it).
#include <cmath>
#include <filesystem>

#include "demo/demo_scenes.hpp"
#include "voxfx/error.hpp"

namespace voxfx::demo {

namespace {

// A (p, q) torus knot as a closed tube: `segments` along the curve, `sides` around the tube.
Mesh glassDemoTorusKnot(int p, int q, double R, double r, double tube, int segments, int sides) {
    auto curve = [&](double t) {
        const double rr = R + r * std::cos(q * t);
        return Vec3d{rr * std::cos(p * t), -r * std::sin(q * t), rr * std::sin(p * t)};
    };
    Mesh m;
    for (int i = 0; i < segments; ++i) {
        const double t = 2 * M_PI * i / segments, h = 1e-4;
        const Vec3d c = curve(t);
        const Vec3d T = normalize(curve(t + h) - curve(t - h));
        const Vec3d N = normalize(curve(t + h) - c * 2.0 + curve(t - h));
        const Vec3d B = cross(T, N);
        for (int j = 0; j < sides; ++j) {
            const double a = 2 * M_PI * j / sides;
            m.positions.push_back(Vec3f(c + (N * std::cos(a) + B * std::sin(a)) * tube));
        }
    }
    auto id = [&](int i, int j) {
        return uint32_t(((i + segments) % segments) * sides + (j + sides) % sides);
    };
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j)
            for (const uint32_t v :
                 {id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i + 1, j)})
                m.indices.push_back(v);
    // Outward orientation: flip when the enclosed signed volume is negative.
    double volume = 0;
    for (size_t t = 0; t < m.triangleCount(); ++t) {
        const Vec3d a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]),
            c(m.positions[m.indices[3 * t + 2]]);
        volume += dot(a, cross(b, c));
    }
    if (volume < 0)
        for (size_t t = 0; t < m.triangleCount(); ++t) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
    return m;
}

// A closed UV sphere (outward CCW): `rings` latitude bands, `segments` longitudes, poles shared.
Mesh glassDemoSphere(const Vec3d& centre, double radius, int rings, int segments) {
    Mesh m;
    m.positions.push_back(Vec3f(centre + Vec3d{0, -radius, 0}));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
            m.positions.push_back(
                Vec3f(centre + Vec3d{radius * std::sin(theta) * std::cos(phi), -radius * std::cos(theta),
                                     -radius * std::sin(theta) * std::sin(phi)}));
        }
    m.positions.push_back(Vec3f(centre + Vec3d{0, radius, 0}));
    const auto top = uint32_t(m.positions.size() - 1);
    auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j + segments) % segments); };
    for (int j = 0; j < segments; ++j) {
        for (const uint32_t t : {uint32_t(0), ring(1, j + 1), ring(1, j)}) m.indices.push_back(t);
        for (const uint32_t t : {top, ring(rings - 1, j), ring(rings - 1, j + 1)}) m.indices.push_back(t);
        for (int i = 1; i + 1 < rings; ++i)
            for (const uint32_t t : {ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i, j),
                                     ring(i + 1, j + 1), ring(i + 1, j)})
                m.indices.push_back(t);
    }
    return m;
}

Material glassDemoMaterial(const char* name, Vec3f tint, Vec3f attenuation, float distance) {
    Material g;
    g.name = name;
    g.baseColor = tint;
    g.transmission = 1;
    g.ior = 1.5f;
    g.attenuationColor = attenuation;
    g.attenuationDistance = distance;
    g.specular = 0.5f;
    g.shininess = 200;
    return g;
}

// Stands `mesh` on the ground, `height` tall, centred at (x, z).
void glassDemoPlace(Mesh& mesh, double height, double x, double y0, double z) {
    const Box3d b = computeBounds(mesh.view());
    const double s = height / std::max(b.extent().y, 1e-12);
    const Vec3d c = b.center();
    for (Vec3f& p : mesh.positions)
        p = Vec3f(
            Vec3d{(double(p.x) - c.x) * s + x, (double(p.y) - b.lo.y) * s + y0, (double(p.z) - c.z) * s + z});
}

// The checkered ground (the "texture" the glass distorts): 16 x 16 tiles of two materials over
// [-4, 4]^2, their contrast fading to their mean over the next 8 units (a ring of 2 tiles per step),
// then a ground of that mean out to 500 units, so the ground, not a wall of the sky's ground
// colour, meets the horizon (the sky's ground beyond has the same albedo: groundAlbedo).
constexpr Vec3f kTileLight{0.80f, 0.78f, 0.72f}, kTileDark{0.12f, 0.13f, 0.16f};
constexpr Vec3f kGroundMean{0.46f, 0.455f, 0.44f};

void appendGroundQuad(Mesh& m, double x0, double z0, double x1, double z1) {
    const auto b = uint32_t(m.positions.size());
    for (const Vec3d p : {Vec3d{x0, 0, z0}, Vec3d{x0, 0, z1}, Vec3d{x1, 0, z1}, Vec3d{x1, 0, z0}})
        m.positions.push_back(Vec3f(p));
    m.indices.insert(m.indices.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
}

uint32_t groundMaterial(Scene& scene, const std::string& name, Vec3f colour) {
    Material m;
    m.name = name;
    m.baseColor = colour;
    m.specular = 0.05f;
    return scene.addMaterial(m);
}

// checker: step 0 (the scene's first meshes and materials, as before the fade); else the rest.
void glassDemoGround(Scene& scene, bool checker) {
    const double tile = 0.5;
    const int inner = 8, steps = 8; // tiles from the centre to the checker's edge; fading steps
    auto ground = [&](const std::string& name, uint32_t material) {
        SceneMesh g;
        g.name = name;
        g.material = material;
        g.castsShadow = false;
        return g;
    };
    // Step 0: the full checker (|i|, |j| < inner tiles); step k: the ring of 2 tiles beyond step k - 1.
    for (int step = checker ? 0 : 1; step <= (checker ? 0 : steps); ++step) {
        const float contrast = 1 - float(step) / float(steps + 1);
        auto faded = [&](Vec3f c) { return step == 0 ? c : kGroundMean + (c - kGroundMean) * contrast; };
        const std::string suffix = step == 0 ? "" : "-fade" + std::to_string(step);
        SceneMesh parts[2] = {
            ground("Ground-light" + suffix, groundMaterial(scene, "tile-light" + suffix, faded(kTileLight))),
            ground("Ground-dark" + suffix, groundMaterial(scene, "tile-dark" + suffix, faded(kTileDark)))};
        const int lo = step == 0 ? 0 : inner + 2 * (step - 1), hi = step == 0 ? inner : inner + 2 * step;
        for (int i = -hi; i < hi; ++i)
            for (int j = -hi; j < hi; ++j) {
                const int r = std::max(i < 0 ? -i - 1 : i, j < 0 ? -j - 1 : j); // ring of tile (i, j)
                if (r < lo || r >= hi) continue;
                appendGroundQuad(parts[(i + j + 2 * hi) % 2].mesh, i * tile, j * tile, (i + 1) * tile,
                                 (j + 1) * tile);
            }
        for (SceneMesh& p : parts) scene.meshes.push_back(std::move(p));
    }
    if (checker) return;
    // The plain ground: four quads around the fading square, out to 500 units.
    const double e = (inner + 2 * steps) * tile, far = 500;
    SceneMesh plain = ground("Ground-far", groundMaterial(scene, "ground-far", kGroundMean));
    appendGroundQuad(plain.mesh, -far, -far, far, -e);
    appendGroundQuad(plain.mesh, -far, e, far, far);
    appendGroundQuad(plain.mesh, -far, -e, -e, e);
    appendGroundQuad(plain.mesh, e, -e, far, e);
    scene.meshes.push_back(std::move(plain));
}

} // namespace

Scene makeGlassScene(const std::string& meshesDir) {
    std::optional<Mesh> bunny = loadDemoMesh(meshesDir, "bunny00.off");
    if (!bunny)
        fail("demo 'glass': ", (std::filesystem::path(meshesDir) / "bunny00.off").string(), " not found");
    Scene scene;
    scene.source = "demo:glass";
    glassDemoGround(scene, true);
    const uint32_t clear =
        scene.addMaterial(glassDemoMaterial("clear-glass", {1, 1, 1}, {0.85f, 0.95f, 0.92f}, 1.0f));
    const uint32_t green =
        scene.addMaterial(glassDemoMaterial("green-glass", {1, 1, 1}, {0.35f, 0.85f, 0.45f}, 0.6f));
    const uint32_t amber =
        scene.addMaterial(glassDemoMaterial("amber-glass", {1, 1, 1}, {0.95f, 0.6f, 0.15f}, 0.5f));
    const uint32_t blue =
        scene.addMaterial(glassDemoMaterial("blue-glass", {1, 1, 1}, {0.25f, 0.45f, 0.95f}, 0.5f));

    // CHANG fig. 3: an object inside a glass object. A ruby bunny (index 1.76) in a clear ball: rays
    // refract at the ball, again between the glasses (1.5 to 1.76) and back.
    const uint32_t ruby =
        scene.addMaterial(glassDemoMaterial("ruby-glass", {1, 1, 1}, {0.9f, 0.12f, 0.2f}, 0.25f));
    scene.materials[ruby].ior = 1.76f;
    const Vec3d ballCentre{-0.65, 0.46, 1.15};
    SceneMesh ball;
    ball.name = "Ball";
    ball.mesh = glassDemoSphere(ballCentre, 0.46, 48, 96);
    ball.material = clear;
    scene.meshes.push_back(std::move(ball));
    SceneMesh inside;
    inside.name = "Bunny-in-ball";
    inside.mesh = *bunny;
    glassDemoPlace(inside.mesh, 0.4, ballCentre.x, ballCentre.y - 0.2, ballCentre.z);
    inside.material = ruby;
    scene.meshes.push_back(std::move(inside));

    SceneMesh b;
    b.name = "Bunny";
    b.mesh = std::move(*bunny);
    glassDemoPlace(b.mesh, 1.3, -1.7, 0, 0.2);
    b.material = clear;
    scene.meshes.push_back(std::move(b));

    SceneMesh knot;
    knot.name = "TorusKnot";
    knot.mesh = glassDemoTorusKnot(2, 3, 0.5, 0.22, 0.13, 384, 32);
    glassDemoPlace(knot.mesh, 0.75, 0.1, 0.35, -0.2);
    knot.material = green;
    scene.meshes.push_back(std::move(knot));

    // One block of two glasses: amber below, blue above (two meshes touching).
    for (int k = 0; k < 2; ++k) {
        SceneMesh m;
        m.name = k == 0 ? "Block-amber" : "Block-blue";
        appendBox(m.mesh, {1.3, 0.6 * k, -0.5}, {2.0, 0.6 * k + 0.6, 0.3});
        m.material = k == 0 ? amber : blue;
        scene.meshes.push_back(std::move(m));
    }

    glassDemoGround(scene, false);

    Camera cam;
    cam.name = "View";
    cam.position = {0.2, 2.3, 4.6};
    cam.target = {0.1, 0.55, 0};
    cam.fovY = 42 * M_PI / 180;
    cam.nearDepth = 0.05;
    cam.farDepth = 2000;
    scene.cameras.push_back(cam);
    // A second camera close to the ball (render --camera 1): the nested glass fills the view.
    Camera close = cam;
    close.name = "Ball-view";
    close.position = ballCentre + Vec3d{0.5, 0.75, 1.9};
    close.target = ballCentre;
    close.fovY = 30 * M_PI / 180;
    scene.cameras.push_back(close);
    // A third camera on the block of two glasses (render --camera 2): where they touch, a ray
    // passes from one medium straight into the other.
    Camera block = cam;
    block.name = "Block-view";
    block.position = {2.9, 1.5, 2.3};
    block.target = {1.65, 0.6, -0.1};
    block.fovY = 36 * M_PI / 180;
    scene.cameras.push_back(block);
    // Beyond the ground's 1 km the sky's ground runs on to the horizon in the tiles' mean colour.
    scene.settings.render.emplace_back("groundAlbedo", Vec3d(kGroundMean));
    scene.validate();
    return scene;
}

} // namespace voxfx::demo
