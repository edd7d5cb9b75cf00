// voxfx — a light's deep-shadow visibility cached on a volume's lattice (internal; the volume pass,
// render/volume_pass.cpp, and its tests).
//
// The volume pass lights a sample p of a volume by the deep shadow map's lookup one step towards
// the light, DeepShadow::visibility(p + toLight * step, toLight, texel), times the transmittance of
// the volume itself over that step and the lookup's offsets (its own term, which stays per sample:
// it falls by e within a voxel at a dense layer's front, which no lattice resolves). Lights and
// volumes of a cached frame do not move, so that lookup is a fixed function of p: it is evaluated
// once per (volume, light) at the corners of the volume's voxels ((nx + 1) x (ny + 1) x (nz + 1)
// nodes at the volume's own resolution, turned with it), with the texel footprint it returns, and
// read back per sample by trilinear interpolation (RGB and footprint). A cached frame's lookups then
// read eight nodes instead of projecting p into the light's views and searching four texels'
// visibility functions per channel. Outside the volume's box the grid has no value (lookup returns
// false) and the caller looks the map up itself.
//
// The pre-lit volume (built with the own term as a function of the corner): the whole light term,
// irradiance x the lookup x the own transmittance, at the same corners, read back by one trilinear
// lookup (lookupLight). It trades the own term's fall within a voxel at a dense front for one
// lookup per piece: blurred by a voxel there (the error is measured in BENCHMARKS.md, frames-dsm7).
// Its nodes keep the own transmittance alone too, so that a sample inside two volumes takes the
// first one's pre-lit light times the second one's own term (frames-dsm8).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "render/shading.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/volume.hpp"

namespace voxfx::detail {

class LightVisibilityGrid {
public:
    LightVisibilityGrid() = default; ///< no nodes: every lookup false
    /// The lookup of `shadow` at every voxel corner c of `volume` (world point worldFromVoxel(i, j,
    /// k)): shadow.visibility(c + toLight * step, toLight, texel), toLight the unit direction from c
    /// to `light` (lightIrradiance's; `cone` is LightCone(light)). Nodes are filled in parallel,
    /// each on its own: the same values whatever the thread count. With `skip` (the volume's
    /// EmptySpace), only the nodes of voxels within `reach` (world units: the longest interval the
    /// march lights, its step) and a voxel diagonal of a brick that is not empty are filled (the
    /// march lights no piece elsewhere); the others hold NaN, and a lookup that reads one returns
    /// false, so the caller looks the map up itself: never a wrong value, at worst the map's cost.
    /// With `own` (the volume's own transmittance from a corner c towards the light, given the
    /// direction and the lookup's texel footprint), the pre-lit volume as well (lookupLight).
    using OwnTransmittance = std::function<double(const Vec3d& c, const Vec3d& toLight, double texel)>;
    static LightVisibilityGrid build(const Volume& volume, const DeepShadow& shadow, const Light& light,
                                     const LightCone& cone, double step, const EmptySpace* skip = nullptr,
                                     double reach = 0, const OwnTransmittance* own = nullptr);

    /// Trilinear interpolation of the nodes at world point p (visibility per channel and the texel
    /// footprint); false where p lies outside the volume's box (or is NaN) or a node it reads was
    /// not filled.
    bool lookup(const Vec3d& p, Vec3f& visibility, double& texel) const {
        float out[4];
        if (nodes_.empty() || !interpolate(nodes_, place_.voxelCoordinates(p), out)) return false;
        visibility = {out[0], out[1], out[2]};
        texel = double(out[3]);
        return true;
    }

    /// The pre-lit volume (built with `own`): the light's irradiance times the map's lookup times the
    /// volume's own transmittance over the lookup's step and offsets, all evaluated at the voxel
    /// corners, interpolated at p; with `own`, that own transmittance alone as well (its corners'
    /// values interpolated: what a sample inside this volume and another one takes from this one).
    /// False where lookup() is, and where the grid was built without `own`.
    bool lookupLight(const Vec3d& p, Vec3f& light, float* own = nullptr) const {
        return !lit_.empty() && lookupLightVoxel(place_.voxelCoordinates(p), light, own);
    }
    /// lookupLight at the point of the volume's voxel coordinates u (VolumeView::voxelCoordinates).
    bool lookupLightVoxel(const Vec3d& u, Vec3f& light, float* own = nullptr) const {
        float out[4];
        if (!interpolate(lit_, u, out)) return false;
        light = {out[0], out[1], out[2]};
        if (own) *own = out[3];
        return true;
    }
    bool prelit() const { return !lit_.empty(); }

    /// Nodes along each voxel axis (voxels + 1; 0 when empty).
    Vec3i nodeCounts() const;
    /// Nodes filled from the map (all of them without `skip`).
    int64_t filledNodes() const { return filled_; }
    std::size_t bytes() const { return (nodes_.size() + lit_.size()) * sizeof(Node); }

private:
    struct Node {
        float v[4]; ///< visibility r, g, b; the texel footprint (lit_: the light r, g, b; the own
                    ///< transmittance)
    };
    VolumeView place_;        ///< the volume's placement (no values): voxelCoordinate and voxel counts
    std::vector<Node> nodes_; ///< x fastest: i + (nx + 1) (j + (ny + 1) k)
    std::vector<Node> lit_;   ///< the pre-lit volume, the same nodes (empty without `own`)

    // Trilinear interpolation of `nodes` at the point of voxel coordinates uv; false outside the box,
    // at a NaN point or an unfilled node.
    bool interpolate(const std::vector<Node>& nodes, const Vec3d& uv, float (&out)[4]) const {
        if (nodes.empty()) return false;
        const int64_t n[3] = {place_.nx, place_.ny, place_.nz};
        int64_t i[3];
        float t[3];
        for (int a = 0; a < 3; ++a) {
            const double u = uv[a];
            if (!(u >= 0 && u <= double(n[a]))) return false;
            i[a] = std::min(int64_t(u), n[a] - 1); // u >= 0: truncation is floor
            t[a] = float(u - double(i[a]));
        }
        const int64_t sx = 1, sy = n[0] + 1, sz = sy * (n[1] + 1);
        const Node* c = nodes.data() + (i[0] * sx + i[1] * sy + i[2] * sz);
        const float w0 = 1 - t[0], w1 = t[0];
        for (int k = 0; k < 4; ++k) {
            const float x00 = c[0].v[k] * w0 + c[sx].v[k] * w1;
            const float x10 = c[sy].v[k] * w0 + c[sy + sx].v[k] * w1;
            const float x01 = c[sz].v[k] * w0 + c[sz + sx].v[k] * w1;
            const float x11 = c[sz + sy].v[k] * w0 + c[sz + sy + sx].v[k] * w1;
            const float y0 = x00 + (x10 - x00) * t[1], y1 = x01 + (x11 - x01) * t[1];
            out[k] = y0 + (y1 - y0) * t[2];
        }
        // An unfilled node (NaN) weighs in, even at weight 0.
        return !std::isnan(out[3]);
    }
    int64_t filled_ = 0;
};

/// A volume's gradient (VolumeView::gradient: central differences one voxel either side, in world
/// axes) at every voxel centre, read back by trilinear interpolation: in the interior of the
/// volume (every lattice coordinate c = voxel coordinate - 1/2 within [1, n - 2], where gradient()
/// takes full central differences) that is gradient() itself up to rounding, since a central
/// difference of the trilinear interpolant one lattice unit either side has the same weights as
/// the interpolant of the centres' differences; six trilinear lookups become one of three floats.
/// Nearer the faces (one-sided differences) lookup returns false and the caller asks the volume.
class GradientGrid {
public:
    GradientGrid() = default; ///< no nodes: every lookup false
    explicit GradientGrid(const Volume& volume);

    bool lookup(const Vec3d& p, Vec3d& gradient) const {
        return !nodes_.empty() && lookupVoxel(place_.voxelCoordinates(p), gradient);
    }
    /// lookup at the point of the volume's voxel coordinates u (VolumeView::voxelCoordinates).
    bool lookupVoxel(const Vec3d& u, Vec3d& gradient) const {
        if (nodes_.empty()) return false;
        const int64_t n[3] = {place_.nx, place_.ny, place_.nz};
        int64_t i[3];
        float t[3];
        for (int a = 0; a < 3; ++a) {
            const double c = u[a] - 0.5;
            if (!(c >= 1 && c < double(n[a] - 2))) return false;
            i[a] = int64_t(c); // c >= 1: truncation is floor; i + 1 <= n - 2
            t[a] = float(c - double(i[a]));
        }
        const int64_t sx = 1, sy = n[0], sz = n[0] * n[1];
        const Vec3f* c = nodes_.data() + (i[0] + i[1] * sy + i[2] * sz);
        const float w0 = 1 - t[0], w1 = t[0];
        const Vec3f x00 = c[0] * w0 + c[sx] * w1, x10 = c[sy] * w0 + c[sy + sx] * w1;
        const Vec3f x01 = c[sz] * w0 + c[sz + sx] * w1, x11 = c[sz + sy] * w0 + c[sz + sy + sx] * w1;
        const Vec3f y0 = x00 + (x10 - x00) * t[1], y1 = x01 + (x11 - x01) * t[1];
        gradient = Vec3d(y0 + (y1 - y0) * t[2]);
        return true;
    }

private:
    VolumeView place_;         ///< the volume's placement (no values)
    std::vector<Vec3f> nodes_; ///< per voxel centre, x fastest (zero on the outermost layer, unused)
};

/// One light's grids over a volume scene, per object (no nodes for objects that are not volumes):
/// what the RenderCache keeps per (volume pass setup, light's shadow).
struct VolumeLightGrids {
    std::vector<LightVisibilityGrid> objects;
};

} // namespace voxfx::detail
