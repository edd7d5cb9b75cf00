// Samples for learning (voxfx/surface_sampling.hpp): sample_surface and sample_near_surface, as
// DeepSDF and Occupancy Networks prepare their data. The Python wrappers (voxfx/_datasets.py) add
// torch tensors in and out.
#include <cmath>
#include <cstring>
#include <variant>

#include "common.hpp"
#include "voxfx/surface_sampling.hpp"

namespace voxfx::python {
namespace {

uint64_t samplingSeed(int64_t seed) {
    if (seed < 0) throw ArgumentError("seed must be >= 0");
    return uint64_t(seed);
}

void samplingCount(int64_t n, int threads) {
    if (n < 0) throw ArgumentError("n must be >= 0");
    if (threads < 0) throw ArgumentError("threads must be >= 0");
}

/// (n, 3) float64 positions in world coordinates (the mesh's origin added back).
py::array_t<double> samplePoints(const std::vector<Vec3d>& p, const Vec3d& origin) {
    py::array_t<double> out({py::ssize_t(p.size()), py::ssize_t(3)});
    double* d = out.mutable_data();
    for (std::size_t i = 0; i < p.size(); ++i)
        for (int k = 0; k < 3; ++k) d[3 * i + std::size_t(k)] = p[i][k] + origin[k];
    return out;
}

py::object sampleSurfaceArrays(const py::object& meshObj, int64_t n, int64_t seed, int threads) {
    samplingCount(n, threads);
    const uint64_t s = samplingSeed(seed);
    const auto mesh = meshArgument(meshObj, py::none());
    asArgument([&] { validateMesh(mesh->mesh.view(), "mesh"); });
    SurfaceSamples samples;
    interruptible([&](Cancel& cancel) {
        SurfaceSampleOptions o;
        o.threads = threads;
        o.progress = &cancel;
        samples = sampleSurface(mesh->mesh.view(), n, s, o);
    });
    py::array_t<float> normals({py::ssize_t(n), py::ssize_t(3)});
    py::array_t<int64_t> faces{py::ssize_t(n)};
    if (n > 0)
        std::memcpy(normals.mutable_data(), samples.normals.data(), samples.normals.size() * sizeof(Vec3f));
    std::copy(samples.faces.begin(), samples.faces.end(), faces.mutable_data());
    const py::object type = py::module_::import("voxfx._voxfx").attr("SurfaceSamples");
    return type(samplePoints(samples.points, mesh->origin), normals, faces);
}

py::object sampleNearSurfaceArrays(const py::object& meshObj, int64_t n,
                                   const std::variant<double, std::vector<double>>& sigma, int64_t seed,
                                   double uniform, double boxMargin, const std::string& sign,
                                   double windingBeta, int threads) {
    samplingCount(n, threads);
    const uint64_t s = samplingSeed(seed);
    NearSurfaceOptions o;
    if (const auto* one = std::get_if<double>(&sigma))
        o.sigmas = {*one};
    else
        o.sigmas = std::get<std::vector<double>>(sigma);
    o.uniformFraction = uniform;
    o.boxMargin = boxMargin;
    o.sign = asArgument([&] { return parseSignMethod(sign); });
    if (!(windingBeta >= 0)) throw ArgumentError("winding_beta must be >= 0");
    o.windingBeta = windingBeta;
    o.threads = threads;
    if (o.sigmas.empty()) throw ArgumentError("sigma: give at least one standard deviation");
    for (const double x : o.sigmas)
        if (!(x > 0) || !std::isfinite(x)) throw ArgumentError("sigma must be finite and > 0 (world units)");
    if (!(uniform >= 0 && uniform <= 1)) throw ArgumentError("uniform must lie in [0, 1]");
    if (!(boxMargin >= 0) || !std::isfinite(boxMargin))
        throw ArgumentError("box_margin must be finite and >= 0");
    const auto mesh = meshArgument(meshObj, py::none());
    asArgument([&] { validateMesh(mesh->mesh.view(), "mesh"); });
    NearSurfaceSamples samples;
    interruptible([&](Cancel& cancel) {
        o.progress = &cancel;
        samples = sampleNearSurface(mesh->mesh.view(), n, s, o);
    });
    py::array_t<double> sdf{py::ssize_t(n)};
    py::array_t<bool> inside{py::ssize_t(n)};
    std::copy(samples.distances.begin(), samples.distances.end(), sdf.mutable_data());
    bool* in = inside.mutable_data();
    for (std::size_t i = 0; i < samples.inside.size(); ++i) in[i] = samples.inside[i] != 0;
    const py::object type = py::module_::import("voxfx._voxfx").attr("NearSurfaceSamples");
    return type(samplePoints(samples.points, mesh->origin), sdf, inside);
}

} // namespace

void bindSampling(py::module_& m) {
    const py::object namedtuple = py::module_::import("collections").attr("namedtuple");
    m.attr("SurfaceSamples") = namedtuple("SurfaceSamples", py::make_tuple("points", "normals", "faces"));
    m.attr("SurfaceSamples").attr("__module__") = "voxfx";
    m.attr("SurfaceSamples").attr("__doc__") =
        "sample_surface() result: points (n, 3) float64 on the surface, normals (n, 3) float32 (the unit "
        "normal of each point's face, its counter-clockwise side: outward for a closed mesh oriented so), "
        "faces (n,) int64 (the triangle each point lies on)";
    m.attr("NearSurfaceSamples") =
        namedtuple("NearSurfaceSamples", py::make_tuple("points", "sdf", "inside"));
    m.attr("NearSurfaceSamples").attr("__module__") = "voxfx";
    m.attr("NearSurfaceSamples").attr("__doc__") =
        "sample_near_surface() result: points (n, 3) float64, sdf (n,) float64 (exact signed distance, "
        "negative inside: voxfx's convention), inside (n,) bool (sdf < 0, -0.0 included)";

    m.def(
        "sample_surface", &sampleSurfaceArrays, py::arg("mesh"), py::arg("n"), py::arg("seed") = 0,
        py::kw_only(), py::arg("threads") = 0,
        "n points uniformly distributed over the mesh's surface (area-weighted: a triangle is picked with "
        "probability area / total area, then a uniform point in it). Returns SurfaceSamples(points, normals, "
        "faces). Deterministic: sample i depends only on (seed, i), so the result is the same for any thread "
        "count and the first k samples of a call for n are those of a call for k. mesh: anything voxelize "
        "takes. The GIL is released; Ctrl-C stops it.");
    m.def(
        "sample_near_surface", &sampleNearSurfaceArrays, py::arg("mesh"), py::arg("n"), py::arg("sigma"),
        py::arg("seed") = 0, py::kw_only(), py::arg("uniform") = 0.0, py::arg("box_margin") = 0.1,
        py::arg("sign") = "auto", py::arg("winding_beta") = 3.0, py::arg("threads") = 0,
        "n points near the surface with their exact signed distances (negative inside) and inside labels, as "
        "DeepSDF and Occupancy Networks prepare data: surface samples (sample_surface's, the same seed) "
        "moved "
        "by Gaussian offsets of standard deviation sigma (world units; a list cycles through several sigmas, "
        "sample i using sigma[i % len]), and the last round(n * uniform) points uniform in the mesh's "
        "bounding "
        "box grown by box_margin times its longest side on every side. Distances as signed_distance (sign: "
        "auto | parity | winding). Returns NearSurfaceSamples(points, sdf, inside). Deterministic for a seed "
        "whatever the thread count. The GIL is released; Ctrl-C stops it.");
}

} // namespace voxfx::python
