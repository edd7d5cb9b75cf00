// voxfx — the closed set of glass methods (voxfx/glass.hpp): names and dispatch.
#include "voxfx/glass.hpp"

#include <type_traits>

#include "render/technique_list.hpp"

namespace voxfx {

std::string_view glassName(const GlassOptions& options) {
    return std::visit([](const auto& o) { return std::string_view(o.kName); }, options);
}

std::vector<std::string_view> glassNames() { return detail::alternativeNames<GlassOptions>(); }

GlassOptions glassOptionsNamed(std::string_view name) {
    return detail::alternativeNamed<GlassOptions>(name, "glass method");
}

std::string_view glassSummary(std::string_view name) {
    return detail::alternativeSummary<GlassOptions>(name, "glass method");
}

GlassOptions defaultGlass(const Scene& scene) {
    for (const SceneMesh& m : scene.meshes)
        if (m.material < scene.materials.size() && scene.materials[m.material].isGlass())
            return ExactGlassOptions{};
    return NoGlassOptions{};
}

namespace {

// What every method but none takes (GlassSceneOptions), or null.
const GlassSceneOptions* sceneOptions(const GlassOptions& options) {
    return std::visit(
        []<class O>(const O& o) -> const GlassSceneOptions* {
            if constexpr (std::is_base_of_v<GlassSceneOptions, O>)
                return &o;
            else
                return nullptr;
        },
        options);
}

} // namespace

bool glassSeesSceneBehind(const GlassOptions& options) {
    const GlassSceneOptions* o = sceneOptions(options);
    return o && o->sceneBehind;
}

double glassAbsorptionConstant(const GlassOptions& options) {
    const GlassSceneOptions* o = sceneOptions(options);
    return o ? o->absorptionConstant : 1.0;
}

BuiltGlass buildGlass(const GlassInput& input, const GlassOptions& options) {
    return std::visit(
        [&]<class O>(const O& o) -> BuiltGlass { return detail::BuiltFor<BuiltGlass, O>::build(input, o); },
        options);
}

GlassPath traceGlass(const BuiltGlass& glass, const GlassHit& hit) {
    return std::visit([&](const auto& g) { return g.trace(hit); }, glass);
}

} // namespace voxfx
