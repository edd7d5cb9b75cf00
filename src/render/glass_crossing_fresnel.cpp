// voxfx — the Fresnel loss of every glass crossing along the columns of a light view
// (render/glass_crossing_fresnel.hpp).
#include "render/glass_crossing_fresnel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include "render/light_grid_lookup.hpp"
#include "voxfx/gbuffer.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

ShadowGlass collectShadowGlass(const Scene& scene) {
    Scene glass;
    glass.materials = scene.materials;
    for (const SceneMesh& m : scene.meshes) {
        const Material& mat = scene.materials[m.material];
        if (m.castsShadow && mat.isGlass() && !mat.isOpaque()) glass.meshes.push_back(m);
    }
    ShadowGlass out;
    if (glass.meshes.empty()) return out;
    SceneGeometry g = flattenScene(glass);
    out.mesh = std::move(g.mesh);
    out.normals = std::move(g.normals);
    out.ior.reserve(g.triangleMaterial.size());
    for (const uint32_t m : g.triangleMaterial) out.ior.push_back(std::max(1.0f, scene.materials[m].ior));
    return out;
}

namespace {

// Grid coordinates in fixed point (1/256 of a column): exact edge functions. Triangles reaching
// beyond +-2^29 (a perspective view's vertex near the eye's plane) are left out; their products
// stay below 2^61.
constexpr int kFixedShift = 8;
constexpr double kFixedScale = 1 << kFixedShift;
constexpr int64_t kFixedLimit = int64_t(1) << 29;

struct Crossing {
    uint32_t column, slice;
    float depth; // e
    bool operator<(const Crossing& o) const {
        return std::tie(column, slice, depth) < std::tie(o.column, o.slice, o.depth);
    }
};

// Edge a -> b at sample (px, py): > 0 on the left of a counter-clockwise triangle.
int64_t edgeAt(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t px, int64_t py) {
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// Top-left rule: a sample on an edge belongs to the one triangle of the two sharing it that has
// the edge pointing up (or, horizontal, pointing left); the other traverses it the opposite way.
bool ownsEdge(int64_t ax, int64_t ay, int64_t bx, int64_t by) { return by > ay || (by == ay && bx < ax); }

// The optical depth of a crossing at cosine c: -ln(1 - F(c)), beyond normal incidence's (+ ln(1 -
// F0)) where asked, capped.
float crossingDepth(double c, double ior, bool beyondNormalIncidence) {
    const double f0 = ((ior - 1) / (ior + 1)) * ((ior - 1) / (ior + 1));
    const double pass = 1 - fresnelDielectric(std::clamp(c, 0.0, 1.0), 1.0, ior);
    const double e = -std::log(std::max(pass, 1e-30)) + (beyondNormalIncidence ? std::log(1 - f0) : 0.0);
    return float(std::clamp(e, 0.0, 60.0));
}

// The crossings of triangle t with the centre lines of the view's columns.
void rasterizeCrossings(const ShadowGlass& glass, std::size_t t, const Frame& f, bool beyond,
                        std::vector<Crossing>& out) {
    std::array<Vec3d, 3> p, g, n;
    std::array<int64_t, 3> X, Y;
    for (int k = 0; k < 3; ++k) {
        const uint32_t v = glass.mesh.indices[3 * t + size_t(k)];
        p[size_t(k)] = Vec3d(glass.mesh.positions[v]);
        n[size_t(k)] = Vec3d(glass.normals[v]);
        if (f.isPerspective() && !(f.viewDepth(p[size_t(k)]) > 0)) return;
        g[size_t(k)] = f.gridFromWorld(p[size_t(k)]);
        const double x = std::round(g[size_t(k)].x * kFixedScale),
                     y = std::round(g[size_t(k)].y * kFixedScale);
        if (!(std::abs(x) < double(kFixedLimit) && std::abs(y) < double(kFixedLimit))) return;
        X[size_t(k)] = int64_t(x);
        Y[size_t(k)] = int64_t(y);
    }
    int64_t area = edgeAt(X[0], Y[0], X[1], Y[1], X[2], Y[2]);
    if (area == 0) return; // seen edge-on: no column centre crosses it
    std::array<int, 3> order{0, 1, 2};
    if (area < 0) {
        std::swap(order[1], order[2]);
        area = -area;
    }
    const auto [xlo, xhi] = std::minmax({X[0], X[1], X[2]});
    const auto [ylo, yhi] = std::minmax({Y[0], Y[1], Y[2]});
    // Columns whose centre (x + 1/2) lies in [lo, hi].
    const int64_t s = int64_t(1) << kFixedShift, h = s / 2;
    const int64_t cx0 = std::max<int64_t>(0, (xlo - h + s - 1) >> kFixedShift);
    const int64_t cx1 = std::min(f.width() - 1, (xhi - h) >> kFixedShift);
    const int64_t cy0 = std::max<int64_t>(0, (ylo - h + s - 1) >> kFixedShift);
    const int64_t cy1 = std::min(f.height() - 1, (yhi - h) >> kFixedShift);
    const Vec3d face = normalize(cross(p[1] - p[0], p[2] - p[0]));
    for (int64_t cy = cy0; cy <= cy1; ++cy)
        for (int64_t cx = cx0; cx <= cx1; ++cx) {
            const int64_t px = cx * s + h, py = cy * s + h;
            std::array<int64_t, 3> e{}; // e[k]: the edge opposite corner order[k]
            bool inside = true;
            for (int k = 0; k < 3 && inside; ++k) {
                const auto a = size_t(order[size_t((k + 1) % 3)]), b = size_t(order[size_t((k + 2) % 3)]);
                e[size_t(k)] = edgeAt(X[a], Y[a], X[b], Y[b], px, py);
                inside = e[size_t(k)] > 0 || (e[size_t(k)] == 0 && ownsEdge(X[a], Y[a], X[b], Y[b]));
            }
            if (!inside) continue;
            // Barycentrics in the grid; in a perspective view, corrected by the corners' depths.
            std::array<double, 3> w{};
            double sum = 0;
            for (int k = 0; k < 3; ++k) {
                const auto c = size_t(order[size_t(k)]);
                w[c] = double(e[size_t(k)]) / double(area) / (f.isPerspective() ? g[c].z : 1.0);
                sum += w[c];
            }
            Vec3d hit{0, 0, 0}, normal{0, 0, 0};
            for (size_t c = 0; c < 3; ++c) {
                hit += p[c] * (w[c] / sum);
                normal += n[c] * (w[c] / sum);
            }
            const double depth = f.gridFromWorld(hit).z;
            const Vec3d ray = f.worldFromGrid({double(cx) + 0.5, double(cy) + 0.5, depth + 1}) -
                              f.worldFromGrid({double(cx) + 0.5, double(cy) + 0.5, depth});
            const double nl = length(normal) * length(ray);
            const double cosine =
                nl > 1e-12 ? std::abs(dot(normal, ray)) / nl : std::abs(dot(face, normalize(ray)));
            const int64_t column = cy * f.width() + cx;
            const double slice = f.depthToSlice(column)(depth);
            if (!(slice >= 0)) continue;
            out.push_back({uint32_t(column), uint32_t(std::min(slice, double(f.depth()))),
                           crossingDepth(cosine, double(glass.ior[t]), beyond)});
        }
}

} // namespace

GlassCrossingFresnel GlassCrossingFresnel::build(const ShadowGlass& glass, const LightView& view,
                                                 bool beyondNormalIncidence) {
    GlassCrossingFresnel out;
    const Frame& f = view.frame;
    out.width_ = f.width();
    const auto T = int64_t(glass.mesh.triangleCount());
    std::vector<Crossing> all = parallelReduce(
        0, T, 1024, std::vector<Crossing>{},
        [&](int64_t t0, int64_t t1) {
            std::vector<Crossing> part;
            for (int64_t t = t0; t < t1; ++t)
                rasterizeCrossings(glass, size_t(t), f, beyondNormalIncidence, part);
            return part;
        },
        [](std::vector<Crossing> a, const std::vector<Crossing>& b) {
            a.insert(a.end(), b.begin(), b.end());
            return a;
        });
    std::erase_if(all, [](const Crossing& c) { return !(c.depth > 0); });
    if (all.empty()) return out;
    std::sort(all.begin(), all.end());
    out.x0_ = out.width_;
    out.y0_ = f.height();
    for (const Crossing& c : all) {
        const int64_t x = int64_t(c.column) % out.width_, y = int64_t(c.column) / out.width_;
        out.x0_ = std::min(out.x0_, x);
        out.x1_ = std::max(out.x1_, x + 1);
        out.y0_ = std::min(out.y0_, y);
        out.y1_ = std::max(out.y1_, y + 1);
    }
    const int64_t w = out.x1_ - out.x0_;
    out.offsets_.assign(size_t(w * (out.y1_ - out.y0_) + 1), 0);
    out.slices_.reserve(all.size());
    out.passes_.reserve(all.size());
    double sum = 0;
    for (std::size_t i = 0; i < all.size(); ++i) {
        const Crossing& c = all[i];
        if (i == 0 || c.column != all[i - 1].column) sum = 0;
        sum += double(c.depth);
        const int64_t x = int64_t(c.column) % out.width_, y = int64_t(c.column) / out.width_;
        ++out.offsets_[size_t((y - out.y0_) * w + (x - out.x0_)) + 1];
        out.slices_.push_back(c.slice);
        out.passes_.push_back(float(std::exp(-sum)));
    }
    for (std::size_t i = 1; i < out.offsets_.size(); ++i) out.offsets_[i] += out.offsets_[i - 1];
    return out;
}

double GlassCrossingFresnel::pass(int64_t column, int64_t end) const {
    if (passes_.empty()) return 1;
    const int64_t x = column % width_, y = column / width_;
    if (x < x0_ || x >= x1_ || y < y0_ || y >= y1_) return 1;
    const auto i = size_t((y - y0_) * (x1_ - x0_) + (x - x0_));
    double out = 1;
    for (uint32_t k = offsets_[i]; k < offsets_[i + 1] && int64_t(slices_[k]) < end; ++k) out = passes_[k];
    return out;
}

GlassFresnelViews buildGlassFresnelViews(const Scene& scene, const std::vector<LightView>& views,
                                         bool beyondNormalIncidence) {
    GlassFresnelViews out;
    const ShadowGlass glass = collectShadowGlass(scene);
    if (glass.empty()) return out;
    for (const LightView& v : views)
        out.push_back(std::make_shared<const GlassCrossingFresnel>(
            GlassCrossingFresnel::build(glass, v, beyondNormalIncidence)));
    return out;
}

double glassFresnelPassThrough(const GlassFresnelViews& fresnel, const std::vector<LightView>& views, int i,
                               const Vec3d& q, const Vec3d& n, const LightGridOptions& grid) {
    if (i < 0 || size_t(i) >= fresnel.size() || fresnel[size_t(i)]->empty()) return 1;
    const LightView& view = views[size_t(i)];
    if (!view.covers(q)) return 1;
    const GlassCrossingFresnel& f = *fresnel[size_t(i)];
    auto pass = [&](const ColumnAt& c) {
        return f.pass(c.column, slicesInFront(view.frame, c.column, c.depth, grid.skipCells));
    };
    return grid.bilinear ? bilinearColumns<double, double>(view, q, n, pass, grid.sharpness)
                         : pass(nearestColumn(view, q));
}

} // namespace voxfx::detail
