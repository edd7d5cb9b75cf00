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
// bilinearly between the four texels around it (filter bilinear, the default), or read from the
// one texel p falls in (filter none). Points outside every view are lit.
//
// Clustering (§4, clusters > 1): the casting objects are grouped by the distance of their
// light-space projected boxes (clusterBoxes; for a point light the largest distance over the six
// cube directions), each cluster gets its own maps fitted to its objects, and the visibility is the
// product over clusters. Directional lights: one map per cluster. Spot and point lights: one
// perspective map aimed at the cluster when its objects lie within a cone of at most 120 degrees
// around the light, else the spot's own frame or the cube faces its objects reach (so a point light
// may need fewer than six maps). Where the build context has a camera (voxfx/build_context.hpp; the
// renderer passes its frame's), distances are scaled by how near the pair is to the camera against
// the casters' centre (the light-space perspective idea: resolution where the viewer is close), so
// objects near the camera get clusters, and maps, of their own. With clusterEqualTexels (default) the
// clustered maps share the texels of the unclustered maps (the paper's 4 x 128^2 against 256^2): the trade is
// at equal memory.
//
// Thread-safety: build uses worker threads; a built DeepShadow is read-only (lookups from any number
// of threads).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/build_context.hpp"
#include "voxfx/dsm.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/options.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/shadow_options.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {

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
/// The same heuristic over any symmetric distance: dist[i * n + j] for n objects.
std::vector<int> clusterByDistance(std::size_t n, const std::vector<double>& dist, int maxClusters,
                                   double d0);

class DeepShadow {
public:
    using Options = DeepShadowOptions;
    using Stats = DeepShadowStats;
    DeepShadow() = default; ///< no maps: visibility 1
    /// One deep shadow map per view of `light` fitted to the casters' bounds (all objects with
    /// castsShadow). Throws voxfx::Error for an invalid scene or options, or when progress cancels.
    static DeepShadow build(const VolumeScene& scene, const Light& light, const DeepShadowOptions& options,
                            Progress* progress = nullptr);
    /// The same with clusters fitted to the context's camera, where it has one.
    static DeepShadow build(const VolumeScene& scene, const Light& light, const DeepShadowOptions& options,
                            const BuildContext& context, Progress* progress = nullptr);
    /// The same with given views (a fitted frustum per cluster, tests).
    static DeepShadow build(const VolumeScene& scene, std::vector<LightView> views,
                            const DeepShadowOptions& options, Progress* progress = nullptr);
    /// The renderer's scene (volumeSceneOf: every mesh, then its volume scene). No maps (visibility
    /// 1) when nothing casts: no caster triangle and no volume scene.
    static DeepShadow build(const Scene& scene, const Light& light, const DeepShadowOptions& options,
                            Progress* progress = nullptr);
    /// The same with clusters fitted to the context's camera, where it has one (the renderer's call).
    static DeepShadow build(const Scene& scene, const Light& light, const DeepShadowOptions& options,
                            const BuildContext& context, Progress* progress = nullptr);

    /// RGB fraction of the light reaching world point p (see the file comment); `n` the unit normal
    /// turned towards the light (zero: no offset), with the options' normalOffset and depthBias.
    Vec3f visibility(const Vec3d& p, const Vec3d& n) const;
    /// The same with the given offsets (texel footprints at p).
    Vec3f visibility(const Vec3d& p, const Vec3d& n, double normalOffset, double depthBias) const;
    /// visibility(p, n), and in `texel` the texel footprint at p of the view that covers p
    /// (viewIndexFor over views(); 0 where none does): the lookup's own, not searched again.
    Vec3f visibility(const Vec3d& p, const Vec3d& n, double& texel) const;
    const std::vector<LightView>& views() const { return views_; }
    /// One map per view: the red channel, or every channel where the view's scene is grey.
    const std::vector<DeepShadowMap>& maps() const { return maps_; }
    /// Per view, the green and blue channels' maps, or none (grey).
    const std::vector<std::vector<DeepShadowMap>>& greenBlueMaps() const { return greenBlue_; }
    /// Clusters: views [groupBegin[g], groupBegin[g + 1]) hold the objects of cluster g; the
    /// visibility is the product over clusters. One group without clustering.
    const std::vector<std::size_t>& groupBegin() const { return groupBegin_; }
    /// Per object of the scene it was built from, its cluster (-1: casts no shadow); empty without
    /// clustering.
    const std::vector<int>& objectClusters() const { return objectClusters_; }
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
    std::vector<int> objectClusters_;
    DeepShadowStats clusterStats_; ///< the cluster counters (clusteredLights ... singleObjectLights)
};

/// The exact (uncompressed, epsilon ignored) visibility function along texel (x, y) of `view`, as
/// the deep shadow map builds it: for tests and error measurements.
std::vector<DsmNode> deepShadowTexel(const VolumeScene& scene, const LightView& view, int64_t x, int64_t y,
                                     const DeepShadowOptions& options);

} // namespace voxfx
