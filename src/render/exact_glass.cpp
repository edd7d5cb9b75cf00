// voxfx — exact glass: the reference on the triangles (Embree), voxfx/exact_glass.hpp.
#include "voxfx/exact_glass.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "render/media_stack.hpp"
#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx {

std::span<const OptionField<ExactGlassOptions>> ExactGlassOptions::fields() {
    using O = ExactGlassOptions;
    static const std::vector<OptionField<O>> table = {
        numberOption<O, &O::maxEvents>("maxEvents",
                                       "glass: refractions and reflections followed per ray (then it leaves "
                                       "along its current direction)",
                                       1, 1024),
        numberOption<O, &O::absorptionConstant>(
            "absorptionConstant",
            "glass (CHANG's absorption constant): every glass material's attenuation per world unit "
            "(KHR_materials_volume) times this (0: no absorption inside glass)",
            0, 1e6),
        flagOption<O, &O::sceneBehind>(
            "sceneBehind", "glass: the light leaving it comes from the opaque scene, traced exactly "
                           "(off: the environment alone after the last exit, as CHANG)")};
    return table;
}

namespace {

Vec3d outwardNormal(const Mesh& mesh, uint32_t t) {
    const uint32_t ia = mesh.indices[3 * t], ib = mesh.indices[3 * t + 1], ic = mesh.indices[3 * t + 2];
    const Vec3d a(mesh.positions[ia]), b(mesh.positions[ib]), c(mesh.positions[ic]);
    return normalize(cross(b - a, c - a));
}

} // namespace

// The medium's coarse occupancy (MediumTriangles::occupied): about kCellsPerAxis cells along the
// reach's longest side, as many along the others as keep them near cubes; each triangle's bounds
// grown by `grow` (three epsilons: the query reaches one) set the cells they overlap. Indices are
// clamped into the grid both here and in mayTouch, so a point on a cell's face is never lost.
void ExactGlass::markOccupied(MediumTriangles& mt, const Mesh& sub, double grow) {
    constexpr double kCellsPerAxis = 64;
    const Vec3d extent = mt.reach.extent();
    const double side = std::max({extent.x, extent.y, extent.z});
    if (!(side > 0)) return; // no grid: every crossing in reach is queried
    for (int k = 0; k < 3; ++k)
        mt.cells[size_t(k)] =
            std::clamp(int(std::ceil(kCellsPerAxis * extent[k] / side)), 1, int(kCellsPerAxis));
    const size_t nx = size_t(mt.cells[0]), ny = size_t(mt.cells[1]);
    mt.occupied.assign((nx * ny * size_t(mt.cells[2]) + 63) / 64, 0);
    for (size_t t = 0; t < sub.triangleCount(); ++t) {
        Box3d b;
        for (int k = 0; k < 3; ++k) b.extend(Vec3d(sub.positions[sub.indices[3 * t + size_t(k)]]));
        int lo[3], hi[3];
        for (int k = 0; k < 3; ++k) {
            lo[k] = mt.cellAlong(k, b.lo[k] - grow);
            hi[k] = mt.cellAlong(k, b.hi[k] + grow);
        }
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x) {
                    const size_t c = (size_t(z) * ny + size_t(y)) * nx + size_t(x);
                    mt.occupied[c / 64] |= uint64_t(1) << (c % 64);
                }
    }
}

int ExactGlass::MediumTriangles::cellAlong(int axis, double v) const {
    const int n = cells[size_t(axis)];
    return std::clamp(int(std::floor((v - reach.lo[axis]) * cellScale[axis])), 0, n - 1);
}

bool ExactGlass::MediumTriangles::mayTouch(const Vec3d& x) const {
    if (occupied.empty()) return true;
    const size_t c =
        (size_t(cellAlong(2, x.z)) * size_t(cells[1]) + size_t(cellAlong(1, x.y))) * size_t(cells[0]) +
        size_t(cellAlong(0, x.x));
    return (occupied[c / 64] >> (c % 64)) & 1;
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
    const Mesh& traced = tracer_->mesh();
    faces_.resize(medium_.size());
    for (uint32_t t = 0; t < medium_.size(); ++t) {
        Face& f = faces_[t];
        f.normal = outwardNormal(traced, t);
        f.corner = traced.positions[traced.indices[3 * size_t(t)]];
        f.medium = medium_[t];
        for (int k = 0; k < 3; ++k)
            f.vertexNormal[k] =
                normals_.empty() ? Vec3f{0, 0, 0} : normals_[traced.indices[3 * size_t(t) + size_t(k)]];
    }
    // Several media: each one's triangles in a tracer of their own, so that a face of another
    // medium lying on the face just hit (touching objects) is found however Embree orders them.
    std::vector<uint8_t> used(media_.size());
    for (const uint32_t m : medium_) used[m] = 1;
    if (std::count(used.begin(), used.end(), uint8_t(1)) < 2) return;
    for (uint32_t m = 0; m < media_.size(); ++m) {
        if (!used[m]) continue;
        MediumTriangles mt;
        mt.medium = m;
        const Mesh& all = tracer_->mesh();
        Mesh sub;
        sub.positions = all.positions;
        for (uint32_t t = 0; t < medium_.size(); ++t) {
            if (medium_[t] != m) continue;
            mt.triangle.push_back(t);
            for (int k = 0; k < 3; ++k) sub.indices.push_back(all.indices[3 * size_t(t) + size_t(k)]);
        }
        mt.tracer = std::make_shared<const TriangleTracer>(sub.view());
        mt.reach = computeBounds(sub.view());
        const double grow = 2 * tracer_->epsilon();
        mt.reach.lo = mt.reach.lo - Vec3d{grow, grow, grow};
        mt.reach.hi = mt.reach.hi + Vec3d{grow, grow, grow};
        markOccupied(mt, sub, 1.5 * grow);
        byMedium_.push_back(std::move(mt));
    }
}

namespace {

// The shading normal at hit h of face f (outward face normal f.normal): the vertex normals
// interpolated (on the face normal's side), or the face normal without them.
Vec3d shadingNormal(bool vertexNormals, const ExactGlass::Face& f, const TriangleTracer::Hit& h) {
    const Vec3d& ng = f.normal;
    if (!vertexNormals) return ng;
    const Vec3d ns = normalize(Vec3d(f.vertexNormal[0]) * (1 - h.u - h.v) + Vec3d(f.vertexNormal[1]) * h.u +
                               Vec3d(f.vertexNormal[2]) * h.v);
    if (!(length(ns) > 0)) return ng;
    return dot(ns, ng) < 0 ? -ns : ns;
}

// The surface the ray was last at (a plane through its origin): the next hit skips only faces lying
// on it (the triangle just crossed, its coplanar neighbours, a touching medium's face on it), never
// every hit within epsilon: a sheet thinner than epsilon, or a face meeting the one just crossed,
// is a surface of its own. From a surface the search starts 1/100 of epsilon along the ray
// (kSurfaceStart): started at 0, Embree found the triangle just crossed again, at a t of the
// origin's rounding, on 46 % of the glass demo's events, and each such hit cost a second query; a
// face closer than that to the crossing (1e-7 of the glass's diagonal) is passed.
class SurfaceSkip {
public:
    SurfaceSkip(const TriangleTracer& tracer, const std::vector<ExactGlass::Face>& faces)
        : tracer_(tracer), faces_(faces) {}

    // The ray's next hit from o along d, past faces of the last surface.
    TriangleTracer::Hit nextHit(const Vec3d& o, const Vec3d& d) const {
        const double epsilon = tracer_.epsilon();
        double tNear = onSurface_ ? kSurfaceStart * epsilon : 0;
        for (int skip = 0;; ++skip) {
            const TriangleTracer::Hit h =
                tracer_.intersect(o, d, tNear, std::numeric_limits<double>::infinity());
            if (!h.hit || !onSurface_ || h.t >= epsilon || skip >= 16 ||
                !liesOnSurface(h.triangle, o, o + d * h.t))
                return h;
            tNear = h.t + 1e-3 * epsilon;
        }
    }
    // The ray is now at a surface with outward face normal ng.
    void at(const Vec3d& ng) {
        onSurface_ = true;
        surfaceNormal_ = ng;
    }

private:
    static constexpr double kSurfaceStart = 1e-2;

    bool liesOnSurface(uint32_t t, const Vec3d& o, const Vec3d& at) const {
        const double planeTolerance = 0.1 * tracer_.epsilon();
        const Vec3d& nt = faces_[t].normal;
        if (std::abs(dot(nt, surfaceNormal_)) < 1 - 1e-6) return false;
        const Vec3d a(faces_[t].corner);
        return std::abs(dot(at - a, nt)) < planeTolerance && std::abs(dot(o - a, nt)) < planeTolerance;
    }

    const TriangleTracer& tracer_;
    const std::vector<ExactGlass::Face>& faces_;
    bool onSurface_ = false;
    Vec3d surfaceNormal_{0, 0, 1};
};

// One step of GlassPath::crossed's hash (splitmix64's finalizer over the running value and `v`).
uint64_t mixCrossed(uint64_t h, uint64_t v) {
    uint64_t z = h ^ (v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

} // namespace

void ExactGlass::facesAt(const Vec3d& x, const Vec3d& d, uint32_t t, std::vector<CrossedFace>& faces) const {
    const double epsilon = tracer_->epsilon();
    faces.assign(1, CrossedFace{faces_[t].medium, dot(d, faces_[t].normal) < 0});
    for (const MediumTriangles& mt : byMedium_) {
        if (mt.medium == faces_[t].medium) continue;
        // The query below spans x +- epsilon along d: none of the medium's triangles within reach
        // when x lies outside their bounds grown by twice that.
        const Box3d& r = mt.reach;
        if (x.x < r.lo.x || x.y < r.lo.y || x.z < r.lo.z || x.x > r.hi.x || x.y > r.hi.y || x.z > r.hi.z)
            continue;
        if (!mt.mayTouch(x)) continue;
        const TriangleTracer::Hit c = mt.tracer->intersect(x - d * epsilon, d, 0, 2 * epsilon);
        if (c.hit) {
            const uint32_t ct = mt.triangle[c.triangle];
            faces.push_back({faces_[ct].medium, dot(d, faces_[ct].normal) < 0});
        }
    }
}

GlassPath ExactGlass::trace(const Vec3d& origin, const Vec3d& dir, int maxEvents) const {
    GlassPath p;
    Vec3d o = origin, d = normalize(dir);
    Vec3f thr{1, 1, 1};
    detail::MediaStack stack(media_), next(media_);
    SurfaceSkip skip(*tracer_, faces_);
    std::vector<CrossedFace> faces;
    int crossings = 0; // every crossing, including ignored ones: bounds the loop
    while (true) {
        const TriangleTracer::Hit h = skip.nextHit(o, d);
        if (!h.hit) {
            p.exitPoint = o;
            p.exitDir = d;
            p.throughput = thr;
            return p;
        }
        const Face& face = faces_[h.triangle];
        const Vec3d& ng = face.normal;
        const Vec3d n = shadingNormal(!normals_.empty(), face, h);
        const Vec3d x = o + d * h.t;
        thr = thr * stack.attenuation(h.t);
        o = x;
        skip.at(ng);
        if (++crossings > 4 * maxEvents + 8 || p.events >= maxEvents) {
            if (!p.hit) return p;
            p.truncate(x, d, thr);
            return p;
        }
        // Every face at this point (within epsilon): the one hit and those of other media lying on it
        // (two objects touching). They are crossed together, as one interface.
        facesAt(x, d, h.triangle, faces);
        Vec3f tint{1, 1, 1};
        if (!mediaAfter(faces, stack, next, tint)) continue;
        // Facing the ray: the shading normal unless it faces away (grazing), then the face's.
        const Vec3d nf = dot(d, ng) < 0 ? (dot(d, n) < 0 ? n : ng) : (dot(d, n) > 0 ? -n : -ng);
        const double etaFrom = stack.current().ior, etaTo = next.current().ior;
        const double F = fresnelDielectric(-dot(d, nf), etaFrom, etaTo);
        if (!p.hit) {
            p.hit = true;
            p.reflectDir = reflectDirection(d, nf);
            p.reflectance = float(F);
        }
        Vec3d r;
        const bool refracted = refractDirection(d, nf, etaFrom / etaTo, r);
        if (refracted) {
            thr = thr * tint * float(1 - F);
            d = r;
            std::swap(stack, next);
        } else {
            d = reflectDirection(d, nf); // total internal reflection: the ray stays where it was
        }
        for (const CrossedFace& f : faces)
            p.crossed = mixCrossed(p.crossed, 2 * uint64_t(f.medium) + f.entering);
        p.crossed = mixCrossed(p.crossed, refracted ? ~uint64_t(0) : ~uint64_t(1));
        ++p.events;
    }
}

bool ExactGlass::mediaAfter(const std::vector<CrossedFace>& faces, const detail::MediaStack& stack,
                            detail::MediaStack& next, Vec3f& tint) const {
    // Leave first (the innermost copy of each medium left), then enter. A face that leaves a medium
    // the ray is not in (an open mesh's back face seen from outside) is passed through.
    next = stack;
    bool changed = false;
    for (const CrossedFace& f : faces)
        if (!f.entering && next.leave(f.medium)) changed = true;
    for (const CrossedFace& f : faces) {
        if (!f.entering) continue;
        next.enter(f.medium);
        tint = tint * media_[f.medium].tint;
        changed = true;
    }
    return changed;
}

} // namespace voxfx
