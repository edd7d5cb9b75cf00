// voxfx — shadow volumes' geometry: closed casters with edge adjacency (welded by position), a
// caster's set-up for one light (unlit triangles, far plane, depth-pass or depth-fail), and the
// volume's mesh (near cap, silhouette quads, far cap; one closed piece per run).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "render/shadow_volume_internal.hpp"

namespace voxfx::detail::shadowvolume {

namespace {

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

double svDistanceToSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    const Vec3d ab = b - a;
    const double len2 = dot(ab, ab);
    const double t = len2 > 0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    return length(p - (a + ab * t));
}

} // namespace

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

namespace {

Vec3d svExtrude(const Vec3d& v, const SvCasterLight& s, double far) {
    const Vec3d q = v - s.origin;
    const double d = dot(q, s.axis);
    if (s.directional) return v + s.axis * (far - d);
    return s.origin + q * (far / d);
}

} // namespace

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
            // Near cap, reversed: V lies behind the unlit side. On an opaque caster depth-pass needs
            // none (every eye ray through it ends on the caster); the camera sees receivers through a
            // see-through one, and rays entering its volume there cross the cap.
            if (!fromCaster || !s.depthPass || c.seeThrough) tri(a, cc, b);
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

} // namespace voxfx::detail::shadowvolume

namespace voxfx {

ShadowCasterSet ShadowCasterSet::build(const Scene& scene) {
    using namespace detail::shadowvolume;
    ShadowCasterSet set;
    for (const SceneMesh& m : scene.meshes) {
        if (!m.castsShadow || m.mesh.indices.empty()) continue;
        ShadowCaster c;
        c.name = m.name;
        c.seeThrough = m.material < scene.materials.size() && scene.materials[m.material].blend;
        const int64_t open = svBuildCaster(m.mesh, c);
        if (open > 0)
            fail("shadow volumes need closed casters: mesh '", m.name, "' has ", open,
                 " edges not shared by exactly two consistently oriented triangles (mark it "
                 "castsShadow = false, or use --shadows map)");
        set.casters.push_back(std::move(c));
    }
    return set;
}

Mesh shadowVolumeMesh(const ShadowCasterSet& casters, const Light& light, const Box3d& sceneBounds) {
    using namespace detail::shadowvolume;
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

} // namespace voxfx
