// Tests of src/render/scene*.cpp: a hand-written glTF 2.0 file (node hierarchy with TRS, instancing,
// KHR_lights_punctual, a perspective camera, KHR_materials_transmission / _ior / _volume, a primitive
// without material) whose expected world-space values are derived by hand; writeGltf round trips
// (.gltf and .glb), and the written files read from the glTF 2.0 specification (the JSON with
// nlohmann-json, the buffer by hand, no Assimp); the JSON wrapper; material rules; bad input with clear
// messages; scene-info.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "demo/demo_scenes.hpp"
#include "test_util.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/scene_io.hpp"

namespace voxfx {
namespace {

using namespace voxfx::demo;

using test::base64;

// One triangle (0,0,0) (1,0,0) (0,1,0) as float positions + uint16 indices (padded): 44 bytes.
std::string triangleBuffer() {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint16_t idx[4] = {0, 1, 2, 0};
    std::string b(reinterpret_cast<const char*>(p), sizeof p);
    b.append(reinterpret_cast<const char*>(idx), sizeof idx);
    return b;
}

// The hand-written test scene. `sunRotation` lets a test break the sun's node transform.
std::string handGltf(const std::string& sunNodeExtra = R"("rotation": [-0.70710678, 0, 0, 0.70710678])",
                     const std::string& spotType = "spot") {
    return R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)" +
           base64(triangleBuffer()) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
  "materials": [
    {"name": "Glass", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.95, 1.0, 1.0]},
     "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9},
                    "KHR_materials_ior": {"ior": 1.45},
                    "KHR_materials_volume": {"thicknessFactor": 0.1, "attenuationDistance": 2.0,
                                             "attenuationColor": [0.8, 0.9, 1.0]}}},
    {"name": "Leaf", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.4, 0.05, 0.6]},
     "alphaMode": "BLEND", "doubleSided": true}],
  "meshes": [
    {"name": "LeafTri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 1}]},
    {"name": "GlassTri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
    {"name": "PlainTri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1, "zfar": 50}}],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"name": "Sun", "type": "directional", "intensity": 3},
    {"name": "Spot", "type": ")" +
           spotType + R"(", "intensity": 40, "color": [1, 0.5, 0.25],
     "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
    {"name": "Bulb", "type": "point", "intensity": 10}]}},
  "scene": 0,
  "scenes": [{"nodes": [0, 1, 2, 3, 4, 5, 6, 8, 9]}],
  "nodes": [
    {"name": "Tri", "mesh": 0, "translation": [1, 2, 3], "scale": [2, 2, 2]},
    {"name": "TriRot", "mesh": 0, "rotation": [0, 0, 0.70710678, 0.70710678], "translation": [0, 0, -5]},
    {"name": "SunNode", "extensions": {"KHR_lights_punctual": {"light": 0}}, )" +
           sunNodeExtra + R"(},
    {"name": "SpotNode", "extensions": {"KHR_lights_punctual": {"light": 1}}, "translation": [0, 4, 0],
     "rotation": [-0.70710678, 0, 0, 0.70710678]},
    {"name": "BulbNode", "extensions": {"KHR_lights_punctual": {"light": 2}}, "translation": [1, 1, 1]},
    {"name": "CamNode", "camera": 0, "translation": [0, 1, 10]},
    {"name": "Parent", "translation": [10, 0, 0], "children": [7]},
    {"name": "Child", "mesh": 0, "translation": [0, 1, 0]},
    {"name": "Lens", "mesh": 1},
    {"name": "Plain", "mesh": 2, "translation": [0, -3, 0]}]
})";
}

const SceneMesh& meshNamed(const Scene& s, const std::string& name) {
    for (const SceneMesh& m : s.meshes)
        if (m.name == name) return m;
    throw std::runtime_error("no mesh " + name);
}

const Light& lightNamed(const Scene& s, const std::string& name) {
    for (const Light& l : s.lights)
        if (l.name == name) return l;
    throw std::runtime_error("no light " + name);
}

void expectVec(const Vec3d& a, const Vec3d& b, double tol = 1e-5) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

std::string errorOf(const std::string& path) {
    try {
        loadScene(path);
    } catch (const Error& e) { return e.what(); }
    return "(no error)";
}

TEST(SceneTest, GltfNodeTransformsGiveHandDerivedWorldPositions) {
    test::TempDir dir;
    const Scene s = loadScene(test::writeFile(dir.file("hand.gltf"), handGltf()));
    ASSERT_EQ(s.meshes.size(), 5u);
    // translation (1,2,3) after scale 2.
    const Mesh& tri = meshNamed(s, "Tri").mesh;
    expectVec(Vec3d(tri.positions[0]), {1, 2, 3});
    expectVec(Vec3d(tri.positions[1]), {3, 2, 3});
    expectVec(Vec3d(tri.positions[2]), {1, 4, 3});
    // 90 degrees about z: (1,0,0) -> (0,1,0), (0,1,0) -> (-1,0,0); then z - 5.
    const Mesh& rot = meshNamed(s, "TriRot").mesh;
    expectVec(Vec3d(rot.positions[1]), {0, 1, -5});
    expectVec(Vec3d(rot.positions[2]), {-1, 0, -5});
    // Parent (10,0,0) * child (0,1,0).
    expectVec(Vec3d(meshNamed(s, "Child").mesh.positions[0]), {10, 1, 0});
    EXPECT_EQ(meshNamed(s, "Tri").mesh.triangleCount(), 1u);
}

TEST(SceneTest, GltfMaterialsIncludingExtensions) {
    test::TempDir dir;
    const Scene s = loadScene(test::writeFile(dir.file("hand.gltf"), handGltf()));
    const Material& leaf = s.materials[meshNamed(s, "Tri").material];
    EXPECT_EQ(leaf.name, "Leaf");
    EXPECT_FLOAT_EQ(leaf.opacity, 0.6f); // alphaMode BLEND: alpha is the opacity
    EXPECT_TRUE(leaf.blend);             // and the camera sees through it
    EXPECT_TRUE(leaf.doubleSided);
    EXPECT_FLOAT_EQ(leaf.baseColor.y, 0.4f);
    EXPECT_FALSE(leaf.isOpaque());
    const Material& glass = s.materials[meshNamed(s, "Lens").material];
    EXPECT_EQ(glass.name, "Glass");
    EXPECT_FLOAT_EQ(glass.opacity, 1.0f); // OPAQUE alpha mode ignores alpha
    EXPECT_FALSE(glass.blend);
    EXPECT_FLOAT_EQ(glass.transmission, 0.9f);
    EXPECT_FLOAT_EQ(glass.ior, 1.45f);
    EXPECT_FLOAT_EQ(glass.thickness, 0.1f);
    EXPECT_FLOAT_EQ(glass.attenuationDistance, 2.0f);
    EXPECT_FLOAT_EQ(glass.attenuationColor.y, 0.9f);
    // Hand: (1 - 1) + 1 * 0.9 * colour.
    EXPECT_NEAR(glass.crossingTransmittance().y, 0.9f * 0.95f, 1e-6f);
    const Material& plain = s.materials[meshNamed(s, "Plain").material];
    EXPECT_EQ(plain.name, "default");
    EXPECT_TRUE(plain.isOpaque());
    EXPECT_FLOAT_EQ(plain.baseColor.x, 1.0f); // glTF's default material is white
}

TEST(SceneTest, GltfLightsAndCameraFollowTheirNodes) {
    test::TempDir dir;
    const Scene s = loadScene(test::writeFile(dir.file("hand.gltf"), handGltf()));
    ASSERT_EQ(s.lights.size(), 3u);
    // -90 degrees about x turns the node's -Z (the light direction) into -Y.
    const Light& sun = lightNamed(s, "Sun");
    EXPECT_EQ(sun.type, LightType::Directional);
    expectVec(sun.direction, {0, -1, 0});
    EXPECT_FLOAT_EQ(sun.intensity, 3.0f);
    const Light& spot = lightNamed(s, "Spot");
    EXPECT_EQ(spot.type, LightType::Spot);
    expectVec(spot.position, {0, 4, 0});
    expectVec(spot.direction, {0, -1, 0});
    EXPECT_DOUBLE_EQ(spot.innerConeAngle, 0.2);
    EXPECT_DOUBLE_EQ(spot.outerConeAngle, 0.5);
    EXPECT_FLOAT_EQ(spot.intensity, 40.0f); // not folded into the colour
    EXPECT_FLOAT_EQ(spot.color.y, 0.5f);
    const Light& bulb = lightNamed(s, "Bulb");
    EXPECT_EQ(bulb.type, LightType::Point);
    expectVec(bulb.position, {1, 1, 1});
    ASSERT_EQ(s.cameras.size(), 1u);
    const Camera& c = s.cameras[0];
    expectVec(c.position, {0, 1, 10});
    expectVec(normalize(c.target - c.position), {0, 0, -1}); // glTF cameras look along -Z
    EXPECT_DOUBLE_EQ(c.fovY, 0.6);                           // vertical, radians, as in the file
    EXPECT_DOUBLE_EQ(c.nearDepth, 0.1);
}

// ---- The written glTF read from the specification, without voxfx's or Assimp's loader ----------

using test::unbase64;

uint32_t u32At(const std::string& bytes, size_t at) {
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | uint8_t(bytes.at(at + size_t(i)));
    return v;
}

// glTF 2.0 JSON and its one binary buffer: a .gltf with a base64 data URI, or a .glb container
// (12-byte header "glTF", version 2, total length; a JSON chunk, then a BIN chunk).
struct GltfFile {
    nlohmann::json doc;
    std::string bin;
};

GltfFile readGltfBySpec(const std::string& path) {
    const std::string bytes = test::readFileBytes(path);
    GltfFile f;
    if (path.ends_with(".glb")) {
        EXPECT_EQ(u32At(bytes, 0), 0x46546C67u) << "magic";
        EXPECT_EQ(u32At(bytes, 4), 2u) << "version";
        EXPECT_EQ(u32At(bytes, 8), bytes.size()) << "length";
        const uint32_t jsonLength = u32At(bytes, 12);
        EXPECT_EQ(u32At(bytes, 16), 0x4E4F534Au) << "the first chunk is JSON";
        EXPECT_EQ(jsonLength % 4, 0u) << "chunks are 4-byte aligned";
        f.doc = nlohmann::json::parse(bytes.substr(20, jsonLength));
        const size_t binAt = 20 + jsonLength;
        EXPECT_EQ(u32At(bytes, binAt + 4), 0x004E4942u) << "the second chunk is BIN";
        f.bin = bytes.substr(binAt + 8, u32At(bytes, binAt));
        EXPECT_FALSE(f.doc["buffers"][0].contains("uri")) << "a GLB buffer lives in the BIN chunk";
    } else {
        f.doc = nlohmann::json::parse(bytes);
        const std::string uri = f.doc["buffers"][0]["uri"];
        const std::string prefix = "data:application/octet-stream;base64,";
        EXPECT_EQ(uri.substr(0, prefix.size()), prefix);
        f.bin = unbase64(uri.substr(prefix.size()));
    }
    EXPECT_GE(f.bin.size(), f.doc["buffers"][0]["byteLength"].get<size_t>());
    return f;
}

// The elements of accessor `index` (floats or unsigned ints), through its buffer view.
template <class T>
std::vector<T> accessorData(const GltfFile& f, size_t index, int componentType, const std::string& type) {
    const nlohmann::json& a = f.doc["accessors"][index];
    EXPECT_EQ(a["componentType"].get<int>(), componentType);
    EXPECT_EQ(a["type"].get<std::string>(), type);
    const nlohmann::json& view = f.doc["bufferViews"][a["bufferView"].get<size_t>()];
    const size_t offset = view.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0));
    const size_t n = a["count"].get<size_t>() * (type == "VEC3" ? 3 : 1);
    EXPECT_EQ(offset % 4, 0u) << "accessor data must be aligned to its component size";
    EXPECT_LE(n * sizeof(T), view["byteLength"].get<size_t>());
    std::vector<T> out(n);
    if (offset + n * sizeof(T) > f.bin.size()) {
        ADD_FAILURE() << "accessor " << index << " runs past the buffer";
        return {};
    }
    std::memcpy(out.data(), f.bin.data() + offset, n * sizeof(T));
    return out;
}

// The written file, read by the specification, holds `tree`'s meshes, materials and lights exactly.
void expectGltfHoldsSceneBySpec(const Scene& tree, const std::string& path) {
    const GltfFile f = readGltfBySpec(path);
    EXPECT_EQ(f.doc["asset"]["version"], "2.0");
    ASSERT_EQ(f.doc["meshes"].size(), tree.meshes.size());
    ASSERT_EQ(f.doc["materials"].size(), tree.materials.size());
    for (size_t i = 0; i < tree.meshes.size(); ++i) {
        const SceneMesh& m = tree.meshes[i];
        const nlohmann::json& gm = f.doc["meshes"][i];
        EXPECT_EQ(gm["name"], m.name);
        const nlohmann::json& prim = gm["primitives"][0];
        EXPECT_EQ(prim.value("mode", 4), 4) << "triangles";
        EXPECT_EQ(f.doc["materials"][prim["material"].get<size_t>()]["name"],
                  tree.materials[m.material].name);
        const size_t pos = prim["attributes"]["POSITION"].get<size_t>();
        EXPECT_TRUE(f.doc["accessors"][pos].contains("min") && f.doc["accessors"][pos].contains("max"))
            << "POSITION needs min and max";
        const std::vector<float> p = accessorData<float>(f, pos, 5126, "VEC3");
        ASSERT_EQ(p.size(), 3 * m.mesh.positions.size()) << m.name;
        int64_t wrong = 0;
        for (size_t v = 0; v < m.mesh.positions.size(); ++v)
            wrong += !(Vec3f{p[3 * v], p[3 * v + 1], p[3 * v + 2]} == m.mesh.positions[v]);
        EXPECT_EQ(wrong, 0) << m.name;
        EXPECT_EQ(accessorData<uint32_t>(f, prim["indices"].get<size_t>(), 5125, "SCALAR"), m.mesh.indices)
            << m.name;
    }
    const nlohmann::json& lights = f.doc["extensions"]["KHR_lights_punctual"]["lights"];
    ASSERT_EQ(lights.size(), tree.lights.size());
    EXPECT_EQ(lights[0]["type"], "directional");
    EXPECT_NE(
        std::find(f.doc["extensionsUsed"].begin(), f.doc["extensionsUsed"].end(), "KHR_lights_punctual"),
        f.doc["extensionsUsed"].end());
}

TEST(SceneTest, WriteGltfRoundTripsGltfAndGlbAndFollowsTheSpec) {
    TreeOptions o;
    o.leaves = 200;
    Scene tree = makeTreeScene(o);
    // Leaves are drawn solid (MASK); one material blended (BLEND) so that both round trip.
    for (Material& m : tree.materials)
        if (m.opacity < 1) {
            m.blend = true;
            break;
        }
    test::TempDir dir;
    for (const char* name : {"tree.gltf", "tree.glb"}) {
        const std::string path = dir.file(name);
        writeGltf(tree, path);
        SCOPED_TRACE(name);
        expectGltfHoldsSceneBySpec(tree, path); // without voxfx's or Assimp's loader
        const Scene back = loadScene(path);
        ASSERT_EQ(back.meshes.size(), tree.meshes.size()) << name;
        for (size_t i = 0; i < tree.meshes.size(); ++i) {
            const SceneMesh& a = tree.meshes[i];
            const SceneMesh& b = meshNamed(back, a.name);
            EXPECT_EQ(a.mesh.positions, b.mesh.positions) << name << " " << a.name;
            EXPECT_EQ(a.mesh.indices, b.mesh.indices) << name << " " << a.name;
            EXPECT_EQ(a.castsShadow, b.castsShadow) << name << " " << a.name;
            const Material &ma = tree.materials[a.material], &mb = back.materials[b.material];
            EXPECT_EQ(ma.name, mb.name);
            EXPECT_TRUE(ma.crossingTransmittance() == mb.crossingTransmittance()) << ma.name;
            EXPECT_EQ(ma.blend, mb.blend) << ma.name;
            EXPECT_FLOAT_EQ(ma.shininess, mb.shininess);
            EXPECT_FLOAT_EQ(ma.specular, mb.specular);
        }
        ASSERT_EQ(back.lights.size(), 1u);
        expectVec(back.lights[0].direction, tree.lights[0].direction, 1e-9);
        EXPECT_EQ(back.lights[0].intensity, tree.lights[0].intensity);
        ASSERT_EQ(back.cameras.size(), 1u);
        expectVec(back.cameras[0].position, tree.cameras[0].position, 1e-9);
        expectVec(normalize(back.cameras[0].target - back.cameras[0].position),
                  normalize(tree.cameras[0].target - tree.cameras[0].position), 1e-9);
        EXPECT_DOUBLE_EQ(back.cameras[0].fovY, tree.cameras[0].fovY);
    }
}

TEST(SceneTest, JsonWrapperAddsMeshesLightsCamerasAndSettings) {
    test::TempDir dir;
    test::writeFile(dir.file("hand.gltf"), handGltf());
    test::writeFile(dir.file("tet.off"),
                    "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    const std::string wrapper = test::writeFile(dir.file("scene.json"), R"({
      "gltf": "hand.gltf",
      "meshes": [{"file": "tet.off", "name": "Tet", "scale": 2, "rotate": [0, 1, 0, 90], "translate": [1, 0, 0],
                  "material": {"name": "red", "baseColor": [0.8, 0.1, 0.1], "opacity": 0.5}},
                 {"file": "tet.off", "name": "TetPlain"}],
      "lights": [{"type": "spot", "name": "Extra", "position": [0, 5, 0], "target": [0, 0, 0],
                  "outerConeDegrees": 30, "intensity": 7}],
      "cameras": [{"position": [0, 2, 6], "target": [0, 0, 0], "fovYDegrees": 40}],
      "receiversOnly": ["Plain"],
      "render": {"shadows": "transmittance", "width": 320, "height": 200, "gridResolution": 128,
                 "slicing": "local"},
      "environmentMap": "sky.pfm"
    })");
    const Scene s = loadScene(wrapper);
    const SceneMesh& tet = meshNamed(s, "Tet");
    // (1,0,0): scale 2 -> (2,0,0); 90 degrees about y -> (0,0,-2); translate -> (1,0,-2).
    expectVec(Vec3d(tet.mesh.positions[1]), {1, 0, -2});
    EXPECT_EQ(s.materials[tet.material].name, "red");
    EXPECT_FLOAT_EQ(s.materials[tet.material].opacity, 0.5f);
    EXPECT_TRUE(s.materials[tet.material].blend); // see-through unless "blend": false
    // A wrapper mesh without a material gets the default (opaque grey) material, not the glTF's
    // first one (here the glass, a partial occluder).
    const Material& plain = s.materials[meshNamed(s, "TetPlain").material];
    EXPECT_NE(plain.name, "Glass");
    EXPECT_TRUE(plain.isOpaque());
    EXPECT_EQ(plain.baseColor, Material{}.baseColor);
    EXPECT_FALSE(meshNamed(s, "Plain").castsShadow);
    EXPECT_TRUE(meshNamed(s, "Tri").castsShadow);
    const Light& extra = lightNamed(s, "Extra");
    expectVec(extra.direction, {0, -1, 0});
    EXPECT_NEAR(extra.outerConeAngle, M_PI / 6, 1e-12);
    ASSERT_EQ(s.cameras.size(), 2u); // the wrapper's camera first, then the glTF's
    expectVec(s.cameras[0].position, {0, 2, 6});
    EXPECT_NEAR(s.cameras[0].fovY, 40 * M_PI / 180, 1e-12);
    ASSERT_EQ(s.settings.render.size(), 5u); // as the file gives them
    const auto shadows = std::find_if(s.settings.render.begin(), s.settings.render.end(),
                                      [](const auto& setting) { return setting.first == "shadows"; });
    ASSERT_NE(shadows, s.settings.render.end());
    EXPECT_EQ(std::get<std::string>(shadows->second), "transmittance");
    EXPECT_EQ(s.settings.environmentMap, (dir.path() / "sky.pfm").string());
    // Applied by the library: the scene's technique and its settings over the defaults.
    const RenderOptions o = renderOptionsFor(s);
    EXPECT_EQ(o.width, 320);
    EXPECT_EQ(o.height, 200);
    ASSERT_TRUE(std::holds_alternative<TransmittanceShadowOptions>(o.shadow));
    EXPECT_EQ(std::get<TransmittanceShadowOptions>(o.shadow).grid.resolution, 128);
    EXPECT_EQ(std::get<TransmittanceShadowOptions>(o.shadow).grid.slicing, Slicing::Local);
    EXPECT_EQ(std::get<TransmittanceShadowOptions>(o.shadow).grid.depth, LightGridOptions{}.depth);
    // A technique a front end asks for wins; the scene's settings still apply where it has them.
    const RenderOptions m = renderOptionsFor(s, "map");
    EXPECT_TRUE(std::holds_alternative<ShadowMapOptions>(m.shadow));
    EXPECT_EQ(m.width, 320);
    EXPECT_TRUE(std::holds_alternative<ExactGlassOptions>(m.glass)); // the glTF's glass
}

TEST(SceneTest, MaterialCrossingTransmittanceIsHandDerived) {
    Material m;
    m.baseColor = {0.2f, 0.6f, 1.0f};
    m.opacity = 0.7f;
    m.transmission = 0.5f;
    // (1 - 0.7) + 0.7 * 0.5 * c
    EXPECT_NEAR(m.crossingTransmittance().x, 0.3f + 0.35f * 0.2f, 1e-6f);
    EXPECT_NEAR(m.crossingTransmittance().z, 0.3f + 0.35f, 1e-6f);
    m.opacity = 1;
    m.transmission = 0;
    EXPECT_TRUE(m.isOpaque());
    m.opacity = 0;
    EXPECT_TRUE(m.crossingTransmittance() == (Vec3f{1, 1, 1}));
}

TEST(SceneTest, BadInputGivesClearErrors) {
    test::TempDir dir;
    const std::string missing = dir.file("nope.gltf");
    EXPECT_NE(errorOf(missing).find("no such file"), std::string::npos) << errorOf(missing);
    EXPECT_NE(errorOf(missing).find(missing), std::string::npos);

    const std::string unknown = test::writeFile(dir.file("scene.xyz"), "hello");
    EXPECT_NE(errorOf(unknown).find("unknown scene extension '.xyz'"), std::string::npos) << errorOf(unknown);
    EXPECT_NE(errorOf(unknown).find(".gltf"), std::string::npos);

    const std::string broken =
        test::writeFile(dir.file("broken.gltf"), "{\"asset\": {\"version\": \"2.0\"}, ");
    EXPECT_NE(errorOf(broken).find("malformed JSON"), std::string::npos) << errorOf(broken);

    // A light node scaled to zero has no direction.
    const std::string flat = test::writeFile(dir.file("flat.gltf"), handGltf(R"("scale": [0, 0, 0])"));
    EXPECT_NE(errorOf(flat).find("has no direction"), std::string::npos) << errorOf(flat);
    EXPECT_NE(errorOf(flat).find("Sun"), std::string::npos) << errorOf(flat);

    const std::string laser = test::writeFile(dir.file("laser.gltf"), handGltf(R"("name": "x")", "laser"));
    EXPECT_NE(errorOf(laser).find("unknown light type 'laser'"), std::string::npos) << errorOf(laser);

    const std::string truncated = test::writeFile(dir.file("cut.glb"), std::string("glTF\x02\0\0\0", 8));
    EXPECT_NE(errorOf(truncated).find("cut.glb"), std::string::npos) << errorOf(truncated);

    const std::string noDir =
        test::writeFile(dir.file("nodir.json"), R"({"lights": [{"type": "directional", "name": "sun"}]})");
    EXPECT_NE(errorOf(noDir).find("has no direction"), std::string::npos) << errorOf(noDir);
    EXPECT_NE(errorOf(noDir).find("sun"), std::string::npos) << errorOf(noDir);

    const std::string typo = test::writeFile(dir.file("typo.json"), R"({"lihgts": []})");
    EXPECT_NE(errorOf(typo).find("unknown key \"lihgts\""), std::string::npos) << errorOf(typo);

    const std::string noMesh =
        test::writeFile(dir.file("nomesh.json"), R"({"meshes": [{"file": "gone.off"}]})");
    EXPECT_NE(errorOf(noMesh).find("gone.off"), std::string::npos) << errorOf(noMesh);

    test::writeFile(dir.file("tri.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    const std::string blend =
        test::writeFile(dir.file("blend.json"),
                        R"({"meshes": [{"file": "tri.off", "material": {"opacity": 0.5, "blend": "yes"}}]})");
    EXPECT_NE(errorOf(blend).find("\"blend\" must be true or false"), std::string::npos) << errorOf(blend);

    const std::string cam = test::writeFile(dir.file("cam.json"),
                                            R"({"cameras": [{"position": [1, 1, 1], "target": [1, 1, 1]}]})");
    EXPECT_NE(errorOf(cam).find("position equals target"), std::string::npos) << errorOf(cam);

    const std::string cone = test::writeFile(
        dir.file("cone.json"),
        R"({"lights": [{"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "outerConeDegrees": 120}]})");
    EXPECT_NE(errorOf(cone).find("cone"), std::string::npos) << errorOf(cone);

    Scene bad;
    bad.addMaterial(Material{});
    SceneMesh m;
    m.name = "m";
    m.mesh = test::makeBox({0, 0, 0}, {1, 1, 1});
    m.material = 3;
    bad.meshes.push_back(m);
    EXPECT_THROW(bad.validate(), Error);
    EXPECT_THROW(writeGltf(Scene{}, dir.file("x.obj")), Error);
}

TEST(SceneTest, SceneInfoPrintsWhatWasUnderstood) {
    test::TempDir dir;
    const std::string path = test::writeFile(dir.file("hand.gltf"), handGltf());
    const test::CommandRun r = test::runVoxfx(dir, "scene-info " + path);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("5 meshes"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("3 lights"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("'Spot' spot"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("partial occluder"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ior 1.45"), std::string::npos) << r.out;
    const test::CommandRun bad = test::runVoxfx(dir, "scene-info " + dir.file("missing.glb"));
    EXPECT_EQ(bad.exitCode, 1);
    EXPECT_NE(bad.err.find("voxfx: error:"), std::string::npos) << bad.err;
}

} // namespace
} // namespace voxfx
