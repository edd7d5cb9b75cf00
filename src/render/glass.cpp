// voxfx — the closed set of glass methods (voxfx/glass.hpp): names and dispatch.
#include "voxfx/glass.hpp"

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

bool glassSeesSceneBehind(const GlassOptions& options) {
    return std::visit(
        [](const auto& o) {
            if constexpr (requires { o.sceneBehind; })
                return o.sceneBehind;
            else
                return false;
        },
        options);
}

double glassAbsorptionConstant(const GlassOptions& options) {
    return std::visit(
        [](const auto& o) {
            if constexpr (requires { o.absorptionConstant; })
                return o.absorptionConstant;
            else
                return 1.0;
        },
        options);
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
