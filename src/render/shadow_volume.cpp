// voxfx — shadow volumes: closed casters with edge adjacency, per-light volume construction
// (near cap, silhouette quads, far cap on a plane), ED06 §3.2 culling and clamping against light
// slicemaps, and the per-pixel counting consumer of the one rasterizer. See shadow_volume.hpp.
#include "voxfx/shadow_volume.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>
#include <unordered_map>

#include "voxfx/bitgrid.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/text.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {

namespace {

using SvClock = std::chrono::steady_clock;
double svMsSince(SvClock::time_point t0) {
    return std::chrono::duration<double, std::milli>(SvClock::now() - t0).count();
}

struct SvVec3fHash {
    std::size_t operator()(const Vec3f& v) const {
        uint32_t b[3];
        std::memcpy(b, &v.x, sizeof b);
        uint64_t h = 1469598103934665603ull;
        for (const uint32_t w : b) h = (h ^ w) * 1099511628211ull;
        return std::size_t(h);
    }
};

// Welds by exact position (+0 and -0 are one vertex) and builds the twin of every directed edge;
// returns the number of directed edges without a proper twin.
int64_t svBuildCaster(const Mesh& mesh, ShadowCaster& c) {
    std::unordered_map<Vec3f, uint32_t, SvVec3fHash> index;
    std::vector<uint32_t> remap(mesh.positions.size());
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        Vec3f p = mesh.positions[i];
        for (int k = 0; k < 3; ++k)
            if (p[k] == 0.0f) p[k] = 0.0f;
        const auto [it, added] = index.try_emplace(p, uint32_t(c.positions.size()));
        if (added) c.positions.push_back(p);
        remap[i] = it->second;
    }
    c.indices.resize(mesh.indices.size());
    for (std::size_t i = 0; i < mesh.indices.size(); ++i) c.indices[i] = remap[mesh.indices[i]];
    // Directed edges sorted by their undirected key: a closed, consistently oriented manifold has
    // exactly two per key, in opposite directions.
    const std::size_t E = c.indices.size();
    std::vector<std::pair<uint64_t, uint32_t>> edges(E);
    for (std::size_t e = 0; e < E; ++e) {
        const uint32_t a = c.indices[e], b = c.indices[e - e % 3 + (e % 3 + 1) % 3];
        edges[e] = {(uint64_t(std::min(a, b)) << 32) | std::max(a, b), uint32_t(e)};
    }
    std::sort(edges.begin(), edges.end());
    c.twin.assign(E, 0xffffffffu);
    int64_t unmatched = 0;
    for (std::size_t i = 0; i < E;) {
        std::size_t j = i;
        while (j < E && edges[j].first == edges[i].first) ++j;
        const uint32_t e0 = edges[i].second;
        const bool pair =
            j - i == 2 && c.indices[e0] != c.indices[e0 - e0 % 3 + (e0 % 3 + 1) % 3] &&
            c.indices[e0] ==
                c.indices[edges[i + 1].second - edges[i + 1].second % 3 + (edges[i + 1].second % 3 + 1) % 3];
        if (pair) {
            c.twin[e0] = edges[i + 1].second;
            c.twin[edges[i + 1].second] = e0;
        } else {
            unmatched += int64_t(j - i);
        }
        i = j;
    }
    Box3d b;
    for (const Vec3f& p : c.positions) b.extend(Vec3d(p));
    c.sphereCentre = b.center();
    for (const Vec3f& p : c.positions)
        c.sphereRadius = std::max(c.sphereRadius, length(Vec3d(p) - c.sphereCentre));
    return unmatched;
}

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

double svDistanceToSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    const Vec3d ab = b - a;
    const double len2 = dot(ab, ab);
    const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    return length(p - (a + ab * t));
}

SvCasterLight svSetup(const ShadowCaster& c, const Light& light, const Box3d& sceneBounds,
                      const Frame& camera) {
    SvCasterLight s;
    s.directional = light.type == LightType::Directional;
    if (s.directional) {
        s.axis = normalize(light.direction);
        s.origin = {0, 0, 0};
    } else {
        s.origin = light.position;
        const Vec3d toCentre = c.sphereCentre - light.position;
        if (!(length(toCentre) > 0))
            fail("shadow volumes: light '", light.name, "' sits at the centre of caster '", c.name, "'");
        s.axis = normalize(toCentre);
    }
    const std::size_t T = c.indices.size() / 3;
    s.unlit.resize(T);
    for (std::size_t t = 0; t < T; ++t) {
        const Vec3d a(c.positions[c.indices[3 * t]]), b(c.positions[c.indices[3 * t + 1]]),
            cc(c.positions[c.indices[3 * t + 2]]);
        const Vec3d n = cross(b - a, cc - a);
        const Vec3d toLight = s.directional ? -s.axis : light.position - a;
        s.unlit[t] = !(dot(n, toLight) > 0);
    }
    s.radius = c.sphereRadius;
    s.centreDepth = dot(c.sphereCentre - s.origin, s.axis);
    s.maxVertexDepth = -std::numeric_limits<double>::infinity();
    for (const Vec3f& p : c.positions) {
        const Vec3d q = Vec3d(p) - s.origin;
        const double d = dot(q, s.axis);
        // A point light must see the whole caster in front of it, well inside a half space: the
        // extruded vertex is v + (v - L) (far / d - 1).
        if (!s.directional && !(d > 0.05 * length(q)))
            fail("shadow volumes: light '", light.name, "' lies beside or inside caster '", c.name,
                 "' (a vertex is not in front of the light along the caster's direction)");
        s.maxVertexDepth = std::max(s.maxVertexDepth, d);
    }
    double sceneFar = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < 8; ++k) {
        const Vec3d q{(k & 1) ? sceneBounds.hi.x : sceneBounds.lo.x,
                      (k & 2) ? sceneBounds.hi.y : sceneBounds.lo.y,
                      (k & 4) ? sceneBounds.hi.z : sceneBounds.lo.z};
        sceneFar = std::max(sceneFar, dot(q - s.origin, s.axis));
    }
    const double diag = length(sceneBounds.extent());
    s.far = std::max(sceneFar, s.maxVertexDepth) + 0.01 * diag + 1e-6;
    // Depth-pass when a ball around the eye covering what the near clip cuts off is lit by the
    // caster's bounding sphere (its light rays miss the sphere).
    const double tx = camera.tanHalfFovY() * double(camera.width()) / double(camera.height());
    const double ty = camera.tanHalfFovY();
    const double rho = camera.nearDepth() * std::sqrt(1 + tx * tx + ty * ty);
    const Vec3d eye = camera.eye();
    const double reach = c.sphereRadius * (1 + 1e-9) + rho;
    if (s.directional) {
        const Vec3d far = eye - s.axis * (4 * diag + length(eye - c.sphereCentre) + 4 * c.sphereRadius);
        s.depthPass = svDistanceToSegment(c.sphereCentre, eye, far) > reach;
    } else {
        s.depthPass = svDistanceToSegment(c.sphereCentre, light.position, eye) > reach;
    }
    return s;
}

constexpr double kSvInfD = std::numeric_limits<double>::infinity();

Vec3d svExtrude(const Vec3d& v, const SvCasterLight& s, double far) {
    const Vec3d q = v - s.origin;
    const double d = dot(q, s.axis);
    if (s.directional) return v + s.axis * (far - d);
    return s.origin + q * (far / d);
}

// One layer of a volume along the caster's axis: [lo, hi]; lo = -inf starts at the caster.
struct SvRun {
    double lo, hi;
};

// Appends the volume of caster c over the unlit triangles flagged in `cap` (s.unlit, less those
// dropped as shadowed), one closed piece per run (the caster to `far` when `runs` is empty); mode 1
// per depth-fail triangle. A piece that starts behind the caster has its near cap at the
// projection of the triangles on its start plane, drawn in both counting modes.
void svAppendVolume(const ShadowCaster& c, const SvCasterLight& s, const std::vector<uint8_t>& cap,
                    double far, const std::vector<SvRun>& runs, Mesh& out, std::vector<uint8_t>& mode,
                    int64_t& silhouettes) {
    const std::vector<SvRun> pieces = runs.empty() ? std::vector<SvRun>{{-kSvInfD, far}} : runs;
    const auto n = uint32_t(c.positions.size());
    const uint8_t m = s.depthPass ? 0 : 1;
    auto tri = [&](uint32_t a, uint32_t b, uint32_t cc) {
        out.indices.insert(out.indices.end(), {a, b, cc});
        mode.push_back(m);
    };
    const std::size_t T = c.indices.size() / 3;
    for (std::size_t piece = 0; piece < pieces.size(); ++piece) {
        const bool fromCaster = !(pieces[piece].lo > -kSvInfD);
        const auto base = uint32_t(out.positions.size());
        if (fromCaster)
            out.positions.insert(out.positions.end(), c.positions.begin(), c.positions.end());
        else
            for (const Vec3f& p : c.positions)
                out.positions.push_back(Vec3f(svExtrude(Vec3d(p), s, pieces[piece].lo)));
        for (const Vec3f& p : c.positions)
            out.positions.push_back(Vec3f(svExtrude(Vec3d(p), s, pieces[piece].hi)));
        for (std::size_t t = 0; t < T; ++t) {
            if (!cap[t]) continue;
            const uint32_t a = base + c.indices[3 * t], b = base + c.indices[3 * t + 1],
                           cc = base + c.indices[3 * t + 2];
            // Near cap, reversed: V lies behind the unlit side (on the caster, depth-pass needs none).
            if (!fromCaster || !s.depthPass) tri(a, cc, b);
            tri(a + n, b + n, cc + n); // far cap
            for (int k = 0; k < 3; ++k) {
                const uint32_t e = uint32_t(3 * t + k);
                if (cap[c.twin[e] / 3]) continue;
                const uint32_t p = base + c.indices[e], q = base + c.indices[3 * t + (k + 1) % 3];
                tri(p, q, q + n);
                tri(p, q + n, p + n);
                if (piece == 0) ++silhouettes;
            }
        }
    }
}

// Per-pixel signed crossing counts (see the file comment of shadow_volume.hpp).
struct SvCountConsumer {
    int64_t width;
    const float* depth;
    const uint8_t* mode;
    int32_t* count;
    std::atomic<int64_t>* fragments;
    struct Sink {
        int64_t width;
        const float* depth;
        const uint8_t* mode;
        int32_t* count;
        std::atomic<int64_t>* fragments;
        int64_t local = 0;
        void fragment(int64_t x, int64_t y, double d, uint32_t triangle, bool front) {
            ++local;
            const auto i = size_t(y * width + x);
            const double g = double(depth[i]);
            if (!std::isfinite(g)) return;
            if (mode[triangle]) {
                if (d > g) count[i] += front ? -1 : 1;
            } else if (d < g) {
                count[i] += front ? 1 : -1;
            }
        }
        void finish() { fragments->fetch_add(local, std::memory_order_relaxed); }
    };
    Sink tile(const Tile&) const { return {width, depth, mode, count, fragments}; }
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

// Receivers of one light view as a slicemap.
struct SvReceiverView {
    LightView view;
    BitGrid bits;
};

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

ShadowCasterSet ShadowCasterSet::build(const Scene& scene) {
    ShadowCasterSet set;
    for (const SceneMesh& m : scene.meshes) {
        if (!m.castsShadow || m.mesh.indices.empty()) continue;
        ShadowCaster c;
        c.name = m.name;
        const int64_t open = svBuildCaster(m.mesh, c);
        if (open > 0)
            fail("shadow volumes need closed casters: mesh '", m.name, "' has ", open,
                 " edges not shared by exactly two consistently oriented triangles (mark it "
                 "castsShadow = false, or use --shadows map)");
        set.casters.push_back(std::move(c));
    }
    return set;
}

float ShadowVolumeMask::visibility(const Vec3d& p) const {
    if (shadowed.empty()) return 1.0f;
    if (!(camera.viewDepth(p) > 0)) return 1.0f;
    const Vec3d g = camera.gridFromWorld(p);
    const double fx = std::floor(g.x), fy = std::floor(g.y);
    if (!(fx >= 0 && fy >= 0 && fx < double(camera.width()) && fy < double(camera.height()))) return 1.0f;
    return shadowed[size_t(int64_t(fy) * camera.width() + int64_t(fx))] ? 0.0f : 1.0f;
}

bool ShadowVolumeMask::atSurface(const Vec3d& p) const {
    if (shadowed.empty() || depth.size() != shadowed.size()) return false;
    if (!(camera.viewDepth(p) > 0)) return false;
    const Vec3d g = camera.gridFromWorld(p);
    const double fx = std::floor(g.x), fy = std::floor(g.y);
    if (!(fx >= 0 && fy >= 0 && fx < double(camera.width()) && fy < double(camera.height()))) return false;
    const double d = depth[size_t(int64_t(fy) * camera.width() + int64_t(fx))];
    return std::abs(g.z - d) <= 1e-5 * std::max(std::abs(d), 1e-3);
}

std::vector<uint8_t> shadowVolumeReceivers(const GBuffer& gbuffer, const SceneGeometry& geometry,
                                           std::span<const Material> materials, const Light& light) {
    const int64_t W = gbuffer.frame.width(), H = gbuffer.frame.height();
    std::vector<uint8_t> out(size_t(W * H), 0);
    parallelFor(0, H, 16, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                SurfacePoint s;
                if (!surfaceAt(gbuffer, geometry, x, y, s)) continue;
                const Vec3d toLight = light.type == LightType::Directional ? -normalize(light.direction)
                                                                           : light.position - s.position;
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

Mesh shadowVolumeMesh(const ShadowCasterSet& casters, const Light& light, const Box3d& sceneBounds) {
    Mesh out;
    std::vector<uint8_t> mode;
    int64_t silhouettes = 0;
    // A camera far from everything: depth-fail volumes (all caps) as the counting uses them.
    const Frame probe = Frame::perspective(sceneBounds.hi + sceneBounds.extent() * 1e3 + Vec3d{1, 1, 1},
                                           sceneBounds.center(), {0, 1, 0.1}, 0.5, 4, 4, 1e-3, 1, 1);
    for (const ShadowCaster& c : casters.casters) {
        SvCasterLight s = svSetup(c, light, sceneBounds, probe);
        s.depthPass = false;
        svAppendVolume(c, s, s.unlit, s.far, {}, out, mode, silhouettes);
    }
    return out;
}

namespace {

constexpr float kSvInf = std::numeric_limits<float>::infinity();

// False when caster c's bounding sphere lies wholly outside a perspective view's frustum (it then
// has no fragment there); always true for orthographic views.
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

namespace {

// What culling and clamping decide for one light: per caster, whether its volume is drawn and the
// plane its extrusion ends on; `mask` receives the culled flags and the counters.
struct SvDecision {
    std::vector<uint8_t> keep;
    std::vector<double> far;
    std::vector<std::vector<SvRun>> runs;  ///< per caster; empty: one piece, caster to far
    std::vector<std::vector<uint8_t>> cap; ///< per caster: the unlit triangles drawn
};

// The visible receivers (G-buffer points flagged in `receivers`) in world space, and the light's
// views fitted to them and the casters.
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

// The receivers as one slicemap per view; false when some receiver lies outside every view (then
// nothing may be culled or clamped for this light).
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

// ED06 §3.2 against the receivers: a caster whose footprint holds no receiver is culled; the
// volumes of the others are clamped to the runs of depth holding their receivers.
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

// ED06 §3.2, second test, among the casters left: the light's map shows unlit triangles (or a
// whole caster) in other casters' shadow. Views (cube faces) run in parallel, each clearing its own
// flags.
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

// The volumes kept, extruded to their far planes, counted per pixel of the G-buffer.
void svCount(const ShadowCasterSet& casters, const std::vector<SvCasterLight>& setup, const SvDecision& d,
             const GBuffer& gbuffer, ShadowVolumeMask& out) {
    ShadowVolumeStats& st = out.stats;
    auto t0 = SvClock::now();
    Mesh volumes;
    std::vector<uint8_t> mode;
    for (std::size_t i = 0; i < casters.casters.size(); ++i) {
        if (!d.keep[i]) continue;
        (setup[i].depthPass ? st.depthPass : st.depthFail)++;
        svAppendVolume(casters.casters[i], setup[i], d.cap[i].empty() ? setup[i].unlit : d.cap[i], d.far[i],
                       d.runs[i], volumes, mode, st.silhouetteEdges);
    }
    st.volumeTriangles = int64_t(mode.size());
    st.buildMs = svMsSince(t0);

    t0 = SvClock::now();
    const Frame& cam = gbuffer.frame;
    std::vector<int32_t> count(size_t(cam.width() * cam.height()), 0);
    std::atomic<int64_t> fragments{0};
    if (!volumes.indices.empty()) {
        SvCountConsumer consumer{cam.width(), gbuffer.depth.data(), mode.data(), count.data(), &fragments};
        RasterOptions ro;
        rasterize<Coverage::Center>(cam, volumes.view(), ro, consumer);
    }
    st.fragments = fragments.load();
    for (std::size_t i = 0; i < count.size(); ++i)
        out.shadowed[i] = gbuffer.triangle[i] != GBuffer::kNone && count[i] != 0;
    st.rasterMs = svMsSince(t0);
}

} // namespace

ShadowVolumeMask computeShadowVolumes(const ShadowCasterSet& casters, const Light& light,
                                      const GBuffer& gbuffer, const std::vector<uint8_t>& receivers,
                                      const Box3d& sceneBounds, const ShadowVolumeOptions& options) {
    ShadowVolumeMask out;
    out.camera = gbuffer.frame;
    out.depth = gbuffer.depth;
    const Frame& cam = gbuffer.frame;
    out.shadowed.assign(size_t(cam.width() * cam.height()), 0);
    out.stats.casters = int64_t(casters.casters.size());
    if (casters.casters.empty()) return out;
    if (receivers.size() != size_t(cam.width() * cam.height()))
        fail("shadow volumes: one receiver flag per G-buffer pixel needed");
    if (options.mapResolution <= 0 || options.receiverSlices <= 0)
        fail("shadow volumes: culling resolutions must be positive");
    const std::size_t N = casters.casters.size();
    out.culled.assign(N, 0);

    const auto t0 = SvClock::now();
    std::vector<SvCasterLight> setup;
    setup.reserve(N);
    for (const ShadowCaster& c : casters.casters) setup.push_back(svSetup(c, light, sceneBounds, cam));
    SvDecision d{std::vector<uint8_t>(N, 1), std::vector<double>(N), std::vector<std::vector<SvRun>>(N),
                 std::vector<std::vector<uint8_t>>(N)};
    for (std::size_t i = 0; i < N; ++i) d.far[i] = setup[i].far;
    const bool byReceivers = options.cullReceivers || options.clamp || options.clampRuns;
    const bool byOccluders = options.cullOccluded || options.cullShadowedParts;
    if (byReceivers || byOccluders) {
        std::vector<Vec3d> points;
        const std::vector<LightView> views =
            svReceiverViews(casters, light, gbuffer, receivers, options, points);
        if (byReceivers) {
            std::vector<BitGrid> slicemaps;
            out.stats.receiversCovered = svReceiverSlicemaps(views, points, slicemaps);
            if (out.stats.receiversCovered)
                svCullByReceivers(casters, setup, views, slicemaps, options, d, out);
        }
        if (byOccluders) svCullOccluded(casters, setup, views, options, d, out);
    }
    out.stats.cullMs = svMsSince(t0);
    svCount(casters, setup, d, gbuffer, out);
    return out;
}

std::span<const OptionField<ShadowVolumeOptions>> ShadowVolumeOptions::fields() {
    using O = ShadowVolumeOptions;
    static const std::vector<OptionField<O>> table = [] {
        std::vector<OptionField<O>> t;
        OptionField<O> all =
            optionField<O>("volumeCulling",
                           "shadow volumes: ED06 culling and clamping (the same image; off: more fragments)",
                           OptionType::Flag);
        all.store = +[](O& o, const OptionValue& v) {
            o.cullReceivers = o.cullOccluded = o.clamp = o.clampRuns = o.cullShadowedParts =
                o.dropShadowedReceivers = std::get<bool>(v);
        };
        all.get = +[](const O& o) {
            return OptionValue(o.cullReceivers && o.cullOccluded && o.clamp && o.clampRuns &&
                               o.cullShadowedParts && o.dropShadowedReceivers);
        };
        t.push_back(all);
        t.push_back(flagOption<O, &O::cullReceivers>(
            "cullReceivers", "shadow volumes: skip volumes holding no visible receiver"));
        t.push_back(flagOption<O, &O::cullOccluded>(
            "cullOccluded", "shadow volumes: skip casters entirely in other casters' shadow"));
        t.push_back(flagOption<O, &O::cullShadowedParts>(
            "cullShadowedParts",
            "shadow volumes: drop the unlit triangles of a caster lying in other casters' shadow"));
        t.push_back(flagOption<O, &O::dropShadowedReceivers>(
            "dropShadowedReceivers", "shadow volumes: leave a receiver in another caster's shadow to that "
                                     "caster (culling, clamping)"));
        t.push_back(flagOption<O, &O::clamp>("volumeClamping",
                                             "shadow volumes: end each volume at its last receiver slab"));
        t.push_back(flagOption<O, &O::clampRuns>(
            "clampRuns",
            "shadow volumes: cut each volume to its runs of receiver slabs (near end and gaps)"));
        t.push_back(numberOption<O, &O::mapResolution>(
            "cullResolution", "shadow volumes: culling light views, columns along the longer side", 1,
            16384));
        t.push_back(numberOption<O, &O::receiverSlices>(
            "receiverSlices", "shadow volumes: slices of the receiver slicemap", 1, 16384));
        return t;
    }();
    return table;
}

ShadowVolumeStats& ShadowVolumeStats::operator+=(const ShadowVolumeStats& o) {
    casters += o.casters;
    culledNoReceiver += o.culledNoReceiver;
    culledOccluded += o.culledOccluded;
    clamped += o.clamped;
    nearClamped += o.nearClamped;
    gaps += o.gaps;
    culledTriangles += o.culledTriangles;
    droppedReceivers += o.droppedReceivers;
    depthPass += o.depthPass;
    depthFail += o.depthFail;
    silhouetteEdges += o.silhouetteEdges;
    volumeTriangles += o.volumeTriangles;
    fragments += o.fragments;
    receiversCovered = receiversCovered && o.receiversCovered;
    cullMs += o.cullMs;
    buildMs += o.buildMs;
    rasterMs += o.rasterMs;
    return *this;
}

std::string ShadowVolumeStats::summary() const {
    return countText(fragments) + " volume fragments; " + countText(culledNoReceiver + culledOccluded) +
           " of " + countText(casters) + " casters culled, " + countText(culledTriangles) +
           " shadowed triangles dropped, " + countText(clamped) + " clamped (" + countText(nearClamped) +
           " near ends, " + countText(gaps) + " gaps); " + countText(droppedReceivers) +
           " shadowed receiver cells left; culling " + msText(cullMs) + ", volumes " + msText(buildMs) +
           ", counting " + msText(rasterMs);
}

VolumeShadow VolumeShadow::build(const Scene& scene, const Light& light, const ShadowVolumeOptions& options,
                                 Progress*) {
    VolumeShadow out;
    out.options_ = options;
    out.casters_ = std::make_shared<const ShadowCasterSet>(ShadowCasterSet::build(scene));
    out.light_ = light;
    out.sceneBounds_ = scene.bounds(false);
    out.materials_ = scene.materials;
    // The exact answer off the G-buffer's surfaces: the same casters, each opaque, traced.
    Mesh all;
    for (const ShadowCaster& c : out.casters_->casters) {
        const auto base = uint32_t(all.positions.size());
        all.positions.insert(all.positions.end(), c.positions.begin(), c.positions.end());
        for (const uint32_t i : c.indices) all.indices.push_back(base + i);
    }
    if (!all.indices.empty()) out.tracer_ = std::make_shared<const TriangleTracer>(all.view());
    return out;
}

void VolumeShadow::prepare(const GBuffer& gbuffer, const SceneGeometry& geometry) {
    if (!casters_) return;
    mask_ = computeShadowVolumes(*casters_, light_, gbuffer,
                                 shadowVolumeReceivers(gbuffer, geometry, materials_, light_), sceneBounds_,
                                 options_);
}

float VolumeShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    if (mask_.shadowed.empty() || mask_.atSurface(p) || !tracer_) return mask_.visibility(p); // 1 unprepared
    // Off the G-buffer's surfaces (blended surfaces, volume samples, refracted points): whether
    // the segment towards the light crosses a caster, from p moved 10 epsilons along n.
    Vec3d l;
    double distance = std::numeric_limits<double>::infinity();
    if (light_.type == LightType::Directional) {
        l = -normalize(light_.direction);
    } else {
        l = light_.position - p;
        distance = length(l);
        l = l / std::max(distance, 1e-300);
    }
    const Vec3d o = p + n * (tracer_->epsilon() * 10);
    return tracer_->intersect(o, l, 0.0, distance).hit ? 0.0f : 1.0f;
}

} // namespace voxfx
