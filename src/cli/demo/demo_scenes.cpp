// voxfx — procedural demo scenes for shadows through foliage (the scenes of ED06 §3.1 fig. 7 and
// CHANG fig. 2: a tree with thousands of leaves over an opaque trunk; an object under a canopy).
//
// World is y-up (as glTF). Leaves are double-sided quads (two triangles) whose material lets part of
// the light through (opacity < 1, transmission > 0), in colour groups: one shadow channel each.
#include "demo/demo_scenes.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <random>

#include "voxfx/environment.hpp"
#include "voxfx/error.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx::demo {

std::optional<Mesh> loadDemoMesh(const std::string& folder, const std::string& file) {
    const std::string path = (std::filesystem::path(folder) / file).string();
    if (!std::filesystem::exists(path)) return std::nullopt;
    return loadMesh(path);
}

namespace {

using Rng = std::mt19937_64;

double uniform(Rng& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

Vec3d randomUnit(Rng& rng) {
    for (;;) {
        const Vec3d v{uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
        const double l = length(v);
        if (l > 1e-3 && l <= 1) return v / l;
    }
}

void appendQuad(Mesh& m, const Vec3d& c, const Vec3d& u, const Vec3d& v) {
    const auto base = uint32_t(m.positions.size());
    m.positions.push_back(Vec3f(c - u - v));
    m.positions.push_back(Vec3f(c + u - v));
    m.positions.push_back(Vec3f(c + u + v));
    m.positions.push_back(Vec3f(c - u + v));
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

/// A closed tapered cylinder from a (radius ra) to b (radius rb), outward counter-clockwise.
void appendCylinder(Mesh& m, const Vec3d& a, const Vec3d& b, double ra, double rb, int sides) {
    const Vec3d axis = normalize(b - a);
    const Vec3d hint = std::abs(axis.y) < 0.9 ? Vec3d{0, 1, 0} : Vec3d{1, 0, 0};
    const Vec3d e1 = normalize(cross(axis, hint)), e2 = cross(axis, e1);
    const auto base = uint32_t(m.positions.size());
    for (int i = 0; i < sides; ++i) {
        const double t = 2 * M_PI * i / sides;
        const Vec3d dir = e1 * std::cos(t) + e2 * std::sin(t);
        m.positions.push_back(Vec3f(a + dir * ra));
        m.positions.push_back(Vec3f(b + dir * rb));
    }
    const auto ca = uint32_t(m.positions.size()), cb = ca + 1;
    m.positions.push_back(Vec3f(a));
    m.positions.push_back(Vec3f(b));
    for (int i = 0; i < sides; ++i) {
        const uint32_t j = uint32_t((i + 1) % sides);
        const uint32_t a0 = base + 2 * uint32_t(i), b0 = a0 + 1, a1 = base + 2 * j, b1 = a1 + 1;
        // e1 x e2 = axis: increasing angle runs counter-clockwise seen from b.
        m.indices.insert(m.indices.end(), {a0, a1, b1, a0, b1, b0, ca, a1, a0, cb, b0, b1});
    }
}

SceneMesh groundPlane(double halfSize, uint32_t material) {
    SceneMesh g;
    g.name = "Ground";
    // Counter-clockwise seen from above (+y): the normal points up.
    appendQuad(g.mesh, {0, 0, 0}, {0, 0, halfSize}, {halfSize, 0, 0});
    g.material = material;
    g.castsShadow = false;
    return g;
}

Material leafMaterial(const char* name, Vec3f colour, float opacity, float transmission) {
    Material m;
    m.name = name;
    m.baseColor = colour;
    m.opacity = opacity;
    m.transmission = transmission;
    m.specular = 0.15f;
    m.shininess = 24;
    m.doubleSided = true;
    return m;
}

const Vec3f kLeafColours[4] = {
    {0.10f, 0.32f, 0.05f}, {0.33f, 0.42f, 0.04f}, {0.62f, 0.16f, 0.03f}, {0.55f, 0.40f, 0.05f}};
const char* kLeafNames[4] = {"leaves-green", "leaves-lime", "leaves-red", "leaves-gold"};

/// The leaf meshes of `groups` colour groups (1..4), empty, their materials added to the scene.
std::vector<SceneMesh> leafMeshes(Scene& scene, int groups, float opacity, float transmission) {
    groups = std::clamp(groups, 1, 4);
    std::vector<SceneMesh> meshes(static_cast<std::size_t>(groups));
    for (int g = 0; g < groups; ++g) {
        meshes[size_t(g)].name = kLeafNames[g];
        meshes[size_t(g)].material =
            scene.addMaterial(leafMaterial(kLeafNames[g], kLeafColours[g], opacity, transmission));
    }
    return meshes;
}

/// `count` leaves scattered in the given spheres (centre, radius), split over the colour meshes.
void scatterLeaves(std::vector<SceneMesh>& meshes, const std::vector<std::pair<Vec3d, double>>& clusters,
                   int count, double size, Rng& rng, double flatten = 1.0) {
    const int groups = int(meshes.size());
    for (int i = 0; i < count; ++i) {
        const auto& [centre, radius] = clusters[size_t(i) % clusters.size()];
        Vec3d offset;
        do offset = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
        while (dot(offset, offset) > 1);
        offset.y *= flatten;
        // Leaves face mostly up, tilted at random.
        Vec3d n = normalize(Vec3d{0, 1.2, 0} + randomUnit(rng));
        if (!(length(n) > 0)) n = {0, 1, 0};
        const Vec3d t = normalize(cross(n, randomUnit(rng)));
        const Vec3d b = cross(n, t);
        const double s = size * uniform(rng, 0.7, 1.3);
        // Mostly the first colour: 55 % / 25 % / 12 % / 8 % for four groups (renormalized for fewer).
        static const double weights[4] = {0.55, 0.25, 0.12, 0.08};
        double total = 0;
        for (int k = 0; k < groups; ++k) total += weights[k];
        double pick = uniform(rng, 0, total);
        int g = 0;
        while (g + 1 < groups && pick >= weights[g]) pick -= weights[g++];
        appendQuad(meshes[size_t(g)].mesh, centre + offset * radius, t * (0.5 * s), b * (0.32 * s));
    }
}

/// Moves the meshes that received triangles into the scene.
void addNonEmpty(Scene& scene, std::vector<SceneMesh>& meshes) {
    for (SceneMesh& m : meshes)
        if (!m.mesh.indices.empty()) scene.meshes.push_back(std::move(m));
}

/// Leaves scattered in the given spheres (centre, radius), split over `groups` colour meshes.
void addLeaves(Scene& scene, const std::vector<std::pair<Vec3d, double>>& clusters, int count, int groups,
               double size, float opacity, float transmission, Rng& rng, double flatten = 1.0) {
    std::vector<SceneMesh> meshes = leafMeshes(scene, groups, opacity, transmission);
    scatterLeaves(meshes, clusters, count, size, rng, flatten);
    addNonEmpty(scene, meshes);
}

/// One procedural tree about 4 units tall standing at the origin: the trunk and seven branches
/// appended to `wood`, `leaves` leaf quads of edge `leafSize` at the branch tips and around the
/// crown appended to the colour meshes. The branches are drawn from `rng` before the leaves, so
/// the tree's shape does not depend on its leaf count.
void growTree(Mesh& wood, std::vector<SceneMesh>& leafColours, int leaves, double leafSize, int trunkSides,
              Rng& rng) {
    const Vec3d top{0, 2.3, 0};
    appendCylinder(wood, {0, -0.05, 0}, top, 0.16, 0.09, trunkSides);
    std::vector<std::pair<Vec3d, double>> clusters{{{0, 3.0, 0}, 0.9}};
    const int branches = 7;
    for (int i = 0; i < branches; ++i) {
        const double angle = 2 * M_PI * (i + uniform(rng, -0.2, 0.2)) / branches;
        const double start = uniform(rng, 1.5, 2.2);
        const Vec3d a{0, start, 0};
        const Vec3d dir = normalize(Vec3d{std::cos(angle), uniform(rng, 0.5, 0.9), std::sin(angle)});
        const double len = uniform(rng, 1.0, 1.5);
        const Vec3d b = a + dir * len;
        appendCylinder(wood, a, b, 0.06, 0.025, std::max(6, trunkSides / 2));
        clusters.push_back({b, uniform(rng, 0.55, 0.75)});
    }
    scatterLeaves(leafColours, clusters, leaves, leafSize, rng);
}

/// Scales the vertices of `m` from index `first` on by `scale` about the origin, turns them by
/// `yaw` radians about +y and moves them by `offset`.
void placeVertices(Mesh& m, size_t first, const Vec3d& offset, double scale, double yaw) {
    const double c = std::cos(yaw), s = std::sin(yaw);
    for (size_t i = first; i < m.positions.size(); ++i) {
        const Vec3d p = Vec3d(m.positions[i]) * scale;
        m.positions[i] = Vec3f(offset + Vec3d{c * p.x + s * p.z, p.y, -s * p.x + c * p.z});
    }
}

/// Rotates a mesh by `rotateX` degrees about x, scales it to `height` and stands it on the
/// ground at (x, z).
SceneMesh placedMesh(Mesh mesh, const std::string& name, double height, double x, double z, double rotateX,
                     double rotateY, uint32_t material) {
    SceneMesh m;
    m.name = name;
    m.mesh = std::move(mesh);
    const double ax = rotateX * M_PI / 180, ay = rotateY * M_PI / 180;
    for (Vec3f& p : m.mesh.positions) {
        Vec3d q(p);
        q = {q.x, q.y * std::cos(ax) - q.z * std::sin(ax), q.y * std::sin(ax) + q.z * std::cos(ax)};
        q = {q.x * std::cos(ay) + q.z * std::sin(ay), q.y, -q.x * std::sin(ay) + q.z * std::cos(ay)};
        p = Vec3f(q);
    }
    const Box3d b = computeBounds(m.mesh.view());
    const double s = height / std::max(b.extent().y, 1e-12);
    const Vec3d c = b.center();
    for (Vec3f& p : m.mesh.positions)
        p = Vec3f(
            Vec3d{(double(p.x) - c.x) * s + x, (double(p.y) - b.lo.y) * s, (double(p.z) - c.z) * s + z});
    m.material = material;
    return m;
}

Material solid(const char* name, Vec3f colour, float specular = 0.2f, float shininess = 32) {
    Material m;
    m.name = name;
    m.baseColor = colour;
    m.specular = specular;
    m.shininess = shininess;
    return m;
}

/// A scene with its source name and a receive-only ground plane of the given size and colour.
Scene groundedScene(const char* source, double groundHalfSize, const char* groundName, Vec3f groundColour) {
    Scene scene;
    scene.source = source;
    scene.meshes.push_back(
        groundPlane(groundHalfSize, scene.addMaterial(solid(groundName, groundColour, 0.05f, 8))));
    return scene;
}

/// Square posts of half width `half` and height `height` standing on the ground at every (x, z).
void appendPosts(Mesh& m, std::initializer_list<double> xs, std::initializer_list<double> zs, double half,
                 double height) {
    for (const double x : xs)
        for (const double z : zs) appendBox(m, {x - half, 0, z - half}, {x + half, height, z + half});
}

Light directionalLight(const char* name, const Vec3d& direction, Vec3f colour, float intensity) {
    Light l;
    l.name = name;
    l.type = LightType::Directional;
    l.direction = normalize(direction);
    l.color = colour;
    l.intensity = intensity;
    return l;
}

/// Render settings that put the procedural sky's sun where the scene's sun light comes from (when
/// it has one: `towardsSun`, else the sky's default) and give the sky's ground below the horizon the
/// albedo of the scene's ground, so the ground runs on to the horizon in its own colour.
void matchSky(Scene& scene, Vec3f groundAlbedo, std::optional<Vec3d> towardsSun = std::nullopt) {
    if (towardsSun) {
        const Vec3d t = normalize(*towardsSun);
        scene.settings.render.emplace_back("sunElevation", std::asin(t.y) * 180 / M_PI);
        scene.settings.render.emplace_back("sunAzimuth", std::atan2(t.x, -t.z) * 180 / M_PI);
    }
    scene.settings.render.emplace_back("groundAlbedo", Vec3d(groundAlbedo));
}

/// The demo scenes' camera ("View", near 0.05, far 100); adds it, validates and returns the scene.
Scene withView(Scene scene, const Vec3d& position, const Vec3d& target, double fovYDegrees) {
    Camera cam;
    cam.name = "View";
    cam.position = position;
    cam.target = target;
    cam.fovY = fovYDegrees * M_PI / 180;
    cam.nearDepth = 0.05;
    cam.farDepth = 100;
    scene.cameras.push_back(cam);
    scene.validate();
    return scene;
}

} // namespace

Scene makeTreeScene(const TreeOptions& o) {
    Scene scene;
    scene.source = "demo:tree";
    Rng rng(o.seed);
    const uint32_t bark = scene.addMaterial(solid("bark", {0.20f, 0.12f, 0.06f}, 0.05f, 8));
    if (o.ground)
        scene.meshes.push_back(
            groundPlane(60.0, scene.addMaterial(solid("grass", {0.30f, 0.36f, 0.16f}, 0.05f, 8))));

    // Trunk and branches; leaf clusters sit at the branch tips and around the crown.
    SceneMesh wood;
    wood.name = "Trunk";
    wood.material = bark;
    std::vector<SceneMesh> leaves = leafMeshes(scene, o.colourGroups, o.leafOpacity, o.leafTransmission);
    growTree(wood.mesh, leaves, o.leaves, o.leafSize, o.trunkSides, rng);
    scene.meshes.push_back(std::move(wood));
    addNonEmpty(scene, leaves);

    scene.lights.push_back(directionalLight("Sun", {0.55, -1.0, 0.35}, {1.0f, 0.95f, 0.85f}, 3.2f));
    matchSky(scene, {0.30f, 0.36f, 0.16f}, Vec3d{-0.55, 1.0, -0.35});
    return withView(std::move(scene), {-2.2, 1.9, 6.2}, {0.8, 1.55, 0.2}, 50);
}

Scene makeForestScene(const ForestOptions& o) {
    if (o.trees < 1 || o.leavesPerTree < 0)
        fail("demo 'forest': needs at least one tree and no negative leaf count, got ", o.trees, " trees of ",
             o.leavesPerTree, " leaves");
    Scene scene;
    scene.source = "demo:forest";
    const uint32_t bark = scene.addMaterial(solid("bark", {0.20f, 0.12f, 0.06f}, 0.05f, 8));
    scene.meshes.push_back(
        groundPlane(60.0, scene.addMaterial(solid("grass", {0.30f, 0.36f, 0.16f}, 0.05f, 8))));
    SceneMesh wood;
    wood.name = "Trunks";
    wood.material = bark;
    std::vector<SceneMesh> leaves = leafMeshes(scene, o.colourGroups, o.leafOpacity, o.leafTransmission);
    // A square lattice of ceil(sqrt(trees)) columns centred on the origin, each tree moved by up to
    // a quarter of the spacing, scaled and turned at random. The layout comes from one generator,
    // each tree's shape and leaves from its own, so the trees stand where they stood whatever
    // leavesPerTree is.
    const int columns = int(std::ceil(std::sqrt(double(o.trees))));
    const int rows = (o.trees + columns - 1) / columns;
    Rng layout(o.seed);
    for (int i = 0; i < o.trees; ++i) {
        const int row = i / columns, column = i % columns;
        const Vec3d at{(column - 0.5 * (columns - 1)) * o.spacing + uniform(layout, -0.25, 0.25) * o.spacing,
                       0, (row - 0.5 * (rows - 1)) * o.spacing + uniform(layout, -0.25, 0.25) * o.spacing};
        const double scale = uniform(layout, 0.8, 1.25), yaw = uniform(layout, 0, 2 * M_PI);
        Rng rng(o.seed * 0x9E3779B97F4A7C15ull + uint64_t(i) + 1);
        const size_t woodFirst = wood.mesh.positions.size();
        std::vector<size_t> leafFirst;
        for (const SceneMesh& m : leaves) leafFirst.push_back(m.mesh.positions.size());
        growTree(wood.mesh, leaves, o.leavesPerTree, o.leafSize, o.trunkSides, rng);
        placeVertices(wood.mesh, woodFirst, at, scale, yaw);
        for (size_t g = 0; g < leaves.size(); ++g)
            placeVertices(leaves[g].mesh, leafFirst[g], at, scale, yaw);
    }
    scene.meshes.push_back(std::move(wood));
    addNonEmpty(scene, leaves);

    // The tree scene's sun; the camera looks down the lattice's diagonal from outside a corner.
    scene.lights.push_back(directionalLight("Sun", {0.55, -1.0, 0.35}, {1.0f, 0.95f, 0.85f}, 3.2f));
    matchSky(scene, {0.30f, 0.36f, 0.16f}, Vec3d{-0.55, 1.0, -0.35});
    const double half = 0.5 * o.spacing * std::max(columns, rows);
    return withView(std::move(scene), {-0.55 * half, 0.75 * half + 2, 1.9 * half + 3}, {0, 1.2, -0.1 * half},
                    50);
}

int64_t leafTriangleCount(const Scene& scene) {
    int64_t n = 0;
    for (const SceneMesh& m : scene.meshes)
        if (m.castsShadow && !scene.materials[m.material].isOpaque()) n += int64_t(m.mesh.triangleCount());
    return n;
}

void appendBox(Mesh& m, const Vec3d& lo, const Vec3d& hi) {
    const Mesh box = boxMesh({lo, hi});
    const auto base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), box.positions.begin(), box.positions.end());
    for (const uint32_t i : box.indices) m.indices.push_back(base + i);
}

Scene makeBunnyScene(const std::string& meshesDir, int leaves, uint64_t seed) {
    std::optional<Mesh> bunny = loadDemoMesh(meshesDir, "bunny00.off");
    if (!bunny)
        fail("demo 'bunny': ", (std::filesystem::path(meshesDir) / "bunny00.off").string(), " not found");
    Scene scene = groundedScene("demo:bunny", 30.0, "ground", {0.45f, 0.42f, 0.36f});
    Rng rng(seed);
    const uint32_t fur = scene.addMaterial(solid("bunny", {0.75f, 0.72f, 0.66f}, 0.25f, 40));
    scene.meshes.push_back(placedMesh(std::move(*bunny), "Bunny", 1.2, 0, 0, 0, 0, fur));
    // A canopy: four posts and a flat, dense layer of leaves above the bunny.
    SceneMesh posts;
    posts.name = "Posts";
    posts.material = scene.addMaterial(solid("wood", {0.30f, 0.20f, 0.11f}, 0.05f, 8));
    appendPosts(posts.mesh, {-1.6, 1.6}, {-1.6, 1.6}, 0.06, 2.3);
    scene.meshes.push_back(std::move(posts));
    std::vector<std::pair<Vec3d, double>> clusters;
    for (int i = -2; i <= 2; ++i)
        for (int j = -2; j <= 2; ++j) clusters.push_back({{0.65 * i, 2.45, 0.65 * j}, 0.6});
    addLeaves(scene, clusters, leaves, 2, 0.15, 0.65f, 0.6f, rng, 0.35);

    Light spot;
    spot.name = "Spot";
    spot.type = LightType::Spot;
    spot.position = {1.8, 5.2, 1.4};
    spot.direction = normalize(Vec3d{0, 0.3, 0} - spot.position);
    spot.color = {1.0f, 0.96f, 0.9f};
    spot.intensity = 90;
    spot.innerConeAngle = 25 * M_PI / 180;
    spot.outerConeAngle = 38 * M_PI / 180;
    scene.lights.push_back(spot);
    // A low afternoon sun behind the camera, the sky's: without it the ground outside the spot was
    // lit by the blue sky alone (dark navy) under a sky that shows daylight.
    const Vec3d towardsSun = sunDirectionFromAngles(25, 130);
    scene.lights.push_back(directionalLight("Sun", -towardsSun, {1.0f, 0.95f, 0.86f}, 2.5f));
    matchSky(scene, {0.45f, 0.42f, 0.36f}, towardsSun);

    return withView(std::move(scene), {-1.0, 1.3, 6.4}, {0.2, 1.15, 0}, 46);
}

Scene makeCgalScene(const std::string& meshesDir, int leaves, uint64_t seed) {
    Scene scene = groundedScene("demo:cgal", 30.0, "ground", {0.42f, 0.40f, 0.34f});
    Rng rng(seed);
    struct Item {
        const char* file;
        const char* name;
        double height, x, z, rotateX, rotateY;
        Vec3f colour;
    };
    const Item items[] = {{"elephant.off", "Elephant", 1.3, -1.3, 0.2, 0, 30, {0.50f, 0.48f, 0.46f}},
                          {"armadillo.off", "Armadillo", 1.4, 0.6, -0.4, 0, 180, {0.62f, 0.45f, 0.30f}},
                          {"camel.off", "Camel", 1.2, 1.7, 0.9, 0, -70, {0.70f, 0.58f, 0.38f}}};
    int loaded = 0;
    std::string lastError;
    for (const Item& it : items) {
        std::optional<Mesh> mesh = loadDemoMesh(meshesDir, it.file);
        if (!mesh) {
            scene.warnings.push_back("missing " + (std::filesystem::path(meshesDir) / it.file).string());
            continue;
        }
        const uint32_t mat = scene.addMaterial(solid(it.name, it.colour, 0.2f, 30));
        scene.meshes.push_back(
            placedMesh(std::move(*mesh), it.name, it.height, it.x, it.z, it.rotateX, it.rotateY, mat));
        ++loaded;
    }
    if (loaded == 0) fail("demo 'cgal': none of elephant.off, armadillo.off, camel.off found in ", meshesDir);
    // A pergola: posts, beams and a roof of leaves.
    SceneMesh wood;
    wood.name = "Pergola";
    wood.material = scene.addMaterial(solid("wood", {0.32f, 0.21f, 0.12f}, 0.05f, 8));
    appendPosts(wood.mesh, {-2.6, 2.6}, {-1.7, 1.7}, 0.08, 2.6);
    for (const double z : {-1.7, 1.7}) appendBox(wood.mesh, {-2.8, 2.6, z - 0.07}, {2.8, 2.75, z + 0.07});
    for (int i = -4; i <= 4; ++i)
        appendBox(wood.mesh, {0.6 * i - 0.04, 2.75, -2.0}, {0.6 * i + 0.04, 2.83, 2.0});
    scene.meshes.push_back(std::move(wood));
    std::vector<std::pair<Vec3d, double>> clusters;
    for (int i = -4; i <= 4; ++i)
        for (int j = -3; j <= 3; ++j) clusters.push_back({{0.6 * i, 2.95, 0.55 * j}, 0.45});
    addLeaves(scene, clusters, leaves, 3, 0.16, 0.7f, 0.6f, rng, 0.4);

    scene.lights.push_back(directionalLight("Sun", {-0.35, -1.0, -0.3}, {1.0f, 0.95f, 0.86f}, 2.6f));
    matchSky(scene, {0.42f, 0.40f, 0.34f}, Vec3d{0.35, 1.0, 0.3});
    Light lamp;
    lamp.name = "Lamp";
    lamp.type = LightType::Point;
    lamp.position = {2.2, 1.6, 2.6};
    lamp.color = {1.0f, 0.7f, 0.4f};
    lamp.intensity = 6;
    scene.lights.push_back(lamp);

    return withView(std::move(scene), {0.4, 2.2, 7.6}, {0.1, 1.0, 0}, 50);
}

std::vector<std::string> demoSceneNames() { return {"tree", "bunny", "cgal", "glass"}; }

std::vector<std::string> largeDemoSceneNames() { return {"forest"}; }

Scene makeDemoScene(const std::string& name, const std::string& meshesDir) {
    if (name == "tree") return makeTreeScene();
    if (name == "bunny") return makeBunnyScene(meshesDir);
    if (name == "cgal") return makeCgalScene(meshesDir);
    if (name == "glass") return makeGlassScene(meshesDir);
    if (name == "forest") return makeForestScene();
    fail("unknown demo scene '", name, "' (allowed: tree, bunny, cgal, glass, forest)");
}

} // namespace voxfx::demo
