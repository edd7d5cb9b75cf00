// voxfx — glass: refraction through transparent objects, by voxels and by an exact reference.
//
// Materials with transmission > 0 (KHR_materials_transmission) and no gaps (opacity 1) are glass
// (Material::isGlass; a leaf's transmission with opacity < 1 is a sheet). A camera ray that hits
// glass (the G-buffer's nearest surface) splits at that front surface, with the exact dielectric
// Fresnel factor F (unpolarized, the same in every method): F of the environment seen along the
// mirror direction, plus (1 - F) times the light that comes through, tinted by the base colour.
// What comes through depends on GlassOptions::kind:
//
//   Exact       ray tracing on the actual triangles (Embree 3, through the voxfx_embree module):
//               Snell's law at every crossing with the interpolated vertex normal, total internal
//               reflection where Snell has no solution, (1 - F) at every refraction, Beer–Lambert
//               exp(-sigma * length) over the true path length inside, until the ray leaves every
//               object; then the environment. The reference for the voxel methods.
//   Multi       CHANG §4.1.1: the refracted ray marches through an attribute grid of the glass (one
//               voxel at a time with the one DDA, voxfx/dda.hpp); at a boundary voxel, whose stored
//               normal points along the ray when inside (leaving) or against it when outside
//               (entering), Snell with the voxel's averaged normal and its material's index; total
//               internal reflection where there is no solution; a refraction is skipped when its
//               normal is within angleThreshold of the previous one (CHANG's guard against refracting
//               twice at one surface spread over neighbouring voxels); Beer–Lambert with the
//               coefficient of the material the ray is in, per voxel segment; until the ray leaves
//               the grid, then the environment.
//   Frosted     ED06 §3.3: the glass's front faces and back faces (seen from the eye) voxelized into
//               two slicemaps in a camera-aligned perspective frame; each pixel's column is walked
//               front to back counting inside cells (a front-only cell enters, a back-only cell
//               leaves, a cell with both is resolved by the state carried from the previous cell:
//               from outside a thin sliver, from inside the way out; it counts once and leaves the
//               ray outside, which errs thin rather than filling the rest of the column). The count gives the
//               thickness L the eye ray crosses; the light comes from the refracted direction
//               displaced by L, attenuated by exp(-sigma L), blurred over a cone that grows with L
//               (a lookup into the environment's pre-filtered pyramid).
//   TwoSurface  Wyman 2005 as CHANG's baseline: the same march stops at the first back surface: one
//               refraction there (or the mirror direction under total internal reflection), then the
//               environment. It cannot see a second part of the object behind the first.
//
// The renderer then looks up what the leaving ray meets: the opaque scene (GlassOptions::sceneBehind,
// the same exact ray cast for every method, so the methods differ only inside the glass) or the
// environment.
//
// Attenuation: KHR_materials_volume's sigma = -ln(attenuationColor) / attenuationDistance per
// channel (zero when the distance is infinite).
//
// EXPERIMENTAL until the glass issue closes.
// Thread-safety: the optics functions are pure; a TriangleTracer is read-only after construction
// and may be queried from any number of threads.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "voxfx/attribute_grid.hpp"
#include "voxfx/bitgrid.hpp"
#include "voxfx/enum_names.hpp"
#include "voxfx/frame.hpp"
#include "voxfx/image.hpp"
#include "voxfx/math.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/scene.hpp"

namespace voxfx {

enum class GlassKind : uint8_t { None, Exact, Multi, TwoSurface, Frosted };
inline constexpr EnumName<GlassKind> kGlassKindNames[] = {{"none", GlassKind::None},
                                                          {"exact", GlassKind::Exact},
                                                          {"multi", GlassKind::Multi},
                                                          {"two-surface", GlassKind::TwoSurface},
                                                          {"frosted", GlassKind::Frosted}};
const char* toString(GlassKind k);
/// Parses none | exact | multi | two-surface | frosted; throws voxfx::Error listing them otherwise.
GlassKind parseGlassKind(const std::string& name);
/// The method a scene's glass renders with when none is asked for: Exact where some mesh has a
/// material with transmission > 0 (the reference, and on CPUs the fastest: see BENCHMARKS.md, the
/// voxel methods are built for a GPU's texture fetches), else None.
GlassKind defaultGlassKind(const Scene& scene);

struct GlassOptions {
    GlassKind kind = GlassKind::None;
    int64_t gridResolution = 128; ///< voxel methods: cubic voxels, this many along the glass's longest side
    /// Voxel methods: Coverage::Conservative writes every voxel a triangle touches (no holes on
    /// steep triangles: CHANG's widened slabs taken to the limit), Center one voxel per column.
    Coverage coverage = Coverage::Conservative;
    int maxEvents = 16;           ///< refractions and reflections followed per ray, all methods
    double angleThreshold = 0.35; ///< radians; Multi skips a refraction this close to the last normal
    /// The light leaving the glass (and the first surface's reflection) comes from the opaque scene
    /// where the ray meets it (found exactly, with Embree, for every method, and shaded with the
    /// lights and shadows), else from the environment. False: always the environment (CHANG).
    bool sceneBehind = true;
    /// Frosted: blur cone angle (radians) of the environment seen through a thickness equal to the
    /// glass bounds' diagonal (proportional below it).
    double frostedBlur = 0.6;
};

// ---- optics (closed form) -----------------------------------------------------------------------

/// Mirror direction of d about the unit normal n.
inline Vec3d reflectDirection(const Vec3d& d, const Vec3d& n) { return d - n * (2 * dot(d, n)); }
/// Snell's law: the refracted direction of unit d at a surface whose unit normal n faces the
/// incoming ray (dot(d, n) < 0), with eta = n_incident / n_transmitted. False (out untouched) under
/// total internal reflection.
bool refractDirection(const Vec3d& d, const Vec3d& n, double eta, Vec3d& out);
/// Exact unpolarized dielectric Fresnel reflectance for cos(incidence) cosI in [0, 1] from a medium of
/// index etaI into etaT; 1 under total internal reflection.
double fresnelDielectric(double cosI, double etaI, double etaT);
/// KHR_materials_volume attenuation coefficient per channel (per world unit).
Vec3f attenuationCoefficient(const Material& m);
/// exp(-sigma * length) per channel.
Vec3f beerLambert(const Vec3f& sigma, double length);

// ---- the exact reference ------------------------------------------------------------------------

/// Nearest-hit ray queries on triangles (Embree 3 in the voxfx_embree module, loaded on first use).
class TriangleTracer {
public:
    struct Hit {
        bool hit = false;
        double t = 0;          ///< distance along the (unit) direction
        uint32_t triangle = 0; ///< index into the mesh given to the constructor
        double u = 0, v = 0;   ///< barycentrics of corners 1 and 2
    };
    /// Builds the acceleration structure over `mesh` (world space). Throws voxfx::Error when the
    /// module is missing or Embree fails.
    explicit TriangleTracer(const MeshView& mesh);
    ~TriangleTracer();
    TriangleTracer(const TriangleTracer&) = delete;
    TriangleTracer& operator=(const TriangleTracer&) = delete;
    /// Nearest hit of origin + t * dir (dir unit) with t in (tNear, tFar).
    Hit intersect(const Vec3d& origin, const Vec3d& dir, double tNear, double tFar) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// ---- glass paths ---------------------------------------------------------------------------------

/// What one kind of glass does to light: index of refraction, Beer–Lambert coefficient per world unit
/// and the tint applied once where light enters (KHR_materials_transmission: the base colour).
struct GlassMedium {
    float ior = 1.5f;
    Vec3f sigma{0, 0, 0};
    Vec3f tint{1, 1, 1};
};
/// The medium of a material (ior, attenuationCoefficient, baseColor).
GlassMedium glassMedium(const Material& m);

/// One camera ray through glass.
struct GlassPath {
    bool hit = false;       ///< false: the ray met no glass (the other fields are meaningless)
    Vec3d reflectDir;       ///< mirror direction at the first surface
    float reflectance = 0;  ///< Fresnel F at the first surface
    Vec3d exitPoint;        ///< where the ray last left glass (or the last event)
    Vec3d exitDir;          ///< direction the transmitted light comes from, reversed
    Vec3f throughput;       ///< fraction of the environment along exitDir that arrives (without F)
    int events = 0;         ///< refractions and reflections followed (the first surface included)
    bool truncated = false; ///< stopped at maxEvents: leaves along its current direction
    double blurAngle = 0;   ///< frosted: the cone the environment is averaged over (radians)
};

/// The exact reference: glass triangles in an Embree scene.
class ExactGlass {
public:
    /// `mesh`: the glass triangles (world space, outward CCW); `vertexNormals`: one unit normal per
    /// vertex for smooth shading, or empty (face normals); `triangleMedium`: index into `media` per
    /// triangle.
    ExactGlass(const MeshView& mesh, std::vector<Vec3f> vertexNormals, std::vector<uint32_t> triangleMedium,
               std::vector<GlassMedium> media);
    /// Traces origin + t * dir (unit) through the glass: see the file comment (Exact).
    GlassPath trace(const Vec3d& origin, const Vec3d& dir, int maxEvents) const;

private:
    Mesh mesh_;
    std::vector<Vec3f> normals_;
    std::vector<uint32_t> medium_;
    std::vector<GlassMedium> media_;
    std::unique_ptr<TriangleTracer> tracer_;
    double epsilon_ = 1e-6;
};

/// The voxel methods: an attribute grid (normals and material channel) of the glass triangles.
class VoxelGlass {
public:
    /// Voxelizes `mesh` (world space) into cubic voxels, options.gridResolution along the longest side
    /// of its bounds (one voxel of margin), with options.coverage.
    VoxelGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium, std::vector<GlassMedium> media,
               const GlassOptions& options);
    /// The path of a camera ray along unit `dir` that meets glass at `entry` (a surface point found by
    /// rasterization) with unit outward normal `normal` and medium `medium`: Multi or TwoSurface
    /// (options.kind) march; see the file comment.
    GlassPath trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir,
                    const GlassOptions& options) const;
    const AttributeGrid& grid() const { return grid_; }
    double voxelSize() const { return voxel_; }

private:
    AttributeGrid grid_;
    std::vector<GlassMedium> media_;
    Vec3d origin_;
    double voxel_ = 1;
};

/// ED06 frosted glass: front- and back-face slicemaps of the glass seen from the camera.
class FrostedGlass {
public:
    /// `camera`: the view's perspective frame (the G-buffer's); the slicemaps use its eye, axes and
    /// field of view with options.gridResolution columns across and as many slices over the glass's
    /// depth range.
    FrostedGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium, std::vector<GlassMedium> media,
                 const Frame& camera, const GlassOptions& options);
    /// Inside cells counted in the column of world point p (see the file comment), from p's cell on.
    int64_t insideCells(const Vec3d& p) const;
    /// World length the eye ray through p crosses inside the glass (insideCells times the slice's
    /// length along that ray).
    double thickness(const Vec3d& p) const;
    GlassPath trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir,
                    const GlassOptions& options) const;
    const BitGrid& front() const { return front_; }
    const BitGrid& back() const { return back_; }
    const Frame& frame() const { return frame_; }

private:
    Frame frame_;
    BitGrid front_, back_;
    std::vector<GlassMedium> media_;
    double diagonal_ = 1;
};

/// Mean absolute error and PSNR of `test` against `reference` over the pixels where mask != 0,
/// values clamped to [0, 1] per channel first (peak 1). psnr is +inf for identical images.
struct ImageError {
    double mae = 0, psnr = 0;
    int64_t pixels = 0;
};
ImageError imageError(const Image& test, const Image& reference, const std::vector<uint8_t>& mask);

} // namespace voxfx
