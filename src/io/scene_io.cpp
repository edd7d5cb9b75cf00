// voxfx — scene files: loadScene (glTF through render/scene_gltf, the JSON scene wrapper, or a
// single mesh) and the glTF writer. The scene model itself lives in render/scene.cpp.
#include "voxfx/scene_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <set>

#include "core/atomic_file.hpp"
#include "io/scene_gltf.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/render.hpp"
#include "voxfx/smoke.hpp"
#include "voxfx/volume_io.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {

using detail::concat;
using nlohmann::json;

namespace {

// ---- JSON wrapper --------------------------------------------------------------------------------

// What a file the scene names or a generator it calls throws, prefixed with where in the scene
// file it was asked for (the scene's path and the entry).
template <class F> auto inScene(const std::string& where, F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const Error& e) { fail(where, ": ", e.what()); }
}

void allowKeys(const json& j, std::initializer_list<const char*> keys, const std::string& where) {
    if (!j.is_object()) fail(where, ": expected a JSON object");
    for (const auto& [key, value] : j.items()) {
        bool ok = false;
        for (const char* k : keys) ok = ok || key == k;
        if (!ok) {
            std::string list;
            for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
            fail(where, ": unknown key \"", key, "\" (allowed: ", list, ")");
        }
    }
}

Vec3d vec3(const json& j, const char* key, const std::string& where) {
    const json& v = j.at(key);
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
        fail(where, ": \"", key, "\" must be an array of 3 numbers");
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

Vec3d vec3Or(const json& j, const char* key, Vec3d fallback, const std::string& where) {
    return j.contains(key) ? vec3(j, key, where) : fallback;
}

double num(const json& j, const char* key, double fallback, const std::string& where) {
    if (!j.contains(key)) return fallback;
    if (!j[key].is_number()) fail(where, ": \"", key, "\" must be a number");
    return j[key].get<double>();
}

// A render setting's value: on/off, a whole or real number, a name, or three numbers.
OptionValue settingValue(const json& j, const std::string& where) {
    if (j.is_boolean()) return j.get<bool>();
    if (j.is_number_unsigned()) { // past int64_t: a double, which the range check then refuses
        const uint64_t u = j.get<uint64_t>();
        return u > uint64_t(INT64_MAX) ? OptionValue(double(u)) : OptionValue(int64_t(u));
    }
    if (j.is_number_integer()) return j.get<int64_t>();
    if (j.is_number()) return j.get<double>();
    if (j.is_string()) return j.get<std::string>();
    if (j.is_array() && j.size() == 3 && j[0].is_number() && j[1].is_number() && j[2].is_number())
        return Vec3d{j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
    fail(where, ": expected true or false, a number, a name or [x, y, z]");
}

// A whole number in [lo, hi] (checked before any conversion: a double out of the target type's
// range, or NaN, would make it undefined behaviour).
int64_t wholeNumber(double v, double lo, double hi, const char* key, const std::string& where) {
    if (!(v >= lo && v <= hi) || v != std::floor(v))
        fail(where, ": \"", key, "\" must be a whole number in [", lo, ", ", hi, "], got ", v);
    return int64_t(v);
}

std::string str(const json& j, const char* key, const std::string& where) {
    if (!j.contains(key)) return {};
    if (!j[key].is_string()) fail(where, ": \"", key, "\" must be a string");
    return j[key].get<std::string>();
}

Material wrapperMaterial(const json& j, const std::string& where) {
    allowKeys(j,
              {"name", "baseColor", "opacity", "transmission", "ior", "specular", "shininess", "doubleSided",
               "blend", "diffuseTransmission", "diffuseTransmissionColor", "attenuationDistance",
               "attenuationColor"},
              where);
    Material m;
    m.name = j.contains("name") ? str(j, "name", where) : "material";
    m.baseColor = Vec3f(vec3Or(j, "baseColor", Vec3d(m.baseColor), where));
    m.opacity = float(num(j, "opacity", m.opacity, where));
    m.transmission = float(num(j, "transmission", m.transmission, where));
    m.ior = float(num(j, "ior", m.ior, where));
    m.specular = float(num(j, "specular", m.specular, where));
    m.shininess = float(num(j, "shininess", m.shininess, where));
    m.doubleSided = j.value("doubleSided", false);
    // A translucent solid (Material::diffuseTransmission) and its volume attenuation.
    m.diffuseTransmission = float(num(j, "diffuseTransmission", m.diffuseTransmission, where));
    m.diffuseTransmissionColor =
        Vec3f(vec3Or(j, "diffuseTransmissionColor", Vec3d(m.diffuseTransmissionColor), where));
    m.attenuationDistance = float(num(j, "attenuationDistance", m.attenuationDistance, where));
    m.attenuationColor = Vec3f(vec3Or(j, "attenuationColor", Vec3d(m.attenuationColor), where));
    // A material the author made see-through is drawn see-through, unless "blend": false (foliage).
    if (j.contains("blend") && !j["blend"].is_boolean()) fail(where, ": \"blend\" must be true or false");
    m.blend = j.value("blend", m.opacity < 1);
    return m;
}

// S, then R (axis, degrees), then T.
Mat4d wrapperTransform(const json& j, const std::string& where) {
    Mat4d s, r, t;
    if (j.contains("scale")) {
        const json& v = j["scale"];
        const Vec3d sc = v.is_number() ? Vec3d{v.get<double>(), v.get<double>(), v.get<double>()}
                                       : vec3(j, "scale", where);
        for (int i = 0; i < 3; ++i) s.m[i][i] = sc[i];
    }
    if (j.contains("rotate")) {
        const json& v = j["rotate"];
        if (!v.is_array() || v.size() != 4) fail(where, ": \"rotate\" must be [axis x, y, z, degrees]");
        const Vec3d axis = normalize(Vec3d{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()});
        if (!(length(axis) > 0)) fail(where, ": \"rotate\" has a zero axis");
        const double a = v[3].get<double>() * M_PI / 180, c = std::cos(a), sn = std::sin(a);
        const double x = axis.x, y = axis.y, z = axis.z;
        const double rm[3][3] = {{c + x * x * (1 - c), x * y * (1 - c) - z * sn, x * z * (1 - c) + y * sn},
                                 {y * x * (1 - c) + z * sn, c + y * y * (1 - c), y * z * (1 - c) - x * sn},
                                 {z * x * (1 - c) - y * sn, z * y * (1 - c) + x * sn, c + z * z * (1 - c)}};
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) r.m[i][k] = rm[i][k];
    }
    const Vec3d tr = vec3Or(j, "translate", {0, 0, 0}, where);
    for (int i = 0; i < 3; ++i) t.m[i][3] = tr[i];
    return t * r * s;
}

// Moves the mesh by xf; a mirroring transform (negative determinant) reverses the triangles'
// winding so that they keep facing out.
void placeMesh(Mesh& mesh, const Mat4d& xf) {
    for (Vec3f& p : mesh.positions) p = Vec3f(xf.point(Vec3d(p)));
    const double det = xf.m[0][0] * (xf.m[1][1] * xf.m[2][2] - xf.m[1][2] * xf.m[2][1]) -
                       xf.m[0][1] * (xf.m[1][0] * xf.m[2][2] - xf.m[1][2] * xf.m[2][0]) +
                       xf.m[0][2] * (xf.m[1][0] * xf.m[2][1] - xf.m[1][1] * xf.m[2][0]);
    if (det < 0)
        for (std::size_t t = 0; t < mesh.indices.size(); t += 3)
            std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
}

// ---- volume objects and Boolean shapes (deep shadow maps) ---------------------------------------

struct SceneObjectsParser {
    Scene& scene;
    VolumeScene& vs;
    std::function<std::string(const std::string&)> resolve; // a scene file's names against its folder

    // A shape expression; returns its node. `volumeBox` is the object's volume's box mesh (turned
    // with the volume), or null outside volume objects.
    int32_t shape(const json& j, const Mesh* volumeBox, const std::string& where, bool& plainMesh,
                  Mesh* meshOut) {
        if (!j.is_object() || j.size() == 0) fail(where, ": a shape must be a JSON object");
        for (const auto& [op, what] : {std::pair<const char*, ShapeOp>{"union", ShapeOp::Union},
                                       {"intersection", ShapeOp::Intersection},
                                       {"difference", ShapeOp::Difference}}) {
            if (!j.contains(op)) continue;
            allowKeys(j, {op}, where);
            const json& args = j[op];
            if (!args.is_array() || args.size() < 2 || (what == ShapeOp::Difference && args.size() != 2))
                fail(where, ": \"", op, "\" needs ",
                     what == ShapeOp::Difference ? "two shapes" : "two or more shapes");
            bool dummy = false;
            int32_t node = shape(args[0], volumeBox, concat(where, ".", op, "[0]"), dummy, nullptr);
            for (std::size_t i = 1; i < args.size(); ++i)
                node = vs.addNode(
                    what, node,
                    shape(args[i], volumeBox, concat(where, ".", op, "[", i, "]"), dummy, nullptr));
            plainMesh = false;
            return node;
        }
        Mesh mesh;
        if (j.contains("mesh")) {
            allowKeys(j, {"mesh", "translate", "scale", "rotate"}, where);
            mesh = inScene(where, [&] { return loadMesh(resolve(str(j, "mesh", where))); });
            placeMesh(mesh, wrapperTransform(j, where));
        } else if (j.contains("box")) {
            allowKeys(j, {"box"}, where);
            const json& b = j["box"];
            if (!b.is_array() || b.size() != 2) fail(where, ": \"box\" must be [[lo x, y, z], [hi x, y, z]]");
            const json pair = {{"lo", b[0]}, {"hi", b[1]}};
            Box3d box;
            box.lo = vec3(pair, "lo", where + ".box");
            box.hi = vec3(pair, "hi", where + ".box");
            if (!(box.lo.x < box.hi.x && box.lo.y < box.hi.y && box.lo.z < box.hi.z))
                fail(where, ": \"box\" needs lo < hi on every axis");
            mesh = boxMesh(box);
        } else if (j.contains("volumeBox")) {
            allowKeys(j, {"volumeBox"}, where);
            if (!volumeBox) fail(where, ": \"volumeBox\" outside a volume object");
            mesh = *volumeBox;
        } else {
            fail(where, ": unknown shape (expected mesh, box, volumeBox, union, intersection or difference)");
        }
        plainMesh = true;
        if (meshOut) *meshOut = mesh;
        return vs.addLeaf(std::move(mesh));
    }

    void object(const json& o, const std::string& whereIn) {
        allowKeys(o,
                  {"name", "kind", "opacity", "color", "shape", "castsShadow", "volume", "translate", "scale",
                   "rotate", "transfer", "opacityLength"},
                  whereIn);
        VolumeSceneObject out;
        out.name = o.contains("name") ? str(o, "name", whereIn) : "object";
        const std::string where = concat(whereIn, " '", out.name, "'");
        const std::string kind = o.contains("kind") ? str(o, "kind", where) : "opaque";
        out.castsShadow = o.value("castsShadow", true);
        out.color = Vec3f(vec3Or(o, "color", Vec3d(out.color), where));
        if (kind == "volume") {
            out.kind = ObjectKind::Volume;
            if (!o.contains("volume")) fail(where, ": a volume object needs \"volume\"");
            const json& v = o["volume"];
            Volume volume;
            if (v.is_string()) {
                volume = inScene(where, [&] { return loadVolume(resolve(v.get<std::string>())); });
            } else if (v.is_object() && v.contains("file")) {
                // {"file": "smoke.vdb", "grid": "density"}: a named grid of an OpenVDB file.
                allowKeys(v, {"file", "grid"}, where + ".volume");
                VolumeLoadOptions lo;
                if (v.contains("grid")) lo.vdbGrid = str(v, "grid", where + ".volume");
                volume = inScene(where,
                                 [&] { return loadVolume(resolve(str(v, "file", where + ".volume")), lo); });
            } else if (v.is_object() && v.contains("smoke")) {
                const json& sm = v["smoke"];
                allowKeys(sm, {"dims", "box", "seed", "octaves", "frequency"}, where + ".volume.smoke");
                SmokeParams p;
                if (sm.contains("dims")) {
                    const Vec3d d = vec3(sm, "dims", where);
                    const std::string w = where + ".volume.smoke";
                    p.dims = {wholeNumber(d.x, 1, 2147483647.0, "dims", w),
                              wholeNumber(d.y, 1, 2147483647.0, "dims", w),
                              wholeNumber(d.z, 1, 2147483647.0, "dims", w)};
                }
                if (sm.contains("box")) {
                    const json& b = sm["box"];
                    if (!b.is_array() || b.size() != 2) fail(where, ": smoke \"box\" must be [[lo], [hi]]");
                    const json pair = {{"lo", b[0]}, {"hi", b[1]}};
                    p.box.lo = vec3(pair, "lo", where);
                    p.box.hi = vec3(pair, "hi", where);
                }
                p.seed =
                    uint32_t(wholeNumber(num(sm, "seed", p.seed, where), 0, 4294967295.0, "seed", where));
                p.octaves = int(wholeNumber(num(sm, "octaves", p.octaves, where), 1, 16, "octaves", where));
                p.frequency = num(sm, "frequency", p.frequency, where);
                volume = inScene(where + ".volume.smoke", [&] { return makeSmoke(p); });
            } else {
                fail(
                    where,
                    ": \"volume\" must be a file name, {\"file\": ..., \"grid\": ...} or {\"smoke\": {...}}");
            }
            // Placement: world = rotate(file position * scale) + translate (scale, then rotate
            // [axis, degrees] about the file's origin, then translate, as for meshes).
            const double scale = num(o, "scale", 1, where);
            if (!(scale > 0) || !std::isfinite(scale)) fail(where, ": \"scale\" must be a positive number");
            const Vec3d tr = vec3Or(o, "translate", {0, 0, 0}, where);
            const bool turned = o.contains("rotate");
            const Mat4d r = turned ? wrapperTransform(json{{"rotate", o["rotate"]}}, where) : Mat4d{};
            Volume placed(volume.dims(), (turned ? r.vector(volume.lo() * scale) : volume.lo() * scale) + tr,
                          volume.spacing() * scale, volume.sourceType());
            if (turned || !volume.axisAligned())
                inScene(where, [&] {
                    placed.setAxes(r.vector(volume.axis(0)), r.vector(volume.axis(1)),
                                   r.vector(volume.axis(2)));
                });
            placed.values() = std::move(volume.values());
            if (!o.contains("transfer")) fail(where, ": a volume object needs \"transfer\"");
            const json& t = o["transfer"];
            out.transfer =
                t.is_string()
                    ? inScene(where, [&] { return loadTransferFunction(resolve(t.get<std::string>())); })
                    : parseTransferFunction(t.dump(), where + ".transfer");
            const Vec3d sp = placed.spacing();
            out.opacityLength = num(o, "opacityLength", std::min({sp.x, sp.y, sp.z}), where);
            const Mesh box = placed.boxMesh();
            vs.volumes.push_back(std::make_shared<const Volume>(std::move(placed)));
            out.volume = int32_t(vs.volumes.size() - 1);
            bool plain = false;
            out.shape = o.contains("shape") ? shape(o["shape"], &box, where + ".shape", plain, nullptr)
                                            : vs.addLeaf(box);
            vs.addObject(std::move(out));
            return;
        }
        if (kind != "opaque" && kind != "translucent")
            fail(where, ": unknown kind \"", kind, "\" (allowed: opaque, translucent, volume)");
        for (const char* k : {"volume", "transfer", "opacityLength", "translate", "scale", "rotate"})
            if (o.contains(k)) fail(where, ": \"", k, "\" is only for volume objects");
        out.kind = kind == "opaque" ? ObjectKind::Opaque : ObjectKind::Translucent;
        out.opacity = kind == "opaque" ? 1.0f : float(num(o, "opacity", 0.5, where));
        if (!(out.opacity >= 0 && out.opacity <= 1)) fail(where, ": \"opacity\" must be in [0, 1]");
        if (!o.contains("shape")) fail(where, ": needs \"shape\"");
        bool plain = false;
        Mesh mesh;
        const std::size_t leaves = vs.leaves.size(), nodes = vs.nodes.size();
        const int32_t node = shape(o["shape"], nullptr, where + ".shape", plain, &mesh);
        if (plain) {
            // A single mesh: an ordinary scene mesh, drawn and shadowed like the others.
            vs.leaves.resize(leaves);
            vs.nodes.resize(nodes);
            Material m;
            m.name = out.name;
            m.baseColor = out.color;
            m.opacity = out.opacity;
            m.blend = true; // the camera sees through a translucent object
            SceneMesh sm;
            sm.name = out.name;
            sm.mesh = std::move(mesh);
            sm.material = scene.addMaterial(m);
            sm.castsShadow = out.castsShadow;
            scene.meshes.push_back(std::move(sm));
            return;
        }
        out.shape = node;
        vs.addObject(std::move(out));
    }
};

// The wrapper's text; `path` names it in messages and anchors its relative file names.
// Resolves a name the scene file gives against the file's folder.
using Resolve = std::function<std::string(const std::string&)>;

// "meshes": extra meshes in any mesh format, placed and given a material. Wrapper meshes without a
// material get a default one, never the glTF's first material (which may be a leaf or glass: a
// partial occluder).
void wrapperMeshes(const json& doc, const std::string& path, const Resolve& resolve, Scene& scene) {
    int defaultMaterial = scene.materials.empty() ? int(scene.addMaterial(Material{})) : -1;
    auto defaultIndex = [&] {
        if (defaultMaterial < 0) {
            Material d;
            d.name = "default";
            defaultMaterial = int(scene.addMaterial(d));
        }
        return uint32_t(defaultMaterial);
    };
    const json meshes = doc.value("meshes", json::array());
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        const json& m = meshes[i];
        const std::string where = concat(path, ": meshes[", i, "]");
        allowKeys(m, {"file", "name", "translate", "scale", "rotate", "material", "castsShadow"}, where);
        if (!m.contains("file")) fail(where, ": needs \"file\"");
        SceneMesh out;
        out.mesh = inScene(where, [&] { return loadMesh(resolve(str(m, "file", where))); });
        out.name = m.contains("name") ? str(m, "name", where)
                                      : std::filesystem::path(str(m, "file", where)).stem().string();
        placeMesh(out.mesh, wrapperTransform(m, where));
        out.material = m.contains("material")
                           ? scene.addMaterial(wrapperMaterial(m["material"], where + ".material"))
                           : defaultIndex();
        out.castsShadow = m.value("castsShadow", true);
        scene.meshes.push_back(std::move(out));
    }
}

// "lights": point, spot and directional lights (a direction, or a target to look at).
void wrapperLights(const json& doc, const std::string& path, Scene& scene) {
    const json lights = doc.value("lights", json::array());
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const json& l = lights[i];
        std::string where = concat(path, ": lights[", i, "]");
        allowKeys(l,
                  {"type", "name", "position", "direction", "target", "color", "intensity",
                   "innerConeDegrees", "outerConeDegrees"},
                  where);
        Light out;
        out.name = l.contains("name") ? str(l, "name", where) : concat("light", i);
        where += concat(" '", out.name, "'");
        const std::string type = str(l, "type", where);
        out.type = detail::parseLightType(type, where);
        if (out.type != LightType::Directional) {
            if (!l.contains("position")) fail(where, ": a ", type, " light needs \"position\"");
            out.position = vec3(l, "position", where);
        }
        if (out.type != LightType::Point) {
            if (l.contains("direction"))
                out.direction = vec3(l, "direction", where);
            else if (l.contains("target"))
                out.direction = vec3(l, "target", where) - out.position;
            else
                fail(where, ": a ", type, " light has no direction: give \"direction\" or \"target\"");
            if (!(length(out.direction) > 0)) fail(where, ": the light's direction is zero");
            out.direction = normalize(out.direction);
        }
        out.color = Vec3f(vec3Or(l, "color", {1, 1, 1}, where));
        out.intensity = float(num(l, "intensity", 1, where));
        out.innerConeAngle = num(l, "innerConeDegrees", 0, where) * M_PI / 180;
        out.outerConeAngle = num(l, "outerConeDegrees", 45, where) * M_PI / 180;
        scene.lights.push_back(out);
    }
}

// "cameras": they come first, before the glTF's: they are the ones the author meant.
void wrapperCameras(const json& doc, const std::string& path, Scene& scene) {
    const json cameras = doc.value("cameras", json::array());
    for (std::size_t i = 0; i < cameras.size(); ++i) {
        const json& c = cameras[i];
        const std::string where = concat(path, ": cameras[", i, "]");
        allowKeys(c, {"name", "position", "target", "up", "fovYDegrees", "fovY", "near", "far"}, where);
        if (!c.contains("position") || !c.contains("target"))
            fail(where, ": needs \"position\" and \"target\"");
        Camera out;
        out.name = c.contains("name") ? str(c, "name", where) : concat("camera", i);
        out.position = vec3(c, "position", where);
        out.target = vec3(c, "target", where);
        out.up = vec3Or(c, "up", {0, 1, 0}, where);
        // "fovY" in radians (what Camera holds: a saved view keeps it bit for bit), or "fovYDegrees".
        if (c.contains("fovY") && c.contains("fovYDegrees"))
            fail(where, ": give \"fovY\" (radians) or \"fovYDegrees\", not both");
        out.fovY =
            c.contains("fovY") ? num(c, "fovY", 0, where) : num(c, "fovYDegrees", 45, where) * M_PI / 180;
        out.nearDepth = num(c, "near", 0.01, where);
        out.farDepth = num(c, "far", 1.0e4, where);
        scene.cameras.insert(scene.cameras.begin() + std::ptrdiff_t(i), out);
    }
}

// "receiversOnly" (meshes that cast no shadow), "render" (named render settings, checked here
// against what the renderer takes) and "environmentMap".
void wrapperSettings(const json& doc, const std::string& path, const Resolve& resolve, Scene& scene) {
    for (const json& name : doc.value("receiversOnly", json::array())) {
        bool found = false;
        for (SceneMesh& m : scene.meshes)
            if (m.name == name.get<std::string>()) {
                m.castsShadow = false;
                found = true;
            }
        if (!found)
            fail(path, ": receiversOnly names mesh '", name.get<std::string>(), "', which does not exist");
    }
    if (doc.contains("render")) {
        const json& r = doc["render"];
        const std::string where = path + ": render";
        if (!r.is_object()) fail(where, ": expected a JSON object");
        for (const auto& [key, value] : r.items()) {
            const OptionValue v = settingValue(value, concat(where, ".", key));
            checkRenderSetting(key, v, where);
            // A setting of the scene this one adds to ("scene") gives way to this file's.
            // (A copy of the name: clang 14 cannot capture a structured binding.)
            const std::string name = camelCase(key);
            std::erase_if(scene.settings.render,
                          [&](const auto& setting) { return camelCase(setting.first) == name; });
            scene.settings.render.emplace_back(key, v);
        }
    }
    if (doc.contains("environmentMap")) {
        // "sky" is the procedural sky (as loadEnvironment reads it), not a file beside the scene.
        const std::string map = str(doc, "environmentMap", path);
        scene.settings.environmentMap = map == "sky" ? map : resolve(map);
    }
}

// "objects": volume objects and Boolean shapes, as one volume scene.
void wrapperObjects(const json& doc, const std::string& path, const Resolve& resolve, Scene& scene) {
    if (!doc.contains("objects")) return;
    const json& objects = doc["objects"];
    if (!objects.is_array()) fail(path, ": \"objects\" must be an array");
    auto vs = std::make_shared<VolumeScene>();
    SceneObjectsParser parser{scene, *vs, resolve};
    for (std::size_t i = 0; i < objects.size(); ++i)
        parser.object(objects[i], concat(path, ": objects[", i, "]"));
    vs->validate();
    if (!vs->objects.empty()) scene.volumeScene = std::move(vs);
}

Scene loadSceneFile(const std::string& path, std::vector<std::filesystem::path>& chain);

Scene parseWrapper(std::string_view text, const std::string& path,
                   std::vector<std::filesystem::path>& chain) {
    json doc;
    try {
        doc = json::parse(text);
    } catch (const json::exception& e) {
        // parse_error, and out_of_range for a number past double's range (1e999)
        fail(path, ": malformed JSON: ", e.what());
    }
    const std::filesystem::path dir = std::filesystem::path(path).parent_path();
    const Resolve resolve = [dir](const std::string& p) {
        return std::filesystem::path(p).is_absolute() ? p : (dir / p).string();
    };
    Scene scene;
    try {
        allowKeys(doc,
                  {"scene", "gltf", "meshes", "lights", "cameras", "receiversOnly", "render",
                   "environmentMap", "objects"},
                  path);
        if (doc.contains("scene") && doc.contains("gltf"))
            fail(path, ": give \"scene\" or \"gltf\", not both");
        if (doc.contains("gltf")) scene = detail::loadGltfScene(resolve(str(doc, "gltf", path)));
        // "scene": any scene file this one adds to (glTF, another wrapper, a mesh).
        if (doc.contains("scene")) {
            const std::string base = resolve(str(doc, "scene", path));
            scene = inScene(path + ": scene", [&] { return loadSceneFile(base, chain); });
            if (doc.contains("objects") && scene.volumeScene)
                fail(path, ": \"objects\": the scene '", base,
                     "' has objects already (give them all in one of the two files)");
        }
        wrapperMeshes(doc, path, resolve, scene);
        wrapperLights(doc, path, scene);
        wrapperCameras(doc, path, scene);
        wrapperSettings(doc, path, resolve, scene);
        wrapperObjects(doc, path, resolve, scene);
    } catch (const json::exception& e) { fail(path, ": unexpected content: ", e.what()); }
    scene.source = path;
    return scene;
}

// ---- glTF writer ---------------------------------------------------------------------------------

std::string base64(const std::string& bytes) {
    static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t b0 = uint8_t(bytes[i]), b1 = i + 1 < bytes.size() ? uint8_t(bytes[i + 1]) : 0,
                       b2 = i + 2 < bytes.size() ? uint8_t(bytes[i + 2]) : 0;
        const uint32_t v = (b0 << 16) | (b1 << 8) | b2;
        out += table[(v >> 18) & 63];
        out += table[(v >> 12) & 63];
        out += i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? table[v & 63] : '=';
    }
    return out;
}

// Column-major matrix of a node whose -Z axis points along `forward` (lights, cameras).
json orientedNodeMatrix(const Vec3d& position, const Vec3d& forward, const Vec3d& upHint) {
    const Vec3d z = -normalize(forward);
    Vec3d x = cross(upHint, z);
    if (!(length(x) > 1e-9)) x = cross(Vec3d{1, 0, 0}, z);
    if (!(length(x) > 1e-9)) x = cross(Vec3d{0, 1, 0}, z);
    x = normalize(x);
    const Vec3d y = cross(z, x);
    return json::array(
        {x.x, x.y, x.z, 0, y.x, y.y, y.z, 0, z.x, z.y, z.z, 0, position.x, position.y, position.z, 1});
}

} // namespace

namespace {

// loadScene, with the wrappers whose "scene" led here (`chain`, outermost first): a wrapper that
// names itself, directly or through others, is refused instead of recursing without end.
Scene loadSceneFile(const std::string& path, std::vector<std::filesystem::path>& chain) {
    const std::string ext = fileExtension(path);
    Scene scene;
    if (ext == ".gltf" || ext == ".glb") {
        scene = detail::loadGltfScene(path);
    } else if (ext == ".json") {
        std::error_code ec;
        std::filesystem::path canonical = std::filesystem::weakly_canonical(path, ec);
        if (ec) canonical = std::filesystem::absolute(path);
        for (const std::filesystem::path& p : chain)
            if (p == canonical) fail(path, ": the scene includes itself (through \"scene\")");
        chain.push_back(canonical);
        scene = parseWrapper(detail::readTextFile(path, "scene file"), path, chain);
        chain.pop_back();
    } else if (ext == ".off" || ext == ".obj" || ext == ".ply" || ext == ".stl" || ext == ".fbx" ||
               ext == ".dae" || ext == ".3ds") {
        SceneMesh m;
        m.mesh = loadMesh(path);
        m.name = std::filesystem::path(path).stem().string();
        scene.addMaterial(Material{});
        scene.meshes.push_back(std::move(m));
        scene.source = path;
    } else {
        fail(path, ": unknown scene extension '", ext.empty() ? std::string("(none)") : ext,
             "' (allowed: .gltf .glb .json, or a mesh: .off .obj .ply .stl .fbx .dae .3ds)");
    }
    scene.source = path;
    scene.validate();
    return scene;
}

} // namespace

Scene loadScene(const std::string& path) {
    std::vector<std::filesystem::path> chain;
    return loadSceneFile(path, chain);
}

Scene parseSceneJson(std::string_view text, const std::string& path) {
    std::vector<std::filesystem::path> chain;
    Scene scene = parseWrapper(text, path, chain);
    scene.source = path;
    scene.validate();
    return scene;
}

namespace {

// What writeGltf assembles: the JSON arrays of the document and the binary buffer they point into.
struct GltfWriter {
    std::string bin;
    json bufferViews = json::array(), accessors = json::array(), meshes = json::array(),
         nodes = json::array(), materials = json::array(), lights = json::array(), cameras = json::array();
    std::set<std::string> used; ///< extensions

    // A buffer view of `bytes` at the end of the buffer (4-byte aligned); its index.
    std::size_t addView(const void* data, std::size_t bytes, int target) {
        while (bin.size() % 4) bin.push_back('\0');
        bufferViews.push_back(
            {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}, {"target", target}});
        bin.append(static_cast<const char*>(data), bytes);
        return bufferViews.size() - 1;
    }

    // A mesh in world space under an identity node: positions, normals when present, indices.
    void mesh(const SceneMesh& m) {
        const std::size_t nv = m.mesh.positions.size();
        Box3d all; // accessor min/max cover every vertex (glTF requires them for POSITION)
        for (const Vec3f& p : m.mesh.positions) all.extend(Vec3d(p));
        const std::size_t pv = addView(m.mesh.positions.data(), nv * sizeof(Vec3f), 34962);
        accessors.push_back({{"bufferView", pv},
                             {"componentType", 5126},
                             {"count", nv},
                             {"type", "VEC3"},
                             {"min", {float(all.lo.x), float(all.lo.y), float(all.lo.z)}},
                             {"max", {float(all.hi.x), float(all.hi.y), float(all.hi.z)}}});
        json attributes = {{"POSITION", accessors.size() - 1}};
        if (!m.normals.empty()) {
            const std::size_t nvw = addView(m.normals.data(), nv * sizeof(Vec3f), 34962);
            accessors.push_back(
                {{"bufferView", nvw}, {"componentType", 5126}, {"count", nv}, {"type", "VEC3"}});
            attributes["NORMAL"] = accessors.size() - 1;
        }
        const std::size_t iv = addView(m.mesh.indices.data(), m.mesh.indices.size() * 4, 34963);
        accessors.push_back({{"bufferView", iv},
                             {"componentType", 5125},
                             {"count", m.mesh.indices.size()},
                             {"type", "SCALAR"}});
        meshes.push_back({{"name", m.name},
                          {"primitives",
                           {{{"attributes", attributes},
                             {"indices", accessors.size() - 1},
                             {"material", m.material},
                             {"mode", 4}}}}});
        json node = {{"name", m.name}, {"mesh", meshes.size() - 1}};
        if (!m.castsShadow) node["extras"] = {{"voxfx", {{"castsShadow", false}}}};
        nodes.push_back(node);
    }

    // A material with its extensions (transmission, diffuse transmission, ior, volume).
    void material(const Material& m) {
        // roughness from the Blinn–Phong exponent (inverse of the loader's mapping).
        const double a = std::sqrt(2.0 / (double(m.shininess) + 2.0));
        json mat = {{"name", m.name},
                    {"pbrMetallicRoughness",
                     {{"baseColorFactor", {m.baseColor.x, m.baseColor.y, m.baseColor.z, m.opacity}},
                      {"metallicFactor", 0.0},
                      {"roughnessFactor", std::clamp(std::sqrt(a), 0.0, 1.0)}}},
                    // MASK with cutoff 0: drawn solid (foliage), its opacity kept for the shadows.
                    {"alphaMode", m.opacity < 1 ? (m.blend ? "BLEND" : "MASK") : "OPAQUE"},
                    {"doubleSided", m.doubleSided},
                    {"extras", {{"voxfx", {{"specular", m.specular}, {"shininess", m.shininess}}}}}};
        if (m.opacity < 1 && !m.blend) mat["alphaCutoff"] = 0.0;
        json matExt = json::object();
        if (m.transmission > 0) {
            matExt["KHR_materials_transmission"] = {{"transmissionFactor", m.transmission}};
            used.insert("KHR_materials_transmission");
        }
        if (m.diffuseTransmission > 0) {
            matExt["KHR_materials_diffuse_transmission"] = {
                {"diffuseTransmissionFactor", m.diffuseTransmission},
                {"diffuseTransmissionColorFactor",
                 {m.diffuseTransmissionColor.x, m.diffuseTransmissionColor.y, m.diffuseTransmissionColor.z}}};
            used.insert("KHR_materials_diffuse_transmission");
        }
        if (m.ior != 1.5f) {
            matExt["KHR_materials_ior"] = {{"ior", m.ior}};
            used.insert("KHR_materials_ior");
        }
        if (m.thickness > 0 || std::isfinite(m.attenuationDistance)) {
            json v = {
                {"thicknessFactor", m.thickness},
                {"attenuationColor", {m.attenuationColor.x, m.attenuationColor.y, m.attenuationColor.z}}};
            if (std::isfinite(m.attenuationDistance)) v["attenuationDistance"] = m.attenuationDistance;
            matExt["KHR_materials_volume"] = v;
            used.insert("KHR_materials_volume");
        }
        if (!matExt.empty()) mat["extensions"] = matExt;
        materials.push_back(mat);
    }

    // A KHR_lights_punctual light and the node that places it.
    void light(const Light& l) {
        json out = {{"name", l.name},
                    {"type", toString(l.type)},
                    {"color", {l.color.x, l.color.y, l.color.z}},
                    {"intensity", l.intensity}};
        if (l.range > 0) out["range"] = l.range;
        if (l.type == LightType::Spot)
            out["spot"] = {{"innerConeAngle", l.innerConeAngle}, {"outerConeAngle", l.outerConeAngle}};
        lights.push_back(out);
        const Vec3d dir = l.type == LightType::Point ? Vec3d{0, 0, -1} : l.direction;
        nodes.push_back(
            {{"name", l.name},
             {"matrix",
              orientedNodeMatrix(l.type == LightType::Directional ? Vec3d{} : l.position, dir, {0, 1, 0})},
             {"extensions", {{"KHR_lights_punctual", {{"light", lights.size() - 1}}}}}});
    }

    // A perspective camera and the node that places it.
    void camera(const Camera& c) {
        cameras.push_back(
            {{"name", c.name},
             {"type", "perspective"},
             {"perspective", {{"yfov", c.fovY}, {"znear", c.nearDepth}, {"zfar", c.farDepth}}}});
        nodes.push_back({{"name", c.name.empty() ? std::string("camera") : c.name},
                         {"camera", cameras.size() - 1},
                         {"matrix", orientedNodeMatrix(c.position, c.target - c.position, c.up)}});
    }

    // The document; the buffer is embedded as a data URI unless it goes into a GLB container.
    json document(bool glb) {
        json doc;
        doc["asset"] = {{"version", "2.0"}, {"generator", "voxfx"}};
        if (!lights.empty()) {
            used.insert("KHR_lights_punctual");
            doc["extensions"] = {{"KHR_lights_punctual", {{"lights", lights}}}};
        }
        json roots = json::array();
        for (std::size_t i = 0; i < nodes.size(); ++i) roots.push_back(i);
        doc["scene"] = 0;
        doc["scenes"] = {{{"nodes", roots}}};
        doc["nodes"] = nodes;
        if (!meshes.empty()) doc["meshes"] = meshes;
        if (!materials.empty()) doc["materials"] = materials;
        if (!cameras.empty()) doc["cameras"] = cameras;
        if (!used.empty()) doc["extensionsUsed"] = json(used);
        while (bin.size() % 4) bin.push_back('\0');
        if (!bin.empty()) {
            doc["accessors"] = accessors;
            doc["bufferViews"] = bufferViews;
            json buffer = {{"byteLength", bin.size()}};
            if (!glb) buffer["uri"] = "data:application/octet-stream;base64," + base64(bin);
            doc["buffers"] = json::array({buffer});
        }
        return doc;
    }
};

// The .gltf text, or the .glb container (header, JSON chunk, binary chunk), written atomically.
void writeGltfFile(const std::string& path, std::string text, const std::string& bin, bool glb) {
    detail::AtomicFile file(path);
    std::ostream& out = file.stream();
    if (!glb) {
        out << text;
    } else {
        while (text.size() % 4) text.push_back(' ');
        auto u32 = [&](uint32_t v) { out.write(reinterpret_cast<const char*>(&v), 4); };
        const std::size_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size());
        if (total > 0xffffffffu) fail(path, ": the scene is too large for a GLB file (4 GiB)");
        u32(0x46546C67u);
        u32(2);
        u32(uint32_t(total));
        u32(uint32_t(text.size()));
        u32(0x4E4F534Au);
        out << text;
        if (!bin.empty()) {
            u32(uint32_t(bin.size()));
            u32(0x004E4942u);
            out.write(bin.data(), std::streamsize(bin.size()));
        }
    }
    file.commit();
}

} // namespace

void writeGltf(const Scene& scene, const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext != ".gltf" && ext != ".glb") fail(path, ": a glTF file needs the extension .gltf or .glb");
    scene.validate();
    GltfWriter w;
    for (const SceneMesh& m : scene.meshes) w.mesh(m);
    for (const Material& m : scene.materials) w.material(m);
    for (const Light& l : scene.lights) w.light(l);
    for (const Camera& c : scene.cameras) w.camera(c);
    const bool glb = ext == ".glb";
    const json doc = w.document(glb);
    writeGltfFile(path, doc.dump(), w.bin, glb);
}

namespace {

nlohmann::ordered_json vecJson(const Vec3d& v, const std::string& where) {
    if (!isFinite(v)) fail(where, ": not a finite vector");
    return nlohmann::ordered_json::array({v.x, v.y, v.z});
}

nlohmann::ordered_json numberJson(double v, const std::string& where) {
    if (!std::isfinite(v)) fail(where, ": not a finite number (", v, ")");
    return v;
}

} // namespace

void writeSceneView(const SceneView& view, const std::string& path) {
    using ojson = nlohmann::ordered_json;
    if (fileExtension(path) != ".json")
        fail(path, ": a scene view is a JSON wrapper: use the extension .json");
    // Written by hand around compact values: one line per camera field and per setting.
    auto quoted = [](const std::string& s) { return ojson(s).dump(); };
    std::string text = "{";
    const char* comma = "\n";
    if (!view.scene.empty()) {
        text += concat(comma, "  \"scene\": ", quoted(view.scene));
        comma = ",\n";
    }
    if (!view.cameras.empty()) {
        text += concat(comma, "  \"cameras\": [");
        for (std::size_t i = 0; i < view.cameras.size(); ++i) {
            const Camera& c = view.cameras[i];
            const std::string where = concat(path, ": cameras[", i, "]");
            text += concat(i ? ",\n" : "\n", "    {");
            if (!c.name.empty()) text += concat("\"name\": ", quoted(c.name), ",\n     ");
            text += concat("\"position\": ", vecJson(c.position, where + ".position").dump(), ",\n     ");
            text += concat("\"target\": ", vecJson(c.target, where + ".target").dump(), ",\n     ");
            text += concat("\"up\": ", vecJson(c.up, where + ".up").dump(), ",\n     ");
            text += concat("\"fovY\": ", numberJson(c.fovY, where + ".fovY").dump(), ", ");
            text += concat("\"near\": ", numberJson(c.nearDepth, where + ".near").dump(), ", ");
            text += concat("\"far\": ", numberJson(c.farDepth, where + ".far").dump(), "}");
        }
        text += "\n  ]";
        comma = ",\n";
    }
    if (!view.render.empty()) {
        text += concat(comma, "  \"render\": {");
        for (std::size_t i = 0; i < view.render.size(); ++i) {
            const auto& [name, value] = view.render[i];
            const std::string where = concat(path, ": render.", name);
            const ojson v = std::visit(
                [&]<class T>(const T& x) -> ojson {
                    if constexpr (std::is_same_v<T, Vec3d>)
                        return vecJson(x, where);
                    else if constexpr (std::is_same_v<T, double>)
                        return numberJson(x, where);
                    else
                        return x;
                },
                value);
            text += concat(i ? ",\n" : "\n", "    ", quoted(name), ": ", v.dump());
        }
        text += "\n  }";
        comma = ",\n";
    }
    if (!view.environmentMap.empty())
        text += concat(comma, "  \"environmentMap\": ", quoted(view.environmentMap));
    text += "\n}\n";
    detail::AtomicFile file(path);
    file.stream() << text;
    file.commit();
}

} // namespace voxfx
