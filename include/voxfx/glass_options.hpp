// voxfx — what a caller of the renderer sees of the glass methods (voxfx/glass.hpp): each
// method's options (its name, summary, named fields and defaults), the options they share, and
// the variant over them, GlassOptions (RenderOptions::glass). The built methods (ExactGlass,
// MultiGlass, ...) stay in the methods' own headers, which include this one: voxfx/render.hpp
// includes this header and not them.
//
//   none         NoGlassOptions
//   exact        ExactGlassOptions (voxfx/exact_glass.hpp)
//   multi        MultiGlassOptions (voxfx/voxel_glass.hpp)
//   two-surface  TwoSurfaceGlassOptions (voxfx/voxel_glass.hpp)
//   frosted      FrostedGlassOptions (voxfx/frosted_glass.hpp)
//
// GlassOptions lists them in GlassMethods' order (voxfx/glass.hpp checks that they agree).
//
// Thread-safety: values.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <variant>
#include <vector>

#include "voxfx/options.hpp"
#include "voxfx/types.hpp"

namespace voxfx {

struct Scene; // voxfx/scene.hpp

/// What every method takes: where the light leaving the glass comes from.
struct GlassSceneOptions {
    /// The light leaving the glass (and the first surface's reflection) comes from the opaque scene
    /// where the ray meets it (found exactly, with Embree, for every method, and shaded with the
    /// lights and shadows), else from the environment. False: always the environment (CHANG).
    bool sceneBehind = true;
    /// CHANG's absorption constant: every glass medium's attenuation coefficient (its material's
    /// KHR_materials_volume attenuation, per world unit) is multiplied by it. 1 (the default): the
    /// materials as given; 0: no absorption inside glass; must be finite and >= 0.
    double absorptionConstant = 1.0;
};

/// What the methods that follow a path take.
struct GlassPathOptions : GlassSceneOptions {
    int maxEvents = 16; ///< refractions and reflections followed per ray
};

/// The glass grids' resolution where none is chosen from the screen (frosted slicemaps; a VoxelGlass
/// built with gridResolution 0 outside render()).
inline constexpr int64_t kGlassGridResolution = 128;
/// The voxel methods' default gridResolution: auto, sized by render() from the glass objects' size
/// on screen (chooseGlassGrid in voxfx/glass.hpp), within kGlassGridAutoMin..kGlassGridAutoMax.
inline constexpr int64_t kGlassGridAuto = 0;
inline constexpr int64_t kGlassGridAutoMin = 64, kGlassGridAutoMax = 512;

struct NoGlassOptions {
    static constexpr std::string_view kName = "none";
    static constexpr std::string_view kSummary = "shaded like any surface";
    static std::span<const OptionField<NoGlassOptions>> fields() { return {}; }
};

// exact: ray tracing with Embree, the reference (voxfx/exact_glass.hpp).
struct ExactGlassOptions : GlassPathOptions {
    static constexpr std::string_view kName = "exact";
    static constexpr std::string_view kSummary =
        "ray tracing on the triangles (Embree): Snell, Fresnel, total internal reflection, "
        "Beer-Lambert over true lengths; the reference";
    /// maxEvents, absorptionConstant, sceneBehind.
    static std::span<const OptionField<ExactGlassOptions>> fields();
};

// multi and two-surface: the voxel march (voxfx/voxel_glass.hpp).
/// What both voxel methods take.
struct VoxelGlassOptions : GlassPathOptions {
    /// Cubic voxels along the glass's longest side, 2..4096; 0 (the default): auto, from the glass
    /// objects' size on screen (chooseGlassGrid).
    int64_t gridResolution = kGlassGridAuto;
    /// Coverage::Conservative writes every voxel a triangle touches (no holes on steep triangles:
    /// CHANG's widened slabs taken to the limit), Center one voxel per column.
    Coverage coverage = Coverage::Conservative;
    double angleThreshold = 0.35; ///< radians: a refraction this close to the last normal is skipped
    /// CHANG's widened slabs (AttributeOptions::slabOverlap): each slab grows by this many slices on
    /// both sides, 0..4 (more voxels written, fewer holes where faces are steep under center coverage).
    double slabOverlap = 0;
};

struct MultiGlassOptions : VoxelGlassOptions {
    static constexpr std::string_view kName = "multi";
    static constexpr std::string_view kSummary =
        "CHANG: march through an attribute grid, refract at boundary voxels";
    /// glassGrid, glassCoverage, angleThreshold, slabOverlap, maxEvents, absorptionConstant, sceneBehind.
    static std::span<const OptionField<MultiGlassOptions>> fields();
};

struct TwoSurfaceGlassOptions : VoxelGlassOptions {
    static constexpr std::string_view kName = "two-surface";
    static constexpr std::string_view kSummary =
        "Wyman 2005: refract at the front surface and at the first back surface";
    /// glassGrid, glassCoverage, angleThreshold, slabOverlap, maxEvents, absorptionConstant, sceneBehind.
    static std::span<const OptionField<TwoSurfaceGlassOptions>> fields();
};

// frosted: ED06 §3.3 (voxfx/frosted_glass.hpp).
struct FrostedGlassOptions : GlassSceneOptions {
    static constexpr std::string_view kName = "frosted";
    static constexpr std::string_view kSummary =
        "ED06: thickness from front/back-face slicemaps drives a refraction offset, attenuation and a "
        "blurred environment lookup";
    int64_t gridResolution = kGlassGridResolution; ///< slicemap columns across and slices, 2..4096
    /// Blur cone angle (radians) of the environment seen through a thickness equal to the glass
    /// bounds' diagonal (proportional below it).
    double blur = 0.6;
    /// Refraction offset through a thickness equal to the glass bounds' diagonal, as a multiple of
    /// the front surface's refraction (proportional below it): the environment is looked up along
    /// d + refraction * L / diagonal * (t - d), d the eye ray, t the refracted ray.
    double refraction = 1.0;
    /// Its slicemaps are the camera's view of the glass: a renderer's cache rebuilds them when the
    /// camera moves.
    static constexpr bool viewDependent() { return true; }
    /// glassGrid, frostedBlur, frostedRefraction, sceneBehind.
    static std::span<const OptionField<FrostedGlassOptions>> fields();
};

/// The options of one method (which one is the alternative held). Default: none.
using GlassOptions = std::variant<NoGlassOptions, ExactGlassOptions, MultiGlassOptions,
                                  TwoSurfaceGlassOptions, FrostedGlassOptions>;

/// The method's name ("exact", "multi", ...).
std::string_view glassName(const GlassOptions& options);
/// Every method's name, in GlassMethods' order.
std::vector<std::string_view> glassNames();
/// The default options of the method called `name`; voxfx::Error listing the names otherwise.
GlassOptions glassOptionsNamed(std::string_view name);
/// The method's one-line summary (for help).
std::string_view glassSummary(std::string_view name);
/// The method a scene's glass renders with when none is asked for: exact where some mesh has a
/// glass material (Material::isGlass: the reference, and on CPUs the fastest: see BENCHMARKS.md, the
/// voxel methods are built for a GPU's texture fetches), else none.
GlassOptions defaultGlass(const Scene& scene);
/// Whether the light leaving the glass comes from the opaque scene (GlassSceneOptions).
bool glassSeesSceneBehind(const GlassOptions& options);
/// The method's absorption constant (GlassSceneOptions::absorptionConstant; 1 for none).
double glassAbsorptionConstant(const GlassOptions& options);

} // namespace voxfx
