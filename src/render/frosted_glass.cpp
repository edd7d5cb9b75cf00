// voxfx — ED06 §3.3 frosted glass: front- and back-face slicemaps from the eye with local slicing, the
// per-column inside intervals, and the interpolated thickness driving a refraction offset,
// attenuation and blur (voxfx/frosted_glass.hpp).
#include "voxfx/frosted_glass.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

std::span<const OptionField<FrostedGlassOptions>> FrostedGlassOptions::fields() {
    using O = FrostedGlassOptions;
    static const std::vector<OptionField<O>> table = {
        numberOption<O, &O::gridResolution>(
            "glassGrid", "frosted glass: slicemap columns across and slices, 2..4096 (0: the default 128)", 0,
            4096),
        numberOption<O, &O::blur>(
            "frostedBlur", "frosted glass: blur cone (radians) through a thickness of the glass's diagonal",
            0, 3.2),
        numberOption<O, &O::refraction>("frostedRefraction",
                                        "frosted glass: refraction offset through a thickness of the glass's "
                                        "diagonal, as a multiple of the front surface's",
                                        0, 100),
        numberOption<O, &O::absorptionConstant>(
            "absorptionConstant",
            "glass (CHANG's absorption constant): every glass material's attenuation per world unit "
            "(KHR_materials_volume) times this (0: no absorption inside glass)",
            0, 1e6),
        flagOption<O, &O::sceneBehind>(
            "sceneBehind", "glass: the light leaving it comes from the opaque scene (off: the environment)")};
    return table;
}

FrostedGlass FrostedGlass::build(const GlassInput& input, const FrostedGlassOptions& options) {
    return FrostedGlass(input.mesh, input.triangleMedium, input.media, input.camera, options);
}

namespace detail {

void frostedColumnIntervals(const uint64_t* f, const uint64_t* b, int64_t wordsPerColumn, int64_t D,
                            std::vector<double>& out) {
    // Non-empty cells in depth order, with their kind: 1 front only, 2 back only, 3 both.
    thread_local std::vector<std::pair<int64_t, int>> cells;
    cells.clear();
    for (int64_t w = 0; w < wordsPerColumn; ++w) {
        uint64_t any = f[w] | b[w];
        while (any) {
            const int bit = std::countr_zero(any);
            any &= any - 1;
            const int64_t s = w * 64 + bit;
            if (s >= D) break;
            cells.emplace_back(s, int((f[w] >> bit) & 1) | int(((b[w] >> bit) & 1) << 1));
        }
    }
    if (cells.empty()) return;
    const int64_t first = cells.front().first, last = cells.back().first;
    // Local slicing puts the column's nearest fragment on slice 0 and its farthest on slice D.
    auto entry = [&](int64_t s) { return s == first && s == 0 ? 0.0 : double(s) + 0.5; };
    auto exit = [&](int64_t s) { return s == last && s == D - 1 ? double(D) : double(s) + 0.5; };
    bool inside = false;
    double start = 0;
    for (size_t i = 0; i < cells.size(); ++i) {
        const auto [s, kind] = cells[i];
        if (kind == 1) {
            if (!inside) start = entry(s);
            inside = true;
        } else if (kind == 2) {
            if (inside) {
                out.push_back(start);
                out.push_back(exit(s));
            }
            inside = false;
        } else {
            // Ambiguous: the next non-empty cell says where the ray is after it.
            const bool after = i + 1 < cells.size() && cells[i + 1].second != 1;
            if (!inside && after) {
                start = entry(s);
            } else if (inside && !after) {
                out.push_back(start);
                out.push_back(exit(s));
            } else if (!inside && !after) { // a sliver entered and left within the cell
                out.push_back(double(s) + 1.0 / 3);
                out.push_back(double(s) + 2.0 / 3);
            }
            inside = after;
        }
    }
    if (inside) { // a back face the slicemap missed: the ray leaves at the column's end
        out.push_back(start);
        out.push_back(double(D));
    }
}

} // namespace detail

FrostedGlass::FrostedGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium,
                           std::vector<GlassMedium> media, const Frame& camera,
                           const FrostedGlassOptions& options)
    : media_(std::move(media)), blur_(options.blur), refraction_(options.refraction) {
    validateMesh(mesh, "glass mesh");
    if (!camera.isPerspective()) fail("frosted glass needs the camera's perspective frame");
    if (triangleMedium.size() != mesh.triangleCount) fail("frosted glass: one medium per triangle expected");
    for (const uint32_t m : triangleMedium)
        if (m >= media_.size()) fail("frosted glass: medium index ", m, " out of range");
    if ((options.gridResolution < 2 && options.gridResolution != kGlassGridAuto) ||
        options.gridResolution > 4096)
        fail("glass grid resolution must be between 2 and 4096 (or 0), got ", options.gridResolution);
    if (!(options.refraction >= 0) || !std::isfinite(options.refraction))
        fail("frosted glass: refraction scale must be finite and >= 0, got ", options.refraction);
    const Vec3d eye = camera.eye();
    // Split by facing as seen from the eye; the depth range of the glass bounds the slices.
    Mesh front, back;
    front.positions.resize(mesh.vertexCount);
    for (size_t i = 0; i < mesh.vertexCount; ++i) front.positions[i] = Vec3f(mesh.vertex(i));
    back.positions = front.positions;
    double nearD = std::numeric_limits<double>::infinity(), farD = 0;
    for (size_t t = 0; t < mesh.triangleCount; ++t) {
        const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                    c = mesh.vertex(mesh.index(t, 2));
        const bool facing = dot(cross(b - a, c - a), eye - a) > 0;
        for (int k = 0; k < 3; ++k) (facing ? front : back).indices.push_back(mesh.index(t, k));
        for (const Vec3d& p : {a, b, c}) {
            const double d = dot(p - eye, camera.forward());
            nearD = std::min(nearD, d);
            farD = std::max(farD, d);
        }
    }
    const Box3d box = computeBounds(mesh);
    diagonal_ = std::max(1e-12, length(box.extent()));
    farD += 1e-3 * diagonal_;
    nearD = std::max(nearD - 1e-3 * diagonal_, 1e-4 * farD);
    if (!(farD > nearD)) fail("frosted glass: the glass is behind the camera");
    // 0 (what a scene file saved with a voxel method's auto grid holds): the default.
    const int64_t W =
        options.gridResolution == kGlassGridAuto ? kGlassGridResolution : options.gridResolution;
    const int64_t H = std::max<int64_t>(
        1, int64_t(std::lround(double(W) * double(camera.height()) / double(camera.width()))));
    frame_ = Frame::perspective(eye, eye + camera.forward(), camera.up(), 2 * std::atan(camera.tanHalfFovY()),
                                W, H, nearD, farD, W);
    // ED06 local slicing, one depth range per column for both slicemaps: the nearest and farthest
    // fragment of the whole glass (front and back faces) in that column.
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Surface;
    {
        VoxelizeOptions lo = vo;
        lo.slicing = Slicing::Local;
        frame_ = voxelize(mesh, frame_, lo).frame;
    }
    front_ = front.indices.empty() ? BitGrid(W, H, frame_.depth()) : voxelize(front.view(), frame_, vo).bits;
    back_ = back.indices.empty() ? BitGrid(W, H, frame_.depth()) : voxelize(back.view(), frame_, vo).bits;
    // Walk every column once into inside intervals (view depths).
    const int64_t D = frame_.depth();
    spanStart_.assign(size_t(frame_.columnCount()) + 1, 0);
    std::vector<double> slices;
    for (int64_t c = 0; c < frame_.columnCount(); ++c) {
        slices.clear();
        detail::frostedColumnIntervals(front_.column(c), back_.column(c), front_.wordsPerColumn(), D, slices);
        const DepthToSlice m = frame_.depthToSlice(c);
        for (const double s : slices) spans_.push_back(m.near + s / m.scale);
        if (spans_.size() / 2 > std::numeric_limits<uint32_t>::max())
            fail("frosted glass: too many inside intervals at this resolution");
        spanStart_[size_t(c) + 1] = uint32_t(spans_.size() / 2);
    }
}

double FrostedGlass::columnThickness(int64_t x, int64_t y, double fromDepth) const {
    if (x < 0 || y < 0 || x >= frame_.width() || y >= frame_.height()) return 0;
    const size_t c = size_t(y * frame_.width() + x);
    double sum = 0;
    for (uint32_t k = spanStart_[c]; k < spanStart_[c + 1]; ++k)
        if (spans_[2 * k + 1] > fromDepth) sum += spans_[2 * k + 1] - spans_[2 * k];
    return sum;
}

double FrostedGlass::thickness(const Vec3d& p, const Vec3d& normal) const {
    const Vec3d g = frame_.gridFromWorld(p);
    const Vec3d ray = normalize(p - frame_.eye());
    const Vec3d fwd = frame_.forward();
    const double fx = g.x - 0.5, fy = g.y - 0.5;
    const int64_t x0 = int64_t(std::floor(fx)), y0 = int64_t(std::floor(fy));
    const double wx = fx - double(x0), wy = fy - double(y0);
    const bool useNormal = length(normal) > 0;
    const Vec3d n = useNormal ? normalize(normal) : Vec3d{};
    double sum = 0, weights = 0;
    for (int k = 0; k < 4; ++k) {
        const int64_t x = x0 + (k & 1), y = y0 + (k >> 1);
        if (x < 0 || y < 0 || x >= frame_.width() || y >= frame_.height()) continue;
        const double w = ((k & 1) ? wx : 1 - wx) * ((k >> 1) ? wy : 1 - wy);
        if (w <= 0) continue;
        // Where the column's centre ray meets p's tangent plane (p's own depth without a normal
        // or at a grazing angle); intervals ending more than half a slice before it are in front.
        double z = g.z;
        if (useNormal) {
            const Vec3d dc =
                normalize(frame_.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - frame_.eye());
            const double dn = dot(dc, n);
            if (std::abs(dn) > 0.25) {
                const double zc = dot(p - frame_.eye(), n) * dot(dc, fwd) / dn;
                if (zc > 0) z = zc;
            }
        }
        const double halfSlice = 0.5 / frame_.depthToSlice(y * frame_.width() + x).scale;
        const double t = columnThickness(x, y, z - halfSlice);
        if (t <= 0) continue; // no glass at this depth in that column (beyond a silhouette)
        sum += w * t;
        weights += w;
    }
    const double depth = weights > 0 ? sum / weights : 0;
    return depth / std::max(1e-6, dot(ray, fwd));
}

GlassPath FrostedGlass::trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium,
                              const Vec3d& dir) const {
    GlassPath p;
    p.hit = true;
    const Vec3d d = normalize(dir);
    Vec3d n0 = normalize(normal);
    if (dot(d, n0) > 0) n0 = -n0;
    const GlassMedium& m = media_[std::min<size_t>(medium, media_.size() - 1)];
    const double F = fresnelDielectric(-dot(d, n0), 1.0, m.ior);
    p.reflectDir = reflectDirection(d, n0);
    p.reflectance = float(F);
    Vec3d t;
    if (!refractDirection(d, n0, 1.0 / m.ior, t)) t = d;
    const double L = thickness(entry, n0);
    // ED06: the refraction perturbs the environment lookup by an offset scaled with the volume
    // crossed: no glass, no bend; two interfaces at the front surface's Fresnel factor.
    p.exitDir = normalize(d + (t - d) * (refraction_ * L / diagonal_));
    p.exitPoint = entry + p.exitDir * L;
    p.throughput = m.tint * beerLambert(m.sigma, L) * float((1 - F) * (1 - F));
    p.blurAngle = blur_ * std::min(1.0, L / diagonal_);
    p.events = 2;
    return p;
}

} // namespace voxfx
