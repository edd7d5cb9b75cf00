// voxfx — distances from points to a triangle mesh (see voxfx/distance.hpp): closest points over
// the one hierarchy of grid/triangle_bvh.hpp, signed by the inside tests of voxfx/contains.hpp.
#include "voxfx/distance.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

#include "core/progress_range.hpp"
#include "grid/triangle_bvh.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

namespace {

// Points per task: enough to hide the task overhead, few enough to balance and report progress.
constexpr int64_t kChunk = 2048;
// Points sorted together along the Morton curve (bounds the memory of the ordering).
constexpr int64_t kBlock = int64_t(1) << 20;

/// The 21 low bits of x spread to every third bit (bit i to bit 3i).
uint64_t spreadBits(uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

/// Point indices [begin, end) in Morton order of their position in `box` (points outside clamped
/// to it, non-finite ones last): consecutive queries then walk the same part of the tree, which is
/// in cache, and each starts from its predecessor's answer. The order is fixed by the points alone.
std::vector<std::pair<uint64_t, uint32_t>> mortonOrder(std::span<const Vec3d> points, int64_t begin,
                                                       int64_t end, const Box3d& box) {
    std::vector<std::pair<uint64_t, uint32_t>> keys(std::size_t(end - begin));
    const Vec3d e = box.extent();
    parallelFor(begin, end, 16384, [&](int64_t b, int64_t f) {
        for (int64_t i = b; i < f; ++i) {
            const Vec3d& p = points[std::size_t(i)];
            uint64_t key = ~uint64_t(0);
            if (isFinite(p)) {
                key = 0;
                for (int a = 0; a < 3; ++a) {
                    const double t = e[a] > 0 ? std::clamp((p[a] - box.lo[a]) / e[a], 0.0, 1.0) : 0.0;
                    key |= spreadBits(uint64_t(t * 2097151.0)) << a;
                }
            }
            keys[std::size_t(i - begin)] = {key, uint32_t(i - begin)};
        }
    });
    std::sort(keys.begin(), keys.end());
    return keys;
}

// Answers every point with query(index, hint) -> hit, in Morton order within blocks of kBlock
// points, each chunk of kChunk points on one worker, the hint being the previous point's answer;
// `store(index, hit)` writes the answer. Progress between chunks; voxfx::Error "cancelled" when
// the progress object says stop.
template <class Store>
void forPoints(const detail::TriangleBvh& bvh, std::span<const Vec3d> points, int threads, Progress* progress,
               Store&& store) {
    const auto n = int64_t(points.size());
    ProgressSteps steps(progress, (n + kChunk - 1) / kChunk);
    // The points' order is taken in the mesh's box grown by half its size: farther points are
    // clamped to it (they are few, and far from everything anyway).
    Box3d box = bvh.bounds();
    const Vec3d grow = box.extent() * 0.5;
    box.lo -= grow;
    box.hi += grow;
    withThreads(threads, [&] {
        for (int64_t block = 0; block < n && !steps.cancelled(); block += kBlock) {
            const int64_t blockEnd = std::min(n, block + kBlock);
            const auto order = mortonOrder(points, block, blockEnd, box);
            parallelFor(0, blockEnd - block, kChunk, [&](int64_t b, int64_t e) {
                if (steps.cancelled()) return;
                uint32_t hint = UINT32_MAX;
                for (int64_t k = b; k < e; ++k) {
                    const int64_t i = block + order[std::size_t(k)].second;
                    const detail::NearestHit hit =
                        bvh.nearest(points[std::size_t(i)], std::numeric_limits<double>::infinity(), hint);
                    if (hit.face >= 0) hint = hit.index;
                    store(i, hit);
                }
                steps.step();
            });
        }
    });
    if (steps.cancelled()) fail("cancelled");
}

} // namespace

const char* toString(SignMethod m) { return enumName(m, kSignMethodNames); }

SignMethod parseSignMethod(const std::string& name) {
    return parseEnum<SignMethod>(name, "sign method", kSignMethodNames);
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

namespace {
ClosestPoint closestOf(const detail::TriangleBvh& bvh, const detail::NearestHit& hit) {
    ClosestPoint out;
    if (hit.face < 0) return out;
    out.face = hit.face;
    out.distance = std::sqrt(hit.distance2);
    out.barycentric = {1.0 - hit.u - hit.v, hit.u, hit.v};
    // The triangle as the kernel saw it: corner a plus the weighted edges.
    const detail::DistanceTriangle t = bvh.triangle(hit.index);
    out.point = t.a + t.ab * hit.u + t.ac * hit.v;
    return out;
}
} // namespace

ClosestPoint ClosestPointQuery::closest(const Vec3d& p) const { return closestOf(*bvh_, bvh_->nearest(p)); }

void ClosestPointQuery::closest(std::span<const Vec3d> points, std::span<ClosestPoint> out,
                                const DistanceOptions& options) const {
    if (points.size() != out.size())
        fail("closest points: ", points.size(), " points but room for ", out.size(), " answers");
    forPoints(*bvh_, points, options.threads, options.progress,
              [&](int64_t i, const detail::NearestHit& hit) { out[std::size_t(i)] = closestOf(*bvh_, hit); });
}

void ClosestPointQuery::distance(std::span<const Vec3d> points, std::span<double> out,
                                 const DistanceOptions& options) const {
    if (points.size() != out.size())
        fail("distances: ", points.size(), " points but room for ", out.size(), " answers");
    forPoints(*bvh_, points, options.threads, options.progress,
              [&](int64_t i, const detail::NearestHit& hit) {
                  out[std::size_t(i)] =
                      hit.face < 0 ? std::numeric_limits<double>::quiet_NaN() : std::sqrt(hit.distance2);
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
    // The distances, then the inside test, as one progress.
    detail::ProgressRange distanceProgress(options.progress, 0.0, 0.7),
        insideProgress(options.progress, 0.7, 1.0);
    DistanceOptions distanceOptions;
    distanceOptions.threads = options.threads;
    distanceOptions.progress = distanceProgress.get();
    query.distance(points, out, distanceOptions);

    ContainsOptions co;
    co.method = method == SignMethod::Parity ? ContainsMethod::Parity : ContainsMethod::Winding;
    co.windingBeta = options.windingBeta;
    co.threads = options.threads;
    co.progress = insideProgress.get();
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
