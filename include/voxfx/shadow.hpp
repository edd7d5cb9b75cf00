// voxfx — shadows: light views, the standard shadow map (the baseline), the transmittance shadow
// map (ED06 §3.1) and the per-voxel absorption map (CHANG §3), and LightShadow, which combines
// them for one light as the renderer uses it.
//
//   ShadowKind::Map            every caster in one depth map per view, binary visibility, PCF.
//   ShadowKind::Transmittance  ED06: opaque casters keep a standard shadow map; partial occluders
//                              (materials with crossingTransmittance > 0) are grouped by their
//                              transmittance, one slicemap per group (a "channel"), voxelized from
//                              the light (surface or conservative, uniform or local slicing). At a
//                              point p: n_k = filled cells of channel k between the light and p, and
//                              visibility = map(p) * prod_k t_k ^ n_k (t_k: the group's RGB
//                              crossingTransmittance), so groups of different colours tint.
//   ShadowKind::Absorption     CHANG: one attribute voxelization of every caster; each write adds
//                              the material's optical depth sigma = -ln(luminance(t)) (opaque:
//                              ShadowOptions::opaqueAbsorption); visibility = exp(-sum of the
//                              absorption of the cells between the light and p). Grey, per write,
//                              not per unit length: a crossing written once attenuates exactly by
//                              e^-sigma, matching the per-crossing model of the exact reference.
//   ShadowKind::Volumes        exact hard shadows by shadow volumes counted per G-buffer pixel, with
//                              ED06 §3.2 culling and clamping (shadow_volume.hpp); built by the
//                              renderer from its G-buffer (buildVolumeShadow), not by build().
//
// Self-shadowing bias, for all kinds: the lookup point is moved along the surface normal (turned
// towards the light) by `normalOffset` column footprints, and the grids skip the `skipCells` cells
// ending at the point's own cell (default 1: the cell holding p, which holds p's own surface).
//
// Light views: spot lights get one perspective frame along their direction (field of view fitted to
// the casters, at most twice the outer cone, at most 160 degrees); point lights six 90-degree cube
// faces; directional lights an oriented orthographic frame (Frame::orthographic with a basis)
// perpendicular to their direction, fitted to the casters: world-space geometry is rasterized into
// it directly, nothing is rotated or copied.
//
// EXPERIMENTAL until the renderer issue closes.
// Thread-safety: built maps are read-only: visibility and the lookups may run concurrently from
// any number of threads (the renderer does). build() voxelizes or rasterizes with worker threads.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "voxfx/attribute_grid.hpp"
#include "voxfx/device.hpp"
#include "voxfx/dsm.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/voxel_grid.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

enum class ShadowKind : uint8_t { None, Map, Transmittance, Absorption, Volumes, Exact, Deep };
inline constexpr EnumName<ShadowKind> kShadowKindNames[] = {{"none", ShadowKind::None},
                                                            {"map", ShadowKind::Map},
                                                            {"transmittance", ShadowKind::Transmittance},
                                                            {"absorption", ShadowKind::Absorption},
                                                            {"volumes", ShadowKind::Volumes},
                                                            {"exact", ShadowKind::Exact},
                                                            {"deep", ShadowKind::Deep}};
const char* toString(ShadowKind k);
/// Parses none | map | transmittance | absorption | volumes | exact | deep; throws voxfx::Error
/// listing them otherwise.
ShadowKind parseShadowKind(const std::string& name);

struct ShadowOptions {
    ShadowKind kind = ShadowKind::Map;
    int64_t mapResolution = 2048; ///< standard shadow map: texels along the longer side
    int pcfRadius = 1;            ///< PCF over (2r+1)^2 texels (0 = one tap)
    double normalOffset = 1.0;    ///< lookup offset along the normal, in column footprints at p
    double depthBias = 1.0;       ///< shadow map depth bias, in texel footprints at p
    int64_t gridResolution = 256; ///< light grids (transmittance, absorption): columns, longer side
    int64_t gridDepth = 256;      ///< light grids: slices
    Slicing slicing = Slicing::Uniform;
    /// Where the transmittance maps' light-space voxelizations run (voxfx/device.hpp); the grids
    /// are the same on each. Cuda without a usable GPU runs on the CPU.
    Device device = Device::Cpu;
    /// Transmittance grids: Surface (ED06, one cell per triangle and column) or Conservative.
    VoxelizeMode voxelMode = VoxelizeMode::Surface;
    Coverage absorptionCoverage = Coverage::Center; ///< CHANG writes (see attribute_grid.hpp)
    int64_t skipCells = 1;      ///< cells ending at p's own cell that a grid lookup ignores
    float opaqueAbsorption = 8; ///< absorption mode: optical depth of one opaque crossing
    /// Grid lookups interpolate bilinearly between the four columns around p (softer edges, as PCF
    /// filters a shadow map; more self-shadowing on tilted leaves); false: p's own column only
    /// (ED06's lookup, the default: the smaller error against exact transport at high resolution).
    bool bilinear = false;
    /// Volumes: skip volumes without visible receivers (ED06 §3.2); the shadow is unchanged.
    bool volumeCulling = true;
    /// Volumes: end each volume at the last depth slab holding visible receivers; unchanged shadow.
    bool volumeClamping = true;
    /// ShadowKind::Deep (voxfx/deep_shadow.hpp): texels per view side, ε, storage, clusters.
    int64_t dsmResolution = 512;
    double dsmEpsilon = 0.05;
    DsmStorage dsmStorage = DsmStorage::Chunked;
    int dsmClusters = 0;           ///< deep: at most this many clustered maps per light (0, 1: off)
    bool dsmSkipEmptySpace = true; ///< deep: DeepShadowOptions::skipEmptySpace
};

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

/// The standard shadow map: the nearest caster depth per texel (centre-sampled fragments of the
/// one rasterizer), binary depth comparison with percentage-closer filtering.
class ShadowMap {
public:
    ShadowMap() = default;
    /// `casters` in world space. Cost: one rasterization at the view's resolution.
    static ShadowMap build(const MeshView& casters, const LightView& view, Progress* progress = nullptr);
    /// Fraction in [0, 1] of the (2r+1)^2 texels around p's texel whose nearest caster is not in
    /// front of p by more than `bias` (world units). 1 outside the view.
    float visibility(const Vec3d& world, int pcfRadius, double bias) const;
    /// Nearest caster depth of texel (x, y) in frame depth units; +inf where there is none.
    float depthAt(int64_t x, int64_t y) const { return depth_[size_t(y * view_.frame.width() + x)]; }
    const LightView& view() const { return view_; }

private:
    LightView view_;
    std::vector<float> depth_;
};

/// ED06 transmittance shadow map: one slicemap per channel in one light view.
class TransmittanceShadowMap {
public:
    struct Channel {
        VoxelGrid grid;              ///< in the view's frame (local slicing: its own ranges)
        Vec3f crossingTransmittance; ///< RGB factor per filled cell
    };
    TransmittanceShadowMap() = default;
    /// Voxelizes each group (world space) into the view with `mode` (Surface or Conservative) and
    /// `slicing`. groups.size() == transmittances.size(). Throws voxfx::Error otherwise.
    /// `device` picks where the voxelizations run (the same grids on each).
    static TransmittanceShadowMap build(const LightView& view, std::span<const MeshView> groups,
                                        std::span<const Vec3f> transmittances, VoxelizeMode mode,
                                        Slicing slicing, Progress* progress = nullptr,
                                        Device device = Device::Cpu);
    /// Filled cells of channel k in p's column strictly in front of the last `skipCells` cells up to
    /// and including p's cell: popcount of slices [0, s - skipCells + 1) with s = p's slice (whole
    /// words plus a mask). Points in front of the grid count 0, behind it count the whole column.
    int64_t cellsBefore(std::size_t k, const Vec3d& world, int64_t skipCells) const;
    /// prod_k crossingTransmittance_k ^ cellsBefore(k, p). 1 outside the view.
    Vec3f transmittance(const Vec3d& world, int64_t skipCells) const;
    /// Bilinear interpolation of the transmittance of the four columns around p at p's depth;
    /// columns outside the grid hold no caster (1).
    Vec3f transmittanceBilinear(const Vec3d& world, int64_t skipCells) const;
    const LightView& view() const { return view_; }
    const std::vector<Channel>& channels() const { return channels_; }

private:
    // One column of the grids (index y * W + x), at frame depth `depth`.
    Vec3f columnTransmittance(int64_t column, double depth, int64_t skipCells) const;
    int64_t columnCells(std::size_t k, int64_t column, double depth, int64_t skipCells) const;
    LightView view_;
    std::vector<Channel> channels_;
    /// Per channel: crossingTransmittance ^ n for n = 0 .. D (std::pow at build time; a lookup is
    /// then a table read instead of three pow calls per channel).
    std::vector<std::vector<Vec3f>> powers_;
};

/// CHANG per-voxel absorption map: an attribute voxelization from the light (its sparse form,
/// voxelizeAttributeColumns: only written voxels are stored), reduced to inclusive prefix sums of the
/// absorption along each column; a lookup scans the few written voxels of one column.
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

/// Optical depth of one crossing of `m` in absorption mode: -ln(luminance(crossingTransmittance)),
/// or `opaqueAbsorption` for opaque materials (and as an upper bound).
float absorptionPerCrossing(const Material& m, float opaqueAbsorption);

/// The exact reference for shadows through partial occluders: the product of the crossing
/// transmittances of every caster triangle between a point and the light, ray traced on the actual
/// triangles (Embree, glass.hpp's TriangleTracer). ShadowKind::Exact.
///
/// Glass (Material::isGlass: transmission > 0, opacity 1) is a volume, not a sheet: each crossing passes the
/// Fresnel-transmitted fraction 1 - F (exact unpolarized dielectric F at the shadow ray's angle to
/// the face, taken from the outside: by reciprocity the same fraction leaves a parallel slab as
/// enters it), the tint (the material's crossing transmittance) applies once where the ray enters,
/// and Beer–Lambert exp(-sigma * length) applies over the straight length between entering and
/// leaving (a front face, CCW towards the ray, enters). The shadow ray is not bent: light focused or
/// spread by refraction (caustics) is not modelled.
class TriangleTracer;
class ExactShadow {
public:
    /// How glass triangles pass light (see the class comment).
    struct Glass {
        float ior = 1.5f;
        Vec3f sigma{0.0f, 0.0f, 0.0f}; ///< Beer–Lambert coefficient per world unit
        Vec3f tint{1.0f, 1.0f, 1.0f};  ///< applied once per entering crossing
    };
    static constexpr uint32_t kNotGlass = 0xffffffffu;

    /// `casters` in world space; one RGB crossing transmittance per triangle (0 for opaque ones);
    /// optionally, per triangle, an index into `glass` or kNotGlass (empty: no glass).
    ExactShadow(const MeshView& casters, std::vector<Vec3f> triangleTransmittance,
                std::vector<uint32_t> triangleGlass = {}, std::vector<Glass> glass = {});
    /// From scene materials: crossingTransmittance per triangle, and glass for glass materials
    /// (Material::isGlass; ior, KHR_materials_volume attenuation, tint = crossingTransmittance).
    static ExactShadow fromMaterials(const MeshView& casters, std::span<const uint32_t> triangleMaterial,
                                     std::span<const Material> materials);
    /// Light fraction along p + t * dir, t in (epsilon, distance): the product over the crossed
    /// triangles (and glass volumes) described above.
    Vec3f transmittance(const Vec3d& p, const Vec3d& dir, double distance) const;
    double epsilon() const { return epsilon_; }

private:
    Mesh mesh_;
    std::vector<Vec3f> transmittance_;
    std::vector<uint32_t> triangleGlass_;
    std::vector<Glass> glass_;
    std::shared_ptr<const TriangleTracer> tracer_;
    double epsilon_ = 1e-6;
};

struct ShadowBuildTimings {
    double mapMs = 0;            ///< standard shadow map(s)
    double voxelizeMs = 0;       ///< transmittance / attribute voxelization from the light
    double volumeMs = 0;         ///< shadow volumes: culling, construction and counting
    int64_t volumeFragments = 0; ///< shadow-volume fragments rasterized in the camera frame
};

struct ShadowVolumeMask;
class DeepShadow; // voxfx/deep_shadow.hpp

/// All shadow data of one light for one ShadowKind, built from a scene.
class LightShadow {
public:
    LightShadow() = default; ///< kind None: visibility 1 everywhere
    /// Builds what `options.kind` needs from the scene's casters (SceneMesh::castsShadow).
    static LightShadow build(const Scene& scene, const Light& light, const ShadowOptions& options,
                             ShadowBuildTimings* timings = nullptr, Progress* progress = nullptr);
    /// RGB fraction of the light reaching world point p. `n`: unit geometric normal turned towards
    /// the light, for the normal offset (zero vector: no offset, the exact point is looked up).
    Vec3f visibility(const Vec3d& p, const Vec3d& n) const;
    /// ShadowKind::Volumes: wraps a per-pixel mask of the G-buffer the renderer shades (points are
    /// looked up by their pixel; see shadow_volume.hpp).
    static LightShadow fromVolumes(const ShadowOptions& options,
                                   std::shared_ptr<const ShadowVolumeMask> mask);
    ShadowKind kind() const { return options_.kind; }
    const std::vector<ShadowMap>& maps() const { return maps_; }
    const std::vector<TransmittanceShadowMap>& transmittanceMaps() const { return transmittance_; }
    const std::vector<AbsorptionShadowMap>& absorptionMaps() const { return absorption_; }
    /// ShadowKind::Deep: the deep shadow maps (null otherwise).
    const DeepShadow* deepShadow() const { return deep_.get(); }

private:
    ShadowOptions options_{ShadowKind::None};
    std::vector<LightView> mapViews_, gridViews_;
    std::vector<ShadowMap> maps_;
    std::vector<TransmittanceShadowMap> transmittance_;
    std::vector<AbsorptionShadowMap> absorption_;
    std::shared_ptr<const ShadowVolumeMask> volumes_;
    std::shared_ptr<const ExactShadow> exact_; ///< ShadowKind::Exact
    Light light_;                              ///< ShadowKind::Exact: the light traced towards
    std::shared_ptr<const DeepShadow> deep_;
};

} // namespace voxfx
