// voxfx — the closed set of shadow techniques (voxfx/shadow.hpp): names and dispatch. Every
// function here is a std::visit over the variants, so a technique added to ShadowTechniques is
// reached without a case of its own.
#include "voxfx/shadow.hpp"

#include "render/technique_list.hpp"

namespace voxfx {

std::string_view shadowName(const ShadowOptions& options) {
    return std::visit([](const auto& o) { return std::string_view(o.kName); }, options);
}

std::vector<std::string_view> shadowNames() { return detail::alternativeNames<ShadowOptions>(); }

ShadowOptions shadowOptionsNamed(std::string_view name) {
    return detail::alternativeNamed<ShadowOptions>(name, "shadow kind");
}

std::string_view shadowSummary(std::string_view name) {
    return detail::alternativeSummary<ShadowOptions>(name, "shadow kind");
}

LightShadow buildLightShadow(const Scene& scene, const Light& light, const ShadowOptions& options,
                             Progress* progress) {
    return buildLightShadow(scene, light, options, BuildContext{}, progress);
}

LightShadow buildLightShadow(const Scene& scene, const Light& light, const ShadowOptions& options,
                             const BuildContext& context, Progress* progress) {
    return std::visit(
        [&]<class O>(const O& o) -> LightShadow {
            using S = detail::BuiltFor<LightShadow, O>;
            if constexpr (requires { S::build(scene, light, o, context, progress); })
                return S::build(scene, light, o, context, progress);
            else
                return S::build(scene, light, o, progress);
        },
        options);
}

void prepareLightShadow(LightShadow& shadow, const GBuffer& gbuffer, const SceneGeometry& geometry) {
    std::visit(
        [&]<class S>(S& s) {
            if constexpr (PreparedShadow<S>) s.prepare(gbuffer, geometry);
        },
        shadow);
}

Vec3f shadowVisibility(const LightShadow& shadow, const Vec3d& p, const Vec3d& n) {
    return std::visit(
        [&](const auto& s) -> Vec3f {
            const auto v = s.visibility(p, n);
            if constexpr (std::is_same_v<std::remove_cvref_t<decltype(v)>, Vec3f>)
                return v;
            else
                return {float(v), float(v), float(v)};
        },
        shadow);
}

ShadowStats shadowStats(const LightShadow& shadow) {
    return std::visit([](const auto& s) -> ShadowStats { return s.stats(); }, shadow);
}

void accumulate(ShadowStats& sum, const ShadowStats& more) {
    if (sum.index() != more.index()) {
        sum = more;
        return;
    }
    std::visit([&]<class T>(T& s) { s += std::get<T>(more); }, sum);
}

std::string summary(const ShadowStats& stats) {
    return std::visit([](const auto& s) { return std::string(s.summary()); }, stats);
}

} // namespace voxfx
