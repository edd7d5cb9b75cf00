// voxfx — shadow volumes (Crow 1977; depth-fail counting, Carmack / Everitt & Kilgard 2002) with
// ED06 §3.2's voxel-based culling and clamping: exact hard shadows for point, spot and directional
// lights, counted per pixel of the camera's G-buffer by a consumer of the one rasterizer. Shadow
// technique "volumes" (voxfx/shadow.hpp): the one that needs the G-buffer, so VolumeShadow has the
// prepare step (build: the casters; prepare: culling, volumes and counting for that G-buffer).
//
// Casters. Each SceneMesh that casts shadows is welded by exact vertex position and its edge
// adjacency is built once (ShadowCasterSet). A caster must be closed (every edge shared by exactly
// two triangles traversing it in opposite directions); open or non-manifold casters are refused
// with an error naming the mesh (their shadow volume is not a closed surface, so counting is
// meaningless): mark them castsShadow = false or use another shadow technique.
//
// Volumes. For a light, the triangles of a caster facing away from it (normal . toLight <= 0)
// form the *near cap*, reversed; silhouette edges (between a lit and an unlit triangle) are
// extruded away from the light into quads; the unlit triangles extruded form the *far cap*. So a
// caster's volume V holds exactly the points whose segment to the light crosses an unlit triangle
// of the caster before reaching them: lit surfaces never lie on their own volume's boundary. The
// extrusion ends on a plane: dot(x - L, a) = Z (point and spot lights: a = the unit direction from
// the light to the caster's bounding-sphere centre, and every vertex must lie in front of the
// light along a, else the caster is refused; directional lights: a = the light direction). Z
// passes the whole scene, or, *clamped*, the last depth slab holding visible receivers in V.
//
// Counting. Volume triangles are rasterized (centre-sampled, strict tie rule: watertight) in the
// camera frame; per pixel the consumer adds, for depth-fail volumes, +1 for each back-facing and
// -1 for each front-facing fragment *behind* the G-buffer depth, and for depth-pass volumes +1 for
// each front-facing and -1 for each back-facing fragment *in front of* it. The sum is the number
// of volumes holding the pixel's surface point: shadowed iff it is not 0. Depth-pass is used for a
// caster when a ball around the eye (covering what the near clip cuts off) is lit by it
// (conservatively, by its bounding sphere); it then needs no near cap, unless the caster is
// see-through (blended: the G-buffer shows what lies behind it, and an eye ray through it enters
// its volume through the near cap). Depth-fail everywhere else.
//
// Culling and clamping (ED06 §3.2), all conservative, so the shadow is the same pixel for pixel;
// each switchable on its own (the options below) so each saving can be measured:
//   receivers  the visible *receivers* (G-buffer points facing the light, or of a translucent
//              material) voxelized into a slicemap in the light's views (makeLightViews fitted to
//              casters and receivers). A caster whose unlit triangles' conservative footprint,
//              dilated by one column and one slice, holds no receiver cell at or behind them is
//              skipped (cullReceivers). Receivers outside every view turn all of it off for that
//              light.
//   clamping   volumeClamping: the far cap ends at the farthest such cell. clampRuns: the volume
//              is cut into *layers*, one per run of depth (along the caster's axis) holding such
//              cells: the near end moves from the caster to the first run (when that run lies
//              wholly behind the caster) and gaps between runs are left out. Behind the caster's
//              deepest vertex the volume's cross-section is the unlit triangles projected from the
//              light, so a layer [a, b] is closed by those projections at a and b and the
//              silhouette quads between them (both caps drawn in either counting mode).
//   shadowed receivers  dropShadowedReceivers: a receiver cell in a texel that another caster B
//              covers (texel clean, as below) with B's farthest fragment in front of both the cell
//              and this caster's nearest unlit depth around it is left to B (ED06 fig. 8, right):
//              it lies in B's volume, and "strictly in front" is acyclic for casters that do not
//              interpenetrate, so the front-most such caster keeps it.
//   occluded   then, among the casters left: a caster lying entirely in the shadow of the others
//              (cullOccluded), and with cullShadowedParts the unlit triangles of the others that lie
//              in the shadow of the others (ED06 fig. 8, left). An unlit triangle's whole
//              conservative footprint in the light's map must be *clean* (no other caster's
//              silhouette edge touches the texel, so every ray through it meets the same other
//              casters) and covered by another caster whose farthest lit fragment in the texel is in
//              front of the triangle's nearest one. Then the triangle's shadow prism is already in
//              those casters' volumes (casters are assumed not to interpenetrate); the volume of the
//              triangles kept is closed by quads on the edges between kept and dropped triangles.
//              A caster with every unlit triangle dropped is culled whole.
// Culling costs rasterizations into the light's views per caster; on the CPU that can exceed the
// fill it saves (BENCHMARKS.md).
//
// Lookups: the mask answers for the surface point of each G-buffer pixel. A point that is not
// the G-buffer surface of the pixel it projects to (its depth differs from the pixel's: a blended
// surface or a volume sample in front of it, a refracted or reflected point) gets the exact answer
// instead: the segment from it to the light traced against the same closed casters (Embree,
// voxfx/triangle_tracer.hpp), so it does not take the shadow of the opaque surface behind it.
//
// Thread-safety: ShadowCasterSet is read-only after build; computeShadowVolumes may run
// concurrently on the same set and G-buffer (it uses worker threads itself); the result does not
// depend on the thread count.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/gbuffer.hpp"
#include "voxfx/light_view.hpp"
#include "voxfx/options.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_options.hpp"

namespace voxfx {

class TriangleTracer;

/// One closed caster: welded positions, triangles and, per directed edge 3t+k (from corner k to
/// corner k+1 of triangle t), the directed edge of the neighbour traversing it backwards.
struct ShadowCaster {
    std::string name;
    std::vector<Vec3f> positions;
    std::vector<uint32_t> indices;
    std::vector<uint32_t> twin;
    Vec3d sphereCentre; ///< bounding sphere (centre of the bounds, radius to the farthest vertex)
    double sphereRadius = 0;
    /// Of a blended material (Material::blend): not in the G-buffer, so the camera sees receivers
    /// through it, and a depth-pass count needs its near cap too.
    bool seeThrough = false;
};

/// The closed casters of a scene with their edge adjacency, built once and used for every light.
struct ShadowCasterSet {
    std::vector<ShadowCaster> casters;
    /// Every SceneMesh with castsShadow. Throws voxfx::Error naming the first open or non-manifold
    /// caster (with its count of unmatched edges).
    static ShadowCasterSet build(const Scene& scene);
};

/// Per pixel of a G-buffer: whether its surface point lies in some caster's shadow for one light.
struct ShadowVolumeMask {
    Frame camera; ///< the G-buffer's frame
    std::vector<uint8_t> shadowed;
    std::vector<float> depth; ///< the G-buffer's depth per pixel
    ShadowVolumeStats stats;
    /// Per caster: 0 drawn, 1 culled (no visible receiver), 2 culled (in other casters' shadow).
    std::vector<uint8_t> culled;
    /// 1 where the pixel under p (a G-buffer point) is not shadowed, 0 where it is; 1 outside.
    float visibility(const Vec3d& p) const;
    /// Whether p is the surface point of the pixel it projects to (its frame depth within 1e-5,
    /// relative, of the pixel's G-buffer depth): the points the mask answers for.
    bool atSurface(const Vec3d& p) const;
};

/// Which G-buffer pixels count as receivers for culling: a surface facing the light (geometric
/// normal, towards the viewer, . direction to the light > 0) or of a non-opaque material.
std::vector<uint8_t> shadowVolumeReceivers(const GBuffer& gbuffer, const SceneGeometry& geometry,
                                           std::span<const Material> materials, const Light& light);

/// Shadow volumes of `casters` for `light`, counted per pixel of `gbuffer`. `sceneBounds` bounds
/// every surface that can receive (the unclamped volumes pass it); `receivers` as returned by
/// shadowVolumeReceivers (used for culling and clamping only). Throws voxfx::Error for a caster
/// the light lies beside or inside (point and spot lights; see the file comment).
ShadowVolumeMask computeShadowVolumes(const ShadowCasterSet& casters, const Light& light,
                                      const GBuffer& gbuffer, const std::vector<uint8_t>& receivers,
                                      const Box3d& sceneBounds, const ShadowVolumeOptions& options = {});

/// The triangles of every caster's volume (near cap, silhouette quads, far cap, as the counting
/// rasterizes them for depth-fail), unclamped and unculled, outward facing. For tests and
/// inspection.
Mesh shadowVolumeMesh(const ShadowCasterSet& casters, const Light& light, const Box3d& sceneBounds);

/// The shadow of one light as the renderer uses it: built from the scene's casters, then prepared
/// (counted) for the G-buffer of the frame it shades.
class VolumeShadow {
public:
    using Options = ShadowVolumeOptions;
    using Stats = ShadowVolumeStats;
    VolumeShadow() = default; ///< no casters: visibility 1
    /// The scene's closed casters (ShadowCasterSet::build: throws voxfx::Error naming an open one).
    static VolumeShadow build(const Scene& scene, const Light& light, const ShadowVolumeOptions& options,
                              Progress* progress = nullptr);
    /// Counts the volumes over `gbuffer` (computeShadowVolumes with the receivers it shows).
    void prepare(const GBuffer& gbuffer, const SceneGeometry& geometry);
    /// At a G-buffer surface point (ShadowVolumeMask::atSurface): 1 where its pixel is lit, 0 where
    /// it is shadowed; elsewhere 1 or 0 as the segment from p (moved 10 tracer epsilons along n)
    /// to the light misses or crosses a caster. 1 before prepare.
    float visibility(const Vec3d& p, const Vec3d& n) const;
    Stats stats() const { return mask_.stats; }
    const ShadowVolumeMask& mask() const { return mask_; }

private:
    ShadowVolumeOptions options_;
    std::shared_ptr<const ShadowCasterSet> casters_;
    Light light_;
    Box3d sceneBounds_;
    std::vector<Material> materials_;
    std::shared_ptr<const TriangleTracer> tracer_; ///< the casters, for points off the G-buffer
    ShadowVolumeMask mask_;
};

} // namespace voxfx
