// Attribute grids from Python (voxfx/attribute_grid.hpp, voxfx/attribute_io.hpp: `voxfx attributes`)
// and per-vertex colours voxelized (voxfx/vertex_colors.hpp), as NumPy arrays indexed [x, y, z];
// load_colored_mesh keeps a PLY or COFF file's vertex colours. The Python class
// voxfx.AttributeGrid (voxfx/_datasets.py) holds the arrays (it pickles as plain data) and writes
// them through _write_attributes.
#include <cmath>
#include <cstring>
#include <memory>

#include "common.hpp"
#include "voxfx/attribute_io.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/scene_io.hpp"
#include "voxfx/vertex_colors.hpp"

namespace voxfx::python {
namespace {

/// A mesh for the attribute voxelizer: one material per triangle and the material table (the
/// scene's for a scene file, one default material otherwise), and the colours when there are some.
struct AttributeInput {
    std::shared_ptr<PyMesh> mesh;
    std::vector<uint32_t> triangleMaterial;
    std::vector<AttributeMaterial> materials;
    std::vector<Vec3f> colors;
};

bool attributeMeshFile(const std::string& path) {
    const std::string ext = fileExtension(path);
    return ext == ".off" || ext == ".ply" || ext == ".obj" || ext == ".stl";
}

/// A path is loaded as `voxfx attributes` loads it (a scene: its materials), keeping a PLY or COFF
/// file's colours; anything else is a mesh argument with one default material.
AttributeInput attributeInput(const py::object& meshObj) {
    AttributeInput in;
    in.mesh = std::make_shared<PyMesh>();
    const Material defaults;
    if (py::isinstance<py::str>(meshObj) || py::isinstance<py::bytes>(meshObj) ||
        py::hasattr(meshObj, "__fspath__")) {
        const std::string path = pathString(meshObj);
        in.mesh->source = path;
        py::gil_scoped_release release;
        if (attributeMeshFile(path)) {
            in.mesh->mesh = loadMesh(path, nullptr, &in.colors);
            in.materials = {{defaults.ior, attenuationCoefficient(defaults)}};
        } else {
            const Scene scene = loadScene(path);
            for (const SceneMesh& s : scene.meshes) {
                const auto base = uint32_t(in.mesh->mesh.positions.size());
                in.mesh->mesh.positions.insert(in.mesh->mesh.positions.end(), s.mesh.positions.begin(),
                                               s.mesh.positions.end());
                for (const uint32_t i : s.mesh.indices) in.mesh->mesh.indices.push_back(base + i);
                in.triangleMaterial.insert(in.triangleMaterial.end(), s.mesh.indices.size() / 3, s.material);
            }
            for (const Material& mat : scene.materials)
                in.materials.push_back({mat.ior, attenuationCoefficient(mat)});
        }
    } else {
        in.mesh = meshArgument(meshObj, py::none());
        in.materials = {{defaults.ior, attenuationCoefficient(defaults)}};
    }
    if (in.triangleMaterial.empty()) in.triangleMaterial.assign(in.mesh->mesh.triangleCount(), 0);
    return in;
}

/// (V, 3) or (V, 4) colours: unsigned 8-bit over 255, floating point as given (alpha dropped).
std::vector<Vec3f> colorsArgument(const py::object& obj, std::size_t vertices) {
    const py::array a = py::array::ensure(obj);
    if (!a || a.ndim() != 2 || (a.shape(1) != 3 && a.shape(1) != 4))
        throw ArgumentError("colors must be an array of shape (V, 3) or (V, 4), one colour per vertex");
    if (std::size_t(a.shape(0)) != vertices)
        throw ArgumentError("colors has " + std::to_string(a.shape(0)) + " rows for " +
                            std::to_string(vertices) + " vertices");
    const char kind = a.dtype().kind();
    if (kind != 'f' && kind != 'u' && kind != 'i') throw py::type_error("colors must hold numbers");
    const bool bytes = a.dtype().is(py::dtype::of<uint8_t>());
    const auto f = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    const double* d = f.data();
    const auto cols = std::size_t(a.shape(1));
    std::vector<Vec3f> out(vertices);
    for (std::size_t v = 0; v < vertices; ++v)
        for (int k = 0; k < 3; ++k)
            out[v][k] = float(bytes ? d[v * cols + std::size_t(k)] / 255.0 : d[v * cols + std::size_t(k)]);
    return out;
}

/// The channels asked for: names of AttributeChannel plus "color".
void attributeChannels(const py::object& channels, bool haveColors, AttributeChannels& ch, bool& color) {
    color = false;
    std::vector<std::string> names;
    if (channels.is_none()) {
        names = {"count", "normal", "material", "ior"};
        if (haveColors) names.push_back("color");
    } else if (py::isinstance<py::str>(channels)) {
        std::string list = channels.cast<std::string>();
        for (std::size_t start = 0; start <= list.size();) {
            const std::size_t comma = std::min(list.find(',', start), list.size());
            names.push_back(list.substr(start, comma - start));
            start = comma + 1;
        }
    } else {
        for (const py::handle h : channels) names.push_back(py::str(h).cast<std::string>());
    }
    std::string library;
    for (const std::string& n : names) {
        if (n == "color" || n == "colour") {
            if (!haveColors)
                throw ArgumentError(
                    "channel 'color' needs per-vertex colours: give colors=, or a PLY or COFF file that "
                    "has them");
            color = true;
        } else {
            library += (library.empty() ? "" : ",") + n;
        }
    }
    if (library.empty() && !color) throw ArgumentError("channels: give at least one channel");
    ch = library.empty() ? AttributeChannels{false, false, false, false, false, false}
                         : asArgument([&] { return parseAttributeChannels(library); });
    if (ch.absorption)
        throw ArgumentError(
            "channels: absorption needs per-triangle values (the absorption shadows' input); choose "
            "from count, normal, material, ior, attenuation, color");
}

/// A per-voxel array [x, y, z] (with `components` values per voxel) from an attribute layout
/// ((y * nx + x) * nz + z).
template <class Out, class In, class Get>
py::array_t<Out> attributeArray(const Frame& f, int components, const std::vector<In>& v, Get get) {
    const int64_t nx = f.width(), ny = f.height(), nz = f.depth();
    std::vector<py::ssize_t> shape{py::ssize_t(nx), py::ssize_t(ny), py::ssize_t(nz)};
    if (components > 1) shape.push_back(components);
    py::array_t<Out> out(shape);
    Out* o = out.mutable_data();
    {
        py::gil_scoped_release release;
        parallelFor(0, nx * ny, 64, [&](int64_t b, int64_t e) {
            for (int64_t c = b; c < e; ++c) {
                const int64_t x = c / ny, y = c % ny;
                for (int64_t z = 0; z < nz; ++z)
                    get(v[std::size_t((y * nx + x) * nz + z)], o + ((c * nz + z) * components));
            }
        });
    }
    return out;
}

py::dict attributes(const py::object& meshObj, const py::object& channels, const py::object& colors,
                    std::optional<Int> resolution, std::optional<double> voxelSize,
                    std::optional<std::vector<int64_t>> dims, const py::object& bounds, int64_t margin,
                    bool cube, int64_t padding, const std::string& coverage, double slabOverlap,
                    int threads) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
    if (padding < 0) throw ArgumentError("padding must be >= 0");
    if (!(slabOverlap >= 0) || !std::isfinite(slabOverlap))
        throw ArgumentError("slab_overlap must be finite and >= 0");
    if (!resolution && !voxelSize && !dims) resolution = 128; // the command's default
    FitOptions fo = fitOptions(resolution, voxelSize, dims, bounds, margin, "z", cube);
    if (padding > 0) {
        if (fo.resolution <= 2 * padding)
            throw ArgumentError("padding needs a resolution above 2 * padding (the cells left for the mesh)");
        fo.resolution -= 2 * padding;
        fo.marginCells += padding;
    }
    AttributeOptions ao;
    ao.coverage = asArgument([&] { return parseCoverage(coverage); });
    ao.slabOverlap = slabOverlap;
    ao.threads = threads;
    AttributeInput in = attributeInput(meshObj);
    if (!colors.is_none()) in.colors = colorsArgument(colors, in.mesh->mesh.positions.size());
    bool wantColor = false;
    attributeChannels(channels, !in.colors.empty(), ao.channels, wantColor);
    ao.triangleMaterial = in.triangleMaterial;
    ao.materials = in.materials;
    const MeshView view = in.mesh->mesh.view();
    asArgument([&] { validateMesh(view, "mesh"); });
    if (!fo.bounds.empty() && in.mesh->shifted()) {
        fo.bounds.lo = fo.bounds.lo - in.mesh->origin;
        fo.bounds.hi = fo.bounds.hi - in.mesh->origin;
    }
    const Frame frame = asArgument([&] { return fitFrame(computeBounds(view), fo); });
    const AttributeChannels& ch = ao.channels;
    const bool anyLibrary = ch.count || ch.normals || ch.material || ch.ior || ch.attenuation;
    AttributeGrid grid;
    ColorGrid colorGrid;
    interruptible([&](Cancel& cancel) {
        if (anyLibrary) {
            ao.progress = &cancel;
            grid = voxelizeAttributes(view, frame, {}, ao);
        }
        if (wantColor) {
            VertexColorOptions co;
            co.coverage = ao.coverage;
            co.threads = threads;
            co.progress = &cancel;
            colorGrid = voxelizeVertexColors(view, in.colors, frame, co);
        }
    });
    py::dict out;
    if (ch.count)
        out["count"] =
            attributeArray<uint16_t>(frame, 1, grid.count, [](uint16_t v, uint16_t* o) { *o = v; });
    if (ch.normals)
        out["normal"] = attributeArray<float>(frame, 3, grid.normalSum, [](const Vec3f& v, float* o) {
            const Vec3f n = normalize(v);
            o[0] = n.x, o[1] = n.y, o[2] = n.z;
        });
    if (ch.material)
        out["material"] = attributeArray<int32_t>(frame, 1, grid.material, [](uint32_t v, int32_t* o) {
            *o = v == AttributeGrid::kNoMaterial ? -1 : int32_t(v);
        });
    if (ch.ior) out["ior"] = attributeArray<float>(frame, 1, grid.ior, [](float v, float* o) { *o = v; });
    if (ch.attenuation)
        out["attenuation"] = attributeArray<float>(
            frame, 3, grid.attenuation, [](const Vec3f& v, float* o) { o[0] = v.x, o[1] = v.y, o[2] = v.z; });
    if (wantColor) {
        out["color"] = attributeArray<float>(
            frame, 3, colorGrid.color, [](const Vec3f& v, float* o) { o[0] = v.x, o[1] = v.y, o[2] = v.z; });
        out["color_count"] =
            attributeArray<uint32_t>(frame, 1, colorGrid.count, [](uint32_t v, uint32_t* o) { *o = v; });
    }
    out["origin"] = vec3(frame.box().lo + in.mesh->origin);
    out["cell_size"] = vec3(frame.cellSize());
    out["dims"] = py::make_tuple(frame.width(), frame.height(), frame.depth());
    return out;
}

/// The arrays of an AttributeGrid back into the library's grid, for writeAttributeGrid.
void writeAttributes(const py::object& pathObj, const py::dict& arrays, const std::vector<double>& origin,
                     const std::vector<double>& cell, const std::vector<int64_t>& dims,
                     const py::object& channel) {
    if (origin.size() != 3 || cell.size() != 3 || dims.size() != 3)
        throw ArgumentError("origin, cell_size and dims need 3 values");
    const int64_t nx = dims[0], ny = dims[1], nz = dims[2];
    Box3d box;
    box.lo = {origin[0], origin[1], origin[2]};
    box.hi = {origin[0] + double(nx) * cell[0], origin[1] + double(ny) * cell[1],
              origin[2] + double(nz) * cell[2]};
    AttributeGrid g;
    g.frame = asArgument([&] { return Frame::orthographic(box, Axis::Z, nx, ny, nz); });
    const auto voxels = std::size_t(nx * ny * nz);
    // Element (x, y, z) of an [x, y, z(, c)] array goes to (y * nx + x) * nz + z.
    const auto fill = [&](const char* name, int components, auto& dst, auto set) {
        if (!arrays.contains(name)) return;
        const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(arrays[name]);
        if (!a || a.size() != py::ssize_t(voxels) * components)
            throw ArgumentError(std::string("channel '") + name + "' does not match the grid's dims");
        dst.resize(voxels);
        const double* d = a.data();
        for (int64_t x = 0; x < nx; ++x)
            for (int64_t y = 0; y < ny; ++y)
                for (int64_t z = 0; z < nz; ++z)
                    set(dst[std::size_t((y * nx + x) * nz + z)], d + ((x * ny + y) * nz + z) * components);
    };
    fill("count", 1, g.count, [](uint16_t& o, const double* v) { o = uint16_t(*v); });
    fill("normal", 3, g.normalSum, [](Vec3f& o, const double* v) {
        o = {float(v[0]), float(v[1]), float(v[2])};
    });
    fill("material", 1, g.material,
         [](uint32_t& o, const double* v) { o = *v < 0 ? AttributeGrid::kNoMaterial : uint32_t(*v); });
    fill("ior", 1, g.ior, [](float& o, const double* v) { o = float(*v); });
    fill("attenuation", 3, g.attenuation, [](Vec3f& o, const double* v) {
        o = {float(v[0]), float(v[1]), float(v[2])};
    });
    std::optional<AttributeChannel> only;
    if (!channel.is_none()) {
        const std::string name = channel.cast<std::string>();
        if (name == "color" || name == "colour")
            throw ArgumentError(
                "the color channel is voxfx's own: the attribute files hold the library's channels "
                "(np.save(path, grid.color) writes it)");
        only = asArgument([&] {
            return parseEnum(name, "attribute channel",
                             std::span<const EnumName<AttributeChannel>>(kAttributeChannelNames));
        });
    }
    const std::string path = pathString(pathObj);
    py::gil_scoped_release release;
    writeAttributeGrid(g, path, only);
}

} // namespace

void bindAttributes(py::module_& m) {
    m.def("_attributes", &attributes, py::arg("mesh"), py::kw_only(), py::arg("channels") = py::none(),
          py::arg("colors") = py::none(), py::arg("resolution") = py::none(),
          py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(), py::arg("bounds") = py::none(),
          py::arg("margin") = 1, py::arg("cube") = false, py::arg("padding") = 0,
          py::arg("coverage") = "center", py::arg("slab_overlap") = 0.0, py::arg("threads") = 0,
          "voxfx.attributes' arrays (see voxfx.attributes)");
    m.def("_write_attributes", &writeAttributes, py::arg("path"), py::arg("arrays"), py::arg("origin"),
          py::arg("cell_size"), py::arg("dims"), py::arg("channel") = py::none(),
          "AttributeGrid.save's writer (voxfx::writeAttributeGrid)");
    m.def(
        "load_colored_mesh",
        [](const py::object& pathObj) {
            auto mesh = std::make_shared<PyMesh>();
            mesh->source = pathString(pathObj);
            std::vector<Vec3f> colors;
            {
                py::gil_scoped_release release;
                mesh->mesh = loadMesh(mesh->source, nullptr, &colors);
            }
            if (colors.empty()) return py::make_tuple(mesh, py::none());
            py::array_t<float> c({py::ssize_t(colors.size()), py::ssize_t(3)});
            std::memcpy(c.mutable_data(), colors.data(), colors.size() * sizeof(Vec3f));
            return py::make_tuple(mesh, c);
        },
        py::arg("path"),
        "load_mesh, keeping the file's per-vertex colours: (voxfx.Mesh, colors) with colors an (V, 3) "
        "float32 "
        "array of RGB in [0, 1] (PLY red/green/blue, integer types over their largest value; COFF vertex "
        "colours, integers over 255), or None when the file has none (OBJ, STL, glTF: always None).");
}

} // namespace voxfx::python
