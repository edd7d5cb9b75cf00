// voxfx — per-voxel absorption shadows (CHANG §3, "Real-time Realistic Voxel-based Rendering").
// Shadow technique "absorption" (voxfx/shadow.hpp).
//
// An attribute voxelization of the casters from the light; each write adds the material's optical
// depth per channel, sigma = -ln(shadowCrossingTransmittance) (opaque materials and the cap:
// `opaqueAbsorption`), so dense foliage that writes a voxel several times absorbs more. At p,
// visibility = exp(-sum of the absorption of the cells between the light and p), per channel. Per
// write, not per unit length: a crossing written once attenuates exactly by e^-sigma, matching the
// per-crossing model of the exact reference. Grey materials (opaque ones, grey leaves) share one
// voxelization whose writes carry their scalar depth; each coloured material (its RGB depth and
// glass attenuation) has its own, so an opaque-only scene keeps one grid and a grey lookup. A glass
// crossing's Fresnel loss, -ln(1 - F) at the angle between the light and the triangle's normal (as
// exact shadows pass it), is written per triangle into the grey grid; its tint into its own. Glass
// pairs its writes along a column (the first enters, the next leaves; a voxel written twice holds
// both) and adds Beer–Lambert's sigma_glass x chord (Material::shadowAttenuationCoefficient), up to
// p when p lies inside. Columns are reduced to prefix sums once, so a lookup scans the few written
// voxels of one column per grid (voxfx/light_grid.hpp for the lookup's bias).
//
// Thread-safety: a built shadow is read-only (lookups from any number of threads); build voxelizes
// with worker threads.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/attribute_grid.hpp"
#include "voxfx/light_grid.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/options.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_options.hpp"

namespace voxfx {

namespace detail {
class GlassCrossingFresnel;
}

/// The absorption columns of one light view: per group of casters an attribute voxelization (its
/// sparse form, voxelizeAttributeColumns: only written voxels are stored), reduced to inclusive
/// prefix sums of the absorption along each column.
class AbsorptionShadowMap {
public:
    /// Casters that absorb alike: `mesh` (world space) with a scalar per triangle added per write,
    /// the RGB optical depth per unit of that sum (grey: {1, 1, 1}) and, for glass, the
    /// Beer–Lambert coefficient over the chord between paired writes (per world unit; else zero).
    struct Group {
        MeshView mesh;
        std::span<const float> triangleAbsorption;
        Vec3f depthPerUnit{1, 1, 1};
        Vec3f attenuation{0, 0, 0};
    };
    AbsorptionShadowMap() = default;
    /// `casters` in world space; triangleAbsorption: optical depth added per write, one per triangle
    /// (one grey group).
    static AbsorptionShadowMap build(const LightView& view, const MeshView& casters,
                                     std::span<const float> triangleAbsorption, Coverage coverage,
                                     Slicing slicing, Progress* progress = nullptr);
    static AbsorptionShadowMap build(const LightView& view, std::span<const Group> groups, Coverage coverage,
                                     Slicing slicing, Progress* progress = nullptr);
    /// RGB sum of the absorption of the cells in front of the last `skipCells` cells up to p's cell
    /// (with the glass chords' Beer–Lambert depth).
    Vec3f opticalDepth(const Vec3d& world, int64_t skipCells) const;
    /// exp(-opticalDepth). 1 outside the view.
    Vec3f transmittance(const Vec3d& world, int64_t skipCells) const;
    /// Bilinear interpolation of exp(-optical depth) of the four columns around p, each read at the
    /// depth where the receiver's tangent plane (normal `normal`) crosses it; at p's depth for a
    /// zero normal; beyond the grid's border, its border column; sharpened (LightGridOptions::sharpness).
    Vec3f transmittanceBilinear(const Vec3d& world, int64_t skipCells, const Vec3d& normal = {},
                                double sharpness = 1) const;
    const LightView& view() const { return view_; }
    /// The first group's frame (with local slicing when requested: each group fits its own).
    const Frame& frame() const { return grids_.empty() ? view_.frame : grids_[0].frame; }
    int64_t writeCount() const { return writes_; }
    int64_t groupCount() const { return int64_t(grids_.size()); }

private:
    struct Grid {
        Frame frame;                  ///< the grid's frame (with local slicing when requested)
        Vec3f depthPerUnit{1, 1, 1};  ///< RGB optical depth per unit of prefix
        Vec3f attenuation{0, 0, 0};   ///< glass: Beer–Lambert per world unit over the chord
        std::vector<int64_t> offsets; ///< per column, into slice and prefix
        std::vector<uint32_t> slice;
        std::vector<float> prefix;
        /// Glass: per entry, the chord (slices) of the passages closed up to it, and the slice
        /// coordinate where the open passage entered (-1: outside after it).
        std::vector<float> chord, open;
    };
    // Grid g's column: the prefix sum and chord (frame depth units) in front of p's skipped cells.
    float columnSum(const Grid& g, int64_t column, double depth, int64_t skipCells, double& chord) const;
    Vec3f columnDepth(int64_t column, double depth, int64_t skipCells, double lengthPerDepth) const;
    // exp(-optical depth) of one column in front of `depth`: with entryLight_, one scan and a read.
    Vec3f columnLight(int64_t column, double depth, int64_t skipCells, double lengthPerDepth) const;
    LightView view_;
    std::vector<Grid> grids_;
    int64_t writes_ = 0;
    /// One bit per column: set where some grid holds a write (a lookup of an empty column needs
    /// neither its depth nor its entries; a few kilobytes where the entries' offsets take hundreds).
    std::vector<uint64_t> occupied_;
    /// Grids without glass on one frame (every grey scene, and coloured foliage: a grid per
    /// colour): per column the union of their entries' slices (entryOffsets_, entrySlice_), each
    /// with exp(-optical depth) of every grid's entries up to it, as columnDepth sums them, so
    /// that a lookup scans one run of entries and needs no exp.
    std::vector<int64_t> entryOffsets_;
    std::vector<uint32_t> entrySlice_;
    std::vector<Vec3f> entryLight_;
    void buildEntryLight();
};

/// RGB optical depth of one crossing of `m`: -ln(shadowCrossingTransmittance) per channel, or
/// `opaqueAbsorption` for opaque materials (and as an upper bound).
Vec3f absorptionPerCrossing(const Material& m, float opaqueAbsorption);

/// The shadow of one light: one absorption map per light view.
class AbsorptionShadow {
public:
    using Options = AbsorptionShadowOptions;
    using Stats = AbsorptionShadowStats;
    AbsorptionShadow() = default; ///< no casters: visibility 1
    /// From the scene's casters (SceneMesh::castsShadow). Throws voxfx::Error for resolutions < 1
    /// or skipped cells < 0.
    static AbsorptionShadow build(const Scene& scene, const Light& light,
                                  const AbsorptionShadowOptions& options, Progress* progress = nullptr);
    /// RGB fraction of the light reaching p; `n` the unit geometric normal turned towards the light.
    Vec3f visibility(const Vec3d& p, const Vec3d& n) const;
    Stats stats() const;
    const std::vector<AbsorptionShadowMap>& maps() const { return maps_; }

private:
    AbsorptionShadowOptions options_;
    std::vector<LightView> views_;
    std::vector<AbsorptionShadowMap> maps_;
    // Per view: the whole Fresnel of each glass crossing at its angle (none without glass).
    std::vector<std::shared_ptr<const detail::GlassCrossingFresnel>> fresnel_;
};

} // namespace voxfx
