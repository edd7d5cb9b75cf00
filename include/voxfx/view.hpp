// voxfx — interactive viewing: the camera moves of a viewer (orbit, pan, dolly), the cheap preview
// a moving camera renders, the render options as the named settings a scene file stores (what a
// viewer saves so that `voxfx render` reproduces its frame), and the one object through which a
// front end renders frame after frame (`voxfx view`, Python's voxfx.Renderer).
//
// Camera moves keep Camera::up (a turntable: the horizon stays level) and the field of view:
//   orbit  the eye turns about the target: `yaw` radians about up, `pitch` radians about the
//          camera's right axis, the angle between the view direction and +-up kept at least
//          kMinPoleAngle (the view never looks along up, where right is undefined).
//   pan    eye and target move together, across the view: `right` and `up` in view heights at
//          the target's distance (a drag of the whole window height moves the scene by that height).
//   dolly  the eye moves along the view direction to `factor` times its distance from the target;
//          near and far planes scale with it (a default camera's near plane hugs the scene).
//
// Thread-safety: the functions are pure; a FrameRenderer renders one frame at a time (render() is
// not to be called concurrently on one object), each with the options' worker threads.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "voxfx/options.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {

/// The smallest angle (radians, 1 degree) orbitCamera leaves between the view direction and +-up.
inline constexpr double kMinPoleAngle = M_PI / 180;

/// The camera turned about its target (see the file comment). Throws voxfx::Error for a camera
/// whose eye is its target, whose up is zero or along the view direction, or a non-finite angle.
Camera orbitCamera(const Camera& camera, double yaw, double pitch);
/// The camera moved across the view by `right` and `up` view heights at the target's distance.
Camera panCamera(const Camera& camera, double right, double up);
/// The camera moved along the view direction to `factor` (> 0, finite) times its distance from
/// the target, near and far planes scaled alike.
Camera dollyCamera(const Camera& camera, double factor);

/// The same view (eye, direction, up, field of view: the same image) with its target moved along
/// the view direction to the depth of the centre of the scene's bounds, so that orbit turns about
/// the scene and pan moves it with the mouse (a glTF camera has no target of its own: the loader
/// puts one a unit ahead). Unchanged when the scene is empty or its centre lies behind the eye.
Camera aimAtScene(const Camera& camera, const Scene& scene);

/// The options of a preview frame of `full`: width and height divided by `scale` (rounded up, at
/// least 1 pixel), one sample per pixel (supersample 1, anti-aliasing off) and no ambient occlusion;
/// everything else (shadows, glass, lighting, tone map) as `full`. Throws voxfx::Error for scale < 1.
RenderOptions previewOptions(const RenderOptions& full, int scale);

/// Every named setting of `options` (voxfx/render.hpp: RenderOptions' fields, "shadows" and the
/// chosen technique's fields, "glass" and the chosen method's fields), lowerCamelCase, with the
/// values `options` holds. A scene whose settings are these renders (renderOptionsFor) with
/// `options` again, field for field; what has no name (environment, threads, progress) is not
/// among them.
std::vector<std::pair<std::string, OptionValue>> renderSettings(const RenderOptions& options);

/// Renders one scene again and again from moving cameras: the one call a viewer's frames go through.
class FrameRenderer {
public:
    explicit FrameRenderer(std::shared_ptr<const Scene> scene);
    const Scene& scene() const { return *scene_; }
    const std::shared_ptr<const Scene>& scenePointer() const { return scene_; }
    /// render(scene(), camera, options) with the object's RenderCache: what the scene's frames share
    /// (flattened scene, shadows, occlusion field, glass setup, frame buffers) is built once and
    /// reused while the camera moves or the options switch back and forth. Throws as render does
    /// (voxfx::Error, also when options.progress cancels).
    RenderResult render(const Camera& camera, const RenderOptions& options);

private:
    std::shared_ptr<const Scene> scene_;
    RenderCache cache_;
};

} // namespace voxfx
