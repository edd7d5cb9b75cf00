// voxfx — translucency shadows (GI08 §7, "Single-pass GPU Solid Voxelization for Real-time
// Applications").
//
// The casters are voxelized as a solid from the light (GI08 §4–5). The matter the light crosses to
// reach p is the count of filled cells in front of p along its column (GI08 §6 "counting",
// countColumnRange) times the world length of one slice along the column's centre ray; the light
// is attenuated by exp(-sigma_c * length) per channel (Beer-Lambert; GI08's jade dragon).
#include "voxfx/translucency_shadow.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "render/light_grid_lookup.hpp"
#include "render/shadow_casters.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/text.hpp"

namespace voxfx {

namespace {

// Light views are perspective or oriented frames, where flood and vote cannot run.
Fill parseLightFill(const std::string& name) {
    const Fill f = parseFill(name);
    if (f == Fill::Flood || f == Fill::Vote)
        fail("fill '", name, "' needs an axis-aligned grid; light views take auto, parity, winding or gwn");
    return f;
}

} // namespace

TranslucencyShadowMap TranslucencyShadowMap::build(const LightView& view, const MeshView& casters, Fill fill,
                                                   Slicing slicing, Progress* progress) {
    TranslucencyShadowMap map;
    map.view_ = view;
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Solid;
    vo.fill = fill;
    vo.slicing = slicing;
    vo.progress = progress;
    map.grid_ = voxelize(casters, view.frame, vo);
    return map;
}

double TranslucencyShadowMap::columnPath(int64_t column, double depth, int64_t skipCells) const {
    const Frame& f = grid_.frame;
    const int64_t end = detail::slicesInFront(f, column, depth, skipCells);
    const int64_t n = countColumnRange(grid_.bits.column(column), f.depth(), 0, end);
    if (n == 0) return 0.0;
    // World length of one depth unit along the column's centre ray (a perspective frame's depth is
    // the distance along its axis, so the ray is longer by 1 / cos of its angle to the axis), over
    // the column's slices per depth unit.
    const int64_t W = f.width();
    const double gx = double(column % W) + 0.5, gy = double(column / W) + 0.5;
    const double d0 = std::max(depth, f.isPerspective() ? f.nearDepth() : 0.0);
    const double perDepth = length(f.worldFromGrid({gx, gy, d0 + 1}) - f.worldFromGrid({gx, gy, d0}));
    return double(n) * perDepth / f.depthToSlice(column).scale;
}

double TranslucencyShadowMap::pathLength(const Vec3d& world, int64_t skipCells) const {
    if (grid_.bits.empty() || !view_.covers(world)) return 0.0;
    const detail::ColumnAt c = detail::nearestColumn(view_, world);
    return columnPath(c.column, c.depth, skipCells);
}

namespace {

Vec3f beerLambert(const Vec3d& sigma, double length) {
    if (length == 0) return {1, 1, 1};
    return {float(std::exp(-sigma.x * length)), float(std::exp(-sigma.y * length)),
            float(std::exp(-sigma.z * length))};
}

} // namespace

Vec3f TranslucencyShadowMap::transmittance(const Vec3d& world, int64_t skipCells, const Vec3d& sigma) const {
    return beerLambert(sigma, pathLength(world, skipCells));
}

Vec3f TranslucencyShadowMap::transmittanceBilinear(const Vec3d& world, int64_t skipCells, const Vec3d& sigma,
                                                   const Vec3d& normal, double sharpness) const {
    if (grid_.bits.empty() || !view_.covers(world)) return {1, 1, 1};
    return detail::bilinearColumns<Vec3f, float>(
        view_, world, normal,
        [&](const detail::ColumnAt& c) {
            return beerLambert(sigma, columnPath(c.column, c.depth, skipCells));
        },
        sharpness);
}

ViewMatter ViewMatter::build(const Frame& camera, const MeshView& solids, Fill fill, int64_t slices) {
    if (!camera.isPerspective()) fail("view translucency: the camera frame must be perspective");
    if (slices < 1) fail("view translucency: slices must be >= 1, got ", slices);
    ViewMatter out;
    if (solids.triangleCount == 0) return out;
    // The solids' view-depth range, in front of the camera.
    const Box3d b = computeBounds(solids);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < 8; ++k) {
        const Vec3d q{(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z};
        const double d = dot(q - camera.eye(), camera.forward());
        lo = std::min(lo, d);
        hi = std::max(hi, d);
    }
    lo = std::max(lo, camera.nearDepth());
    if (!(hi > lo)) return out;
    const Frame f = Frame::perspective(camera.eye(), camera.eye() + camera.forward(), camera.up(),
                                       2 * std::atan(camera.tanHalfFovY()), camera.width(), camera.height(),
                                       lo, hi, slices);
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Solid;
    vo.fill = fill;
    out.grid_ = voxelize(solids, f, vo);
    out.ds_ = f.depthToSlice(0);
    out.slices_ = slices;
    out.lo_ = lo;
    return out;
}

double ViewMatter::between(int64_t x, int64_t y, double from, double until) const {
    const Frame& f = grid_.frame;
    if (slices_ == 0 || !std::isfinite(from) || x < 0 || y < 0 || x >= f.width() || y >= f.height()) return 0;
    const int64_t S = slices_;
    const double t = ds_(from);
    const int64_t s0 = t <= 0 ? 0 : t >= double(S) ? S : int64_t(t);
    int64_t s1 = S;
    if (std::isfinite(until)) {
        // Cells whose centre (k + 0.5) lies in front of the end depth.
        const double e = std::ceil(ds_(until) - 0.5);
        s1 = e <= double(s0) ? s0 : e >= double(S) ? S : int64_t(e);
    }
    const int64_t n = countColumnRange(grid_.bits.column(y * f.width() + x), S, s0, s1);
    if (n == 0) return 0;
    // A slice's world length along the column's centre ray (depth is along the axis).
    const double gx = double(x) + 0.5, gy = double(y) + 0.5;
    const double perDepth = length(f.worldFromGrid({gx, gy, lo_ + 1}) - f.worldFromGrid({gx, gy, lo_}));
    return double(n) * perDepth / ds_.scale;
}

std::vector<double> viewMatterBehind(const Frame& camera, const MeshView& solids,
                                     std::span<const float> depth, Fill fill, int64_t slices,
                                     std::span<const float> until) {
    const int64_t W = camera.width(), H = camera.height();
    if (!camera.isPerspective()) fail("view translucency: the camera frame must be perspective");
    if (slices < 1) fail("view translucency: slices must be >= 1, got ", slices);
    if (depth.size() != size_t(W * H))
        fail("view translucency: ", depth.size(), " depths for ", W * H, " pixels");
    if (!until.empty() && until.size() != depth.size())
        fail("view translucency: ", until.size(), " end depths for ", W * H, " pixels");
    std::vector<double> out(size_t(W * H), 0.0);
    const ViewMatter matter = ViewMatter::build(camera, solids, fill, slices);
    const double none = std::numeric_limits<double>::infinity();
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto i = size_t(y * W + x);
                out[i] = matter.between(x, y, double(depth[i]), until.empty() ? none : double(until[i]));
            }
    });
    return out;
}

std::span<const OptionField<TranslucencyShadowOptions>> TranslucencyShadowOptions::fields() {
    using O = TranslucencyShadowOptions;
    static const std::vector<OptionField<O>> table = [] {
        std::vector<OptionField<O>> t;
        detail::appendLightGridFields(t);
        t.push_back(numberOption<O, &O::grid, &LightGridOptions::normalOffset>(
            "normalOffset", "lookup offset along the surface normal, in column footprints", 0, 1000));
        t.push_back(numberOption<O, &O::extinction>(
            "extinction",
            "extinction per world unit of see-through casters without attenuation of their own (opaque "
            "ones stay opaque)",
            0, 1e9));
        t.push_back(tripleOption<O, &O::tint>(
            "tint", "relative mean free path per channel (1,1,1 grey; 0.35,1,0.55 jade)", 1e-6, 1));
        t.push_back(nameOption<O, parseLightFill, optionName<Fill>, &O::fill>(
            "fill", "how the casters' inside is decided (auto: parity if closed, else gwn)",
            "auto | parity | winding | gwn"));
        return t;
    }();
    return table;
}

TranslucencyShadowStats& TranslucencyShadowStats::operator+=(const TranslucencyShadowStats& o) {
    grids += o.grids;
    filledCells += o.filledCells;
    return *this;
}

std::string TranslucencyShadowStats::summary() const {
    return countText(grids) + (grids == 1 ? " solid light grid, " : " solid light grids, ") +
           countText(filledCells) + " filled cells";
}

Vec3d translucencyExtinction(const Material& m, const TranslucencyShadowOptions& options) {
    const double inf = std::numeric_limits<double>::infinity();
    if (m.isOpaque() && !m.isTranslucent()) return {inf, inf, inf};
    const Vec3f own = attenuationCoefficient(m);
    if (own.x > 0 || own.y > 0 || own.z > 0) return Vec3d(own);
    const Vec3f& t = options.tint;
    return {options.extinction / t.x, options.extinction / t.y, options.extinction / t.z};
}

TranslucencyShadow TranslucencyShadow::build(const Scene& scene, const Light& light,
                                             const TranslucencyShadowOptions& options, Progress* progress) {
    detail::checkLightGrid(options.grid, "translucency");
    const Vec3f& t = options.tint;
    if (!(options.extinction >= 0) || !std::isfinite(options.extinction))
        fail("translucency shadows: extinction must be finite and >= 0, got ", options.extinction);
    for (int c = 0; c < 3; ++c)
        if (!(t[c] > 0 && t[c] <= 1))
            fail("translucency shadows: tint components must lie in (0, 1], got ", t.x, ", ", t.y, ", ", t.z);
    TranslucencyShadow out;
    out.options_ = options;
    const detail::CasterSets casters = detail::collectCasters(scene);
    if (casters.all.indices.empty()) return out;
    // The casters by their matter's extinction (opaque: infinite), one solid grid per group and view.
    std::map<std::array<double, 3>, std::size_t> groupOf;
    std::vector<Mesh> groups;
    const Mesh& all = casters.all;
    for (std::size_t tr = 0; tr < casters.allMaterialIndex.size(); ++tr) {
        const Vec3d sigma = translucencyExtinction(scene.materials[casters.allMaterialIndex[tr]], options);
        const auto [it, added] =
            groupOf.emplace(std::array<double, 3>{sigma.x, sigma.y, sigma.z}, groups.size());
        if (added) {
            groups.emplace_back().positions = all.positions;
            out.sigmas_.push_back(sigma);
        }
        for (int k = 0; k < 3; ++k) groups[it->second].indices.push_back(all.indices[3 * tr + size_t(k)]);
    }
    out.views_ =
        makeLightViews(light, computeBounds(all.view()), options.grid.resolution, options.grid.depth);
    for (const Mesh& g : groups)
        for (const LightView& v : out.views_)
            out.maps_.push_back(
                TranslucencyShadowMap::build(v, g.view(), options.fill, options.grid.slicing, progress));
    return out;
}

Vec3f TranslucencyShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    Vec3d q;
    const int i = detail::lookupView(views_, p, n, options_.grid.normalOffset, q);
    if (i < 0) return {1, 1, 1};
    const int64_t skip = options_.grid.skipCells;
    Vec3f v{1, 1, 1};
    for (std::size_t g = 0; g < sigmas_.size(); ++g) {
        const TranslucencyShadowMap& m = maps_[g * views_.size() + size_t(i)];
        v = v * (options_.grid.bilinear
                     ? m.transmittanceBilinear(q, skip, sigmas_[g], n, options_.grid.sharpness)
                     : m.transmittance(q, skip, sigmas_[g]));
    }
    return v;
}

double TranslucencyShadow::pathLength(const Vec3d& p, const Vec3d& n) const {
    Vec3d q;
    const int i = detail::lookupView(views_, p, n, options_.grid.normalOffset, q);
    double total = 0;
    for (std::size_t g = 0; i >= 0 && g < sigmas_.size(); ++g)
        total += maps_[g * views_.size() + size_t(i)].pathLength(q, options_.grid.skipCells);
    return total;
}

TranslucencyShadow::Stats TranslucencyShadow::stats() const {
    Stats s;
    for (const TranslucencyShadowMap& m : maps_) {
        ++s.grids;
        s.filledCells += m.grid().bits.count();
    }
    return s;
}

} // namespace voxfx
