// voxfx — shadow volumes, ED06 §3.2's first test: the receivers the camera sees (G-buffer points
// lit from the light's side), as slicemaps in the light's views; a caster whose footprint holds none
// is culled, the others' volumes clamped to the runs of depth that hold their receivers.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "render/shadow_volume_internal.hpp"

namespace voxfx {

std::vector<uint8_t> shadowVolumeReceivers(const GBuffer& gbuffer, const SceneGeometry& geometry,
                                           std::span<const Material> materials, const Light& light) {
    const int64_t W = gbuffer.frame.width(), H = gbuffer.frame.height();
    std::vector<uint8_t> out(size_t(W * H), 0);
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                SurfacePoint s;
                if (!surfaceAt(gbuffer, geometry, x, y, s)) continue;
                const Vec3d toLight = light.towards(s.position);
                // Outside a spot light's outer cone nothing arrives (shading's falloff is 0).
                if (light.type == LightType::Spot && dot(-normalize(toLight), normalize(light.direction)) <
                                                         std::cos(light.outerConeAngle) - 1e-9)
                    continue;
                out[size_t(y * W + x)] =
                    dot(s.geometricNormal, toLight) > 0 || !materials[s.material].isOpaque();
            }
    });
    return out;
}

} // namespace voxfx

namespace voxfx::detail::shadowvolume {

namespace {

// World depth range (dot(x - origin, axis)) of cell (x, y, s) of a view: min and max over corners.
std::pair<double, double> svCellRange(const Frame& f, int64_t x, int64_t y, int64_t s, const Vec3d& origin,
                                      const Vec3d& axis) {
    const DepthToSlice m = f.depthToSlice(y * f.width() + x);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < 8; ++k) {
        const double depth = m.near + double(s + ((k >> 2) & 1)) / m.scale;
        const Vec3d p = f.worldFromGrid({double(x + (k & 1)), double(y + ((k >> 1) & 1)), depth});
        const double d = dot(p - origin, axis);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
    }
    return {lo, hi};
}

} // namespace

std::vector<LightView> svReceiverViews(const ShadowCasterSet& casters, const Light& light,
                                       const GBuffer& gbuffer, const std::vector<uint8_t>& receivers,
                                       const ShadowVolumeOptions& options, std::vector<Vec3d>& points) {
    const Frame& cam = gbuffer.frame;
    const int64_t W = cam.width(), H = cam.height();
    Box3d bounds;
    for (const ShadowCaster& c : casters.casters)
        for (const Vec3f& p : c.positions) bounds.extend(Vec3d(p));
    for (int64_t y = 0; y < H; ++y)
        for (int64_t x = 0; x < W; ++x) {
            const auto i = size_t(y * W + x);
            if (!receivers[i] || gbuffer.triangle[i] == GBuffer::kNone) continue;
            points.push_back(cam.worldFromGrid({double(x) + 0.5, double(y) + 0.5, double(gbuffer.depth[i])}));
            bounds.extend(points.back());
        }
    return makeLightViews(light, bounds, options.mapResolution, options.receiverSlices);
}

bool svReceiverSlicemaps(const std::vector<LightView>& views, const std::vector<Vec3d>& points,
                         std::vector<BitGrid>& slicemaps) {
    for (const LightView& v : views)
        slicemaps.emplace_back(v.frame.width(), v.frame.height(), v.frame.depth());
    for (const Vec3d& p : points) {
        const int k = viewIndexFor(views, p);
        if (k < 0 || !views[size_t(k)].covers(p)) return false;
        const Frame& f = views[size_t(k)].frame;
        const Vec3d g = f.gridFromWorld(p);
        const int64_t x = std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, f.width() - 1);
        const int64_t y = std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, f.height() - 1);
        const double s = f.depthToSlice(y * f.width() + x)(g.z);
        if (!(s >= 0 && s < double(f.depth()))) return false;
        slicemaps[size_t(k)].set(x, y, int64_t(s));
    }
    return true;
}

namespace {

// Bits of column c set in [from, D), in increasing order, handed to op(slice).
template <class Op> void svForSlices(const BitGrid& g, int64_t c, int64_t from, Op op) {
    const int64_t D = g.depth();
    from = std::max<int64_t>(from, 0);
    if (from >= D) return;
    const uint64_t* w = g.column(c);
    for (int64_t k = from >> 6; k <= (D - 1) >> 6; ++k) {
        uint64_t bits = w[k];
        if (k == (from >> 6)) bits &= ~uint64_t(0) << (from & 63);
        while (bits) {
            op(k * 64 + std::countr_zero(bits));
            bits &= bits - 1;
        }
    }
}

// The receiver cells at or behind the conservative footprint of `back` (one caster's unlit
// triangles) in one view, dilated by one column and one slice, as depth intervals along the
// caster's axis appended to `cells`. With `cover`, a cell another caster covers in front of it and
// of this caster (SvCover::frontOther) is left to that caster and counted in `dropped`.
// `minDepth` is a W x H scratch map of +inf, left so.
void svReceiverCells(const Frame& f, const BitGrid& bits, const Mesh& back, const SvCasterLight& setup,
                     const SvCover* cover, int32_t id, std::vector<float>& minDepth,
                     std::vector<std::pair<double, double>>& cells, int64_t& dropped) {
    const int64_t VW = f.width(), VH = f.height();
    SvRect rect;
    float* mp = minDepth.data();
    svRasterTexels<Coverage::Conservative>(
        f, back, [mp](int64_t texel, double dmin, double) { mp[texel] = std::min(mp[texel], float(dmin)); },
        rect);
    if (rect.empty()) return;
    const int64_t x0 = std::max<int64_t>(0, rect.v[0] - 1), y0 = std::max<int64_t>(0, rect.v[1] - 1);
    const int64_t x1 = std::min<int64_t>(VW - 1, rect.v[2] + 1),
                  y1 = std::min<int64_t>(VH - 1, rect.v[3] + 1);
    for (int64_t y = y0; y <= y1; ++y)
        for (int64_t x = x0; x <= x1; ++x) {
            float m = kSvInf;
            for (int64_t yy = std::max<int64_t>(0, y - 1); yy <= std::min(VH - 1, y + 1); ++yy)
                for (int64_t xx = std::max<int64_t>(0, x - 1); xx <= std::min(VW - 1, x + 1); ++xx)
                    m = std::min(m, minDepth[size_t(yy * VW + xx)]);
            if (!(m < kSvInf)) continue;
            const int64_t col = y * VW + x;
            const DepthToSlice ds = f.depthToSlice(col);
            const int64_t s0 = int64_t(std::floor(ds(double(m)))) - 1;
            // Another caster wholly in front of this one's unlit side here takes the cells behind it.
            const double front = cover ? double(cover->frontOther(size_t(col), id)) : kSvInfD;
            const bool mayDrop = front < double(m);
            svForSlices(bits, col, s0, [&](int64_t slice) {
                if (mayDrop && front < ds.near + double(slice) / ds.scale) {
                    ++dropped;
                    return;
                }
                cells.push_back(svCellRange(f, x, y, slice, setup.origin, setup.axis));
            });
        }
    svReset(minDepth, VW, rect, kSvInf);
}

// The layers of one volume from its receiver cells (depth intervals along the caster's axis):
// runs of overlapping cells, each padded; a run that reaches the caster's deepest vertex starts at
// the caster. `far` on: the last run ends at the last cell, else at the unclamped far plane.
// `runs` off: one run from the caster (the far end only).
std::vector<SvRun> svLayers(std::vector<std::pair<double, double>>& cells, const SvCasterLight& s, bool far,
                            bool runs) {
    auto pad = [](double v) { return 1e-6 * std::abs(v) + 1e-9; };
    std::sort(cells.begin(), cells.end());
    std::vector<SvRun> out;
    const double md = s.maxVertexDepth + pad(s.maxVertexDepth);
    // A gap is left out only when it is longer than twice the volume's width there (the caster's
    // bounding diameter, scaled by the depth for a point light): the two caps it adds cost about
    // the width squared in fill, the side quads it saves the width times its length.
    auto worth = [&](double from, double to) {
        const double width = 2 * s.radius * (s.directional ? 1.0 : to / std::max(s.centreDepth, 1e-300));
        return to - from > 2 * width;
    };
    for (const auto& [lo0, hi0] : cells) {
        const double lo = lo0 - pad(lo0), hi = hi0 + pad(hi0);
        if (out.empty() ? !(runs && lo > md && worth(md, lo))
                        : !(runs && lo > out.back().hi && worth(out.back().hi, lo))) {
            if (out.empty())
                out.push_back({-kSvInfD, hi});
            else
                out.back().hi = std::max(out.back().hi, hi);
        } else {
            out.push_back({lo, hi});
        }
    }
    if (out.empty()) return out;
    if (!runs) out.front().lo = -kSvInfD; // the near end stays on the caster
    // At most 8 layers: every layer costs two caps of fill; close the narrowest gaps first.
    while (out.size() > 8) {
        std::size_t best = 1;
        for (std::size_t k = 2; k < out.size(); ++k)
            if (out[k].lo - out[k - 1].hi < out[best].lo - out[best - 1].hi) best = k;
        out[best - 1].hi = out[best].hi;
        out.erase(out.begin() + std::ptrdiff_t(best));
    }
    out.front().hi = std::max(out.front().hi, md);
    if (!far) {
        out.back().hi = s.far;
    } else {
        for (SvRun& r : out) r.hi = std::min(r.hi, s.far);
    }
    return out;
}

} // namespace

void svCullByReceivers(const ShadowCasterSet& casters, const std::vector<SvCasterLight>& setup,
                       const std::vector<LightView>& views, const std::vector<BitGrid>& slicemaps,
                       const ShadowVolumeOptions& options, SvDecision& d, ShadowVolumeMask& out) {
    const std::size_t N = casters.casters.size();
    // Each caster's unlit triangles, once for all views.
    std::vector<Mesh> backs(N);
    parallelFor(0, int64_t(N), 4, [&](int64_t c0, int64_t c1) {
        for (std::size_t i = size_t(c0); i < size_t(c1); ++i)
            backs[i] = svSubMesh(casters.casters[i], [&](std::size_t t) { return setup[i].unlit[t] != 0; });
    });
    // Views share the light: the receiver cells over all of them. Casters run in parallel, each
    // chunk with its own scratch map; each caster writes only its own entries.
    std::vector<std::vector<std::pair<double, double>>> cells(N);
    std::vector<int64_t> dropped(N, 0);
    for (std::size_t v = 0; v < views.size(); ++v) {
        const Frame& f = views[v].frame;
        SvCover cover;
        if (options.dropShadowedReceivers) cover = svCoverMap(casters.casters, setup, d.keep, views[v]);
        parallelFor(0, int64_t(N), 4, [&](int64_t c0, int64_t c1) {
            std::vector<float> minDepth(size_t(f.width() * f.height()), kSvInf);
            for (std::size_t i = size_t(c0); i < size_t(c1); ++i)
                if (d.keep[i] && svMayTouch(views[v], casters.casters[i]))
                    svReceiverCells(f, slicemaps[v], backs[i], setup[i],
                                    options.dropShadowedReceivers ? &cover : nullptr, int32_t(i), minDepth,
                                    cells[i], dropped[i]);
        });
    }
    ShadowVolumeStats& st = out.stats;
    for (std::size_t i = 0; i < N; ++i) {
        if (!d.keep[i]) continue;
        st.droppedReceivers += dropped[i];
        if (cells[i].empty()) { // no receiver in the volume
            if (options.cullReceivers) {
                d.keep[i] = 0;
                out.culled[i] = 1;
                ++st.culledNoReceiver;
            }
            continue;
        }
        if (!options.clamp && !options.clampRuns) continue;
        std::vector<SvRun> runs = svLayers(cells[i], setup[i], options.clamp, options.clampRuns);
        if (runs.back().hi < setup[i].far) ++st.clamped;
        if (runs.front().lo > -kSvInfD) ++st.nearClamped;
        st.gaps += int64_t(runs.size()) - 1;
        d.far[i] = runs.back().hi;
        if (runs.size() > 1 || runs.front().lo > -kSvInfD) d.runs[i] = std::move(runs);
    }
}

} // namespace voxfx::detail::shadowvolume
