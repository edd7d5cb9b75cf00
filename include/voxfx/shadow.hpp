// voxfx — shadows: the closed set of shadow techniques the renderer uses, one room each.
//
//   none           NoShadow: every point lit
//   map            voxfx/shadow_map.hpp: the standard shadow map with PCF (the baseline)
//   transmittance  voxfx/transmittance_shadow.hpp: ED06 §3.1, per-cell attenuation in coloured
//                  channels, opaque casters in a standard map
//   absorption     voxfx/absorption_shadow.hpp: CHANG §3, per-write absorption summed from the light
//   translucency   voxfx/translucency_shadow.hpp: GI08 §7, Beer-Lambert over the solid matter crossed
//   volumes        voxfx/shadow_volume.hpp: exact hard shadows by shadow volumes counted over the
//                  camera's G-buffer, with ED06 §3.2 culling and clamping
//   exact          voxfx/exact_shadow.hpp: ray traced on the triangles with Embree (the reference)
//   deep           voxfx/deep_shadow.hpp: Bornik et al.'s deep shadow maps over fragment lists
//
// A technique is an options type O and a built type S (the shadow of one light), S::Options = O:
//   O::kName, O::kSummary           its name (--shadows NAME) and one line about it
//   O::fields()                     its named options (voxfx/options.hpp): what the CLI, scene files
//                                   and Python set; the defaults are O's member initializers
//   S::build(scene, light, o, p)    what it needs from the scene's casters for one light
//   S::build(scene, light, o, context, p)  optional: the same fitted to the renderer's frame (its
//                                   camera, voxfx/build_context.hpp); deep shadows' clusters
//   s.prepare(gbuffer, geometry)    only where it needs the camera's G-buffer (volumes)
//   s.visibility(p, n)              fraction of the light reaching world point p (grey float or RGB);
//                                   n: unit geometric normal turned towards the light (zero: no
//                                   normal offset)
//   s.stats(), S::Stats             its counters; Stats += Stats (the lights of a frame) and
//                                   Stats::summary() (one line)
// ShadowTechniques lists the techniques; ShadowOptions, LightShadow and ShadowStats are variants
// over them, and the functions below dispatch with std::visit. The options, the counters and their
// variants are in voxfx/shadow_options.hpp, what voxfx/render.hpp includes (the built shadows stay
// here and in the techniques' headers). Adding a technique is its own files, its options and Stats
// in voxfx/shadow_options.hpp (and their entries in ShadowOptions and ShadowStats), and one entry in
// ShadowTechniques: the concept ShadowTechnique checks its interface, and the renderer, the CLI and
// the Python module find it through these functions.
//
// Thread-safety: built shadows are read-only: visibility may run concurrently from any number of
// threads (the renderer does); build and prepare use worker threads.
#pragma once

#include <concepts>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "voxfx/absorption_shadow.hpp"
#include "voxfx/build_context.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/exact_shadow.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/options.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_map.hpp"
#include "voxfx/shadow_options.hpp"
#include "voxfx/shadow_volume.hpp"
#include "voxfx/translucency_shadow.hpp"
#include "voxfx/transmittance_shadow.hpp"

namespace voxfx {

class NoShadow {
public:
    using Options = NoShadowOptions;
    using Stats = NoShadowStats;
    static NoShadow build(const Scene&, const Light&, const NoShadowOptions&, Progress* = nullptr) {
        return {};
    }
    float visibility(const Vec3d&, const Vec3d&) const { return 1.0f; }
    Stats stats() const { return {}; }
};

/// The interface every shadow technique has (see the file comment).
template <class S>
concept ShadowTechnique = NamedOptions<typename S::Options> &&
    requires(const S& s, const Scene& scene, const Light& light, const typename S::Options& o, Progress* p,
             const Vec3d& v, typename S::Stats& stats) {
    { S::build(scene, light, o, p) } -> std::same_as<S>;
    {s.visibility(v, v)};
    { s.stats() } -> std::same_as<typename S::Stats>;
    {stats += stats};
    { stats.summary() } -> std::convertible_to<std::string>;
};

/// The optional G-buffer step of a technique.
template <class S>
concept PreparedShadow = requires(S& s, const GBuffer& g, const SceneGeometry& geometry) {
    s.prepare(g, geometry);
};

template <ShadowTechnique... S> struct TechniqueList {
    using Options = std::variant<typename S::Options...>;
    using Built = std::variant<S...>;
    using Stats = std::variant<typename S::Stats...>;
};

/// Every shadow technique, in the order the CLI lists them.
using ShadowTechniques = TechniqueList<NoShadow, MapShadow, TransmittanceShadow, AbsorptionShadow,
                                       TranslucencyShadow, VolumeShadow, ExactShadow, DeepShadow>;

// ShadowOptions and ShadowStats (voxfx/shadow_options.hpp) are the variants over this list.
static_assert(
    std::is_same_v<ShadowOptions, ShadowTechniques::Options>,
    "ShadowOptions (voxfx/shadow_options.hpp) lists the techniques of ShadowTechniques, in its order");
static_assert(
    std::is_same_v<ShadowStats, ShadowTechniques::Stats>,
    "ShadowStats (voxfx/shadow_options.hpp) lists the techniques of ShadowTechniques, in its order");
/// The built shadow of one light.
using LightShadow = ShadowTechniques::Built;

/// Builds the technique `options` holds for `light` from the scene's casters.
LightShadow buildLightShadow(const Scene& scene, const Light& light, const ShadowOptions& options,
                             Progress* progress = nullptr);
/// The same for a frame: a technique whose build takes a BuildContext gets `context` (the renderer
/// passes its camera), the others are built as above.
LightShadow buildLightShadow(const Scene& scene, const Light& light, const ShadowOptions& options,
                             const BuildContext& context, Progress* progress = nullptr);
/// The technique's G-buffer step, where it has one (else nothing).
void prepareLightShadow(LightShadow& shadow, const GBuffer& gbuffer, const SceneGeometry& geometry);
/// RGB fraction of the light reaching p (grey techniques give three equal channels).
Vec3f shadowVisibility(const LightShadow& shadow, const Vec3d& p, const Vec3d& n);
ShadowStats shadowStats(const LightShadow& shadow);

} // namespace voxfx
