// voxfx — light views: the frames that shadow maps, light grids and deep shadow maps live in
// (ED06 §3.1 voxelizes "from the light": a perspective frame for spot and point lights, an
// orthographic one for directional lights).
//
// Spot lights get one perspective frame along their direction (field of view fitted to the
// casters, at most twice the outer cone, at most 160 degrees); point lights six 90-degree cube
// faces; directional lights an oriented orthographic frame (Frame::orthographic with a basis)
// perpendicular to their direction, fitted to the casters: world-space geometry is rasterized into
// it directly, nothing is rotated or copied.
//
// Thread-safety: LightView is a value; makeLightViews and viewIndexFor are pure.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {

/// One view of a light: a frame over world space (perspective, or oriented orthographic for
/// directional lights).
struct LightView {
    Frame frame;
    /// k in 0..5 where makeLightViews made this view as face k of a point light's cube (forward
    /// exactly +x, -x, +y, -y, +z, -z for k = 0..5, the eye the light's position); -1 otherwise.
    /// viewIndexForFaces picks such a cube's face from the largest component of p - eye.
    int cubeFace = -1;

    /// Grid coordinates (gx, gy, frame depth) of a world point; for perspective views the point must
    /// lie in front of the eye (check covers first).
    VOXFX_ALWAYS_INLINE Vec3d gridFromWorld(const Vec3d& world) const { return frame.gridFromWorld(world); }
    /// True when p lies in front of the light (perspective) and projects into the columns.
    VOXFX_ALWAYS_INLINE bool covers(const Vec3d& world) const {
        Vec3d g;
        return locate(world, g);
    }
    /// covers(world), with p's grid coordinates in `grid` where true (one projection for both; the
    /// lookups of the light grids and shadow maps).
    VOXFX_ALWAYS_INLINE bool locate(const Vec3d& world, Vec3d& grid) const {
        if (frame.isPerspective() && !(frame.viewDepth(world) > 0)) return false;
        grid = frame.gridFromWorld(world);
        // A relative tolerance of 1e-9 columns: cube faces meet exactly at their borders, and a point
        // on a face diagonal must not fall between two faces by a rounding error.
        const double ex = 1e-9 * double(frame.width()), ey = 1e-9 * double(frame.height());
        return grid.x >= -ex && grid.x <= double(frame.width()) + ex && grid.y >= -ey &&
               grid.y <= double(frame.height()) + ey;
    }
    /// World size of one column at p (the texel footprint: constant for orthographic views, growing
    /// with the view depth for perspective ones).
    double columnWorldSize(const Vec3d& world) const {
        if (!frame.isPerspective()) return frame.cellSize().x;
        const double depth = std::max(frame.viewDepth(world), frame.nearDepth());
        return depth * 2.0 * frame.tanHalfFovY() / double(frame.height());
    }
    /// World length of one frame depth unit (orthographic: a slice; perspective: 1).
    double worldPerDepthUnit() const { return frame.isPerspective() ? 1.0 : frame.cellSize().z; }
};

/// The views that cover `casterBounds` for `light`, with columns along the longer side and d slices
/// (see the file comment for the fitting). Throws voxfx::Error for an empty or non-finite box.
std::vector<LightView> makeLightViews(const Light& light, const Box3d& casterBounds, int64_t columns,
                                      int64_t d);
/// Index of the view that covers p (the cube face for point lights: the first view whose forward
/// has the largest positive dot product with p - eye), or -1.
int viewIndexForFaces(const std::vector<LightView>& views, const Vec3d& world);
VOXFX_ALWAYS_INLINE inline int viewIndexFor(const std::vector<LightView>& views, const Vec3d& world) {
    if (views.size() == 1) return views[0].covers(world) ? 0 : -1; // inline: once per shaded sample
    return viewIndexForFaces(views, world);
}

} // namespace voxfx
