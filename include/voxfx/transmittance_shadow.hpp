// voxfx — transmittance shadow maps (ED06 §3.1, "Fast Scene Voxelization and Applications"). Shadow
// technique "transmittance" (voxfx/shadow.hpp).
//
// Opaque casters keep a standard shadow map (voxfx/shadow_map.hpp); partial occluders (materials
// whose shadowCrossingTransmittance is not zero) are grouped by that transmittance, one slicemap per
// group (a "channel"), voxelized from the light (surface or conservative, uniform or local
// slicing). At a point p: n_k = filled cells of channel k between the light and p (a popcount of
// the column's words in front of p's slice, leaving out the skipped cells; voxfx/light_grid.hpp;
// conservative grids count runs of consecutive filled cells instead, one per leaf crossed),
// and visibility = map(p) * prod_k t_k ^ n_k (t_k: the group's RGB transmittance), so groups of
// different colours tint. Glass groups (a Beer–Lambert coefficient sigma_k, Material::
// shadowAttenuationCoefficient) pair their crossings along the column, the first entering and the
// next leaving, and multiply by beerLambert(sigma_k, chord): the world length between the paired
// cells (cell centres; conservative grids: run centres), up to p when p lies inside (the column
// holds an even number of crossings and an odd number lies in front of p). A glass crossing at an
// angle passes the Fresnel of that angle, beyond normal incidence's: taken per column of each light
// view where its centre line crosses the glass, with the glass's stored normal interpolated there
// (render/glass_crossing_fresnel.hpp), so a curved glass's shadow darkens smoothly to its rim.
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

#include "voxfx/device.hpp"
#include "voxfx/light_grid.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/options.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_map.hpp"
#include "voxfx/shadow_options.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

namespace detail {
class GlassCrossingFresnel;
}

/// The slicemaps of one light view, one per channel.
class TransmittanceShadowMap {
public:
    struct Channel {
        VoxelGrid grid;              ///< in the view's frame (local slicing: its own ranges)
        Vec3f crossingTransmittance; ///< RGB factor per filled cell
        Vec3f attenuation{0, 0, 0};  ///< glass: Beer–Lambert coefficient over the chord (world units)
    };
    TransmittanceShadowMap() = default;
    /// Voxelizes each group (world space) into the view with `mode` (Surface or Conservative) and
    /// `slicing`. groups.size() == transmittances.size(). Throws voxfx::Error otherwise.
    /// `device` picks where the voxelizations run (the same grids on each). `attenuations`: per
    /// group, the glass's Beer–Lambert coefficient (empty: none is glass).
    static TransmittanceShadowMap build(const LightView& view, std::span<const MeshView> groups,
                                        std::span<const Vec3f> transmittances, VoxelizeMode mode,
                                        Slicing slicing, Progress* progress = nullptr,
                                        Device device = Device::Cpu,
                                        std::span<const Vec3f> attenuations = {});
    /// Surface mode: filled cells of channel k in p's column strictly in front of the last
    /// `skipCells` cells up to and including p's cell: popcount of slices [0, s - skipCells + 1)
    /// with s = p's slice (whole words plus a mask). Conservative mode: the runs of consecutive
    /// filled cells that end in those slices (a leaf fills every cell it touches, 2-3 in a column
    /// when tilted, and is one crossing). Points in front of the grid count 0, behind it count the
    /// whole column.
    int64_t cellsBefore(std::size_t k, const Vec3d& world, int64_t skipCells) const;
    /// prod_k crossingTransmittance_k ^ cellsBefore(k, p), times Beer–Lambert over the chords of
    /// the glass channels. 1 outside the view.
    Vec3f transmittance(const Vec3d& world, int64_t skipCells) const;
    /// Bilinear interpolation of the transmittance of the four columns around p, each read at the
    /// depth where the receiver's tangent plane (normal `normal`) crosses it; at p's depth for a
    /// zero normal; beyond the grid's border, its border column; sharpened (LightGridOptions::sharpness).
    Vec3f transmittanceBilinear(const Vec3d& world, int64_t skipCells, const Vec3d& normal = {},
                                double sharpness = 1) const;
    const LightView& view() const { return view_; }
    const std::vector<Channel>& channels() const { return channels_; }

private:
    // One column of the grids (index y * W + x), at frame depth `depth`; lengthPerDepth: world
    // length along the light's ray per frame depth unit there.
    Vec3f columnTransmittance(int64_t column, double depth, int64_t skipCells, double lengthPerDepth) const;
    // Glass channel k: the chord (frame depth units) inside its glass in front of p's skipped cells.
    double columnChord(std::size_t k, int64_t column, double depth, int64_t skipCells) const;
    int64_t columnCells(std::size_t k, int64_t column, double depth, int64_t skipCells) const;
    LightView view_;
    VoxelizeMode mode_ = VoxelizeMode::Surface;
    std::vector<Channel> channels_;
    /// Per channel: crossingTransmittance ^ n for n = 0 .. D (std::pow at build time; a lookup is
    /// then a table read instead of three pow calls per channel).
    std::vector<std::vector<Vec3f>> powers_;
    // Every channel's columns in one sparse index, where the channels share one frame and none is
    // glass (every leaf scene): per column the slices at which some channel's count steps (a filled
    // cell; conservative grids: the last cell of a run), in depth order, each with the transmittance
    // of every channel's count up to and including it (the product of the power tables that
    // columnTransmittance takes, in its order: the same floats). A lookup then reads one short,
    // mostly empty run of entries instead of a bit column per channel and a table per channel.
    // Built where it is no larger than the bit columns; eventOffsets_ empty otherwise.
    std::vector<uint32_t> eventOffsets_; // columnCount() + 1
    std::vector<uint16_t> eventSlice_;
    std::vector<Vec3f> eventLight_;      // one per event
    std::vector<uint64_t> eventColumns_; // one bit per column: set where it holds an event
    void buildEventIndex();
    // The transmittance of column `column` through its slices [0, end), from the index.
    Vec3f indexedTransmittance(int64_t column, int64_t end) const;
};

/// The shadow of one light: the opaque casters' map and the channels' grids per light view.
class TransmittanceShadow {
public:
    using Options = TransmittanceShadowOptions;
    using Stats = TransmittanceShadowStats;
    TransmittanceShadow() = default; ///< no casters: visibility 1
    /// From the scene's casters (SceneMesh::castsShadow). Throws voxfx::Error for resolutions < 1,
    /// skipped cells < 0 or a voxel mode other than surface and conservative.
    static TransmittanceShadow build(const Scene& scene, const Light& light,
                                     const TransmittanceShadowOptions& options, Progress* progress = nullptr);
    /// RGB fraction of the light reaching p; `n` the unit geometric normal turned towards the light.
    Vec3f visibility(const Vec3d& p, const Vec3d& n) const;
    Stats stats() const;
    const MapShadow& opaque() const { return opaque_; }
    const std::vector<TransmittanceShadowMap>& maps() const { return maps_; }

private:
    TransmittanceShadowOptions options_;
    MapShadow opaque_;
    std::vector<LightView> views_;
    std::vector<TransmittanceShadowMap> maps_;
    // Per view: the Fresnel of each glass crossing beyond normal incidence's (none without glass).
    std::vector<std::shared_ptr<const detail::GlassCrossingFresnel>> fresnel_;
};

} // namespace voxfx
