// voxfx — light views: the frames shadow maps and light grids live in (ED06 §3.1 voxelizes "from the
// light": a perspective frame for spot and point lights, an orthographic one for directional lights).
//
// A directional light's frame is an oriented orthographic frame with basis (right, up, light
// direction), fitted to the casters' bounds in those local coordinates.
#include "voxfx/light_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace voxfx {

namespace {

constexpr double kMaxSpotFov = 160.0 * M_PI / 180.0;

// An up vector not parallel to `forward`.
Vec3d upHint(const Vec3d& forward) { return std::abs(forward.y) < 0.99 ? Vec3d{0, 1, 0} : Vec3d{1, 0, 0}; }

void corners(const Box3d& b, Vec3d out[8]) {
    for (int k = 0; k < 8; ++k)
        out[k] = {(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z};
}

double distanceToBox(const Vec3d& p, const Box3d& b) {
    const Vec3d d = max(max(b.lo - p, p - b.hi), Vec3d{0, 0, 0});
    return length(d);
}

LightView perspectiveView(const Vec3d& eye, const Vec3d& forward, double fovY, const Box3d& bounds,
                          int64_t columns, int64_t d) {
    Vec3d c[8];
    corners(bounds, c);
    double far = 0;
    for (const Vec3d& q : c) far = std::max(far, length(q - eye));
    far = std::max(far * 1.01, 1e-6);
    // Inside the frustum, view depth >= distance * cos(half diagonal angle), tan(half diagonal) =
    // sqrt(2) tan(fov / 2) for square frames.
    const double cosDiagonal = std::cos(std::atan(std::sqrt(2.0) * std::tan(0.5 * fovY)));
    const double near = std::max(far * 1e-4, 0.99 * distanceToBox(eye, bounds) * cosDiagonal);
    LightView v;
    v.frame = Frame::perspective(eye, eye + forward, upHint(forward), fovY, columns, columns,
                                 std::min(near, far * 0.5), far, d);
    return v;
}

// The six views are the faces of one axis cube as makeLightViews makes them (cubeFace k in order,
// one eye: the same bits, compared as bytes, so that no floating-point compare branches on NaN).
bool isAxisCube(const std::vector<LightView>& views) {
    bool cube = true;
    for (int k = 0; k < 6; ++k)
        cube &= views[size_t(k)].cubeFace == k &&
                std::memcmp(&views[size_t(k)].frame.eye(), &views[0].frame.eye(), sizeof(Vec3d)) == 0;
    return cube;
}

} // namespace

std::vector<LightView> makeLightViews(const Light& light, const Box3d& bounds, int64_t columns, int64_t d) {
    if (bounds.empty() || !isFinite(bounds.lo) || !isFinite(bounds.hi))
        fail("light '", light.name, "': nothing to fit a light view to (no shadow casters)");
    if (columns <= 0 || d <= 0) fail("light views need positive resolutions, got ", columns, " x ", d);
    std::vector<LightView> views;
    switch (light.type) {
    case LightType::Directional: {
        // Local coordinates (p . right, p . up, p . direction), a right-handed basis
        // (right x up = direction).
        const Vec3d dir = normalize(light.direction);
        const Vec3d hint = upHint(dir);
        const Vec3d up = normalize(hint - dir * dot(hint, dir));
        const Vec3d right = cross(up, dir);
        LightView v;
        Vec3d c[8];
        corners(bounds, c);
        Box3d box;
        for (const Vec3d& q : c) box.extend(Vec3d{dot(q, right), dot(q, up), dot(q, dir)});
        // Pad by 1 % of the largest extent (and never flat), so that geometry on the bounds lies inside.
        const Vec3d ext = box.extent();
        const double pad = 0.01 * std::max({ext.x, ext.y, ext.z, 1e-9});
        box.lo -= Vec3d{pad, pad, pad};
        box.hi += Vec3d{pad, pad, pad};
        // Square columns: the longer side gets `columns`.
        const Vec3d e = box.extent();
        const double cell = std::max(e.x, e.y) / double(columns);
        const int64_t w = std::max<int64_t>(1, int64_t(std::ceil(e.x / cell - 1e-9)));
        const int64_t h = std::max<int64_t>(1, int64_t(std::ceil(e.y / cell - 1e-9)));
        const Vec3d mid = box.center();
        box.lo.x = mid.x - 0.5 * double(w) * cell;
        box.hi.x = mid.x + 0.5 * double(w) * cell;
        box.lo.y = mid.y - 0.5 * double(h) * cell;
        box.hi.y = mid.y + 0.5 * double(h) * cell;
        v.frame = Frame::orthographic(box, right, up, dir, w, h, d);
        views.push_back(v);
        break;
    }
    case LightType::Spot: {
        const Vec3d fwd = normalize(light.direction);
        double fov = std::min(2 * light.outerConeAngle, kMaxSpotFov);
        // Narrow the frustum to the casters when they all lie in front of the light.
        const Vec3d up0 = normalize(upHint(fwd) - fwd * dot(upHint(fwd), fwd));
        const Vec3d right0 = cross(fwd, up0);
        Vec3d c[8];
        corners(bounds, c);
        double maxTan = 0;
        bool inFront = true;
        for (const Vec3d& q : c) {
            const double z = dot(q - light.position, fwd);
            if (!(z > 1e-9)) {
                inFront = false;
                break;
            }
            maxTan = std::max({maxTan, std::abs(dot(q - light.position, right0)) / z,
                               std::abs(dot(q - light.position, up0)) / z});
        }
        if (inFront) fov = std::min(fov, 2 * std::atan(maxTan * 1.02));
        views.push_back(perspectiveView(light.position, fwd, fov, bounds, columns, d));
        break;
    }
    case LightType::Point: {
        // Six 90-degree cube faces; viewIndexFor picks the face of the dominant axis.
        const Vec3d axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (int k = 0; k < 6; ++k) {
            views.push_back(perspectiveView(light.position, axes[k], M_PI / 2, bounds, columns, d));
            // normalize((eye + a) - eye) is exactly a (the other components are exactly 0, and
            // x / sqrt(x * x) is exactly +-1), but say so only where it holds.
            const Frame& f = views.back().frame;
            if (f.forward() == axes[k] && f.eye() == light.position) views.back().cubeFace = k;
        }
        break;
    }
    }
    return views;
}

int viewIndexForFaces(const std::vector<LightView>& views, const Vec3d& world) {
    if (views.empty()) return -1;
    if (views.size() == 1) return views[0].covers(world) ? 0 : -1;
    // Cube faces share the eye: the face whose axis is closest to the direction owns the point.
    if (views.size() == 6 && isAxisCube(views)) {
        // dot(p - eye, +-axis) is exactly +-(p - eye)[axis], so the loop below reduces to the first
        // strictly largest positive |component| in the order x, y, z: three comparisons instead of
        // six dot products. Non-finite components (where 0 * inf makes the loop's products NaN) are
        // left to the loop.
        const Vec3d r = world - views[0].frame.eye();
        const double ax = std::abs(r.x), ay = std::abs(r.y), az = std::abs(r.z);
        if (std::isfinite(ax + ay + az)) {
            int face = -1;
            double largest = 0;
            if (ax > largest) {
                face = r.x > 0 ? 0 : 1;
                largest = ax;
            }
            if (ay > largest) {
                face = r.y > 0 ? 2 : 3;
                largest = ay;
            }
            if (az > largest) face = r.z > 0 ? 4 : 5;
            return face;
        }
    }
    int best = -1;
    double bestDot = 0;
    for (std::size_t i = 0; i < views.size(); ++i) {
        const double dd = dot(world - views[i].frame.eye(), views[i].frame.forward());
        if (dd > bestDot) {
            bestDot = dd;
            best = int(i);
        }
    }
    return best;
}

} // namespace voxfx
