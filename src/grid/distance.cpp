// voxfx — distances from points to a triangle mesh (see voxfx/distance.hpp): closest points over
// the one hierarchy of grid/triangle_bvh.hpp, signed by the inside tests of voxfx/contains.hpp.
#include "voxfx/distance.hpp"

#include <atomic>
#include <cmath>
#include <mutex>

#include "core/enum_names.hpp"
#include "grid/triangle_bvh.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

namespace {

constexpr detail::EnumName<SignMethod> kSignMethodNames[] = {{"auto", SignMethod::Auto},
                                                             {"parity", SignMethod::Parity},
                                                             {"winding", SignMethod::Winding},
                                                             {"gwn", SignMethod::Winding, true}};

// Points per task: enough to hide the task overhead, few enough to balance and report progress.
constexpr int64_t kChunk = 2048;

// Runs body(b, e) over chunks of [0, n) on up to `threads` workers, reporting progress between
// chunks; voxfx::Error "cancelled" when the progress object says stop.
template <class Body> void forPointChunks(int64_t n, int threads, Progress* progress, Body&& body) {
    std::atomic<bool> cancelled{false};
    std::atomic<int64_t> done{0};
    std::mutex progressMutex;
    const int64_t chunks = (n + kChunk - 1) / kChunk;
    withThreads(threads, [&] {
        parallelFor(0, n, kChunk, [&](int64_t b, int64_t e) {
            if (cancelled.load(std::memory_order_relaxed)) return;
            body(b, e);
            const int64_t d = ++done;
            if (!progress) return;
            std::lock_guard<std::mutex> lock(progressMutex);
            if (!progress->update(double(d) / double(chunks))) cancelled = true;
        });
    });
    if (cancelled) fail("cancelled");
}

} // namespace

const char* toString(SignMethod m) {
    switch (m) {
    case SignMethod::Auto:
        return "auto";
    case SignMethod::Parity:
        return "parity";
    case SignMethod::Winding:
        return "winding";
    }
    return "?";
}

SignMethod parseSignMethod(const std::string& name) {
    return detail::parseEnum<SignMethod>(name, "sign method", kSignMethodNames);
}

ClosestPointQuery::ClosestPointQuery(const MeshView& mesh) {
    validateMesh(mesh, "closest points");
    if (mesh.triangleCount == 0) fail("closest points: the mesh has no triangles");
    bvh_ = std::make_unique<detail::TriangleBvh>(mesh);
}

ClosestPointQuery::~ClosestPointQuery() = default;
ClosestPointQuery::ClosestPointQuery(ClosestPointQuery&&) noexcept = default;
ClosestPointQuery& ClosestPointQuery::operator=(ClosestPointQuery&&) noexcept = default;

std::size_t ClosestPointQuery::triangleCount() const { return bvh_->triangleCount(); }

ClosestPoint ClosestPointQuery::closest(const Vec3d& p) const {
    ClosestPoint out;
    const detail::NearestHit hit = bvh_->nearest(p);
    if (hit.face < 0) return out;
    out.face = hit.face;
    out.distance = std::sqrt(hit.distance2);
    out.barycentric = {1.0 - hit.u - hit.v, hit.u, hit.v};
    // The triangle as the kernel saw it: corner a plus the weighted edges.
    const detail::DistanceTriangle& t = bvh_->triangle(hit.index);
    out.point = t.a + t.ab * hit.u + t.ac * hit.v;
    return out;
}

void ClosestPointQuery::closest(std::span<const Vec3d> points, std::span<ClosestPoint> out,
                                const DistanceOptions& options) const {
    if (points.size() != out.size())
        fail("closest points: ", points.size(), " points but room for ", out.size(), " answers");
    forPointChunks(int64_t(points.size()), options.threads, options.progress, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i) out[std::size_t(i)] = closest(points[std::size_t(i)]);
    });
}

void ClosestPointQuery::distance(std::span<const Vec3d> points, std::span<double> out,
                                 const DistanceOptions& options) const {
    if (points.size() != out.size())
        fail("distances: ", points.size(), " points but room for ", out.size(), " answers");
    forPointChunks(int64_t(points.size()), options.threads, options.progress, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i) {
            const detail::NearestHit hit = bvh_->nearest(points[std::size_t(i)]);
            out[std::size_t(i)] =
                hit.face < 0 ? std::numeric_limits<double>::quiet_NaN() : std::sqrt(hit.distance2);
        }
    });
}

std::vector<ClosestPoint> closestPoints(const MeshView& mesh, std::span<const Vec3d> points,
                                        const DistanceOptions& options) {
    const ClosestPointQuery query(mesh);
    std::vector<ClosestPoint> out(points.size());
    query.closest(points, out, options);
    return out;
}

void signedDistance(const MeshView& mesh, std::span<const Vec3d> points, std::span<double> out,
                    const SignedDistanceOptions& options) {
    if (points.size() != out.size())
        fail("signed distance: ", points.size(), " points but room for ", out.size(), " answers");
    const ClosestPointQuery query(mesh);
    SignMethod method = options.sign;
    if (method == SignMethod::Auto)
        method = analyzeTopology(mesh).closed() ? SignMethod::Parity : SignMethod::Winding;
    if (options.used) *options.used = method;
    DistanceOptions distanceOptions;
    distanceOptions.threads = options.threads;
    distanceOptions.progress = options.progress;
    query.distance(points, out, distanceOptions);

    ContainsOptions co;
    co.method = method == SignMethod::Parity ? ContainsMethod::Parity : ContainsMethod::Winding;
    co.windingBeta = options.windingBeta;
    co.threads = options.threads;
    std::vector<uint8_t> inside(points.size());
    contains(mesh, points, inside, co);
    for (std::size_t i = 0; i < out.size(); ++i)
        if (inside[i]) out[i] = -out[i];
}

std::vector<double> signedDistance(const MeshView& mesh, std::span<const Vec3d> points,
                                   const SignedDistanceOptions& options) {
    std::vector<double> out(points.size());
    signedDistance(mesh, points, out, options);
    return out;
}

} // namespace voxfx
