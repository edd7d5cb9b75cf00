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

#include <cstdint>
#include <vector>

#include "voxfx/frame.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {

/// One view of a light: a frame over world space (perspective, or oriented orthographic for
/// directional lights).
struct LightView {
    Frame frame;

    /// Grid coordinates (gx, gy, frame depth) of a world point; for perspective views the point must
    /// lie in front of the eye (check covers first).
    Vec3d gridFromWorld(const Vec3d& world) const { return frame.gridFromWorld(world); }
    /// True when p lies in front of the light (perspective) and projects into the columns.
    bool covers(const Vec3d& world) const;
    /// World size of one column at p (the texel footprint: constant for orthographic views, growing
    /// with the view depth for perspective ones).
    double columnWorldSize(const Vec3d& world) const;
    /// World length of one frame depth unit (orthographic: a slice; perspective: 1).
    double worldPerDepthUnit() const;
};

/// The views that cover `casterBounds` for `light`, with columns along the longer side and d slices
/// (see the file comment for the fitting). Throws voxfx::Error for an empty or non-finite box.
std::vector<LightView> makeLightViews(const Light& light, const Box3d& casterBounds, int64_t columns,
                                      int64_t d);
/// Index of the view that covers p (the cube face for point lights), or -1.
int viewIndexFor(const std::vector<LightView>& views, const Vec3d& world);

} // namespace voxfx
