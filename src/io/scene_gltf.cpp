// voxfx — glTF 2.0 scene loading (Khronos glTF 2.0 specification; KHR_lights_punctual,
// KHR_materials_transmission, KHR_materials_diffuse_transmission, KHR_materials_ior,
// KHR_materials_volume).
//
// Geometry comes through Assimp (accessors, buffers, data URIs, GLB, sparse data, node tree) in
// the voxfx_assimp module, whose one conversion (shared with loadMesh) gives every mesh instance
// its node's world transform and keeps its material. Materials, cameras and lights are read from the file's
// JSON: Assimp 5.2 folds the light intensity into the colour, reports the camera's field of view
// horizontally, and exposes neither KHR_materials_ior nor the volume attenuation. Assimp imports glTF
// materials in the order meshes first use them (not in file order) and adds a default one, so its materials
// are matched back to the file's by name, then base colour (materialMapping).
#include "io/scene_gltf.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "io/module_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"

namespace voxfx::detail {

using nlohmann::json;

LightType parseLightType(const std::string& type, const std::string& where) {
    return parseEnum<LightType>(type, "light type", kLightTypeNames, where);
}

std::string readTextFile(const std::string& path, const char* what) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) fail(path, ": cannot open ", what, ": no such file");
    if (std::filesystem::is_directory(path, ec)) fail(path, ": cannot read ", what, ": it is a directory");
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, ": cannot open ", what, ": ", std::strerror(errno));
    std::ostringstream s;
    s << in.rdbuf();
    if (in.bad()) fail(path, ": cannot read ", what);
    return s.str();
}

namespace {

uint32_t readU32(const std::string& bytes, std::size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v; // glTF is little-endian, as is every machine we build for
}

double number(const json& j, const char* key, double fallback, const std::string& where) {
    if (!j.is_object() || !j.contains(key)) return fallback;
    const json& v = j.at(key);
    if (!v.is_number()) fail(where, ": \"", key, "\" must be a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(where, ": \"", key, "\" is not finite");
    return d;
}

Vec3f colour(const json& j, const char* key, Vec3f fallback, const std::string& where,
             float* alpha = nullptr) {
    if (!j.is_object() || !j.contains(key)) return fallback;
    const json& v = j.at(key);
    const std::size_t n = alpha ? 4 : 3;
    if (!v.is_array() || v.size() != n) fail(where, ": \"", key, "\" must be an array of ", n, " numbers");
    float c[4];
    for (std::size_t i = 0; i < n; ++i) {
        if (!v[i].is_number()) fail(where, ": \"", key, "\" must be an array of ", n, " numbers");
        c[i] = v[i].get<float>();
    }
    if (alpha) *alpha = c[3];
    return {c[0], c[1], c[2]};
}

Mat4d nodeLocalTransform(const json& node, const std::string& where) {
    Mat4d m;
    if (node.contains("matrix")) {
        const json& a = node.at("matrix");
        if (!a.is_array() || a.size() != 16) fail(where, ": \"matrix\" must hold 16 numbers");
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) m.m[r][c] = a[size_t(c * 4 + r)].get<double>(); // column-major
        return m;
    }
    Mat4d t, r, s;
    if (node.contains("translation")) {
        const json& a = node.at("translation");
        for (int i = 0; i < 3; ++i) t.m[i][3] = a.at(size_t(i)).get<double>();
    }
    if (node.contains("rotation")) {
        const json& a = node.at("rotation"); // unit quaternion (x, y, z, w)
        const double x = a.at(0).get<double>(), y = a.at(1).get<double>(), z = a.at(2).get<double>(),
                     w = a.at(3).get<double>();
        r.m[0][0] = 1 - 2 * (y * y + z * z);
        r.m[0][1] = 2 * (x * y - z * w);
        r.m[0][2] = 2 * (x * z + y * w);
        r.m[1][0] = 2 * (x * y + z * w);
        r.m[1][1] = 1 - 2 * (x * x + z * z);
        r.m[1][2] = 2 * (y * z - x * w);
        r.m[2][0] = 2 * (x * z - y * w);
        r.m[2][1] = 2 * (y * z + x * w);
        r.m[2][2] = 1 - 2 * (x * x + y * y);
    }
    if (node.contains("scale")) {
        const json& a = node.at("scale");
        for (int i = 0; i < 3; ++i) s.m[i][i] = a.at(size_t(i)).get<double>();
    }
    return t * r * s;
}

Material readMaterial(const json& j, std::size_t index, const std::string& path) {
    const std::string where = concat(path, ": material ", index);
    Material m;
    m.name = j.value("name", concat("material", index));
    const json pbr = j.value("pbrMetallicRoughness", json::object());
    float alpha = 1;
    m.baseColor = colour(pbr, "baseColorFactor", {1, 1, 1}, where, &alpha);
    const std::string alphaMode = j.value("alphaMode", "OPAQUE");
    if (alphaMode != "OPAQUE" && alphaMode != "BLEND" && alphaMode != "MASK")
        fail(where, ": unknown alphaMode '", alphaMode, "' (allowed: OPAQUE, BLEND, MASK)");
    m.opacity = alphaMode == "OPAQUE" ? 1.0f : std::clamp(alpha, 0.0f, 1.0f);
    m.blend = alphaMode == "BLEND";
    m.doubleSided = j.value("doubleSided", false);
    const double roughness = std::clamp(number(pbr, "roughnessFactor", 1.0, where), 0.0, 1.0);
    // Blinn–Phong from roughness: alpha = roughness^2, exponent 2 / alpha^2 - 2 (Walter et al. 2007).
    const double a = std::max(roughness * roughness, 0.03);
    m.shininess = float(std::clamp(2.0 / (a * a) - 2.0, 1.0, 1000.0));
    m.specular = float(0.04 + 0.3 * (1.0 - roughness));
    const json ext = j.value("extensions", json::object());
    if (ext.contains("KHR_materials_transmission"))
        m.transmission = float(std::clamp(
            number(ext["KHR_materials_transmission"], "transmissionFactor", 0.0, where), 0.0, 1.0));
    if (ext.contains("KHR_materials_diffuse_transmission")) {
        const json& d = ext["KHR_materials_diffuse_transmission"];
        m.diffuseTransmission = float(number(d, "diffuseTransmissionFactor", 0.0, where));
        m.diffuseTransmissionColor = colour(d, "diffuseTransmissionColorFactor", {1, 1, 1}, where);
    }
    if (ext.contains("KHR_materials_ior")) m.ior = float(number(ext["KHR_materials_ior"], "ior", 1.5, where));
    if (ext.contains("KHR_materials_volume")) {
        const json& v = ext["KHR_materials_volume"];
        m.thickness = float(number(v, "thicknessFactor", 0.0, where));
        m.attenuationDistance =
            float(number(v, "attenuationDistance", std::numeric_limits<double>::infinity(), where));
        m.attenuationColor = colour(v, "attenuationColor", {1, 1, 1}, where);
    }
    // voxfx's own Blinn–Phong parameters survive a round trip through writeGltf.
    if (j.contains("extras") && j["extras"].contains("voxfx")) {
        const json& x = j["extras"]["voxfx"];
        m.specular = float(number(x, "specular", m.specular, where));
        m.shininess = float(number(x, "shininess", m.shininess, where));
    }
    return m;
}

struct GltfNodes {
    std::vector<Mat4d> world;                // per JSON node
    std::vector<bool> reached;               // part of the displayed scene
    std::map<std::string, bool> castsShadow; // node name -> extras.voxfx.castsShadow
};

GltfNodes resolveNodes(const json& doc, const std::string& path) {
    const json nodes = doc.value("nodes", json::array());
    GltfNodes out;
    out.world.assign(nodes.size(), Mat4d{});
    out.reached.assign(nodes.size(), false);
    std::vector<std::size_t> roots;
    if (doc.contains("scenes") && !doc["scenes"].empty()) {
        const std::size_t s = doc.value("scene", 0u);
        if (s >= doc["scenes"].size()) fail(path, ": \"scene\" ", s, " does not exist");
        for (const json& n : doc["scenes"][s].value("nodes", json::array()))
            roots.push_back(n.get<std::size_t>());
    } else {
        std::vector<bool> child(nodes.size(), false);
        for (const json& n : nodes)
            for (const json& c : n.value("children", json::array()))
                if (c.get<std::size_t>() < nodes.size()) child[c.get<std::size_t>()] = true;
        for (std::size_t i = 0; i < nodes.size(); ++i)
            if (!child[i]) roots.push_back(i);
    }
    std::vector<std::pair<std::size_t, Mat4d>> stack;
    for (const std::size_t r : roots) stack.push_back({r, Mat4d{}});
    while (!stack.empty()) {
        const auto [i, parent] = stack.back();
        stack.pop_back();
        if (i >= nodes.size()) fail(path, ": node ", i, " does not exist");
        if (out.reached[i]) fail(path, ": node ", i, " has two parents or is part of a cycle");
        const std::string where = concat(path, ": node ", i);
        out.reached[i] = true;
        out.world[i] = parent * nodeLocalTransform(nodes[i], where);
        for (const json& c : nodes[i].value("children", json::array()))
            stack.push_back({c.get<std::size_t>(), out.world[i]});
    }
    for (const json& n : nodes)
        if (n.contains("name") && n.contains("extras") && n["extras"].contains("voxfx"))
            out.castsShadow[n["name"].get<std::string>()] = n["extras"]["voxfx"].value("castsShadow", true);
    return out;
}

void readLightsAndCameras(const json& doc, const GltfNodes& g, const std::string& path, Scene& scene) {
    const json nodes = doc.value("nodes", json::array());
    json lights = json::array();
    if (doc.contains("extensions") && doc["extensions"].contains("KHR_lights_punctual"))
        lights = doc["extensions"]["KHR_lights_punctual"].value("lights", json::array());
    const json cameras = doc.value("cameras", json::array());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        if (!g.reached[i]) continue;
        const json& node = nodes[i];
        const Mat4d& m = g.world[i];
        const std::string nodeName = node.value("name", concat("node", i));
        if (node.contains("camera")) {
            const std::size_t c = node["camera"].get<std::size_t>();
            if (c >= cameras.size()) fail(path, ": node ", i, " uses camera ", c, ", which does not exist");
            const json& cam = cameras[c];
            const std::string where = concat(path, ": camera ", c);
            if (cam.value("type", "") != "perspective") {
                scene.warnings.push_back(concat("camera ", c, " ('", nodeName, "') is ",
                                                cam.value("type", "untyped"),
                                                ": only perspective cameras are used"));
            } else {
                const json p = cam.value("perspective", json::object());
                Camera out;
                out.name = cam.value("name", nodeName);
                out.position = m.point({0, 0, 0});
                out.target = out.position + normalize(m.vector({0, 0, -1})); // glTF cameras look along -Z
                out.up = normalize(m.vector({0, 1, 0}));
                out.fovY = number(p, "yfov", 0.8, where);
                out.nearDepth = number(p, "znear", 0.01, where);
                out.farDepth = number(p, "zfar", 1.0e4, where);
                scene.cameras.push_back(out);
            }
        }
        if (node.contains("extensions") && node["extensions"].contains("KHR_lights_punctual")) {
            const std::size_t l = node["extensions"]["KHR_lights_punctual"].value("light", size_t(-1));
            if (l >= lights.size()) fail(path, ": node ", i, " uses light ", l, ", which does not exist");
            const json& src = lights[l];
            const std::string where = concat(path, ": light ", l);
            Light out;
            out.name = src.value("name", nodeName);
            const std::string type = src.value("type", "");
            out.type = parseLightType(type, where);
            out.color = colour(src, "color", {1, 1, 1}, where);
            out.intensity = float(number(src, "intensity", 1.0, where));
            out.range = number(src, "range", 0.0, where);
            out.position = m.point({0, 0, 0});
            // Lights shine along the node's -Z; a degenerate node transform leaves no direction,
            // which Scene::validate reports.
            const Vec3d d = m.vector({0, 0, -1});
            out.direction = length(d) > 0 ? normalize(d) : d;
            if (out.type == LightType::Spot) {
                const json spot = src.value("spot", json::object());
                out.innerConeAngle = number(spot, "innerConeAngle", 0.0, where);
                out.outerConeAngle = number(spot, "outerConeAngle", M_PI / 4, where);
            }
            scene.lights.push_back(out);
        }
    }
}

/// For each Assimp material, the index of the glTF material it came from, or -1 (Assimp's default).
std::vector<int> materialMapping(const std::vector<AssimpMaterial>& aiMaterials, const json& materials) {
    std::vector<int> map(aiMaterials.size(), -1);
    std::vector<bool> used(materials.size(), false);
    for (std::size_t i = 0; i < aiMaterials.size(); ++i) {
        const AssimpMaterial& a = aiMaterials[i];
        int best = -1, bestScore = 0;
        for (std::size_t k = 0; k < materials.size(); ++k) {
            if (used[k] || materials[k].value("name", std::string()) != a.name) continue;
            json pbr = materials[k].value("pbrMetallicRoughness", json::object());
            json c = pbr.value("baseColorFactor", json::array({1, 1, 1, 1}));
            int score = 1;
            if (c.is_array() && c.size() == 4 && std::abs(c[0].get<double>() - a.baseColor[0]) < 1e-6 &&
                std::abs(c[1].get<double>() - a.baseColor[1]) < 1e-6 &&
                std::abs(c[2].get<double>() - a.baseColor[2]) < 1e-6)
                score = 2;
            if (score > bestScore) {
                best = int(k);
                bestScore = score;
            }
        }
        if (best >= 0) used[size_t(best)] = true;
        map[i] = best;
    }
    return map;
}

// The meshes come from the Assimp module's one conversion (node transforms applied, mirrored
// nodes re-wound); this attaches the glTF materials and the voxfx extras.
void readMeshes(AssimpScene& ai, const GltfNodes& g, const json& materials, Scene& scene) {
    const std::vector<int> materialOf = materialMapping(ai.materials, materials);
    int defaultMaterial = -1; // appended on first use
    for (AssimpPart& part : ai.parts) {
        if (part.indices.empty()) continue;
        SceneMesh out;
        out.name = std::move(part.name);
        const auto it = g.castsShadow.find(part.nodeName);
        if (it != g.castsShadow.end()) out.castsShadow = it->second;
        const int gltfMaterial = part.material < materialOf.size() ? materialOf[part.material] : -1;
        if (gltfMaterial >= 0) {
            out.material = uint32_t(gltfMaterial);
        } else {
            if (defaultMaterial < 0) {
                Material d;
                d.name = "default";
                d.baseColor = {1, 1, 1}; // glTF's default material
                defaultMaterial = int(scene.addMaterial(d));
            }
            out.material = uint32_t(defaultMaterial);
        }
        out.mesh.positions.reserve(part.positions.size() / 3);
        for (std::size_t v = 0; v + 2 < part.positions.size(); v += 3)
            out.mesh.positions.push_back({part.positions[v], part.positions[v + 1], part.positions[v + 2]});
        out.normals.reserve(part.normals.size() / 3);
        for (std::size_t v = 0; v + 2 < part.normals.size(); v += 3)
            out.normals.push_back({part.normals[v], part.normals[v + 1], part.normals[v + 2]});
        out.mesh.indices = std::move(part.indices);
        scene.meshes.push_back(std::move(out));
    }
    if (ai.skippedFaces)
        scene.warnings.push_back(concat(ai.skippedFaces, " point or line primitives ignored (not surfaces)"));
}

} // namespace

json readGltfJson(const std::string& path, bool binary) {
    const std::string bytes = readTextFile(path, "glTF file");
    std::string text;
    if (binary) {
        // GLB: 12-byte header (magic "glTF", version 2, length), then chunks (length, type, data);
        // the first chunk is the JSON.
        if (bytes.size() < 20 || readU32(bytes, 0) != 0x46546C67u)
            fail(path, ": not a GLB file (no 'glTF' magic)");
        if (readU32(bytes, 4) != 2) fail(path, ": GLB version ", readU32(bytes, 4), " (only 2 is supported)");
        const uint32_t chunk = readU32(bytes, 12);
        if (readU32(bytes, 16) != 0x4E4F534Au) fail(path, ": the first GLB chunk is not JSON");
        if (std::size_t(chunk) + 20 > bytes.size())
            fail(path, ": truncated GLB (the JSON chunk ends past the file)");
        text = bytes.substr(20, chunk);
    } else {
        text = bytes;
    }
    try {
        return json::parse(text);
    } catch (const json::exception& e) {
        // parse_error, and out_of_range for a number past double's range (1e999)
        fail(path, ": malformed JSON: ", e.what());
    }
}

Scene loadGltfScene(const std::string& path) {
    const bool binary = fileExtension(path) == ".glb";
    const json doc = readGltfJson(path, binary);
    if (!doc.is_object() || !doc.contains("asset")) fail(path, ": not a glTF 2.0 file (no \"asset\")");
    const std::string version = doc["asset"].value("version", "");
    if (version.rfind("2.", 0) != 0) fail(path, ": glTF version '", version, "' (only 2.x is supported)");

    Scene scene;
    scene.source = path;
    try {
        const json materials = doc.value("materials", json::array());
        for (std::size_t i = 0; i < materials.size(); ++i)
            scene.addMaterial(readMaterial(materials[i], i, path));
        const GltfNodes nodes = resolveNodes(doc, path);
        readLightsAndCameras(doc, nodes, path, scene);

        AssimpScene ai;
        std::string error;
        if (!assimpModule().load(path.c_str(), &ai, &error)) fail(path, ": ", error);
        readMeshes(ai, nodes, materials, scene);
    } catch (const json::exception& e) { fail(path, ": unexpected glTF content: ", e.what()); }
    if (scene.materials.empty()) scene.addMaterial(Material{});
    return scene;
}

} // namespace voxfx::detail
