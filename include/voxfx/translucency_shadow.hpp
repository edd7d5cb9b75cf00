// voxfx — translucency shadows (GI08 §7, "Single-pass GPU Solid Voxelization for Real-time
// Applications": translucency by counting the solid matter light crosses, the jade dragon).
// Shadow technique "translucency" (voxfx/shadow.hpp).
//
// Every caster is voxelized as a *solid* from the light (GI08 §4–5: parity at cell centres; for
// casters that are not closed the generalized winding number fill, voxfx/voxelize.hpp). The light reaching p
// has crossed
//   L = (filled cells of p's column in front of p) x (world length of one slice along that column)
// world units of matter (countColumnRange, GI08 §6 "counting": one popcount per 64 slices), and is
// attenuated by Beer-Lambert, per channel c:
//   visibility_c = exp(-extinction / tint_c * L)
// extinction: the extinction coefficient sigma, per world unit; tint in (0, 1]: each channel's
// relative mean free path (1, 1, 1: grey; a jade green (0.35, 1, 0.55): red and blue die out
// first, thin parts glow green). Each caster is matter of its material's extinction
// (translucencyExtinction): an opaque material stays opaque (infinite extinction: a filled cell in
// front of p stops the light), a material with KHR_materials_volume attenuation has that
// coefficient, and the other see-through ones (translucent solids without attenuation, glass,
// sheets) are GI08's one matter, extinction / tint. The casters are voxelized in one solid grid per
// extinction, and the visibility is the product of the groups' Beer-Lambert terms.
//
// Error: the cell centres inside a chord of length c along a column number floor or ceil of
// c / h (h: the slice's world length along the column), so L differs from the exact chord by less
// than h per entry into the solid (a closed mesh's chords, measured along the column's centre
// ray). The lookup skips the cell holding p and moves p along its normal (voxfx/light_grid.hpp).
//
// Cost: one solid voxelization per light view (W x H x D bits: 256^3 is 2 MiB); a lookup is one
// popcount pass over the column's words in front of p and a division.
// Thread-safety: a built shadow is read-only (lookups from any number of threads); build voxelizes
// with worker threads.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/light_grid.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/options.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_options.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

/// The solid grid of one light view and its lookups.
class TranslucencyShadowMap {
public:
    TranslucencyShadowMap() = default;
    /// `casters` in world space, voxelized as a solid (VoxelizeMode::Solid) with `fill`.
    static TranslucencyShadowMap build(const LightView& view, const MeshView& casters, Fill fill,
                                       Slicing slicing, Progress* progress = nullptr);
    /// World length of matter between the light and `world` along its column: filled cells in front
    /// of the last `skipCells` cells up to p's cell, times the slice's world length along the
    /// column's centre ray. 0 outside the view.
    double pathLength(const Vec3d& world, int64_t skipCells) const;
    /// exp(-sigma_c * pathLength) per channel.
    Vec3f transmittance(const Vec3d& world, int64_t skipCells, const Vec3d& sigma) const;
    /// Bilinear interpolation of the transmittance of the four columns around p, each read at the
    /// depth where the receiver's tangent plane (normal `normal`) crosses it; at p's depth for a
    /// zero normal; beyond the grid's border, its border column.
    Vec3f transmittanceBilinear(const Vec3d& world, int64_t skipCells, const Vec3d& sigma,
                                const Vec3d& normal = {}, double sharpness = 1) const;
    const LightView& view() const { return view_; }
    const VoxelGrid& grid() const { return grid_; }

private:
    double columnPath(int64_t column, double depth, int64_t skipCells) const;
    LightView view_;
    VoxelGrid grid_;
};

/// GI08 §7 for the camera's view of a translucent solid: per pixel (column) of `camera` (a
/// perspective frame, e.g. a G-buffer's), the world length of solid matter along the pixel's centre
/// ray behind view depth depth[pixel] (the visible surface; not finite: 0). `solids` are voxelized
/// as a solid (`fill`, as the translucency shadow) in the camera's own frame with `slices` slices
/// over their depth range; the filled cells from the one holding the surface on, times a slice's
/// world length along the ray, give the length: it differs from the exact chords by less than one
/// slice per entry into the solid. The camera must lie outside the solids (what lies in front of
/// its near plane is not counted). Throws voxfx::Error for an orthographic frame, slices < 1 or a
/// depth of another size than the frame's columns.
/// `until`, when not empty (one view depth per pixel, like `depth`), ends each pixel's count there:
/// the matter between the visible surface and an opaque surface behind it (the cells whose centre
/// lies in front of until[pixel]); a depth that is not finite counts to the end.
std::vector<double> viewMatterBehind(const Frame& camera, const MeshView& solids,
                                     std::span<const float> depth, Fill fill, int64_t slices,
                                     std::span<const float> until = {});

/// The solid grid behind viewMatterBehind, kept for lookups at any depths: the renderer's
/// translucency pass builds it at the output pixels and looks it up per sample (voxfx/render.hpp).
class ViewMatter {
public:
    ViewMatter() = default; ///< no solids: 0 everywhere
    /// `solids` voxelized as a solid (`fill`) in `camera`'s frame (same eye, field of view and
    /// columns) with `slices` slices over their depth range in front of the near plane. Throws
    /// voxfx::Error for an orthographic frame or slices < 1.
    static ViewMatter build(const Frame& camera, const MeshView& solids, Fill fill, int64_t slices);
    /// World length of solid matter along the centre ray of column (x, y) from view depth `from`
    /// (the cell holding it included) to view depth `until` (the cells whose centre lies in front of
    /// it; not finite: to the end). 0 for a `from` that is not finite, or a column outside.
    double between(int64_t x, int64_t y, double from, double until) const;
    const VoxelGrid& grid() const { return grid_; } ///< empty without solids

private:
    VoxelGrid grid_;
    DepthToSlice ds_;
    int64_t slices_ = 0;
    double lo_ = 0;
};

/// The extinction per world unit, per channel, of a caster of material m under the translucency
/// shadow (see the file comment): +inf for an opaque material, attenuationCoefficient(m) where it is
/// not zero, else options.extinction / options.tint.
Vec3d translucencyExtinction(const Material& m, const TranslucencyShadowOptions& options);

/// The shadow of one light: per group of casters of one extinction, one solid grid per light view.
class TranslucencyShadow {
public:
    using Options = TranslucencyShadowOptions;
    using Stats = TranslucencyShadowStats;
    TranslucencyShadow() = default; ///< no casters: visibility 1
    /// From the scene's casters (SceneMesh::castsShadow). Throws voxfx::Error for resolutions < 1,
    /// skipped cells < 0, a negative or non-finite extinction or a tint outside (0, 1].
    static TranslucencyShadow build(const Scene& scene, const Light& light,
                                    const TranslucencyShadowOptions& options, Progress* progress = nullptr);
    /// RGB fraction of the light reaching p; `n` the unit geometric normal turned towards the light.
    Vec3f visibility(const Vec3d& p, const Vec3d& n) const;
    /// World length of matter (of every group) the light crosses to reach p (its own column; the
    /// same normal offset and skipped cells as visibility). 0 where no view covers p.
    double pathLength(const Vec3d& p, const Vec3d& n) const;
    Stats stats() const;
    /// Per group of casters, per light view (group-major).
    const std::vector<TranslucencyShadowMap>& maps() const { return maps_; }

private:
    TranslucencyShadowOptions options_;
    std::vector<Vec3d> sigmas_; ///< per group of casters: its extinction (opaque: infinite)
    std::vector<LightView> views_;
    std::vector<TranslucencyShadowMap> maps_; ///< per group, per view (group-major)
};

} // namespace voxfx
