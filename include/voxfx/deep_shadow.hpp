// voxfx — deep shadow maps of mixed polygon and volume scenes (Bornik et al. 2012 §4), shadow
// technique "deep" (voxfx/shadow.hpp): per light
// view (LightView: spot one perspective frame, point six cube faces, directional one orthographic
// frame) the scene's boundary triangles are rasterized into fragment lists (FragmentLists); every
// texel walks its list front to back (SegmentWalker): crossings of opaque and translucent objects
// are steps (V *= the crossing's transmittance, opaque 0), between a crossing that enters translucent
// glass and the next that leaves it V falls by Beer–Lambert over the chord (VolumeSceneObject::
// attenuation, as ExactShadow), segments inside volume objects are sampled at their ends
// and at steps of `stepVoxels` smallest voxel spacings from a start jittered per texel
// (sampleJitter), each interval with the pre-integrated extinction σ of the values at its ends
// (PreintegratedTransfer: σ = -ln(1 - α(value)) / opacityLength averaged over them, V *= exp(-σ·dl)),
// empty space between fragments is skipped and the walk stops when V falls below `termination`
// (V is then set to 0). The visibility function is ε-compressed on the fly into fixed or chunked
// storage (voxfx/dsm.hpp). Depths are the light frame's depths (perspective: view distance along
// the light's axis; orthographic: slices). Where a casting translucent object colours the light
// (its transmittance or attenuation differs between channels) each view has three maps, one per
// channel; a grey scene (opaque casters, grey leaves, volumes) keeps one.
//
// Lookup: p (moved along its normal by normalOffset texel footprints) is projected into the view
// that covers it; the visibility at its depth (minus depthBias texel footprints) is interpolated
// bilinearly between the four texels around it. Points outside every view are lit.
//
// Thread-safety: build uses worker threads; a built DeepShadow is read-only (lookups from any number
// of threads).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/dsm.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/options.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {

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
    /// Clustering (Bornik et al. §4.4): at most this many maps per light view, each fitted to a
    /// cluster of objects (0 or 1: one map fitted to all casters). Spot and directional lights;
    /// a point light keeps its six cube-face maps, and the stats say so (unclusteredPointLights).
    int clusters = 0;
    /// d0: objects whose light-space projected boxes differ by at most this (fraction of the
    /// light view's side) share a cluster.
    double clusterThreshold = 0.2;
    /// Volume bricks the transfer function leaves transparent are not sampled (EmptySpace in
    /// voxfx/segment_walker.hpp); the map is the same either way, only faster.
    bool skipEmptySpace = true;
    /// Lookups by DeepShadow::visibility(p, n): offset along the normal, in texel footprints at p.
    double normalOffset = 1.0;
    /// Lookups by DeepShadow::visibility(p, n): depth bias, in texel footprints at p.
    double depthBias = 1.0;
    /// dsmResolution, epsilon, dsmStorage, fixedNodes, dsmStep, termination, clusters,
    /// clusterThreshold, emptySpaceSkipping, normalOffset, depthBias.
    static std::span<const OptionField<DeepShadowOptions>> fields();
};

/// The paper's clustering heuristic on boxes (any 2D extent, e.g. light-space projected boxes):
/// d(A, B) = the largest difference of their min and max corners; pairs are visited by increasing
/// d, an object joins the cluster whose members are all within d0 of it (the one with the smallest
/// largest distance), or opens a new one while fewer than maxClusters exist, or else joins the
/// cluster whose largest distance to it is smallest. Returns the cluster of each box (0-based,
/// numbered in order of opening). Deterministic.
struct ProjectedBox {
    double lo[2], hi[2];
};
std::vector<int> clusterBoxes(const std::vector<ProjectedBox>& boxes, int maxClusters, double d0);

struct DeepShadowTimings {
    double fragmentsMs = 0; ///< rasterizing the fragment lists
    double buildMs = 0;     ///< walking the texels, compressing, storing
};

/// Node and memory statistics of the maps (summed over views and lights; maxNodes and maxEpsilon:
/// the largest), their storage and build times.
struct DeepShadowStats : DsmStats {
    DsmStorage storage = DsmStorage::Chunked;
    DeepShadowTimings timings;
    int64_t clusteredMaps = 0; ///< cluster groups of lights built with clusters > 1 (summed)
    /// Lights for which clusters > 1 was asked but not applied: point lights (their six cube-face
    /// maps each fit every caster; clustering them is not implemented).
    int64_t unclusteredPointLights = 0;
    DeepShadowStats& operator+=(const DeepShadowStats& o);
    /// "T texels, nodes per texel mean M max X, B MiB chunked (fixed layout sized by the worst
    /// texel: F MiB)", then ", N clustered maps" or ", clusters not applied to N point light(s)"
    /// where those apply; empty without texels.
    std::string summary() const;
};

class DeepShadow {
public:
    using Options = DeepShadowOptions;
    using Stats = DeepShadowStats;
    DeepShadow() = default; ///< no maps: visibility 1
    /// One deep shadow map per view of `light` fitted to the casters' bounds (all objects with
    /// castsShadow). Throws voxfx::Error for an invalid scene or options, or when progress cancels.
    static DeepShadow build(const VolumeScene& scene, const Light& light, const DeepShadowOptions& options,
                            Progress* progress = nullptr);
    /// The same with given views (a fitted frustum per cluster, tests).
    static DeepShadow build(const VolumeScene& scene, std::vector<LightView> views,
                            const DeepShadowOptions& options, Progress* progress = nullptr);
    /// The renderer's scene (volumeSceneOf: every mesh, then its volume scene). No maps (visibility
    /// 1) when nothing casts: no caster triangle and no volume scene.
    static DeepShadow build(const Scene& scene, const Light& light, const DeepShadowOptions& options,
                            Progress* progress = nullptr);

    /// RGB fraction of the light reaching world point p (see the file comment); `n` the unit normal
    /// turned towards the light (zero: no offset), with the options' normalOffset and depthBias.
    Vec3f visibility(const Vec3d& p, const Vec3d& n) const;
    /// The same with the given offsets (texel footprints at p).
    Vec3f visibility(const Vec3d& p, const Vec3d& n, double normalOffset, double depthBias) const;
    const std::vector<LightView>& views() const { return views_; }
    /// One map per view: the red channel, or every channel where the view's scene is grey.
    const std::vector<DeepShadowMap>& maps() const { return maps_; }
    /// Per view, the green and blue channels' maps, or none (grey).
    const std::vector<std::vector<DeepShadowMap>>& greenBlueMaps() const { return greenBlue_; }
    /// Clusters: views [groupBegin[g], groupBegin[g + 1]) hold the objects of cluster g; the
    /// visibility is the product over clusters. One group without clustering.
    const std::vector<std::size_t>& groupBegin() const { return groupBegin_; }
    /// Node and memory statistics summed over the views (maxNodes: the largest texel of any).
    DeepShadowStats stats() const;
    const DeepShadowTimings& timings() const { return timings_; }

private:
    std::vector<LightView> views_;
    std::vector<DeepShadowMap> maps_;
    std::vector<std::vector<DeepShadowMap>> greenBlue_;
    std::vector<std::size_t> groupBegin_;
    DeepShadowTimings timings_;
    DeepShadowOptions options_;
    bool clustered_ = false, pointUnclustered_ = false; ///< clusters > 1: applied; asked, point light
};

/// The exact (uncompressed, epsilon ignored) visibility function along texel (x, y) of `view`, as
/// the deep shadow map builds it: for tests and error measurements.
std::vector<DsmNode> deepShadowTexel(const VolumeScene& scene, const LightView& view, int64_t x, int64_t y,
                                     const DeepShadowOptions& options);

} // namespace voxfx
