// voxfx — what a renderer's frame tells the techniques it builds (shadows, glass), beyond the
// scene, the light and the technique's own options: the camera and the frame's size. A technique
// whose build takes a BuildContext (S::build(scene, light, options, context, progress), see
// voxfx/shadow.hpp) may fit itself to the view (deep shadows cluster their casters by distance to
// the eye); one that does not take it is built the same for every view. Built without a context
// (a default BuildContext), a technique is view-independent.
//
// Thread-safety: a value.
#pragma once

#include <cstdint>
#include <optional>

#include "voxfx/scene.hpp"

namespace voxfx {

struct BuildContext {
    /// The frame's camera; unset: no view to fit to.
    std::optional<Camera> camera;
    /// The frame's size in samples (the renderer's supersampled image; 0: unknown).
    int64_t width = 0, height = 0;
};

} // namespace voxfx
