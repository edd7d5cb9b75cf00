// voxfx — what a caller of the renderer sees of the shadow techniques (voxfx/shadow.hpp): each
// technique's options (its name, summary, named fields and defaults) and its counters (Stats), and
// the variants over them, ShadowOptions (RenderOptions::shadow) and ShadowStats
// (RenderResult::shadowStats). The built shadows (MapShadow, DeepShadow, ...) stay in the
// techniques' own headers, which include this one: voxfx/render.hpp includes this header and not
// them, so a program that renders does not compile the techniques.
//
//   none           NoShadowOptions
//   map            ShadowMapOptions, MapShadowStats (voxfx/shadow_map.hpp)
//   transmittance  TransmittanceShadowOptions, TransmittanceShadowStats (voxfx/transmittance_shadow.hpp)
//   absorption     AbsorptionShadowOptions, AbsorptionShadowStats (voxfx/absorption_shadow.hpp)
//   translucency   TranslucencyShadowOptions, TranslucencyShadowStats (voxfx/translucency_shadow.hpp)
//   volumes        ShadowVolumeOptions, ShadowVolumeStats (voxfx/shadow_volume.hpp)
//   exact          ExactShadowOptions, ExactShadowStats (voxfx/exact_shadow.hpp)
//   deep           DeepShadowOptions, DeepShadowStats (voxfx/deep_shadow.hpp, voxfx/dsm.hpp)
//
// ShadowOptions and ShadowStats list them in ShadowTechniques' order (voxfx/shadow.hpp checks that
// they agree). What each option does is stated where the technique is (its header's file comment).
//
// Thread-safety: values.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "voxfx/light_grid.hpp"
#include "voxfx/math.hpp"
#include "voxfx/options.hpp"
#include "voxfx/types.hpp"

namespace voxfx {

struct NoShadowOptions {
    static constexpr std::string_view kName = "none";
    static constexpr std::string_view kSummary = "no shadows";
    static std::span<const OptionField<NoShadowOptions>> fields() { return {}; }
};

struct NoShadowStats {
    NoShadowStats& operator+=(const NoShadowStats&) { return *this; }
    std::string summary() const { return {}; }
};

// map: the standard shadow map with PCF (voxfx/shadow_map.hpp).
struct ShadowMapOptions {
    static constexpr std::string_view kName = "map";
    static constexpr std::string_view kSummary = "standard shadow map with PCF (binary: leaves are opaque)";
    int64_t resolution = 2048; ///< texels along the longer side of each light view
    int pcfRadius = 1;         ///< PCF over (2r+1)^2 texels (0 = one tap)
    double normalOffset = 1.0; ///< lookup offset along the normal, in column footprints at p
    double depthBias = 1.0;    ///< depth bias, in texel footprints at p
    /// mapResolution (alias shadowMapResolution), pcf, normalOffset, depthBias.
    static std::span<const OptionField<ShadowMapOptions>> fields();
};

struct MapShadowStats {
    int64_t maps = 0, texels = 0;
    MapShadowStats& operator+=(const MapShadowStats& o);
    std::string summary() const;
};

// transmittance: ED06 §3.1 (voxfx/transmittance_shadow.hpp).
struct TransmittanceShadowOptions {
    static constexpr std::string_view kName = "transmittance";
    static constexpr std::string_view kSummary =
        "ED06: partial occluders (leaves, glass) voxelized from the light; light is attenuated per "
        "filled cell, one channel per leaf colour group; opaque objects keep a standard shadow map";
    LightGridOptions grid;
    /// Surface (ED06, one cell per triangle and column) or Conservative.
    VoxelizeMode voxelMode = VoxelizeMode::Surface;
    /// Where the light-space voxelizations run (voxfx/device.hpp); the grids are the same on each.
    /// Cuda without a usable GPU runs on the CPU.
    Device device = Device::Cpu;
    /// The standard map of the opaque casters (its normalOffset is the grids' too).
    ShadowMapOptions opaque;
    /// gridResolution (alias grid), gridDepth, slicing, skipCells, bilinear, normalOffset,
    /// voxelMode, device, mapResolution, pcf, depthBias.
    static std::span<const OptionField<TransmittanceShadowOptions>> fields();
};

struct TransmittanceShadowStats {
    int64_t grids = 0, channels = 0, filledCells = 0; ///< light grids (views x channels)
    MapShadowStats opaque;
    TransmittanceShadowStats& operator+=(const TransmittanceShadowStats& o);
    std::string summary() const;
};

// absorption: CHANG §3 (voxfx/absorption_shadow.hpp).
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

struct AbsorptionShadowStats {
    int64_t grids = 0, writes = 0;
    AbsorptionShadowStats& operator+=(const AbsorptionShadowStats& o);
    std::string summary() const;
};

// translucency: GI08 §7 (voxfx/translucency_shadow.hpp).
struct TranslucencyShadowOptions {
    static constexpr std::string_view kName = "translucency";
    static constexpr std::string_view kSummary =
        "GI08: solid voxelization from the light, Beer-Lambert over the matter crossed (filled cells "
        "counted along the light's column)";
    LightGridOptions grid;
    double extinction = 1; ///< sigma, per world unit of matter crossed (>= 0)
    Vec3f tint{1, 1, 1};   ///< per channel relative mean free path, each in (0, 1]
    /// How the casters' inside is decided (voxfx/voxelize.hpp): Auto is parity when the casters are
    /// closed (analyzeTopology), else Gwn; Flood and Vote cannot run in light views (refused).
    Fill fill = Fill::Auto;
    /// gridResolution (alias grid), gridDepth, slicing, skipCells, bilinear, normalOffset,
    /// extinction, tint, fill.
    static std::span<const OptionField<TranslucencyShadowOptions>> fields();
};

struct TranslucencyShadowStats {
    int64_t grids = 0, filledCells = 0;
    TranslucencyShadowStats& operator+=(const TranslucencyShadowStats& o);
    std::string summary() const;
};

// volumes: shadow volumes with ED06 §3.2 culling and clamping (voxfx/shadow_volume.hpp).
struct ShadowVolumeOptions {
    static constexpr std::string_view kName = "volumes";
    static constexpr std::string_view kSummary =
        "exact hard shadows: shadow volumes of the closed casters counted per pixel (open casters "
        "are refused), culled and clamped against what the camera sees (ED06 3.2; the same image "
        "without: --no-volume-culling)";
    bool cullReceivers = true;         ///< skip volumes holding no visible receiver
    bool cullOccluded = true;          ///< skip casters entirely in other casters' shadow
    bool clamp = true;                 ///< end each volume at its last receiver slab
    bool clampRuns = true;             ///< also cut the volume to the runs of receiver slabs (near end, gaps)
    bool cullShadowedParts = true;     ///< drop unlit triangles lying in other casters' shadow
    bool dropShadowedReceivers = true; ///< a receiver in another caster's shadow is left to it
    int64_t mapResolution = 256;       ///< light views for culling: columns along the longer side
    int64_t receiverSlices = 128;      ///< receiver slicemap: slices
    /// volumeCulling (every switch of culling and clamping), cullReceivers, cullOccluded,
    /// cullShadowedParts, dropShadowedReceivers, volumeClamping, clampRuns, cullResolution,
    /// receiverSlices.
    static std::span<const OptionField<ShadowVolumeOptions>> fields();
};

struct ShadowVolumeStats {
    int64_t casters = 0;
    int64_t culledNoReceiver = 0; ///< skipped: no visible receiver in the volume
    int64_t culledOccluded = 0;   ///< skipped: entirely in other casters' shadow
    int64_t clamped = 0;          ///< volumes ended before the scene's far bound
    int64_t nearClamped = 0;      ///< volumes whose first layer starts behind the caster
    int64_t gaps = 0;             ///< gaps left out between layers of one volume
    int64_t culledTriangles = 0;  ///< unlit triangles dropped from drawn volumes (in others' shadow)
    int64_t droppedReceivers = 0; ///< receiver cells left to a caster in front (summed over casters)
    int64_t depthPass = 0, depthFail = 0;
    int64_t silhouetteEdges = 0;
    int64_t volumeTriangles = 0;
    int64_t fragments = 0;        ///< volume fragments the rasterizer emitted in the camera frame
    bool receiversCovered = true; ///< false: some receiver lay outside the light views (no culling)
    double cullMs = 0, buildMs = 0, rasterMs = 0;
    /// Sums (receiversCovered: both), for the lights of a frame.
    ShadowVolumeStats& operator+=(const ShadowVolumeStats& o);
    std::string summary() const;
};

// exact: ray traced with Embree, the reference (voxfx/exact_shadow.hpp).
struct ExactShadowOptions {
    static constexpr std::string_view kName = "exact";
    static constexpr std::string_view kSummary =
        "ray traced on the triangles (Embree): the product of the transmittances of every surface "
        "crossed towards the light, volumes marched in fine steps (the reference)";
    /// Step of the march through volume objects, in smallest voxel spacings of the scene's volumes.
    double volumeStep = 0.25;
    /// exactStep (volumeStep).
    static std::span<const OptionField<ExactShadowOptions>> fields();
};

struct ExactShadowStats {
    int64_t triangles = 0;     ///< caster triangles traced, summed over lights
    int64_t volumeObjects = 0; ///< casting objects of the volume scene, summed over lights
    double volumeStep = 0;     ///< world step of the volume march (0: no volume objects)
    ExactShadowStats& operator+=(const ExactShadowStats& o);
    std::string summary() const;
};

// deep: deep shadow maps, Bornik et al. (voxfx/deep_shadow.hpp over voxfx/dsm.hpp).
struct DeepShadowOptions {
    static constexpr std::string_view kName = "deep";
    static constexpr std::string_view kSummary =
        "deep shadow maps (Bornik et al.): per texel an epsilon-compressed visibility function over "
        "all fragments from the light; translucent surfaces are steps, volume objects attenuate "
        "continuously";
    int64_t resolution = 512; ///< texels along the longer side of each view
    double epsilon = 0.05;    ///< compression tolerance (0: every node kept)
    DsmStorage storage = DsmStorage::Chunked;
    int32_t fixedNodes = 0;    ///< fixed storage: nodes per texel, 0 = sized by the worst texel
    double stepVoxels = 1.0;   ///< volume sample step, in smallest voxel spacings
    double termination = 1e-4; ///< early ray termination: V below this becomes 0
    /// Clustering (Bornik et al. §4): at most this many clusters of casting objects per light,
    /// each with its own maps (0 or 1: one set of maps fitted to all casters). See voxfx/deep_shadow.hpp.
    int clusters = 0;
    /// d0: objects whose light-space projected boxes differ by at most this (fraction of the
    /// light view's side) share a cluster.
    double clusterThreshold = 0.2;
    /// Clustered maps share the texels the unclustered maps would have (their resolution is
    /// scaled, up or down, to fit); off: every clustered map has `resolution` texels along its
    /// longer side.
    bool clusterEqualTexels = true;
    /// Filtering of lookups between texels.
    DsmFilter filter = DsmFilter::Bilinear;
    /// Clusters, fitted to the build context's camera (voxfx/deep_shadow.hpp's file comment): a
    /// renderer's cache rebuilds the maps when the camera moves.
    bool viewDependent() const { return clusters > 1; }
    /// Volume bricks the transfer function leaves transparent are not sampled (EmptySpace in
    /// voxfx/segment_walker.hpp); the map is the same either way, only faster.
    bool skipEmptySpace = true;
    /// Lookups by DeepShadow::visibility(p, n): offset along the normal, in texel footprints at p.
    double normalOffset = 1.0;
    /// Lookups by DeepShadow::visibility(p, n): depth bias, in texel footprints at p.
    double depthBias = 1.0;
    /// dsmResolution, epsilon, dsmStorage, fixedNodes, dsmStep, termination, clusters,
    /// clusterThreshold, clusterEqualTexels, dsmFilter, emptySpaceSkipping, normalOffset, depthBias.
    static std::span<const OptionField<DeepShadowOptions>> fields();
};

/// Node counts and memory of a built map.
struct DsmStats {
    int64_t texels = 0;
    int64_t nodes = 0;          ///< total nodes stored
    int64_t maxNodes = 0;       ///< largest texel
    int64_t bytes = 0;          ///< bytes held by the storage (nodes, links, per-texel headers)
    int64_t overflowTexels = 0; ///< fixed storage: texels rebuilt with a larger ε to fit
    double maxEpsilon = 0;      ///< largest ε any texel was built with
    double meanNodes() const { return texels ? double(nodes) / double(texels) : 0.0; }
};

struct DeepShadowTimings {
    double fragmentsMs = 0; ///< rasterizing the fragment lists
    double buildMs = 0;     ///< walking the texels, compressing, storing
};

/// Node and memory statistics of the maps (summed over views and lights; maxNodes and maxEpsilon:
/// the largest), their storage and build times.
struct DeepShadowStats : DsmStats {
    DsmStorage storage = DsmStorage::Chunked;
    DeepShadowTimings timings;
    int64_t clusteredLights = 0; ///< lights built with clusters > 1
    int64_t clusterGroups = 0;   ///< clusters formed (summed over those lights)
    int64_t clusterViews = 0;    ///< their light views (one map each, or three for coloured light)
    /// Texels of the views the unclustered maps of those lights would have (the budget that
    /// clusterEqualTexels keeps to), and of the clustered views.
    int64_t unclusteredViewTexels = 0, clusteredViewTexels = 0;
    /// Lights with clusters > 1 that have a single casting object: one cluster, the same maps as
    /// without clusters (the summary says so).
    int64_t singleObjectLights = 0;
    DeepShadowStats& operator+=(const DeepShadowStats& o);
    /// "T texels, nodes per texel mean M max X, B MiB chunked (fixed layout sized by the worst
    /// texel: F MiB)", then for clusters ", K clusters in V maps (C texels per channel against
    /// U unclustered)" and ", clusters asked but N light(s) have one casting object" where those
    /// apply; empty without texels.
    std::string summary() const;
};

/// The options of one technique (which one is the alternative held). Default: the standard map.
using ShadowOptions =
    std::variant<NoShadowOptions, ShadowMapOptions, TransmittanceShadowOptions, AbsorptionShadowOptions,
                 TranslucencyShadowOptions, ShadowVolumeOptions, ExactShadowOptions, DeepShadowOptions>;
/// The counters of one technique, summed over the lights of a frame.
using ShadowStats =
    std::variant<NoShadowStats, MapShadowStats, TransmittanceShadowStats, AbsorptionShadowStats,
                 TranslucencyShadowStats, ShadowVolumeStats, ExactShadowStats, DeepShadowStats>;

/// The technique's name ("map", "deep", ...).
std::string_view shadowName(const ShadowOptions& options);
/// Every technique's name, in ShadowTechniques' order.
std::vector<std::string_view> shadowNames();
/// The default options of the technique called `name`; voxfx::Error listing the names otherwise.
ShadowOptions shadowOptionsNamed(std::string_view name);
/// The technique's one-line summary (for help).
std::string_view shadowSummary(std::string_view name);
/// Adds `more` to `sum` when they are of one technique; else `sum` becomes `more`.
void accumulate(ShadowStats& sum, const ShadowStats& more);
/// The technique's one line about its counters ("" for none).
std::string summary(const ShadowStats& stats);

} // namespace voxfx
