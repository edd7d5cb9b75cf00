// Distances: closest_points and signed_distance at points (voxfx/distance.hpp), and signed distance
// fields (voxfx/sdf.hpp): sdf and the SignedDistanceField it returns.
#include "voxfx/distance.hpp"

#include <array>
#include <cmath>
#include <memory>
#include <span>
#include <sstream>
#include <variant>

#include "common.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/sdf_io.hpp"

namespace voxfx::python {
namespace {

using SdfPtr = std::shared_ptr<SignedDistanceField>;

/// f(mesh, points in the mesh's coordinates) after the (mesh, points) / (vertices, faces, points)
/// argument dance of contains().
template <class F>
auto withMeshAndPoints(const py::object& meshObj, const py::object& faces, const py::object& points,
                       const char* name, F&& f) {
    py::object facesArg = faces, pointsArg = points;
    if (pointsArg.is_none()) std::swap(facesArg, pointsArg);
    if (pointsArg.is_none())
        throw py::type_error(std::string(name) + " needs points: " + name + "(mesh, points)");
    const auto mesh = meshArgument(meshObj, facesArg);
    const py::array_t<double> pts = pointsArgument(pointsArg, mesh->origin);
    const std::span<const Vec3d> p(reinterpret_cast<const Vec3d*>(pts.data()), std::size_t(pts.shape(0)));
    return f(*mesh, p);
}

void checkDistanceThreads(int threads) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
}

py::object closestPoints(const py::object& meshObj, const py::object& faces, const py::object& points,
                         int threads) {
    checkDistanceThreads(threads);
    return withMeshAndPoints(
        meshObj, faces, points, "closest_points", [&](const PyMesh& mesh, std::span<const Vec3d> p) {
            const py::ssize_t n = py::ssize_t(p.size());
            py::array_t<double> point({n, py::ssize_t(3)}), bary({n, py::ssize_t(3)}), distance(n);
            py::array_t<int64_t> face(n);
            double* pp = point.mutable_data();
            double* bp = bary.mutable_data();
            double* dp = distance.mutable_data();
            int64_t* fp = face.mutable_data();
            interruptible([&](Cancel& cancel) {
                const ClosestPointQuery query(mesh.mesh.view());
                std::vector<ClosestPoint> out(p.size());
                DistanceOptions o;
                o.threads = threads;
                o.progress = &cancel;
                query.closest(p, out, o);
                // Points back in world coordinates (the mesh's origin, when it was recentred).
                for (std::size_t i = 0; i < out.size(); ++i) {
                    for (int k = 0; k < 3; ++k) {
                        pp[3 * i + std::size_t(k)] = out[i].point[k] + mesh.origin[k];
                        bp[3 * i + std::size_t(k)] = out[i].barycentric[k];
                    }
                    dp[i] = out[i].distance;
                    fp[i] = out[i].face;
                }
            });
            const py::object type = py::module_::import("voxfx._voxfx").attr("ClosestPoints");
            return type(point, face, bary, distance);
        });
}

py::array_t<double> signedDistances(const py::object& meshObj, const py::object& faces,
                                    const py::object& points, const std::string& sign, int threads,
                                    double windingBeta) {
    checkDistanceThreads(threads);
    if (!(windingBeta >= 0)) throw ArgumentError("winding_beta must be >= 0");
    SignedDistanceOptions o;
    o.sign = asArgument([&] { return parseSignMethod(sign); });
    o.threads = threads;
    o.windingBeta = windingBeta;
    return withMeshAndPoints(meshObj, faces, points, "signed_distance",
                             [&](const PyMesh& mesh, std::span<const Vec3d> p) {
                                 py::array_t<double> out(py::ssize_t(p.size()));
                                 double* d = out.mutable_data();
                                 interruptible([&](Cancel& cancel) {
                                     SignedDistanceOptions so = o;
                                     so.progress = &cancel;
                                     signedDistance(mesh.mesh.view(), p, std::span<double>(d, p.size()), so);
                                 });
                                 return out;
                             });
}

/// 4 x 4 matrix mapping (i, j, k, 1) to the centre of voxel (i, j, k).
py::array_t<double> sdfAffine(const SignedDistanceField& f) {
    py::array_t<double> a({py::ssize_t(4), py::ssize_t(4)});
    double* p = a.mutable_data();
    std::fill(p, p + 16, 0.0);
    const Vec3d cell = f.frame.cellSize(), c0 = f.frame.box().lo + cell * 0.5;
    for (int k = 0; k < 3; ++k) {
        p[5 * k] = cell[k];
        p[4 * k + 3] = c0[k];
    }
    p[15] = 1;
    return a;
}

py::array_t<float> sdfDense(const SignedDistanceField& f) {
    const Vec3i d = f.dims();
    // [i, j, k] with x fastest in memory: Fortran order over (nx, ny, nz), as dense() fills it.
    py::array_t<float, py::array::f_style> out({py::ssize_t(d.x), py::ssize_t(d.y), py::ssize_t(d.z)});
    float* o = out.mutable_data();
    {
        py::gil_scoped_release release;
        const std::vector<float> v = f.dense();
        std::copy(v.begin(), v.end(), o);
    }
    return out;
}

py::tuple sdfActive(const SignedDistanceField& f) {
    return activeVoxelArrays([&](auto& indices, auto& values) { f.activeVoxels(indices, values); });
}

} // namespace

std::shared_ptr<SignedDistanceField>
makeSdf(const py::object& meshObj, const py::object& faces, std::optional<int64_t> resolution,
        std::optional<double> voxelSize, const py::object& bounds, std::optional<int64_t> margin, bool cube,
        const std::variant<double, std::string>& band, const std::string& fill, int threads) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
    SdfOptions o;
    o.threads = threads;
    if (const auto* s = std::get_if<std::string>(&band)) {
        if (*s != "full")
            throw ArgumentError("band must be a width in voxels (>= 1) or 'full', got '" + *s + "'");
        o.full = true;
    } else {
        o.bandVoxels = std::get<double>(band);
        if (!(o.bandVoxels >= 1) || !std::isfinite(o.bandVoxels))
            throw ArgumentError("band must be a width in voxels (>= 1) or 'full'");
    }
    o.fill = asArgument([&] { return parseFill(fill); });
    // The margin defaults to the band rounded up, so the band outside the mesh is not cut.
    const int64_t m = margin.value_or(o.full ? 0 : int64_t(std::ceil(o.bandVoxels)));
    FitOptions fo = fitOptions(resolution, voxelSize, std::nullopt, bounds, m, "z", cube);
    const auto mesh = meshArgument(meshObj, faces);
    if (!fo.bounds.empty() && mesh->shifted()) {
        fo.bounds.lo = fo.bounds.lo - mesh->origin;
        fo.bounds.hi = fo.bounds.hi - mesh->origin;
    }
    asArgument([&] { validateMesh(mesh->mesh.view(), "mesh"); });
    std::shared_ptr<SignedDistanceField> out;
    interruptible([&](Cancel& cancel) {
        const Frame frame = fitFrame(computeBounds(mesh->mesh.view()), fo);
        o.progress = &cancel;
        out = std::make_shared<SignedDistanceField>(signedDistanceField(mesh->mesh.view(), frame, o));
    });
    if (mesh->shifted()) out->frame = out->frame.translated(mesh->origin);
    return out;
}

void bindDistance(py::module_& m) {
    m.attr("ClosestPoints") =
        py::module_::import("collections")
            .attr("namedtuple")("ClosestPoints", py::make_tuple("point", "face", "barycentric", "distance"));
    m.attr("ClosestPoints").attr("__module__") = "voxfx";
    m.attr("ClosestPoints").attr("__doc__") =
        "closest_points() result: point (K, 3) float64 on the mesh, face (K,) int64 (-1 for a non-finite "
        "query), barycentric (K, 3) float64 weights of the face's corners 0, 1, 2, distance (K,) float64";
    m.def(
        "closest_points", &closestPoints, py::arg("mesh"), py::arg("faces") = py::none(),
        py::arg("points") = py::none(), py::kw_only(), py::arg("threads") = 0,
        "The point of the mesh nearest to each of the (K, 3) points: ClosestPoints(point, face, barycentric, "
        "distance). Exact: the distance to the triangles of the float vertices, in double precision (a few "
        "ulps); ties go to the smallest face index. Non-finite points get NaN and face -1. Called as "
        "closest_points(mesh, points) or closest_points(vertices, faces, points); the GIL is released, "
        "Ctrl-C stops it.");
    m.def("signed_distance", &signedDistances, py::arg("mesh"), py::arg("faces") = py::none(),
          py::arg("points") = py::none(), py::kw_only(), py::arg("sign") = "auto", py::arg("threads") = 0,
          py::arg("winding_beta") = 3.0,
          "(K,) float64: the distance from each point to the mesh, negative inside. sign: auto (parity for "
          "closed meshes, winding otherwise), parity (the exact inside test of contains(), its tie rule) or "
          "winding (generalized winding number >= 0.5, for open meshes).");

    py::class_<SignedDistanceField, SdfPtr>(
        m, "SignedDistanceField",
        "A signed distance field on voxel centres: exact distances in a narrow band (or everywhere), "
        "+-background beyond, negative inside; sparse (8^3 blocks) until to_numpy() asks for every voxel")
        .def_property_readonly("dims", [](const SignedDistanceField& f) { return vec3(f.dims()); })
        .def_property_readonly("cell_size",
                               [](const SignedDistanceField& f) { return vec3(f.frame.cellSize()); })
        .def_property_readonly(
            "origin", [](const SignedDistanceField& f) { return vec3(f.frame.box().lo); },
            "Lower corner of voxel (0, 0, 0); its centre is origin + cell_size / 2")
        .def_property_readonly("affine", &sdfAffine, "4 x 4 matrix from (i, j, k, 1) to the voxel's centre")
        .def_property_readonly(
            "background", [](const SignedDistanceField& f) { return f.background; },
            "The band width (world units): inactive voxels hold +background or -background")
        .def_property_readonly(
            "band", [](const SignedDistanceField& f) { return f.bandVoxels; },
            "The band's half-width in voxels (0 when full)")
        .def_property_readonly("full", [](const SignedDistanceField& f) { return f.full; })
        .def_property_readonly(
            "fill", [](const SignedDistanceField& f) { return std::string(toString(f.fill)); },
            "The inside test behind the sign")
        .def_property_readonly("active_count", &SignedDistanceField::activeCount)
        .def("to_numpy", &sdfDense, "Every voxel's value: float32 array (nx, ny, nz) indexed [i, j, k]")
        .def(
            "__array__", [](const SignedDistanceField& f, const py::object&) { return sdfDense(f); },
            py::arg("dtype") = py::none())
        .def("active", &sdfActive,
             "The band without a dense array: (indices (N, 3) int32, values (N,) float32) of the active "
             "voxels")
        .def(
            "value",
            [](const SignedDistanceField& f, int64_t i, int64_t j, int64_t k) {
                return asArgument([&] { return f.value(i, j, k); });
            },
            py::arg("i"), py::arg("j"), py::arg("k"))
        .def(
            "save",
            [](const SignedDistanceField& f, const py::object& path) {
                const std::string p = pathString(path);
                py::gil_scoped_release release;
                writeSdf(f, p);
            },
            py::arg("path"), "Writes .vdb (OpenVDB level set), .nrrd or .npy (dense float32), atomically")
        .def("__repr__", [](const SignedDistanceField& f) {
            const Vec3i d = f.dims();
            std::ostringstream s;
            s << "<voxfx.SignedDistanceField " << d.x << " x " << d.y << " x " << d.z << ", cell "
              << f.frame.cellSize().x << (f.full ? ", every voxel" : ", band ");
            if (!f.full) s << f.bandVoxels << " voxels";
            s << ", sign from " << toString(f.fill) << ", " << f.activeCount() << " active>";
            return s.str();
        });
    m.def("sdf", &makeSdf, py::arg("mesh"), py::arg("faces") = py::none(), py::kw_only(),
          py::arg("resolution") = py::none(), py::arg("voxel_size") = py::none(),
          py::arg("bounds") = py::none(), py::arg("margin") = py::none(), py::arg("cube") = false,
          py::arg("band") = 3.0, py::arg("fill") = "auto", py::arg("threads") = 0,
          "The signed distance field of a mesh (any mesh voxelize accepts) on the voxel centres of a grid "
          "fitted like voxelize() (resolution, default 256, or voxel_size; bounds; cube=True for "
          "resolution^3 cubic cells; margin, default the band rounded up): exact "
          "distances where they are below band voxels (band='full': everywhere), negative where "
          "voxelize(mode='solid', fill=...) fills the voxel (fill auto: parity for closed meshes, gwn "
          "otherwise). Returns a SignedDistanceField: .to_numpy() dense, .active() the band as indices and "
          "values, .affine, .save(). The GIL is released; Ctrl-C stops it.");
}

} // namespace voxfx::python
