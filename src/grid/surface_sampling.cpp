// voxfx — random points on and near a mesh (see voxfx/surface_sampling.hpp): area-weighted surface
// samples (Osada et al. 2002, "Shape distributions", §4.2) from a counter-based generator, and
// near-surface samples with the exact signed distances of voxfx/distance.hpp (DeepSDF, Park et al.
// 2019, §5; Occupancy Networks, Mescheder et al. 2019, §4).
#include "voxfx/surface_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/progress_range.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

namespace {

// Samples per task: enough to hide the task overhead, few enough to poll for cancellation.
constexpr int64_t kSampleChunk = 16384;

// Random numbers per sample: two for the face (alias table column and coin), two barycentric, four
// for Gaussian offsets (Box-Muller pairs), three for a uniform box point. Stream k of sample i is
// counter i * kSampleStreams + k.
constexpr uint64_t kSampleStreams = 16;
enum SampleStream : uint64_t {
    kStreamFace = 0,
    kStreamCoin,
    kStreamBary1,
    kStreamBary2,
    kStreamGauss0,
    kStreamGauss1,
    kStreamGauss2,
    kStreamGauss3,
    kStreamBoxX,
    kStreamBoxY,
    kStreamBoxZ
};

/// SplitMix64's output function (Steele, Lea & Flood 2014): a bijective mix of 64 bits whose
/// outputs over a counter pass BigCrush. Counter-based: any sample's numbers in O(1).
uint64_t sampleMix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/// The random numbers of one seed: uniform(i, k) is stream k of sample i.
struct SampleRng {
    uint64_t key;
    explicit SampleRng(uint64_t seed) : key(sampleMix64(seed ^ 0x6a09e667f3bcc909ULL)) {}
    /// Uniform in [0, 1): the top 53 bits of the mixed counter.
    double uniform(uint64_t sample, uint64_t stream) const {
        const uint64_t bits = sampleMix64(key + (sample * kSampleStreams + stream) * 0x9e3779b97f4a7c15ULL);
        return double(bits >> 11) * 0x1.0p-53;
    }
    /// Two independent standard normal numbers (Box-Muller) from streams a and b.
    void normals(uint64_t sample, uint64_t a, uint64_t b, double& g0, double& g1) const {
        const double u = 1.0 - uniform(sample, a); // (0, 1]: the logarithm stays finite
        const double v = uniform(sample, b);
        const double r = std::sqrt(-2.0 * std::log(u));
        g0 = r * std::cos(2 * std::numbers::pi * v);
        g1 = r * std::sin(2 * std::numbers::pi * v);
    }
};

/// The triangles' areas as Walker's alias table (Vose's construction, "A linear algorithm for
/// generating random numbers with a given distribution", 1991): column t is kept with probability
/// keep[t], else it gives alias[t], so one uniform column and one coin pick triangle t with
/// probability area(t) / total in O(1) (a binary search over the running sum of the areas cost a
/// cache miss per level on large meshes). Built serially in triangle order: the same table for any
/// thread count. Triangles of zero area have keep 0 and are never picked.
struct SampleAreaTable {
    std::vector<double> keep;
    std::vector<uint32_t> alias;
    std::vector<Vec3f> normals;
    double total = 0;
};

SampleAreaTable sampleAreaTable(const MeshView& mesh) {
    SampleAreaTable table;
    const auto T = int64_t(mesh.triangleCount);
    std::vector<double> area(static_cast<std::size_t>(T));
    table.normals.resize(std::size_t(T));
    parallelFor(0, T, 8192, [&](int64_t b, int64_t e) {
        for (int64_t t = b; t < e; ++t) {
            const Vec3d a = mesh.vertex(mesh.index(std::size_t(t), 0));
            const Vec3d n = cross(mesh.vertex(mesh.index(std::size_t(t), 1)) - a,
                                  mesh.vertex(mesh.index(std::size_t(t), 2)) - a);
            const double twice = length(n);
            area[std::size_t(t)] = 0.5 * twice;
            table.normals[std::size_t(t)] = twice > 0 ? Vec3f(n / twice) : Vec3f{};
        }
    });
    for (const double a : area) table.total += a;
    if (!(table.total > 0) || !std::isfinite(table.total)) return table;
    // Vose: scaled areas (mean 1) split into columns below and above 1; each small column is
    // topped up from a large one, which becomes small when it falls below 1.
    table.keep.resize(std::size_t(T));
    table.alias.resize(std::size_t(T));
    std::vector<uint32_t> small, large;
    uint32_t biggest = 0;
    for (int64_t t = 0; t < T; ++t) {
        const auto k = std::size_t(t);
        table.keep[k] = area[k] * double(T) / table.total;
        table.alias[k] = uint32_t(t);
        (table.keep[k] < 1 ? small : large).push_back(uint32_t(t));
        if (area[k] > area[biggest]) biggest = uint32_t(t);
    }
    while (!small.empty() && !large.empty()) {
        const uint32_t s = small.back(), l = large.back();
        small.pop_back();
        table.alias[s] = l;
        table.keep[l] = (table.keep[l] + table.keep[s]) - 1; // Vose's order of the operations
        if (table.keep[l] < 1) {
            large.pop_back();
            small.push_back(l);
        }
    }
    // What is left is 1 up to rounding; a zero-area triangle left over stays unpicked.
    for (const std::vector<uint32_t>* rest : {&small, &large})
        for (const uint32_t t : *rest) {
            table.keep[t] = area[t] > 0 ? 1.0 : 0.0;
            if (!(area[t] > 0)) table.alias[t] = biggest;
        }
    return table;
}

/// Surface sample i: its face (alias table) and a uniform point in it.
void surfaceSample(const MeshView& mesh, const SampleAreaTable& table, const SampleRng& rng, uint64_t i,
                   Vec3d& point, uint32_t& face) {
    const auto T = table.keep.size();
    // u * T < T for u < 1 in exact arithmetic; rounding may reach T: clamped.
    const auto column = std::min(std::size_t(rng.uniform(i, kStreamFace) * double(T)), T - 1);
    face = rng.uniform(i, kStreamCoin) < table.keep[column] ? uint32_t(column) : table.alias[column];
    const double r = std::sqrt(rng.uniform(i, kStreamBary1)), v = rng.uniform(i, kStreamBary2);
    const Vec3d a = mesh.vertex(mesh.index(face, 0)), b = mesh.vertex(mesh.index(face, 1)),
                c = mesh.vertex(mesh.index(face, 2));
    point = a * (1 - r) + b * (r * (1 - v)) + c * (r * v);
}

/// The checks and the area table shared by both samplers.
SampleAreaTable prepareSampling(const MeshView& mesh, int64_t count, const char* what) {
    if (count < 0) fail(what, ": the sample count must be >= 0, got ", count);
    validateMesh(mesh, "mesh");
    if (mesh.triangleCount == 0) fail(what, ": the mesh has no triangles");
    SampleAreaTable table = sampleAreaTable(mesh);
    if (!(table.total > 0)) fail(what, ": every triangle of the mesh has zero area");
    if (!std::isfinite(table.total)) fail(what, ": the mesh's surface area overflows a double");
    return table;
}

/// Runs body(b, e) over [0, count) in chunks, polling `progress` after each.
template <class Body> void sampleChunks(int64_t count, Progress* progress, const char* what, Body&& body) {
    ProgressSteps steps(progress, (count + kSampleChunk - 1) / kSampleChunk);
    parallelFor(0, count, kSampleChunk, [&](int64_t b, int64_t e) {
        if (steps.cancelled()) return;
        body(b, e);
        steps.step();
    });
    if (steps.cancelled()) fail(what, ": cancelled");
}

} // namespace

SurfaceSamples sampleSurface(const MeshView& mesh, int64_t count, uint64_t seed,
                             const SurfaceSampleOptions& options) {
    SurfaceSamples out;
    withThreads(options.threads, [&] {
        const SampleAreaTable table = prepareSampling(mesh, count, "surface sampling");
        const SampleRng rng(seed);
        out.points.resize(std::size_t(count));
        out.normals.resize(std::size_t(count));
        out.faces.resize(std::size_t(count));
        sampleChunks(count, options.progress, "surface sampling", [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) {
                const auto k = std::size_t(i);
                surfaceSample(mesh, table, rng, uint64_t(i), out.points[k], out.faces[k]);
                out.normals[k] = table.normals[out.faces[k]];
            }
        });
    });
    return out;
}

NearSurfaceSamples sampleNearSurface(const MeshView& mesh, int64_t count, uint64_t seed,
                                     const NearSurfaceOptions& options) {
    const char* what = "near-surface sampling";
    if (options.sigmas.empty()) fail(what, ": give at least one sigma");
    for (const double s : options.sigmas)
        if (!(s > 0) || !std::isfinite(s)) fail(what, ": sigma must be finite and > 0, got ", s);
    if (!(options.uniformFraction >= 0 && options.uniformFraction <= 1))
        fail(what, ": the uniform fraction must lie in [0, 1], got ", options.uniformFraction);
    if (!(options.boxMargin >= 0) || !std::isfinite(options.boxMargin))
        fail(what, ": the box margin must be finite and >= 0, got ", options.boxMargin);
    NearSurfaceSamples out;
    withThreads(options.threads, [&] {
        const SampleAreaTable table = prepareSampling(mesh, count, what);
        const SampleRng rng(seed);
        const auto uniformCount = int64_t(std::llround(double(count) * options.uniformFraction));
        const int64_t nearCount = count - uniformCount;
        Box3d box = computeBounds(mesh);
        const Vec3d extent = box.extent();
        const double grow = options.boxMargin * std::max({extent.x, extent.y, extent.z});
        box.lo = box.lo - Vec3d{grow, grow, grow};
        box.hi = box.hi + Vec3d{grow, grow, grow};
        const auto sigmaCount = uint64_t(options.sigmas.size());
        out.points.resize(std::size_t(count));
        detail::ProgressRange sampling(options.progress, 0.0, 0.1), distances(options.progress, 0.1, 1.0);
        sampleChunks(count, sampling.get(), what, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) {
                Vec3d& p = out.points[std::size_t(i)];
                if (i < nearCount) {
                    uint32_t face = 0;
                    surfaceSample(mesh, table, rng, uint64_t(i), p, face);
                    double g[4];
                    rng.normals(uint64_t(i), kStreamGauss0, kStreamGauss1, g[0], g[1]);
                    rng.normals(uint64_t(i), kStreamGauss2, kStreamGauss3, g[2], g[3]);
                    const double sigma = options.sigmas[std::size_t(uint64_t(i) % sigmaCount)];
                    p += Vec3d{g[0], g[1], g[2]} * sigma;
                } else {
                    for (int a = 0; a < 3; ++a)
                        p[a] = box.lo[a] +
                               rng.uniform(uint64_t(i), kStreamBoxX + uint64_t(a)) * (box.hi[a] - box.lo[a]);
                }
            }
        });
        SignedDistanceOptions so;
        so.sign = options.sign;
        so.windingBeta = options.windingBeta;
        so.threads = options.threads;
        so.progress = distances.get();
        out.distances.resize(std::size_t(count));
        if (count > 0) signedDistance(mesh, out.points, out.distances, so);
        out.inside.resize(std::size_t(count));
        for (std::size_t i = 0; i < out.inside.size(); ++i)
            out.inside[i] = std::signbit(out.distances[i]) ? 1 : 0;
    });
    return out;
}

} // namespace voxfx
