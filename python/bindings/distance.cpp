// Distances: closest_points and signed_distance at points (voxfx/distance.hpp), and signed distance
// fields (voxfx/sdf.hpp): sdf and the SignedDistanceField it returns.
#include "voxfx/distance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
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
    // A bad mesh is a bad argument here as in voxelize (voxfx.ArgumentError, a ValueError).
    asArgument([&] { validateMesh(mesh->mesh.view(), "mesh"); });
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
                                 // A point that is not finite has no distance: NaN (as closest_points).
                                 for (std::size_t i = 0; i < p.size(); ++i)
                                     if (!isFinite(p[i])) d[i] = std::nan("");
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

/// Pickle state: version, the frame (box lo, hi, dims), background, band, full, fill, the leaves as
/// arrays (origins (L, 3) int64, active (L, 8) uint64, values (L, 512) float32) and the inside
/// runs (R, 4) int32.
py::tuple sdfState(const SignedDistanceField& f) {
    const py::ssize_t L = py::ssize_t(f.leaves.size()), R = py::ssize_t(f.insideRuns.size());
    py::array_t<int64_t> origins({L, py::ssize_t(3)});
    py::array_t<uint64_t> active({L, py::ssize_t(8)});
    py::array_t<float> values({L, py::ssize_t(512)});
    py::array_t<int32_t> runs({R, py::ssize_t(4)});
    int64_t* o = origins.mutable_data();
    uint64_t* a = active.mutable_data();
    float* v = values.mutable_data();
    int32_t* r = runs.mutable_data();
    for (const SdfLeaf& leaf : f.leaves) {
        for (int k = 0; k < 3; ++k) *o++ = leaf.origin[k];
        a = std::copy(leaf.active.begin(), leaf.active.end(), a);
        v = std::copy(leaf.values.begin(), leaf.values.end(), v);
    }
    for (const SdfInsideRun& run : f.insideRuns) *r++ = run.x0, *r++ = run.x1, *r++ = run.y, *r++ = run.z;
    const Vec3i d = f.dims();
    return py::make_tuple(1, vec3(f.frame.box().lo), vec3(f.frame.box().hi), vec3(d), f.background,
                          f.bandVoxels, f.full, std::string(toString(f.fill)), origins, active, values, runs);
}

SdfPtr sdfFromState(const py::tuple& t) {
    if (t.size() != 12 || t[0].cast<int>() != 1)
        throw py::value_error("not a voxfx.SignedDistanceField pickle (version 1)");
    auto f = std::make_shared<SignedDistanceField>();
    const auto lo = t[1].cast<std::vector<double>>(), hi = t[2].cast<std::vector<double>>();
    const auto d = t[3].cast<std::vector<int64_t>>();
    Box3d box;
    box.lo = {lo.at(0), lo.at(1), lo.at(2)};
    box.hi = {hi.at(0), hi.at(1), hi.at(2)};
    f->frame = Frame::orthographic(box, Axis::Z, d.at(0), d.at(1), d.at(2));
    f->background = t[4].cast<double>();
    f->bandVoxels = t[5].cast<double>();
    f->full = t[6].cast<bool>();
    f->fill = parseFill(t[7].cast<std::string>());
    constexpr int C = py::array::c_style | py::array::forcecast;
    const auto origins = t[8].cast<py::array_t<int64_t, C>>();
    const auto active = t[9].cast<py::array_t<uint64_t, C>>();
    const auto values = t[10].cast<py::array_t<float, C>>();
    const auto runs = t[11].cast<py::array_t<int32_t, C>>();
    const std::size_t L = std::size_t(origins.size() / 3);
    if (std::size_t(active.size()) != 8 * L || std::size_t(values.size()) != 512 * L || runs.size() % 4)
        throw py::value_error("voxfx.SignedDistanceField pickle: inconsistent arrays");
    f->leaves.resize(L);
    for (std::size_t i = 0; i < L; ++i) {
        SdfLeaf& leaf = f->leaves[i];
        for (int k = 0; k < 3; ++k) leaf.origin[k] = origins.data()[3 * i + std::size_t(k)];
        std::copy_n(active.data() + 8 * i, 8, leaf.active.begin());
        std::copy_n(values.data() + 512 * i, 512, leaf.values.begin());
    }
    f->insideRuns.resize(std::size_t(runs.size() / 4));
    for (std::size_t i = 0; i < f->insideRuns.size(); ++i) {
        const int32_t* r = runs.data() + 4 * i;
        f->insideRuns[i] = {r[0], r[1], r[2], r[3]};
    }
    return f;
}

bool sdfEqual(const SignedDistanceField& a, const SignedDistanceField& b) {
    if (!a.frame.sameGrid(b.frame) || a.background != b.background || a.bandVoxels != b.bandVoxels ||
        a.full != b.full || a.fill != b.fill || a.leaves.size() != b.leaves.size() ||
        a.insideRuns.size() != b.insideRuns.size())
        return false;
    for (std::size_t i = 0; i < a.leaves.size(); ++i)
        if (!(a.leaves[i].origin == b.leaves[i].origin) || a.leaves[i].active != b.leaves[i].active ||
            std::memcmp(a.leaves[i].values.data(), b.leaves[i].values.data(), sizeof(a.leaves[i].values)) !=
                0)
            return false;
    for (std::size_t i = 0; i < a.insideRuns.size(); ++i) {
        const SdfInsideRun &x = a.insideRuns[i], &y = b.insideRuns[i];
        if (x.x0 != y.x0 || x.x1 != y.x1 || x.y != y.y || x.z != y.z) return false;
    }
    return true;
}

py::tuple sdfActive(const SignedDistanceField& f) {
    return activeVoxelArrays([&](auto& indices, auto& values) { f.activeVoxels(indices, values); });
}

} // namespace

std::shared_ptr<SignedDistanceField>
makeSdf(const py::object& meshObj, const py::object& faces, std::optional<int64_t> resolution,
        std::optional<double> voxelSize, const py::object& bounds, std::optional<int64_t> margin, bool cube,
        const std::variant<double, std::string>& band, const std::string& fill, int threads,
        std::optional<int64_t> padding, const py::object& like) {
    if (threads < 0) throw ArgumentError("threads must be >= 0");
    if (!like.is_none() && (resolution || voxelSize || !bounds.is_none() || margin || cube || padding))
        throw ArgumentError("like= takes that grid's frame: give no resolution, voxel_size, bounds, margin, "
                            "cube or padding with it");
    if (padding && *padding < 0) throw ArgumentError("padding must be >= 0");
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
    // The margin defaults to the band rounded up, so the band outside the mesh is not cut. With
    // cube=True (resolution^3 voxels) that default margin lies inside the resolution, as padding
    // does; a margin given is added outside, as voxelize adds it.
    const int64_t bandMargin = o.full ? 0 : int64_t(std::ceil(o.bandVoxels));
    int64_t inner = padding.value_or(0);
    int64_t m = margin.value_or(bandMargin);
    if (cube && !margin) {
        inner = std::max(inner, bandMargin);
        m = 0;
    }
    FitOptions fo = fitOptions(resolution, voxelSize, std::nullopt, bounds, m, "z", cube);
    if (inner > 0) {
        if (fo.resolution == 0) throw ArgumentError("padding needs a resolution (not voxel_size)");
        if (fo.resolution <= 2 * inner)
            throw ArgumentError("a resolution of " + std::to_string(fo.resolution) +
                                " leaves no cells for the mesh "
                                "inside a padding (or cube=True's band) of " +
                                std::to_string(inner) + " cells on every side");
        fo.resolution -= 2 * inner;
        fo.marginCells += inner;
    }
    const auto mesh = meshArgument(meshObj, faces);
    std::optional<Frame> likeFrame;
    if (!like.is_none()) {
        if (py::isinstance<VoxelGrid>(like))
            likeFrame = like.cast<const VoxelGrid&>().frame;
        else if (py::isinstance<SignedDistanceField>(like))
            likeFrame = like.cast<const SignedDistanceField&>().frame;
        else
            throw py::type_error("like must be a voxfx.Grid or a voxfx.SignedDistanceField");
        if (mesh->shifted())
            likeFrame = asArgument([&] { return likeFrame->translated(mesh->origin * -1.0); });
    }
    if (!fo.bounds.empty() && mesh->shifted()) {
        fo.bounds.lo = fo.bounds.lo - mesh->origin;
        fo.bounds.hi = fo.bounds.hi - mesh->origin;
    }
    asArgument([&] { validateMesh(mesh->mesh.view(), "mesh"); });
    std::shared_ptr<SignedDistanceField> out;
    interruptible([&](Cancel& cancel) {
        const Frame frame = likeFrame ? *likeFrame : fitFrame(computeBounds(mesh->mesh.view()), fo);
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
          "winding (generalized winding number >= 0.5, for open meshes). A point with a NaN or infinite "
          "coordinate gets NaN.");

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
        .def(py::pickle(&sdfState, &sdfFromState))
        .def("__eq__",
             [](const SignedDistanceField& a, const py::object& b) -> py::object {
                 if (!py::isinstance<SignedDistanceField>(b))
                     return py::reinterpret_borrow<py::object>(Py_NotImplemented);
                 return py::bool_(sdfEqual(a, b.cast<const SignedDistanceField&>()));
             })
        .def("__repr__", [](const SignedDistanceField& f) {
            const Vec3i d = f.dims();
            std::ostringstream s;
            s << "<voxfx.SignedDistanceField " << d.x << " x " << d.y << " x " << d.z << ", cell "
              << f.frame.cellSize().x << (f.full ? ", every voxel" : ", band ");
            if (!f.full) s << f.bandVoxels << " voxels";
            s << ", sign from " << toString(f.fill) << ", " << f.activeCount() << " active>";
            return s.str();
        });
    m.def(
        "sdf",
        [](const py::object& meshObj, const py::object& faces, std::optional<Int> resolution,
           std::optional<double> voxelSize, const py::object& bounds, std::optional<Int> margin, bool cube,
           const std::variant<double, std::string>& band, const std::string& fill, Int threads,
           std::optional<Int> padding, const py::object& like) {
            const auto opt = [](const std::optional<Int>& v) {
                return v ? std::optional<int64_t>(int64_t(*v)) : std::nullopt;
            };
            return makeSdf(meshObj, faces, opt(resolution), voxelSize, bounds, opt(margin), cube, band, fill,
                           int(threads), opt(padding), like);
        },
        py::arg("mesh"), py::arg("faces") = py::none(), py::kw_only(), py::arg("resolution") = py::none(),
        py::arg("voxel_size") = py::none(), py::arg("bounds") = py::none(), py::arg("margin") = py::none(),
        py::arg("cube") = false, py::arg("band") = 3.0, py::arg("fill") = "auto", py::arg("threads") = 0,
        py::arg("padding") = py::none(), py::arg("like") = py::none(),
        "The signed distance field of a mesh (any mesh voxelize accepts) on the voxel centres of a grid "
        "fitted like voxelize() (resolution, default 256, or voxel_size; bounds; cube=True for "
        "resolution^3 cubic cells, the band's margin inside them; padding: cells kept inside the resolution "
        "on "
        "every side; like=grid or field: that frame exactly; margin, default the band rounded up): exact "
        "distances where they are below band voxels (band='full': everywhere), negative where "
        "voxelize(mode='solid', fill=...) fills the voxel (fill auto: parity for closed meshes, gwn "
        "otherwise). Returns a SignedDistanceField: .to_numpy() dense, .active() the band as indices and "
        "values, .affine, .save(). The GIL is released; Ctrl-C stops it.");
}

} // namespace voxfx::python
