// voxfx — per-voxel absorption shadows (CHANG §3, "Real-time Realistic Voxel-based Rendering").
// Shadow technique "absorption" (voxfx/shadow.hpp).
//
// One attribute voxelization of every caster from the light; each write adds the material's
// optical depth sigma = -ln(luminance(shadowCrossingTransmittance)) (opaque materials:
// `opaqueAbsorption`), so dense foliage that writes a voxel several times absorbs more. At p,
// visibility = exp(-sum of the absorption of the cells between the light and p). Grey, per write,
// not per unit length: a crossing written once attenuates exactly by e^-sigma, matching the
// per-crossing model of the exact reference. Columns are reduced to prefix sums once, so a lookup
// scans the few written voxels of one column (voxfx/light_grid.hpp for the lookup's bias).
//
// Thread-safety: a built shadow is read-only (lookups from any number of threads); build voxelizes
// with worker threads.
#pragma once

#include <cstdint>
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

namespace voxfx {

struct AbsorptionShadowOptions {
    static constexpr std::string_view kName = "absorption";
    static constexpr std::string_view kSummary =
        "CHANG: attribute voxelization from the light, absorption = write count x material constant, "
        "summed along the light path";
    LightGridOptions grid;
    Coverage coverage = Coverage::Center; ///< CHANG's writes (see attribute_grid.hpp)
    float opaqueAbsorption = 8;           ///< optical depth of one crossing of an opaque material
    /// gridResolution (alias grid), gridDepth, slicing, skipCells, bilinear, normalOffset, coverage,
    /// opaqueAbsorption.
    static std::span<const OptionField<AbsorptionShadowOptions>> fields();
};

/// The absorption columns of one light view: an attribute voxelization (its sparse form,
/// voxelizeAttributeColumns: only written voxels are stored), reduced to inclusive prefix sums of
/// the absorption along each column.
class AbsorptionShadowMap {
public:
    AbsorptionShadowMap() = default;
    /// `casters` in world space; triangleAbsorption: optical depth added per write, one per triangle.
    static AbsorptionShadowMap build(const LightView& view, const MeshView& casters,
                                     std::span<const float> triangleAbsorption, Coverage coverage,
                                     Slicing slicing, Progress* progress = nullptr);
    /// Sum of the absorption of the cells in front of the last `skipCells` cells up to p's cell.
    float opticalDepth(const Vec3d& world, int64_t skipCells) const;
    /// exp(-opticalDepth). 1 outside the view.
    float transmittance(const Vec3d& world, int64_t skipCells) const;
    /// Bilinear interpolation of exp(-optical depth) of the four columns around p at p's depth.
    float transmittanceBilinear(const Vec3d& world, int64_t skipCells) const;
    const LightView& view() const { return view_; }
    const Frame& frame() const { return frame_; }
    int64_t writeCount() const { return writes_; }

private:
    float columnDepth(int64_t column, double depth, int64_t skipCells) const;
    LightView view_;
    Frame frame_;                  ///< the grid's frame (with local slicing when requested)
    std::vector<int64_t> offsets_; ///< per column, into slice_ and prefix_
    std::vector<uint32_t> slice_;
    std::vector<float> prefix_;
    int64_t writes_ = 0;
};

/// Optical depth of one crossing of `m`: -ln(luminance(shadowCrossingTransmittance)), or
/// `opaqueAbsorption` for opaque materials (and as an upper bound).
float absorptionPerCrossing(const Material& m, float opaqueAbsorption);

/// The shadow of one light: one absorption map per light view.
class AbsorptionShadow {
public:
    using Options = AbsorptionShadowOptions;
    struct Stats {
        int64_t grids = 0, writes = 0;
        Stats& operator+=(const Stats& o);
        std::string summary() const;
    };
    AbsorptionShadow() = default; ///< no casters: visibility 1
    /// From the scene's casters (SceneMesh::castsShadow). Throws voxfx::Error for resolutions < 1
    /// or skipped cells < 0.
    static AbsorptionShadow build(const Scene& scene, const Light& light,
                                  const AbsorptionShadowOptions& options, Progress* progress = nullptr);
    /// Fraction of the light reaching p; `n` the unit geometric normal turned towards the light.
    float visibility(const Vec3d& p, const Vec3d& n) const;
    Stats stats() const;
    const std::vector<AbsorptionShadowMap>& maps() const { return maps_; }

private:
    AbsorptionShadowOptions options_;
    std::vector<LightView> views_;
    std::vector<AbsorptionShadowMap> maps_;
};

} // namespace voxfx
