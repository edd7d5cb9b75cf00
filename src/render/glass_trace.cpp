// voxfx — glass paths: the exact reference on the triangles (Embree) and the voxel march through an
// attribute grid (CHANG §4.1.1 multiple refraction; Wyman's two-surface refraction as its baseline).
// See voxfx/glass.hpp for the model both follow.
#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/dda.hpp"
#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"

namespace voxfx {

namespace {

// A path that stopped after maxEvents: it leaves along its current direction with what it carries
// (black pixels where a ray is trapped by total internal reflection would be a worse guess).
void glassTruncate(GlassPath& p, const Vec3d& at, const Vec3d& dir, const Vec3f& throughput) {
    p.truncated = true;
    p.exitPoint = at;
    p.exitDir = dir;
    p.throughput = throughput;
}

} // namespace

GlassMedium glassMedium(const Material& m) {
    GlassMedium g;
    g.ior = std::max(1.0f, m.ior);
    g.sigma = attenuationCoefficient(m);
    g.tint = m.baseColor;
    return g;
}

// ---- exact --------------------------------------------------------------------------------------

ExactGlass::ExactGlass(const MeshView& mesh, std::vector<Vec3f> vertexNormals,
                       std::vector<uint32_t> triangleMedium, std::vector<GlassMedium> media)
    : normals_(std::move(vertexNormals)), medium_(std::move(triangleMedium)), media_(std::move(media)) {
    validateMesh(mesh, "glass mesh");
    if (medium_.size() != mesh.triangleCount) fail("exact glass: one medium per triangle expected");
    if (!normals_.empty() && normals_.size() != mesh.vertexCount)
        fail("exact glass: one normal per vertex expected");
    for (const uint32_t m : medium_)
        if (m >= media_.size()) fail("exact glass: medium index ", m, " out of range");
    mesh_.positions.resize(mesh.vertexCount);
    for (size_t i = 0; i < mesh.vertexCount; ++i) mesh_.positions[i] = Vec3f(mesh.vertex(i));
    mesh_.indices.assign(mesh.indices, mesh.indices + 3 * mesh.triangleCount);
    const Box3d box = computeBounds(mesh);
    epsilon_ = box.empty() ? 1e-6 : std::max(1e-9, 1e-5 * length(box.extent()));
    tracer_ = std::make_unique<TriangleTracer>(mesh_.view());
}

GlassPath ExactGlass::trace(const Vec3d& origin, const Vec3d& dir, int maxEvents) const {
    GlassPath p;
    Vec3d o = origin, d = normalize(dir);
    Vec3f thr{1, 1, 1};
    bool inside = false;
    uint32_t cur = 0;
    int crossings = 0; // every crossing, including ignored ones: bounds the loop
    while (true) {
        const TriangleTracer::Hit h =
            tracer_->intersect(o, d, epsilon_, std::numeric_limits<double>::infinity());
        if (!h.hit) {
            p.exitPoint = o;
            p.exitDir = d;
            p.throughput = thr;
            return p;
        }
        const size_t t = h.triangle;
        const uint32_t ia = mesh_.indices[3 * t], ib = mesh_.indices[3 * t + 1],
                       ic = mesh_.indices[3 * t + 2];
        const Vec3d a(mesh_.positions[ia]), b(mesh_.positions[ib]), c(mesh_.positions[ic]);
        const Vec3d ng = normalize(cross(b - a, c - a)); // outward
        Vec3d n = ng;
        if (!normals_.empty()) {
            const Vec3d ns = normalize(Vec3d(normals_[ia]) * (1 - h.u - h.v) + Vec3d(normals_[ib]) * h.u +
                                       Vec3d(normals_[ic]) * h.v);
            if (length(ns) > 0) n = dot(ns, ng) < 0 ? -ns : ns;
        }
        const Vec3d x = o + d * h.t;
        if (inside) thr = thr * beerLambert(media_[cur].sigma, h.t);
        o = x;
        if (++crossings > 4 * maxEvents + 8 || p.events >= maxEvents) {
            if (!p.hit) return p;
            glassTruncate(p, x, d, thr);
            return p;
        }
        const bool entering = dot(d, ng) < 0;
        if (entering) {
            // Facing the ray: the shading normal unless it faces away (grazing), then the face's.
            const Vec3d nf = dot(d, n) < 0 ? n : ng;
            const GlassMedium& m = media_[medium_[t]];
            const double F = fresnelDielectric(-dot(d, nf), 1.0, m.ior);
            if (!p.hit) {
                p.hit = true;
                p.reflectDir = reflectDirection(d, nf);
                p.reflectance = float(F);
            }
            Vec3d r;
            if (!refractDirection(d, nf, 1.0 / m.ior, r))
                r = reflectDirection(d, nf); // cannot happen for ior>=1
            thr = thr * m.tint * float(1 - F);
            d = r;
            inside = true;
            cur = medium_[t];
        } else {
            if (!inside) continue; // a back face seen from outside (open mesh): pass through
            const Vec3d nf = dot(d, n) > 0 ? -n : -ng; // facing the ray, into the glass
            const GlassMedium& m = media_[cur];
            Vec3d r;
            if (refractDirection(d, nf, m.ior, r)) {
                thr = thr * float(1 - fresnelDielectric(-dot(d, nf), m.ior, 1.0));
                d = r;
                inside = false;
            } else {
                d = reflectDirection(d, nf); // total internal reflection
            }
        }
        ++p.events;
    }
}

// ---- voxels -------------------------------------------------------------------------------------

VoxelGlass::VoxelGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium,
                       std::vector<GlassMedium> media, const GlassOptions& options)
    : media_(std::move(media)) {
    validateMesh(mesh, "glass mesh");
    if (triangleMedium.size() != mesh.triangleCount) fail("voxel glass: one medium per triangle expected");
    for (const uint32_t m : triangleMedium)
        if (m >= media_.size()) fail("voxel glass: medium index ", m, " out of range");
    if (options.gridResolution < 2 || options.gridResolution > 4096)
        fail("glass grid resolution must be between 2 and 4096, got ", options.gridResolution);
    const Box3d box = computeBounds(mesh);
    if (box.empty()) fail("voxel glass: no triangles");
    const int64_t n = options.gridResolution;
    const double longest = std::max({box.extent().x, box.extent().y, box.extent().z, 1e-12});
    // One voxel of margin on each side: n - 2 voxels span the longest side.
    voxel_ = longest / double(n - 2);
    int64_t dims[3];
    Box3d grid;
    for (int a = 0; a < 3; ++a) {
        dims[a] = std::min<int64_t>(n, int64_t(std::ceil(box.extent()[a] / voxel_)) + 2);
        const double centre = 0.5 * (box.lo[a] + box.hi[a]);
        grid.lo[a] = centre - 0.5 * double(dims[a]) * voxel_;
        grid.hi[a] = centre + 0.5 * double(dims[a]) * voxel_;
    }
    origin_ = grid.lo;
    AttributeOptions ao;
    ao.coverage = options.coverage;
    ao.channels = AttributeChannels::glass(); // normals and material id: 16 bytes per voxel
    ao.triangleMaterial = triangleMedium;
    grid_ = voxelizeAttributes(mesh, Frame::orthographic(grid, Axis::Z, dims[0], dims[1], dims[2]), {}, ao);
}

GlassPath VoxelGlass::trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir,
                            const GlassOptions& options) const {
    GlassPath p;
    p.hit = true;
    Vec3d d = normalize(dir);
    Vec3d n0 = normalize(normal);
    if (dot(d, n0) > 0) n0 = -n0; // the entry normal faces the ray
    const GlassMedium& m0 = media_[std::min<size_t>(medium, media_.size() - 1)];
    const double F0 = fresnelDielectric(-dot(d, n0), 1.0, m0.ior);
    p.reflectDir = reflectDirection(d, n0);
    p.reflectance = float(F0);
    Vec3d r;
    if (!refractDirection(d, n0, 1.0 / m0.ior, r)) r = p.reflectDir;
    d = r;
    Vec3f thr = m0.tint * float(1 - F0);
    p.events = 1;
    bool inside = true;
    const GlassMedium* cur = &m0;
    Vec3d lastNormal = n0; // the entry surface's outward normal (it faces the incoming ray)
    const double cosThreshold = std::cos(options.angleThreshold);
    const int64_t dims[3] = {grid_.frame.width(), grid_.frame.height(), grid_.frame.depth()};
    const int64_t D = dims[2];
    Vec3d pos = entry;
    bool stop = false;
    while (!stop) {
        const Vec3d g = (pos - origin_) / voxel_;
        const DdaClip clip = clipToGrid(g, d, dims, 0.0, std::numeric_limits<double>::infinity());
        if (clip.empty()) break;
        Dda walk = Dda::start(g, d, dims, clip.t0);
        double tEnter = clip.t0;
        bool restarted = false;
        while (true) {
            const int axis = walk.nextAxis();
            const double tLeave = std::min(walk.tMax[axis], clip.t1);
            const int64_t i = (walk.cell[1] * dims[0] + walk.cell[0]) * D + walk.cell[2];
            if (grid_.written(i)) {
                const Vec3d n = Vec3d(grid_.normal(i));
                const double dn = dot(d, n);
                const bool candidate =
                    length(n) > 0 && (inside ? dn > 0 : dn < 0) && dot(n, lastNormal) < cosThreshold;
                if (candidate) {
                    if (p.events >= options.maxEvents) {
                        glassTruncate(p, origin_ + (g + d * tEnter) * voxel_, d, thr);
                        return p;
                    }
                    const double tEvent = 0.5 * (tEnter + tLeave);
                    if (inside) thr = thr * beerLambert(cur->sigma, (tEvent - tEnter) * voxel_);
                    pos = origin_ + (g + d * tEvent) * voxel_;
                    ++p.events;
                    if (inside) {
                        const Vec3d nf = -n;
                        if (refractDirection(d, nf, cur->ior, r)) {
                            thr = thr * float(1 - fresnelDielectric(-dot(d, nf), cur->ior, 1.0));
                            d = r;
                            inside = false;
                        } else {
                            d = reflectDirection(d, nf);
                        }
                        if (options.kind == GlassKind::TwoSurface) stop = true; // Wyman: one back surface
                    } else {
                        const uint32_t mid = grid_.material.empty() ? medium : grid_.material[size_t(i)];
                        cur = &media_[std::min<size_t>(mid, media_.size() - 1)];
                        const double F = fresnelDielectric(-dn, 1.0, cur->ior);
                        if (!refractDirection(d, n, 1.0 / cur->ior, r)) r = reflectDirection(d, n);
                        thr = thr * cur->tint * float(1 - F);
                        d = r;
                        inside = true;
                    }
                    lastNormal = n;
                    restarted = true;
                    break;
                }
            }
            if (inside) thr = thr * beerLambert(cur->sigma, (tLeave - tEnter) * voxel_);
            tEnter = tLeave;
            if (tLeave >= clip.t1 || !walk.advance(axis)) {
                pos = origin_ + (g + d * tLeave) * voxel_;
                break;
            }
        }
        if (!restarted) break;
    }
    p.exitPoint = pos;
    p.exitDir = d;
    p.throughput = thr;
    return p;
}

} // namespace voxfx
