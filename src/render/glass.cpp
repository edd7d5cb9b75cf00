// voxfx — the closed set of glass methods (voxfx/glass.hpp): names and dispatch.
#include "voxfx/glass.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
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

namespace {

// The longest side, in columns, of box b's projection into `view`, clipped to the frame; the whole
// frame when part of b lies behind the eye.
double glassGridScreenExtent(const Box3d& b, const Frame& view) {
    const double W = double(view.width()), H = double(view.height());
    double x0 = W, y0 = H, x1 = 0, y1 = 0;
    for (int c = 0; c < 8; ++c) {
        const Vec3d p{c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z};
        if (!(view.viewDepth(p) > 0)) return std::max(W, H);
        const Vec3d g = view.gridFromWorld(p);
        x0 = std::min(x0, g.x), y0 = std::min(y0, g.y), x1 = std::max(x1, g.x), y1 = std::max(y1, g.y);
    }
    return std::max({0.0, std::min(x1, W) - std::max(x0, 0.0), std::min(y1, H) - std::max(y0, 0.0)});
}

// The voxels of a grid of n along the longest side of `box` (VoxelGlass's layout: one voxel margin).
double glassGridVoxels(const Box3d& box, int64_t n) {
    const Vec3d e = box.extent();
    const double voxel = std::max({e.x, e.y, e.z, 1e-12}) / double(n - 2);
    double count = 1;
    for (int a = 0; a < 3; ++a) count *= double(std::min<int64_t>(n, int64_t(std::ceil(e[a] / voxel)) + 2));
    return count;
}

} // namespace

GlassGridChoice chooseGlassGrid(int64_t requested, std::span<const Box3d> objects, const Box3d& glassBounds,
                                const Frame& view, double pixelsPerColumn) {
    GlassGridChoice out;
    if (requested != kGlassGridAuto) {
        out.resolution = requested;
        out.reason = "given";
        return out;
    }
    constexpr double kPixelsPerVoxel = 1.5, kMaxVoxels = double(int64_t(1) << 24);
    // The world size of a voxel: the object that spans the most pixels, one voxel per 1.5 of them.
    double voxel = 0;
    for (const Box3d& b : objects) {
        if (b.empty()) continue;
        const double pixels = glassGridScreenExtent(b, view) * pixelsPerColumn;
        const Vec3d e = b.extent();
        if (!(pixels > out.objectPixels)) continue;
        out.objectPixels = pixels;
        voxel = std::max({e.x, e.y, e.z}) / (pixels / kPixelsPerVoxel);
    }
    const Vec3d e = glassBounds.extent();
    const double longest = std::max({e.x, e.y, e.z});
    int64_t n = kGlassGridAutoMin;
    if (voxel > 0 && std::isfinite(longest / voxel))
        n = std::clamp<int64_t>((int64_t(std::ceil(longest / voxel)) + 2 + 31) / 32 * 32, kGlassGridAutoMin,
                                kGlassGridAutoMax);
    const int64_t wanted = n;
    while (n > kGlassGridAutoMin && glassGridVoxels(glassBounds, n) > kMaxVoxels) n -= 32;
    out.resolution = n;
    char text[160];
    if (voxel > 0)
        std::snprintf(text, sizeof text,
                      "auto: the largest glass object spans %.0f px on screen, about one voxel per %g px "
                      "(within %lld..%lld%s)",
                      out.objectPixels, kPixelsPerVoxel, (long long)kGlassGridAutoMin,
                      (long long)kGlassGridAutoMax, n < wanted ? ", at most 2^24 voxels" : "");
    else
        std::snprintf(text, sizeof text, "auto: no glass on screen, the minimum");
    out.reason = text;
    return out;
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
