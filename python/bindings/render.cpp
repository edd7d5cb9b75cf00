// The renderer: voxfx.Scene, load_scene, render (the image as a NumPy array) and the catalog of
// its options; voxfx.Camera with the viewer's moves (orbit, pan, dolly) and voxfx.Renderer, the
// scene kept for frame after frame, with the cheap preview of `voxfx view` (voxfx/view.hpp). Every shadow
// technique's and glass method's options are keyword arguments by the library's names in snake_case
// (render_options() lists them): this file knows none of them, it hands each to setRenderOption, as the
// command line does.
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

/// The image as 8-bit sRGB, a uint8 array (height, width, 3): what writePng stores, ready to show.
py::array_t<uint8_t> srgbArray(const Image& image) {
    const std::vector<uint8_t> bytes = toSrgb8(image);
    py::array_t<uint8_t> out({py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(3)});
    std::memcpy(out.mutable_data(), bytes.data(), bytes.size());
    return out;
}

/// Three numbers from Python (a tuple, a list, a NumPy array).
Vec3d vec3Argument(const char* name, const py::handle& v) {
    if (py::isinstance<py::sequence>(v) || py::isinstance<py::array>(v)) {
        const auto s = v.cast<py::sequence>();
        if (py::len(s) == 3) return Vec3d{s[0].cast<double>(), s[1].cast<double>(), s[2].cast<double>()};
    }
    throw ArgumentError(std::string(name) + ": expected three numbers, got " +
                        py::repr(v).cast<std::string>());
}

/// A camera argument: a voxfx.Camera, or the index of a scene camera (the default camera of a
/// scene without any, fitted to `aspect`).
Camera cameraArgument(const Scene& scene, const py::object& camera, double aspect) {
    if (py::isinstance<Camera>(camera)) return camera.cast<Camera>();
    if (py::isinstance<py::int_>(camera)) {
        const int64_t i = camera.cast<int64_t>();
        return asArgument(
            [&] { return sceneCamera(scene, int(std::clamp<int64_t>(i, -1, INT32_MAX)), aspect); });
    }
    throw ArgumentError("camera: expected a voxfx.Camera or a camera index, got " +
                        py::repr(camera).cast<std::string>());
}

/// voxfx.Renderer: a scene, its options and environment, kept for frame after frame.
struct PyRenderer {
    std::shared_ptr<FrameRenderer> renderer;
    RenderOptions options; ///< full frames (environment loaded once)
    int previewScale = 4;
};

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
    d["glass_paths"] = r.glass.paths;
    d["glass_interpolated"] = r.glass.interpolated;
    d["covered_pixels"] = r.coveredPixels;
    d["volume_samples"] = r.volumeSamples;
    d["volume_interpolated"] = r.volumeInterpolated;
    d["passes_ms"] = passes;
    d["total_ms"] = r.timings.totalMs;
    return d;
}

void bindCamera(py::module_& m) {
    py::class_<Camera>(m, "Camera",
                       "A perspective camera: eye position, target, up, vertical field of view (radians). "
                       "orbit, pan and dolly return moved copies (the moves of voxfx view).")
        .def(py::init([](const py::object& position, const py::object& target, const py::object& up,
                         double fovY, double nearDepth, double farDepth, const std::string& name) {
                 Camera c;
                 c.position = vec3Argument("position", position);
                 c.target = vec3Argument("target", target);
                 c.up = vec3Argument("up", up);
                 c.fovY = fovY;
                 c.nearDepth = nearDepth;
                 c.farDepth = farDepth;
                 c.name = name;
                 if (!(fovY > 0 && fovY < M_PI)) throw ArgumentError("fov_y: must lie in (0, pi) radians");
                 if (!(nearDepth > 0)) throw ArgumentError("near: must be > 0");
                 if (!(length(c.target - c.position) > 0))
                     throw ArgumentError("target: must differ from position");
                 return c;
             }),
             py::arg("position"), py::arg("target"), py::arg("up") = py::make_tuple(0.0, 1.0, 0.0),
             py::arg("fov_y") = Camera{}.fovY, py::arg("near") = Camera{}.nearDepth,
             py::arg("far") = Camera{}.farDepth, py::arg("name") = "")
        .def_property_readonly("position", [](const Camera& c) { return vec3(c.position); })
        .def_property_readonly("target", [](const Camera& c) { return vec3(c.target); })
        .def_property_readonly("up", [](const Camera& c) { return vec3(c.up); })
        .def_property_readonly("fov_y", [](const Camera& c) { return c.fovY; })
        .def_property_readonly("near", [](const Camera& c) { return c.nearDepth; })
        .def_property_readonly("far", [](const Camera& c) { return c.farDepth; })
        .def_property_readonly("name", [](const Camera& c) { return c.name; })
        .def(
            "orbit",
            [](const Camera& c, double yaw, double pitch) {
                return asArgument([&] { return orbitCamera(c, yaw, pitch); });
            },
            py::arg("yaw"), py::arg("pitch") = 0.0,
            "The camera turned about its target: yaw radians about up, pitch radians up over it (stops "
            "a degree short of straight above or below)")
        .def(
            "pan",
            [](const Camera& c, double right, double up) {
                return asArgument([&] { return panCamera(c, right, up); });
            },
            py::arg("right"), py::arg("up") = 0.0,
            "The camera and its target moved across the view by `right` and `up` view heights (at the "
            "target's distance)")
        .def(
            "dolly",
            [](const Camera& c, double factor) { return asArgument([&] { return dollyCamera(c, factor); }); },
            py::arg("factor"),
            "The camera moved along its view to `factor` times its distance from the target (near and far "
            "planes alike)")
        .def("__eq__",
             [](const Camera& a, const Camera& b) {
                 return a.position == b.position && a.target == b.target && a.up == b.up &&
                        a.fovY == b.fovY && a.nearDepth == b.nearDepth && a.farDepth == b.farDepth &&
                        a.name == b.name;
             })
        .def("__repr__", [](const Camera& c) {
            const auto v = [](const Vec3d& p) {
                return "(" + numberText(p.x, 6) + ", " + numberText(p.y, 6) + ", " + numberText(p.z, 6) + ")";
            };
            return "<voxfx.Camera '" + c.name + "' position " + v(c.position) + " target " + v(c.target) +
                   " fov_y " + numberText(c.fovY, 6) + ">";
        });
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
            "cameras", [](const Scene& s) { return s.cameras; },
            "The scene's cameras (voxfx.Camera), in the file's order")
        .def(
            "camera",
            [](const Scene& s, int index, double aspect) {
                return asArgument([&] { return sceneCamera(s, index, aspect); });
            },
            py::arg("index") = 0, py::arg("aspect") = 16.0 / 9.0,
            "The scene's camera `index`; for a scene without cameras, index 0 is a default camera fitted "
            "to the scene at width / height = aspect")
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

/// voxfx.render and voxfx.render_options.
void bindRenderFunction(py::module_& m) {
    m.def(
        "render",
        [](const py::object& sceneOrPath, const std::string& shadows, const std::string& glass,
           const py::object& camera, const py::object& environment, int threads, bool report,
           const py::kwargs& options) -> py::object {
            const ScenePtr scene = sceneArgument(sceneOrPath);
            RenderOptions o = asArgument([&] { return renderOptionsOf(*scene, shadows, glass, options); });
            o.threads = threads;
            const std::string env = environment.is_none() ? std::string() : pathString(environment);
            RenderResult r;
            Camera cam = cameraArgument(*scene, camera, double(o.width) / double(o.height));
            // Without the GIL; Ctrl-C cancels between tiles of a pass (KeyboardInterrupt is raised).
            interruptible([&](Cancel& cancel) {
                o.environment = loadSceneEnvironment(*scene, o, env);
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
lists them, with who uses each and the defaults). `camera` is a scene camera's index or a
voxfx.Camera. Returns the image as a float32 array
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
}

/// voxfx.Renderer: a scene kept for frame after frame, with the viewer's preview.
void bindRendererClass(py::module_& m) {
    py::class_<PyRenderer>(m, "Renderer", R"(A scene kept for frame after frame: voxfx view's renderer.

    r = voxfx.Renderer("scene.glb", shadows="map", width=640, height=360)
    cam = r.camera()                                  # the scene's first camera, at r's aspect
    for k in range(36):
        frame = r.render(cam.orbit(k * math.pi / 18), preview=True)   # (90, 160, 3) uint8

The options are render()'s (the scene file's settings, then shadows, glass and the keywords),
fixed for the renderer's life; the environment is loaded once. render(camera, preview=True)
renders the preview of a moving camera, as `voxfx view` does: 1/preview_scale of the width and
height, one sample per pixel, no ambient occlusion.)")
        .def(py::init([](const py::object& sceneOrPath, const std::string& shadows, const std::string& glass,
                         const py::object& environment, int threads, int previewScale,
                         const py::kwargs& options) {
                 auto out = std::make_unique<PyRenderer>();
                 const ScenePtr scene = sceneArgument(sceneOrPath);
                 out->renderer = std::make_shared<FrameRenderer>(scene);
                 out->options = asArgument([&] { return renderOptionsOf(*scene, shadows, glass, options); });
                 out->options.threads = threads;
                 if (previewScale < 1) throw ArgumentError("preview_scale: must be at least 1");
                 out->previewScale = previewScale;
                 const std::string env = environment.is_none() ? std::string() : pathString(environment);
                 py::gil_scoped_release release;
                 out->options.environment = loadSceneEnvironment(*scene, out->options, env);
                 return out;
             }),
             py::arg("scene"), py::kw_only(), py::arg("shadows") = "", py::arg("glass") = "",
             py::arg("environment") = py::none(), py::arg("threads") = 0, py::arg("preview_scale") = 4)
        .def_property_readonly("width", [](const PyRenderer& r) { return r.options.width; })
        .def_property_readonly("height", [](const PyRenderer& r) { return r.options.height; })
        .def_property_readonly("preview_scale", [](const PyRenderer& r) { return r.previewScale; })
        .def_property_readonly(
            "scene",
            [](const PyRenderer& r) { return std::const_pointer_cast<Scene>(r.renderer->scenePointer()); })
        .def_property_readonly("shadows",
                               [](const PyRenderer& r) { return std::string(shadowName(r.options.shadow)); })
        .def_property_readonly("glass",
                               [](const PyRenderer& r) { return std::string(glassName(r.options.glass)); })
        .def(
            "camera",
            [](const PyRenderer& r, int index) {
                return asArgument([&] {
                    const Scene& s = r.renderer->scene();
                    return aimAtScene(
                        sceneCamera(s, index, double(r.options.width) / double(r.options.height)), s);
                });
            },
            py::arg("index") = 0,
            "The scene's camera `index` (a scene without cameras: a default one at this aspect), its target "
            "moved along the view to the scene's centre, so that orbit turns about the scene (the same "
            "image)")
        .def(
            "render",
            [](PyRenderer& self, const py::object& camera, bool preview, bool linear,
               bool report) -> py::object {
                RenderOptions o = preview ? previewOptions(self.options, self.previewScale) : self.options;
                const Camera cam = cameraArgument(self.renderer->scene(), camera,
                                                  double(self.options.width) / double(self.options.height));
                RenderResult r;
                interruptible([&](Cancel& cancel) {
                    o.progress = &cancel;
                    r = self.renderer->render(cam, o);
                });
                o.progress = nullptr;
                py::object image = linear ? py::object(imageArray(r.image)) : py::object(srgbArray(r.image));
                if (!report) return image;
                py::dict d = reportDict(o, r, cam);
                d["width"] = o.width;
                d["height"] = o.height;
                d["refined_pixels"] = r.refinedPixels;
                d["preview"] = preview;
                return py::make_tuple(image, d);
            },
            py::arg("camera") = 0, py::kw_only(), py::arg("preview") = false, py::arg("linear") = false,
            py::arg("report") = false,
            R"(Renders a frame from `camera` (a voxfx.Camera or a scene camera's index): an (height, width, 3)
uint8 array of 8-bit sRGB (what a PNG stores, ready for matplotlib or PIL), or with linear=True the
float32 linear RGB render() gives. preview=True: the preview of a moving camera (1/preview_scale
of the size, one sample per pixel, no ambient occlusion). report=True: (image, dict) with render()'s
report plus width, height, refined_pixels (pixels shaded at every sample) and preview.)")
        .def("__repr__", [](const PyRenderer& r) {
            return "<voxfx.Renderer " + r.renderer->scene().source + ": " + std::to_string(r.options.width) +
                   " x " + std::to_string(r.options.height) + ", shadows " +
                   std::string(shadowName(r.options.shadow)) + ", glass " +
                   std::string(glassName(r.options.glass)) + ">";
        });
}

/// voxfx.shadow_kinds and voxfx.glass_methods.
void bindRenderCatalogs(py::module_& m) {
    m.def(
        "shadow_kinds", [] { return namesAndSummaries(shadowNames(), shadowSummary); },
        "The shadow kinds, (name, summary) each");
    m.def(
        "glass_methods", [] { return namesAndSummaries(glassNames(), glassSummary); },
        "The glass methods, (name, summary) each");
}

} // namespace

void bindRender(py::module_& m) {
    bindCamera(m);
    bindScene(m);
    bindRenderFunction(m);
    bindRendererClass(m);
    bindRenderCatalogs(m);
}

} // namespace voxfx::python
