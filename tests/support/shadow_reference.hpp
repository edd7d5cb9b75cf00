// voxfx tests — the shadow techniques' exact reference: leaf scenes built here (independent of the
// demo generator), an exact light-transport oracle (a brute-force counter of the surface crossings
// between the light and a point: Moller–Trumbore on every caster triangle, sharing no code with the
// voxel path, with the same per-crossing attenuation), the error statistics against it, and the
// techniques' options set by name through the closed set's dispatch (voxfx/shadow.hpp), as the
// renderer reaches them. Shared by test_transmittance_shadow.cpp, test_light_grid.cpp,
// test_shadow_map.cpp and test_shadow_cross_technique.cpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "test_util.hpp"
#include "voxfx/render.hpp"
#include "voxfx/shadow.hpp"

namespace voxfx::test {

// ---- Scene building ----------------------------------------------------------------------------

inline Material leafMaterial(Vec3f colour, float opacity = 0.7f, float transmission = 0.6f) {
    Material m;
    m.name = "leaf";
    m.baseColor = colour;
    m.opacity = opacity;
    m.transmission = transmission;
    return m;
}

/// One leaf quad (centre c, half axes u and v) of the given material, nothing else.
inline Scene oneLeafScene(const Vec3d& c, const Vec3d& u, const Vec3d& v, const Material& material) {
    Scene s;
    SceneMesh leaf;
    leaf.name = "leaf";
    appendQuad(leaf.mesh, c, u, v);
    leaf.material = s.addMaterial(material);
    s.meshes.push_back(leaf);
    return s;
}

/// The bilinear blend by its definition of value(column) over the four columns of a W x H light
/// grid whose centres surround grid point g (beyond the border, the border column).
template <class Value> Vec3f bilinearByDefinition(int64_t W, int64_t H, const Vec3d& g, const Value& value) {
    Vec3f blend{0, 0, 0};
    const int64_t x0 = int64_t(std::floor(g.x - 0.5)), y0 = int64_t(std::floor(g.y - 0.5));
    const double wx = g.x - 0.5 - double(x0), wy = g.y - 0.5 - double(y0);
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int64_t c =
                std::clamp<int64_t>(y0 + dy, 0, H - 1) * W + std::clamp<int64_t>(x0 + dx, 0, W - 1);
            blend += value(c) * float((dx ? wx : 1 - wx) * (dy ? wy : 1 - wy));
        }
    return blend;
}

/// The lookup tests' sample points: 4000 random points in [-2.5, 2.5] x [0, 3.5] x [-2.5, 2.5]
/// (a fixed seed), those `view` covers, each with its grid position, its own column (y * W + x, the
/// column the point falls in) and a skip of 0, 1 or 2 by turn: visit(i, p, g, column, skip).
template <class Visit> void forEachCoveredPoint(const LightView& view, const Visit& visit) {
    const int64_t W = view.frame.width(), H = view.frame.height();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-2.5, 2.5), h(0, 3.5);
    for (int i = 0; i < 4000; ++i) {
        const Vec3d p{u(rng), h(rng), u(rng)};
        const int64_t skip = i % 3;
        if (!view.covers(p)) continue;
        const Vec3d g = view.gridFromWorld(p);
        const int64_t x = std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, W - 1),
                      y = std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, H - 1);
        visit(i, p, g, y * W + x, skip);
    }
}

/// Random leaf quads (size ~0.25) in the slab [-2, 2] x [1.5, 3] x [-2, 2], `groups` colours, over a
/// ground plane that only receives.
inline Scene leafScene(int leaves, int groups, uint64_t seed, float opacity = 0.7f) {
    static const Vec3f colours[3] = {{0.1f, 0.35f, 0.05f}, {0.6f, 0.15f, 0.03f}, {0.35f, 0.4f, 0.05f}};
    Scene s;
    SceneMesh ground;
    ground.name = "Ground";
    appendQuad(ground.mesh, {0, 0, 0}, {0, 0, 6}, {6, 0, 0});
    ground.material = s.addMaterial(Material{});
    ground.castsShadow = false;
    s.meshes.push_back(ground);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> ux(-2, 2), uy(1.5, 3), ud(-1, 1);
    for (int g = 0; g < groups; ++g) {
        SceneMesh m;
        m.name = "leaves" + std::to_string(g);
        // Opacity 1 means opaque leaves: no transmission through the tissue either.
        m.material = s.addMaterial(leafMaterial(colours[g % 3], opacity, opacity < 1 ? 0.6f : 0.0f));
        s.meshes.push_back(m);
    }
    for (int i = 0; i < leaves; ++i) {
        const Vec3d c{ux(rng), uy(rng), ux(rng)};
        const Vec3d n = normalize(Vec3d{ud(rng), 1.5, ud(rng)});
        const Vec3d t = normalize(cross(n, Vec3d{ud(rng), ud(rng), ud(rng)} + Vec3d{0.01, 0, 0}));
        appendQuad(s.meshes[1 + size_t(i % groups)].mesh, c, t * 0.14, cross(n, t) * 0.1);
    }
    return s;
}

/// A directional light shining along `dir` (normalized), named "sun".
/// Where the plane through p (grid position g of the oriented frame f) with normal n crosses the
/// centre line of column c: solved in world space (the line L(d) = worldFromGrid(x, y, d) is affine
/// in d), kept within two column footprints of p's depth. A crossing within 1e-9 slices of a slice
/// boundary sets `boundary` (the rounding of either side may put it on the other); one more than
/// half a slice off p's depth counts into `tilted`.
inline double receiverPlaneDepth(const Frame& f, const Vec3d& p, const Vec3d& g, const Vec3d& n, int64_t c,
                                 bool& boundary, int& tilted) {
    const double x = double(c % f.width()) + 0.5, y = double(c / f.width()) + 0.5;
    const Vec3d L0 = f.worldFromGrid({x, y, g.z}), L1 = f.worldFromGrid({x, y, g.z + 1});
    const double reach = 2 * length(f.worldFromGrid(g + Vec3d{1, 0, 0}) - p) / length(L1 - L0);
    const double d = g.z + std::clamp(-dot(n, L0 - p) / dot(n, L1 - L0), -reach, reach);
    const double t = f.depthToSlice(c)(d);
    boundary = boundary || std::abs(t - std::round(t)) < 1e-9;
    tilted += std::abs(d - g.z) > 0.5;
    return d;
}

/// A random unit normal for lookup i; odd ones nearly along the rays of f (their crossings clamp).
inline Vec3d randomReceiverNormal(std::mt19937_64& rng, const Frame& f, int i) {
    std::uniform_real_distribution<double> unit(-1, 1);
    Vec3d n = normalize(Vec3d{unit(rng), unit(rng), unit(rng)});
    if (i % 2) n = normalize(n - f.forward() * (dot(n, f.forward()) * 0.999));
    return n;
}

inline Light sun(Vec3d dir = {0.3, -1, 0.2}) {
    Light l;
    l.name = "sun";
    l.type = LightType::Directional;
    l.direction = normalize(dir);
    return l;
}

// ---- The techniques, by name --------------------------------------------------------------------

/// Sets `name` in the technique's options where it has that option (setRenderOption's lookup).
inline void setShadowOption(ShadowOptions& o, std::string_view name, const OptionValue& value) {
    RenderOptions r;
    r.shadow = o;
    setRenderOption(r, name, value);
    o = r.shadow;
}

inline Vec3f visibilityOf(const LightShadow& s, const Vec3d& p, const Vec3d& n) {
    return shadowVisibility(s, p, n);
}

/// The technique `kind` with `n` columns, slices and map texels (where it has them), the slicing
/// and the voxelization mode.
inline ShadowOptions gridOptions(std::string_view kind, int64_t n, Slicing slicing = Slicing::Uniform,
                                 VoxelizeMode mode = VoxelizeMode::Surface) {
    ShadowOptions o = shadowOptionsNamed(kind);
    for (const char* name : {"gridResolution", "gridDepth", "mapResolution"}) setShadowOption(o, name, n);
    setShadowOption(o, "slicing", std::string(toString(slicing)));
    setShadowOption(o, "voxelMode", std::string(toString(mode)));
    return o;
}

// ---- The exact reference -----------------------------------------------------------------------

/// Ray parameter of the hit of o + t d with triangle abc (Moller–Trumbore), or -1.
inline double rayTriangle(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d e1 = b - a, e2 = c - a, h = cross(d, e2);
    const double det = dot(e1, h);
    if (std::abs(det) < 1e-14) return -1;
    const double inv = 1.0 / det;
    const Vec3d s = o - a;
    const double u = dot(s, h) * inv;
    if (u < 0 || u > 1) return -1;
    const Vec3d q = cross(s, e1);
    const double v = dot(d, q) * inv;
    if (v < 0 || u + v > 1) return -1;
    return dot(e2, q) * inv;
}

/// Calls hit(material) for every caster surface crossed between p and the light (p's own surface,
/// within 1e-6, excluded).
template <class Hit> void forEachCrossing(const Scene& s, const Light& light, const Vec3d& p, Hit&& hit) {
    Vec3d dir;
    double tMax;
    if (light.type == LightType::Directional) {
        dir = -normalize(light.direction);
        tMax = 1e30;
    } else {
        dir = light.position - p;
        tMax = length(dir);
        dir = dir / tMax;
    }
    for (const SceneMesh& m : s.meshes) {
        if (!m.castsShadow) continue;
        for (size_t t = 0; t < m.mesh.triangleCount(); ++t) {
            const Vec3d a(m.mesh.positions[m.mesh.indices[3 * t]]),
                b(m.mesh.positions[m.mesh.indices[3 * t + 1]]),
                c(m.mesh.positions[m.mesh.indices[3 * t + 2]]);
            const double h = rayTriangle(p, dir, a, b, c);
            if (h > 1e-6 && h < tMax) hit(s.materials[m.material]);
        }
    }
}

inline Vec3f exactTransmittance(const Scene& s, const Light& light, const Vec3d& p) {
    Vec3f t{1, 1, 1};
    forEachCrossing(s, light, p, [&](const Material& m) { t = t * m.crossingTransmittance(); });
    return t;
}

inline Vec3f exactAbsorption(const Scene& s, const Light& light, const Vec3d& p, float opaque) {
    Vec3f depth{0, 0, 0};
    forEachCrossing(s, light, p, [&](const Material& m) { depth += absorptionPerCrossing(m, opaque); });
    return {std::exp(-depth.x), std::exp(-depth.y), std::exp(-depth.z)};
}

inline int exactCrossings(const Scene& s, const Light& light, const Vec3d& p) {
    int n = 0;
    forEachCrossing(s, light, p, [&](const Material&) { ++n; });
    return n;
}

/// Ground points (y = 0) in [-3, 3]^2 that at least one leaf shadows (the region where the shadow
/// kinds differ; unshadowed points are exact for every kind).
inline std::vector<Vec3d> shadowedGroundPoints(const Scene& s, const Light& light, int count, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-3, 3);
    std::vector<Vec3d> pts;
    while (int(pts.size()) < count) {
        const Vec3d p{u(rng), 0, u(rng)};
        if (exactCrossings(s, light, p) > 0) pts.push_back(p);
    }
    return pts;
}

// ---- Error against the reference ----------------------------------------------------------------

inline float channelMean(const Vec3f& v) { return (v.x + v.y + v.z) / 3; }

struct ErrorStats {
    double mean = 0, p95 = 0;
};

inline ErrorStats stats(std::vector<double> e) {
    ErrorStats s;
    for (const double x : e) s.mean += x;
    s.mean /= double(e.size());
    std::sort(e.begin(), e.end());
    s.p95 = e[size_t(0.95 * double(e.size() - 1))];
    return s;
}

/// Sample points with their exact transmittance (per-crossing colour factors) and absorption.
struct Reference {
    std::vector<Vec3d> points;
    std::vector<Vec3f> transmittance;
    std::vector<Vec3f> absorption;
};

inline Reference exactReference(const Scene& s, const Light& light, int count, uint64_t seed,
                                float opaque = 8) {
    Reference r;
    r.points = shadowedGroundPoints(s, light, count, seed);
    for (const Vec3d& p : r.points) {
        r.transmittance.push_back(exactTransmittance(s, light, p));
        r.absorption.push_back(exactAbsorption(s, light, p, opaque));
    }
    return r;
}

/// |visibility - exact| averaged over the RGB channels, per point: mean and 95th percentile.
inline ErrorStats shadowError(const Scene& s, const Light& light, const Reference& ref,
                              const ShadowOptions& o) {
    const LightShadow shadow = buildLightShadow(s, light, o);
    std::vector<double> err;
    for (size_t i = 0; i < ref.points.size(); ++i) {
        const Vec3f v = visibilityOf(shadow, ref.points[i], {0, 0, 0});
        const Vec3f e = shadowName(o) == "absorption" ? ref.absorption[i] : ref.transmittance[i];
        err.push_back(channelMean({std::abs(v.x - e.x), std::abs(v.y - e.y), std::abs(v.z - e.z)}));
    }
    return stats(err);
}

} // namespace voxfx::test
