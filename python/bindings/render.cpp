// The renderer: voxfx.Scene, load_scene, render (the image as a NumPy array) and the catalog of
// its options. Every shadow technique's and glass method's options are keyword arguments by the
// library's names in snake_case (render_options() lists them): this file knows none of them, it
// hands each to setRenderOption, as the command line does.
#include <cmath>
#include <cstring>

#include "common.hpp"

namespace voxfx::python {
namespace {

using ScenePtr = std::shared_ptr<const Scene>;

/// A Python value as an option value: bool, int, float, str, or three numbers.
OptionValue optionValue(const std::string& name, const py::handle& v) {
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>();
    if (py::isinstance<py::int_>(v)) return v.cast<int64_t>();
    if (py::isinstance<py::float_>(v)) return v.cast<double>();
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    if (py::isinstance<py::sequence>(v) && py::len(v) == 3) {
        const auto s = v.cast<py::sequence>();
        return Vec3d{s[0].cast<double>(), s[1].cast<double>(), s[2].cast<double>()};
    }
    fail(name, ": expected a bool, a number, a name or three numbers, got ", py::repr(v).cast<std::string>());
}

/// The scene of a render argument: a voxfx.Scene, or a scene file (str or os.PathLike).
ScenePtr sceneArgument(const py::object& sceneOrPath) {
    if (py::isinstance<Scene>(sceneOrPath)) return sceneOrPath.cast<std::shared_ptr<Scene>>();
    const std::string path = pathString(sceneOrPath);
    py::gil_scoped_release release;
    return std::make_shared<const Scene>(loadScene(path));
}

/// The users of an option as the catalog names them, without their defaults.
std::string usersOf(const std::string& name) {
    std::string users;
    for (const RenderOptionInfo& info : renderOptionCatalog())
        if (info.name == name)
            for (const std::string& u : info.users)
                users += (users.empty() ? "" : ", ") + u.substr(0, u.rfind(" ("));
    return users;
}

/// The options of a render: the scene's own (renderOptionsFor), then the keywords. A keyword the
/// chosen shadow technique and glass method do not have is an error naming who has it (raised as
/// voxfx.ArgumentError by the caller).
RenderOptions renderOptionsOf(const Scene& scene, const std::string& shadows, const std::string& glass,
                              const py::kwargs& options) {
    RenderOptions o = renderOptionsFor(scene, shadows, glass);
    for (const auto& [key, value] : options) {
        const std::string name = key.cast<std::string>();
        if (setRenderOption(o, name, optionValue(name, value))) continue;
        fail(name, " is not an option of shadows ", shadowName(o.shadow), " or glass ", glassName(o.glass),
             " (it is one of: ", usersOf(camelCase(name)), ")");
    }
    return o;
}

/// The image as a float32 array (height, width, 3), linear RGB, row 0 on top.
py::array_t<float> imageArray(const Image& image) {
    py::array_t<float> out({py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(3)});
    std::memcpy(out.mutable_data(), image.pixels.data(), image.pixels.size() * sizeof(Vec3f));
    return out;
}

/// (name, summary) of each technique.
std::vector<std::pair<std::string, std::string>>
namesAndSummaries(const std::vector<std::string_view>& names, std::string_view (*summary)(std::string_view)) {
    std::vector<std::pair<std::string, std::string>> out;
    for (const std::string_view n : names) out.emplace_back(n, summary(n));
    return out;
}

/// What render(report=True) returns besides the image.
py::dict reportDict(const RenderOptions& o, const RenderResult& r, const Camera& camera) {
    py::dict passes;
    for (const PassTime& p : r.timings.passes) passes[py::str(std::string(p.name))] = p.ms;
    py::dict d;
    d["camera"] = camera.name;
    d["shadows"] = std::string(shadowName(o.shadow));
    d["shadow_options"] = std::visit([](const auto& t) { return optionsText(t, snakeCase); }, o.shadow);
    d["shadow_stats"] = summary(r.shadowStats);
    d["glass"] = std::string(glassName(o.glass));
    d["glass_options"] = std::visit([](const auto& g) { return optionsText(g, snakeCase); }, o.glass);
    d["glass_pixels"] = r.glass.pixels;
    d["covered_pixels"] = r.coveredPixels;
    d["volume_samples"] = r.volumeSamples;
    d["passes_ms"] = passes;
    d["total_ms"] = r.timings.totalMs;
    return d;
}

void bindScene(py::module_& m) {
    py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", "A scene: meshes with materials, lights, cameras")
        .def_property_readonly("source", [](const Scene& s) { return s.source; })
        .def_property_readonly("triangle_count", [](const Scene& s) { return int64_t(s.triangleCount()); })
        .def_property_readonly("mesh_names",
                               [](const Scene& s) {
                                   std::vector<std::string> names;
                                   for (const SceneMesh& mesh : s.meshes) names.push_back(mesh.name);
                                   return names;
                               })
        .def_property_readonly("light_count", [](const Scene& s) { return s.lights.size(); })
        .def_property_readonly("camera_names",
                               [](const Scene& s) {
                                   std::vector<std::string> names;
                                   for (const Camera& c : s.cameras) names.push_back(c.name);
                                   return names;
                               })
        .def_property_readonly(
            "settings",
            [](const Scene& s) {
                py::dict d;
                for (const auto& [name, value] : s.settings.render) d[py::str(name)] = formatOption(value);
                return d;
            },
            "The scene file's render settings, as text by name")
        .def("__repr__", [](const Scene& s) {
            return "<voxfx.Scene " + s.source + ": " + std::to_string(s.triangleCount()) + " triangles, " +
                   std::to_string(s.lights.size()) + " lights, " + std::to_string(s.cameras.size()) +
                   " cameras>";
        });
    m.def(
        "load_scene",
        [](const py::object& path) {
            const std::string p = pathString(path);
            py::gil_scoped_release release;
            return std::make_shared<Scene>(loadScene(p));
        },
        py::arg("path"), "Loads a scene: .gltf .glb, the JSON wrapper .json, or a mesh file");
}

} // namespace

void bindRender(py::module_& m) {
    bindScene(m);
    m.def(
        "render",
        [](const py::object& sceneOrPath, const std::string& shadows, const std::string& glass, int camera,
           const py::object& environment, int threads, bool report, const py::kwargs& options) -> py::object {
            const ScenePtr scene = sceneArgument(sceneOrPath);
            RenderOptions o = asArgument([&] { return renderOptionsOf(*scene, shadows, glass, options); });
            o.threads = threads;
            const std::string env = environment.is_none() ? std::string() : pathString(environment);
            RenderResult r;
            Camera cam;
            // Without the GIL; Ctrl-C cancels between tiles of a pass (KeyboardInterrupt is raised).
            interruptible([&](Cancel& cancel) {
                o.environment = loadSceneEnvironment(*scene, o, env);
                cam = sceneCamera(*scene, camera, double(o.width) / double(o.height));
                o.progress = &cancel;
                r = render(*scene, cam, o);
                o.progress = nullptr;
            });
            py::array_t<float> image = imageArray(r.image);
            if (!report) return image;
            return py::make_tuple(image, reportDict(o, r, cam));
        },
        py::arg("scene"), py::kw_only(), py::arg("shadows") = "", py::arg("glass") = "",
        py::arg("camera") = 0, py::arg("environment") = py::none(), py::arg("threads") = 0,
        py::arg("report") = false,
        R"(Renders a scene (a voxfx.Scene or a scene file) as `voxfx render` does: the scene file's
settings, then `shadows` (a shadow kind, see shadow_kinds()), `glass` (a glass method, see
glass_methods()) and every other option as a keyword by its snake_case name (render_options()
lists them, with who uses each and the defaults). Returns the image as a float32 array
(height, width, 3) of linear RGB, row 0 on top; with report=True, (image, dict of the shadow
technique's counters, the options it ran with and the passes' times).)");
    m.def(
        "render_options",
        [] {
            py::list out;
            for (const RenderOptionInfo& info : renderOptionCatalog()) {
                py::dict d;
                d["name"] = snakeCase(info.name);
                d["type"] = toString(info.type);
                d["help"] = info.help;
                if (info.type == OptionType::Integer || info.type == OptionType::Real ||
                    info.type == OptionType::Triple)
                    d["range"] = py::make_tuple(info.lo, info.hi);
                if (!info.choices.empty()) d["choices"] = info.choices;
                d["users"] = info.users;
                out.append(d);
            }
            return out;
        },
        "Every option render() takes besides shadows and glass: name, type, help, range or choices, and "
        "who uses it (render, a shadow kind, a glass method) with its default");
    m.def(
        "shadow_kinds", [] { return namesAndSummaries(shadowNames(), shadowSummary); },
        "The shadow kinds, (name, summary) each");
    m.def(
        "glass_methods", [] { return namesAndSummaries(glassNames(), glassSummary); },
        "The glass methods, (name, summary) each");
}

} // namespace voxfx::python
