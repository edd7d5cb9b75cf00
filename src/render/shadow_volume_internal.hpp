// voxfx — shadow volumes' internals shared by their files (render/ only): the per-light set-up of
// a caster, the decision culling and clamping make, the texel rasterization the culling uses, and
// one function per step of computeShadowVolumes (shadow_volume.cpp), one file per concern:
//   shadow_volume_geometry.cpp   closed casters, a caster's set-up for a light, the volume's mesh
//   shadow_volume_receivers.cpp  ED06 §3.2 against the receivers: culling, clamping to runs
//   shadow_volume_occluders.cpp  ED06 §3.2 among the casters: casters and triangles in shadow
//   shadow_volume_count.cpp      the per-pixel counting of the volumes kept
//   shadow_volume_options.cpp    the options' named fields and the statistics
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include "voxfx/bitgrid.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/shadow_volume.hpp"

namespace voxfx::detail::shadowvolume {

using SvClock = std::chrono::steady_clock;
inline double svMsSince(SvClock::time_point t0) {
    return std::chrono::duration<double, std::milli>(SvClock::now() - t0).count();
}

inline constexpr double kSvInfD = std::numeric_limits<double>::infinity();
inline constexpr float kSvInf = std::numeric_limits<float>::infinity();

// One caster's volume for one light: which triangles face away from the light, and the plane the
// extrusion ends on (dot(x - origin, axis) = far).
struct SvCasterLight {
    std::vector<uint8_t> unlit; // per triangle
    Vec3d origin, axis;         // origin: the light (point, spot) or 0 (directional)
    bool directional = false;
    double maxVertexDepth = 0; // max over vertices of dot(v - origin, axis)
    double far = 0;            // unclamped: past the scene
    double radius = 0;         // the caster's bounding sphere: radius, depth of its centre
    double centreDepth = 0;
    bool depthPass = false;
};

// One layer of a volume along the caster's axis: [lo, hi]; lo = -inf starts at the caster.
struct SvRun {
    double lo, hi;
};

// The rectangle of texels a rasterization touched (x0, y0, x1, y1 inclusive; x1 < 0: none).
struct SvRect {
    std::atomic<int64_t> v[4] = {std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max(), -1,
                                 -1};
    bool empty() const { return v[2].load() < 0; }
};

// Hands every fragment or conservative span of a mesh to op(texel, depthMin, depthMax) and records
// the touched rectangle. Tiles own their rows, so op writes its texel without atomics.
template <class Op> struct SvTexelConsumer {
    int64_t width;
    Op op;
    SvRect* rect;
    struct Sink {
        int64_t width;
        Op op;
        SvRect* rect;
        int64_t x0 = std::numeric_limits<int64_t>::max(), y0 = x0, x1 = -1, y1 = -1;
        void touch(int64_t x, int64_t y) {
            x0 = std::min(x0, x);
            y0 = std::min(y0, y);
            x1 = std::max(x1, x);
            y1 = std::max(y1, y);
        }
        void call(int64_t texel, double dmin, double dmax, uint32_t triangle) {
            if constexpr (std::is_invocable_v<Op&, int64_t, double, double, uint32_t>)
                op(texel, dmin, dmax, triangle);
            else
                op(texel, dmin, dmax);
        }
        void span(int64_t x, int64_t y, double dmin, double dmax, uint32_t triangle) {
            call(y * width + x, dmin, dmax, triangle);
            touch(x, y);
        }
        void fragment(int64_t x, int64_t y, double depth, uint32_t triangle, bool) {
            call(y * width + x, depth, depth, triangle);
            touch(x, y);
        }
        void finish() {
            if (x1 < 0) return;
            auto lower = [](std::atomic<int64_t>& a, int64_t value) {
                int64_t cur = a.load();
                while (value < cur && !a.compare_exchange_weak(cur, value)) {}
            };
            auto raise = [](std::atomic<int64_t>& a, int64_t value) {
                int64_t cur = a.load();
                while (value > cur && !a.compare_exchange_weak(cur, value)) {}
            };
            lower(rect->v[0], x0);
            lower(rect->v[1], y0);
            raise(rect->v[2], x1);
            raise(rect->v[3], y1);
        }
    };
    Sink tile(const Tile&) const { return {width, op, rect}; }
};

template <Coverage C, class Op> void svRasterTexels(const Frame& f, const Mesh& mesh, Op op, SvRect& rect) {
    if (mesh.indices.empty()) return;
    SvTexelConsumer<Op> consumer{f.width(), op, &rect};
    RasterOptions ro;
    ro.coverage = C;
    ro.rowsPerTile = f.height(); // one tile: callers run casters or views in parallel
    rasterize<C>(f, mesh.view(), ro, consumer);
}

// Triangles of caster c selected by `pick(t)` (same vertices).
template <class Pick> Mesh svSubMesh(const ShadowCaster& c, Pick pick) {
    Mesh m;
    m.positions = c.positions;
    for (std::size_t t = 0; t < c.indices.size() / 3; ++t)
        if (pick(t))
            m.indices.insert(m.indices.end(), c.indices.begin() + 3 * t, c.indices.begin() + 3 * t + 3);
    return m;
}

// Resets texels of `rect` in a W-wide map to `value`.
template <class T> void svReset(std::vector<T>& map, int64_t W, const SvRect& rect, T value) {
    if (rect.empty()) return;
    for (int64_t y = rect.v[1].load(); y <= rect.v[3].load(); ++y)
        std::fill(map.begin() + y * W + rect.v[0].load(), map.begin() + y * W + rect.v[2].load() + 1, value);
}

// One light view's map of the casters: per texel the silhouette owner (-1 none, caster index, -2
// several) and the two smallest "farthest lit depth" of distinct casters covering the texel centre
// (with the caster of the smallest). A texel whose owner is -1 or caster i is *clean* for i: every
// ray through it meets the same other casters, so one covering the centre covers it whole.
struct SvCover {
    std::vector<int32_t> owner;
    std::vector<float> best1, best2;
    std::vector<int32_t> best1Id;
    /// The farthest lit depth of a caster other than i covering texel k (+inf: none), if k is clean
    /// for i.
    float frontOther(std::size_t k, int32_t i) const {
        if (owner[k] != -1 && owner[k] != i) return kSvInf;
        return best1Id[k] != i ? best1[k] : best2[k];
    }
};

// What culling and clamping decide for one light: per caster, whether its volume is drawn and the
// plane its extrusion ends on; `mask` receives the culled flags and the counters.
struct SvDecision {
    std::vector<uint8_t> keep;
    std::vector<double> far;
    std::vector<std::vector<SvRun>> runs;  ///< per caster; empty: one piece, caster to far
    std::vector<std::vector<uint8_t>> cap; ///< per caster: the unlit triangles drawn
};

// ---- shadow_volume_geometry.cpp ---------------------------------------------------------------

/// Caster c's volume set-up for one light: unlit triangles, axis, far plane, depth-pass or -fail.
SvCasterLight svSetup(const ShadowCaster& c, const Light& light, const Box3d& sceneBounds,
                      const Frame& camera);
// Appends the volume of caster c over the unlit triangles flagged in `cap` (s.unlit, less those
// dropped as shadowed), one closed piece per run (the caster to `far` when `runs` is empty); mode 1
// per depth-fail triangle. A piece that starts behind the caster has its near cap at the
// projection of the triangles on its start plane, drawn in both counting modes.
void svAppendVolume(const ShadowCaster& c, const SvCasterLight& s, const std::vector<uint8_t>& cap,
                    double far, const std::vector<SvRun>& runs, Mesh& out, std::vector<uint8_t>& mode,
                    int64_t& silhouettes);

// ---- shadow_volume_receivers.cpp --------------------------------------------------------------

// The visible receivers (G-buffer points flagged in `receivers`) in world space, and the light's
// views fitted to them and the casters.
std::vector<LightView> svReceiverViews(const ShadowCasterSet& casters, const Light& light,
                                       const GBuffer& gbuffer, const std::vector<uint8_t>& receivers,
                                       const ShadowVolumeOptions& options, std::vector<Vec3d>& points);
// The receivers as one slicemap per view; false when some receiver lies outside every view (then
// nothing may be culled or clamped for this light).
bool svReceiverSlicemaps(const std::vector<LightView>& views, const std::vector<Vec3d>& points,
                         std::vector<BitGrid>& slicemaps);
// ED06 §3.2 against the receivers: a caster whose footprint holds no receiver is culled; the
// volumes of the others are clamped to the runs of depth holding their receivers.
void svCullByReceivers(const ShadowCasterSet& casters, const std::vector<SvCasterLight>& setup,
                       const std::vector<LightView>& views, const std::vector<BitGrid>& slicemaps,
                       const ShadowVolumeOptions& options, SvDecision& d, ShadowVolumeMask& out);

// ---- shadow_volume_occluders.cpp --------------------------------------------------------------

// False when caster c's bounding sphere lies wholly outside a perspective view's frustum (it then
// has no fragment there); always true for orthographic views.
bool svMayTouch(const LightView& view, const ShadowCaster& c);
/// One light view's map of the casters (SvCover) for the casters kept.
SvCover svCoverMap(const std::vector<ShadowCaster>& casters, const std::vector<SvCasterLight>& setup,
                   const std::vector<uint8_t>& keep, const LightView& view);
// ED06 §3.2, second test, among the casters left: the light's map shows unlit triangles (or a
// whole caster) in other casters' shadow. Views (cube faces) run in parallel, each clearing its own
// flags.
void svCullOccluded(const ShadowCasterSet& casters, const std::vector<SvCasterLight>& setup,
                    const std::vector<LightView>& views, const ShadowVolumeOptions& options, SvDecision& d,
                    ShadowVolumeMask& out);

// ---- shadow_volume_count.cpp ------------------------------------------------------------------

// The volumes kept, extruded to their far planes, counted per pixel of the G-buffer.
void svCount(const ShadowCasterSet& casters, const std::vector<SvCasterLight>& setup, const SvDecision& d,
             const GBuffer& gbuffer, ShadowVolumeMask& out);

} // namespace voxfx::detail::shadowvolume
