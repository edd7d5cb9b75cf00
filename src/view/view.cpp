// voxfx — interactive viewing (voxfx/view.hpp): camera moves, preview options, the options as
// named settings, and the renderer of a viewer's frames.
#include "voxfx/view.hpp"

#include <algorithm>
#include <cmath>

namespace voxfx {

namespace {

// The camera's unit view direction, its distance to the target and its unit up; voxfx::Error
// when they do not make a view.
struct ViewBasis {
    Vec3d forward, up;
    double distance = 0;
};

ViewBasis viewBasis(const Camera& c, const char* what) {
    ViewBasis b;
    const Vec3d f = c.target - c.position;
    b.distance = length(f);
    if (!(b.distance > 0) || !std::isfinite(b.distance))
        fail(what, ": camera '", c.name, "' has its eye at its target (or a non-finite position)");
    const double upLength = length(c.up);
    if (!(upLength > 0) || !std::isfinite(upLength))
        fail(what, ": camera '", c.name, "' has no up direction");
    b.forward = f / b.distance;
    b.up = c.up / upLength;
    return b;
}

} // namespace

Camera orbitCamera(const Camera& camera, double yaw, double pitch) {
    if (!std::isfinite(yaw) || !std::isfinite(pitch)) fail("orbit: the angles must be finite numbers");
    const ViewBasis b = viewBasis(camera, "orbit");
    // The eye's offset from the target: its angle from up, and its horizontal direction.
    const Vec3d offset = -b.forward;
    const double along = std::clamp(dot(offset, b.up), -1.0, 1.0);
    const Vec3d horizontal = offset - b.up * along;
    const double h = length(horizontal);
    if (!(h > 1e-12)) fail("orbit: camera '", camera.name, "' looks along its up direction");
    const Vec3d e1 = horizontal / h, e2 = cross(b.up, e1);
    const double polar = std::clamp(std::atan2(h, along) - pitch, kMinPoleAngle,
                                    M_PI - kMinPoleAngle); // pitch > 0 raises the eye
    const Vec3d turned = e1 * std::cos(yaw) + e2 * std::sin(yaw);
    Camera out = camera;
    out.position = camera.target + (b.up * std::cos(polar) + turned * std::sin(polar)) * b.distance;
    return out;
}

Camera panCamera(const Camera& camera, double right, double up) {
    if (!std::isfinite(right) || !std::isfinite(up)) fail("pan: the offsets must be finite numbers");
    const ViewBasis b = viewBasis(camera, "pan");
    const Vec3d r = cross(b.forward, b.up);
    const double rl = length(r);
    if (!(rl > 1e-12)) fail("pan: camera '", camera.name, "' looks along its up direction");
    const Vec3d rightAxis = r / rl, upAxis = cross(rightAxis, b.forward);
    const double viewHeight = 2 * b.distance * std::tan(camera.fovY / 2);
    const Vec3d move = (rightAxis * right + upAxis * up) * viewHeight;
    Camera out = camera;
    out.position = camera.position + move;
    out.target = camera.target + move;
    return out;
}

Camera dollyCamera(const Camera& camera, double factor) {
    if (!(factor > 0) || !std::isfinite(factor))
        fail("dolly: the factor must be a finite number > 0, got ", factor);
    const ViewBasis b = viewBasis(camera, "dolly");
    Camera out = camera;
    out.position = camera.target - b.forward * (b.distance * factor);
    out.nearDepth = camera.nearDepth * factor;
    out.farDepth = camera.farDepth * factor;
    return out;
}

Camera aimAtScene(const Camera& camera, const Scene& scene) {
    const Box3d b = scene.bounds();
    if (b.empty()) return camera;
    const ViewBasis v = viewBasis(camera, "aim");
    const double depth = dot(b.center() - camera.position, v.forward);
    if (!(depth > 0) || !std::isfinite(depth)) return camera;
    Camera out = camera;
    out.target = camera.position + v.forward * depth;
    return out;
}

RenderOptions previewOptions(const RenderOptions& full, int scale) {
    if (scale < 1) fail("preview: the scale must be at least 1, got ", scale);
    RenderOptions o = full;
    o.width = std::max<int64_t>(1, (full.width + scale - 1) / scale);
    o.height = std::max<int64_t>(1, (full.height + scale - 1) / scale);
    o.supersample = 1;
    o.antiAliasing = AntiAliasing::Off;
    o.ambientOcclusion = Occlusion::Off;
    return o;
}

std::vector<std::pair<std::string, OptionValue>> renderSettings(const RenderOptions& options) {
    std::vector<std::pair<std::string, OptionValue>> out;
    for (const OptionField<RenderOptions>& f : RenderOptions::fields())
        out.emplace_back(std::string(f.name), f.get(options));
    out.emplace_back("shadows", std::string(shadowName(options.shadow)));
    std::visit(
        [&]<class O>(const O& o) {
            for (const OptionField<O>& f : O::fields()) out.emplace_back(std::string(f.name), f.get(o));
        },
        options.shadow);
    out.emplace_back("glass", std::string(glassName(options.glass)));
    std::visit(
        [&]<class O>(const O& o) {
            for (const OptionField<O>& f : O::fields()) out.emplace_back(std::string(f.name), f.get(o));
        },
        options.glass);
    return out;
}

FrameRenderer::FrameRenderer(std::shared_ptr<const Scene> scene) : scene_(std::move(scene)) {
    if (!scene_) fail("FrameRenderer: no scene");
}

RenderResult FrameRenderer::render(const Camera& camera, const RenderOptions& options) {
    return voxfx::render(*scene_, camera, options, cache_);
}

} // namespace voxfx
