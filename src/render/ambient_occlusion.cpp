// voxfx — distance-field ambient occlusion (voxfx/ambient_occlusion.hpp): the field is the magnitude
// of the narrow-band signed distance field (voxfx/sdf.hpp) of the occluders, densified over the
// region; visibility() traces seven cones through it.
#include "voxfx/ambient_occlusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/error.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {

namespace {

// Cones: half-angle 30 degrees; one along the normal, six at 50 degrees from it. cos 50deg (0.643)
// exceeds tan 30deg (0.577), so a plane through p never enters a cone (see the header).
constexpr double kTanHalfAngle = 0.57735026918962576;
constexpr double kRingAngle = 50 * M_PI / 180;
constexpr int kRing = 6;

// At most this many cells in the field (float each): 64 MiB.
constexpr int64_t kMaxCells = int64_t(1) << 24;

} // namespace

AmbientOcclusion::AmbientOcclusion(const MeshView& occluders, const Box3d& region,
                                   const AmbientOcclusionOptions& options) {
    if (!(options.radius > 0 && std::isfinite(options.radius)))
        fail("ambient occlusion: the radius must be positive and finite, got ", options.radius);
    if (options.resolution < 8 || options.resolution > 2048)
        fail("ambient occlusion: the resolution must be between 8 and 2048 cells, got ", options.resolution);
    if (region.empty() || !std::isfinite(region.lo.x) || !std::isfinite(region.lo.y) ||
        !std::isfinite(region.lo.z) || !std::isfinite(region.hi.x) || !std::isfinite(region.hi.y) ||
        !std::isfinite(region.hi.z))
        fail("ambient occlusion: the region is empty or not finite");
    radius_ = options.radius;
    // Nothing farther than the radius from every occluder can be occluded: the field covers the
    // region and the occluders' bounds, each grown by the radius, where they overlap.
    Box3d occluderBox;
    for (std::size_t i = 0; i < occluders.vertexCount; ++i) {
        const Vec3d v = occluders.vertex(i);
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
            fail("ambient occlusion: vertex ", i, " is not finite");
        occluderBox.extend(v);
    }
    if (occluders.triangleCount == 0 || occluderBox.empty()) return;
    const Vec3d grow{radius_, radius_, radius_};
    Box3d box{max(region.lo, occluderBox.lo) - grow, min(region.hi, occluderBox.hi) + grow};
    if (box.empty()) return;
    // Cubic cells: the longest side gets `resolution` of them, at most kMaxCells in all.
    const Vec3d extent = box.extent();
    const double longest = std::max({extent.x, extent.y, extent.z});
    cell_ = longest / double(options.resolution);
    const auto cellsFor = [&](double cell) {
        return Vec3i{std::max<int64_t>(1, int64_t(std::ceil(extent.x / cell))),
                     std::max<int64_t>(1, int64_t(std::ceil(extent.y / cell))),
                     std::max<int64_t>(1, int64_t(std::ceil(extent.z / cell)))};
    };
    dims_ = cellsFor(cell_);
    while (dims_.x * dims_.y * dims_.z > kMaxCells) {
        cell_ *= 1.25;
        dims_ = cellsFor(cell_);
    }
    lo_ = box.lo;
    const Box3d fieldBox{lo_, lo_ + Vec3d{double(dims_.x), double(dims_.y), double(dims_.z)} * cell_};
    const Frame frame = Frame::orthographic(fieldBox, Axis::Z, dims_.x, dims_.y, dims_.z);
    // Exact at every centre closer than the radius: the band reaches two cells beyond it.
    SdfOptions so;
    so.bandVoxels = std::max(1.0, radius_ / cell_ + 2);
    so.fill = Fill::Parity; // only the magnitude is used: any sign will do, parity is the cheapest
    so.threads = options.threads;
    so.progress = options.progress;
    const SignedDistanceField field = signedDistanceField(occluders, frame, so);
    tracer_ = std::make_shared<const TriangleTracer>(occluders);
    band_ = field.background;
    distance_ = field.dense();
    for (float& d : distance_) d = std::fabs(d);
}

double AmbientOcclusion::distance(const Vec3d& p) const {
    if (distance_.empty()) return std::max(band_, radius_);
    // Cell centres at lo + (i + 1/2) cell: g is p in centre units.
    const Vec3d g = (p - lo_) / cell_ - Vec3d{0.5, 0.5, 0.5};
    if (!(g.x >= 0 && g.y >= 0 && g.z >= 0 && g.x <= double(dims_.x - 1) && g.y <= double(dims_.y - 1) &&
          g.z <= double(dims_.z - 1)))
        return band_;
    const int64_t i = std::min<int64_t>(int64_t(g.x), std::max<int64_t>(0, dims_.x - 2));
    const int64_t j = std::min<int64_t>(int64_t(g.y), std::max<int64_t>(0, dims_.y - 2));
    const int64_t k = std::min<int64_t>(int64_t(g.z), std::max<int64_t>(0, dims_.z - 2));
    const double fx = g.x - double(i), fy = g.y - double(j), fz = g.z - double(k);
    const int64_t sx = dims_.x > 1 ? 1 : 0, sy = dims_.y > 1 ? dims_.x : 0,
                  sz = dims_.z > 1 ? dims_.x * dims_.y : 0;
    const float* c = distance_.data() + (k * dims_.y + j) * dims_.x + i;
    const auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
    const double x00 = lerp(c[0], c[sx], fx), x10 = lerp(c[sy], c[sy + sx], fx);
    const double x01 = lerp(c[sz], c[sz + sx], fx), x11 = lerp(c[sz + sy], c[sz + sy + sx], fx);
    return lerp(lerp(x00, x10, fy), lerp(x01, x11, fy), fz);
}

double AmbientOcclusion::visibility(const Vec3d& p, const Vec3d& n) const {
    if (distance_.empty()) return 1;
    // Every cone sees the whole sky when d(p) >= reach (1 + tan): along an axis d >= d(p) - t.
    const double reach = radius_ * std::cos(std::atan(kTanHalfAngle));
    if (distance(p) >= reach * (1 + kTanHalfAngle)) return 1;
    // An orthonormal basis around n (Duff et al. 2017).
    const double s = n.z >= 0 ? 1.0 : -1.0;
    const double a = -1.0 / (s + n.z), b = n.x * n.y * a;
    const Vec3d t1{1 + s * n.x * n.x * a, s * b, -s * n.x}, t2{b, s + n.y * n.y * a, -n.y};
    // The axes start off the surface by the tracer's step, so p's own triangle is not hit.
    const Vec3d origin = p + n * tracer_->epsilon();
    const double ringCos = std::cos(kRingAngle), ringSin = std::sin(kRingAngle);
    double sum = 0, weights = 0;
    for (int c = 0; c <= kRing; ++c) {
        Vec3d w = n;
        double weight = 1;
        if (c > 0) {
            const double phi = 2 * M_PI * (c - 1) / kRing;
            w = n * ringCos + (t1 * std::cos(phi) + t2 * std::sin(phi)) * ringSin;
            weight = ringCos;
        }
        // The axis first (exact, Embree): the field alone cannot tell a sheet the axis crossed from
        // one it passed by. Then beside the axis: an occluder at distance d from it at depth t
        // covers about 1/2 - d / (2 t tan) of the cone before the axis meets it (half where it
        // grazes the axis), 1/2 + d / (2 t tan) behind the sheet the axis crossed. Steps from a cell
        // out to the reach, each at least half a cell and at most half the distance found. The
        // reach is the radius times cos 30deg: a ray along the cone's side then ends at the radius.
        const TriangleTracer::Hit hit = tracer_->intersect(origin, w, 0, reach);
        const double tHit = hit.hit ? hit.t : std::numeric_limits<double>::infinity();
        double vis = hit.hit ? 0.5 : 1.0;
        for (double t = cell_; t <= reach && vis > 0;) {
            const double d = distance(p + w * t);
            vis = std::min(vis, 0.5 + (t < tHit ? 0.5 : -0.5) * d / (t * kTanHalfAngle));
            t += std::max(0.5 * cell_, 0.5 * d);
        }
        sum += weight * std::clamp(vis, 0.0, 1.0);
        weights += weight;
    }
    return sum / weights;
}

} // namespace voxfx
