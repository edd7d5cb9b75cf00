// voxfx — shadow volumes, ED06 §3.2's second test: in the light's views, the casters (and the
// unlit triangles of a caster) that lie in other casters' shadow need no volume (or no part of it).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "render/shadow_volume_internal.hpp"

namespace voxfx::detail::shadowvolume {

bool svMayTouch(const LightView& view, const ShadowCaster& c) {
    const Frame& f = view.frame;
    if (!f.isPerspective()) return true;
    const Projection& pr = f.projection();
    const Vec3d q = pr.cameraFromWorld(c.sphereCentre);
    const double r = c.sphereRadius * (1 + 1e-6) + 1e-9;
    if (q.z < -r) return false;
    const double nx = std::sqrt(1 + pr.tanX * pr.tanX), ny = std::sqrt(1 + pr.tanY * pr.tanY);
    return (q.x - pr.tanX * q.z) / nx <= r && (-q.x - pr.tanX * q.z) / nx <= r &&
           (q.y - pr.tanY * q.z) / ny <= r && (-q.y - pr.tanY * q.z) / ny <= r;
}

SvCover svCoverMap(const std::vector<ShadowCaster>& casters, const std::vector<SvCasterLight>& setup,
                   const std::vector<uint8_t>& keep, const LightView& view) {
    const Frame& f = view.frame;
    const int64_t W = f.width(), H = f.height();
    const std::size_t N = casters.size();
    SvCover cv{std::vector<int32_t>(size_t(W * H), -1), std::vector<float>(size_t(W * H), kSvInf),
               std::vector<float>(size_t(W * H), kSvInf), std::vector<int32_t>(size_t(W * H), -1)};
    std::vector<float> far(size_t(W * H), -kSvInf);
    std::vector<uint8_t> covered(size_t(W * H), 0);
    for (std::size_t i = 0; i < N; ++i) {
        if (!keep[i] || !svMayTouch(view, casters[i])) continue;
        const ShadowCaster& c = casters[i];
        const SvCasterLight& s = setup[i];
        // Silhouette edges as triangles along the light ray: they project onto the edge.
        Mesh sil;
        for (std::size_t t = 0; t < c.indices.size() / 3; ++t) {
            if (!s.unlit[t]) continue;
            for (int k = 0; k < 3; ++k) {
                const uint32_t e = uint32_t(3 * t + k);
                if (s.unlit[c.twin[e] / 3]) continue;
                const Vec3d p(c.positions[c.indices[e]]), q(c.positions[c.indices[3 * t + (k + 1) % 3]]);
                const Vec3d qq = s.directional ? q + s.axis * (1e-3 * (c.sphereRadius + 1e-9))
                                               : s.origin + (q - s.origin) * 1.001;
                const auto base = uint32_t(sil.positions.size());
                sil.positions.insert(sil.positions.end(), {Vec3f(p), Vec3f(q), Vec3f(qq)});
                sil.indices.insert(sil.indices.end(), {base, base + 1, base + 2});
            }
        }
        SvRect silRect;
        const auto id = int32_t(i);
        int32_t* own = cv.owner.data();
        svRasterTexels<Coverage::Conservative>(
            f, sil,
            [own, id](int64_t texel, double, double) {
                int32_t& o = own[texel];
                o = (o == -1 || o == id) ? id : -2;
            },
            silRect);
        // Lit triangles: farthest conservative depth per texel and centre coverage.
        const Mesh lit = svSubMesh(c, [&](std::size_t t) { return !s.unlit[t]; });
        SvRect farRect, coverRect;
        float* fp = far.data();
        uint8_t* cp = covered.data();
        svRasterTexels<Coverage::Conservative>(
            f, lit,
            [fp](int64_t texel, double, double dmax) { fp[texel] = std::max(fp[texel], float(dmax)); },
            farRect);
        svRasterTexels<Coverage::Center>(
            f, lit, [cp](int64_t texel, double, double) { cp[texel] = 1; }, coverRect);
        if (!coverRect.empty())
            for (int64_t y = coverRect.v[1].load(); y <= coverRect.v[3].load(); ++y)
                for (int64_t x = coverRect.v[0].load(); x <= coverRect.v[2].load(); ++x) {
                    const auto k = size_t(y * W + x);
                    if (!covered[k]) continue;
                    // Round the far depth up: the tests compare it strictly below another's near.
                    const float v = std::nextafter(far[k], kSvInf);
                    if (v < cv.best1[k]) {
                        cv.best2[k] = cv.best1[k];
                        cv.best1[k] = v;
                        cv.best1Id[k] = id;
                    } else if (v < cv.best2[k]) {
                        cv.best2[k] = v;
                    }
                }
        svReset(far, W, farRect, -kSvInf);
        svReset(covered, W, coverRect, uint8_t(0));
    }
    return cv;
}

namespace {

// ED06 §3.2, first test, in one light view (see the file comment of shadow_volume.hpp): clears
// shadowed[i][t] for the unlit triangles t of caster i that this view does not show to lie in other
// casters' shadow (entries start at 1).
void svOccludedInView(const std::vector<ShadowCaster>& casters, const std::vector<SvCasterLight>& setup,
                      const std::vector<uint8_t>& keep, const LightView& view, bool cubeFace,
                      std::vector<std::vector<uint8_t>>& shadowed) {
    const Frame& f = view.frame;
    const std::size_t N = casters.size();
    const SvCover cv = svCoverMap(casters, setup, keep, view);
    for (std::size_t i = 0; i < N; ++i) {
        if (!keep[i]) continue;
        const ShadowCaster& c = casters[i];
        std::vector<uint8_t>& sh = shadowed[i];
        // A single view must hold the caster whole (else part of it goes untested); cube faces
        // each test their own part of it.
        if (cubeFace && !svMayTouch(view, c)) continue; // not in this face: nothing to test here
        if (!cubeFace) {
            bool inside = true;
            for (const Vec3f& p : c.positions) inside = inside && view.covers(Vec3d(p));
            if (!inside) {
                std::fill(sh.begin(), sh.end(), uint8_t(0));
                continue;
            }
        }
        // The unlit triangles (their index in the sub-mesh maps back through `which`), each
        // fragment span tested against the others in front.
        std::vector<uint32_t> which;
        const Mesh back = svSubMesh(c, [&](std::size_t t) {
            if (setup[i].unlit[t]) which.push_back(uint32_t(t));
            return setup[i].unlit[t] != 0;
        });
        SvRect rect;
        const auto id = int32_t(i);
        svRasterTexels<Coverage::Conservative>(
            f, back,
            [&cv, &sh, &which, id](int64_t texel, double dmin, double, uint32_t tri) {
                uint8_t& flag = sh[which[tri]];
                if (flag && !(double(cv.frontOther(size_t(texel), id)) < dmin)) flag = 0;
            },
            rect);
    }
}

} // namespace

void svCullOccluded(const ShadowCasterSet& casters, const std::vector<SvCasterLight>& setup,
                    const std::vector<LightView>& views, const ShadowVolumeOptions& options, SvDecision& d,
                    ShadowVolumeMask& out) {
    const std::size_t N = casters.casters.size();
    std::vector<std::vector<std::vector<uint8_t>>> perView(views.size());
    for (auto& pv : perView) {
        pv.resize(N);
        for (std::size_t i = 0; i < N; ++i) pv[i] = setup[i].unlit;
    }
    parallelFor(0, int64_t(views.size()), 1, [&](int64_t v0, int64_t v1) {
        for (int64_t v = v0; v < v1; ++v)
            svOccludedInView(casters.casters, setup, d.keep, views[size_t(v)], views.size() > 1,
                             perView[size_t(v)]);
    });
    for (std::size_t i = 0; i < N; ++i) {
        if (!d.keep[i]) continue;
        std::vector<uint8_t> cap = setup[i].unlit;
        int64_t shadowed = 0, unlit = 0;
        for (std::size_t t = 0; t < cap.size(); ++t) {
            if (!cap[t]) continue;
            ++unlit;
            bool all = true;
            for (const auto& pv : perView) all = all && pv[i][t];
            if (all) {
                cap[t] = 0;
                ++shadowed;
            }
        }
        if (shadowed == unlit && options.cullOccluded) {
            d.keep[i] = 0;
            out.culled[i] = 2;
            ++out.stats.culledOccluded;
        } else if (shadowed > 0 && options.cullShadowedParts) {
            d.cap[i] = std::move(cap);
            out.stats.culledTriangles += shadowed;
        }
    }
}

} // namespace voxfx::detail::shadowvolume
