// voxfx — exact glass: the reference on the triangles (Embree), voxfx/exact_glass.hpp.
#include "voxfx/exact_glass.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {

std::span<const OptionField<ExactGlassOptions>> ExactGlassOptions::fields() {
    using O = ExactGlassOptions;
    static const std::vector<OptionField<O>> table = {
        numberOption<O, &O::maxEvents>("maxEvents", "glass: refractions and reflections followed per ray", 1,
                                       1024),
        flagOption<O, &O::sceneBehind>(
            "sceneBehind", "glass: the light leaving it comes from the opaque scene (off: the environment)")};
    return table;
}

ExactGlass ExactGlass::build(const GlassInput& input, const ExactGlassOptions& options) {
    ExactGlass g(input.mesh, input.vertexNormals, input.triangleMedium, input.media);
    g.maxEvents_ = options.maxEvents;
    return g;
}

ExactGlass::ExactGlass(const MeshView& mesh, std::vector<Vec3f> vertexNormals,
                       std::vector<uint32_t> triangleMedium, std::vector<GlassMedium> media)
    : normals_(std::move(vertexNormals)), medium_(std::move(triangleMedium)), media_(std::move(media)) {
    validateMesh(mesh, "glass mesh");
    if (medium_.size() != mesh.triangleCount) fail("exact glass: one medium per triangle expected");
    if (!normals_.empty() && normals_.size() != mesh.vertexCount)
        fail("exact glass: one normal per vertex expected");
    for (const uint32_t m : medium_)
        if (m >= media_.size()) fail("exact glass: medium index ", m, " out of range");
    tracer_ = std::make_shared<const TriangleTracer>(mesh);
}

GlassPath ExactGlass::trace(const Vec3d& origin, const Vec3d& dir, int maxEvents) const {
    const Mesh& mesh = tracer_->mesh();
    const double epsilon = tracer_->epsilon();
    GlassPath p;
    Vec3d o = origin, d = normalize(dir);
    Vec3f thr{1, 1, 1};
    bool inside = false;
    uint32_t cur = 0;
    int crossings = 0; // every crossing, including ignored ones: bounds the loop
    while (true) {
        const TriangleTracer::Hit h =
            tracer_->intersect(o, d, epsilon, std::numeric_limits<double>::infinity());
        if (!h.hit) {
            p.exitPoint = o;
            p.exitDir = d;
            p.throughput = thr;
            return p;
        }
        const size_t t = h.triangle;
        const uint32_t ia = mesh.indices[3 * t], ib = mesh.indices[3 * t + 1], ic = mesh.indices[3 * t + 2];
        const Vec3d a(mesh.positions[ia]), b(mesh.positions[ib]), c(mesh.positions[ic]);
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
            p.truncate(x, d, thr);
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

} // namespace voxfx
