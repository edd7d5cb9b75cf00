// voxfx — the march of the voxel glass methods (voxfx/voxel_glass.hpp): a ray refracted at the
// surface the rasterizer found walks the attribute grid voxel by voxel (CHANG §4.1.1) and refracts
// where it crosses a boundary voxel. The walk is VoxelGlass::March::walkSegment; every kind of voxel
// it meets that is not one plain surface has a function of its own below:
//
//   throughSheet        a sheet thinner than a voxel, met from outside (in and out within the voxel)
//   throughFace         the face between two touching media, met from within one of them
//   atSurface           a boundary voxel of one surface (or the far face of a sheet): enter or leave
//     creaseCrossing    a voxel on the edge of two faces (a box's edge), whose normal is no face's
//     touchedAtCornerOnly  a voxel the surface touches only at a corner the ray does not pass
//
// The media the ray is in are a detail::MediaStack, as in exact glass and exact shadows.
#include <algorithm>
#include <cmath>
#include <limits>

#include "render/media_stack.hpp"
#include "voxfx/dda.hpp"
#include "voxfx/voxel_glass.hpp"

namespace voxfx {

namespace voxel_glass_detail {

// Neighbouring voxels whose normals differ from the crossing voxel's by more than this are another
// surface (a crease, as the renderer's crease angle: a box's side is not blended into its bottom).
const double kCosBlend = std::cos(30 * M_PI / 180);

// The most voxels past the first that the run of a surface's voxels along the ray is followed for.
constexpr int kMaxRun = 6;

// What was written into a voxel, told by its write count and the length of its sum of unit normals:
// nothing; both faces of a sheet thinner than the voxel (the normals cancel: the length is below
// half the writes); faces of two surfaces meeting at a crease, a box's edge (the length is below
// cos 30 degrees of the writes: the faces lie further from their mean than the normal
// interpolation blends, so the mean is no face's normal; a box's edge voxel holds the 45-degree
// mean of its side and bottom); or one surface. A voxel two materials wrote (twoMaterials, one byte
// per voxel or empty) is one surface: its normals cancel, but it is no sheet (see throughFace).
enum class VoxelKind : uint8_t { Empty, Sheet, Crease, Surface };
VoxelKind voxelKind(const AttributeGrid& grid, const std::vector<uint8_t>& twoMaterials, int64_t i) {
    if (!grid.written(i)) return VoxelKind::Empty;
    if (grid.count.empty() || grid.count[size_t(i)] < 2 || (!twoMaterials.empty() && twoMaterials[size_t(i)]))
        return VoxelKind::Surface;
    const double sum = length(Vec3d(grid.normalSum[size_t(i)])), writes = double(grid.count[size_t(i)]);
    if (sum < 0.5 * writes) return VoxelKind::Sheet;
    if (sum < kCosBlend * writes) return VoxelKind::Crease;
    return VoxelKind::Surface;
}

// The unit normal at grid point g of the surface whose voxel there has the unit normal `own`:
// trilinear over the eight voxel centres around g, weighting the normals normalOf(voxel index)
// gives (zero: not the surface's) that lie within 30 degrees of `own` (the others lie outside the
// surface's layer or belong to another surface); `own` where none does.
template <class NormalOf>
Vec3d trilinearNormal(const Frame& frame, const Vec3d& g, const Vec3d& own, NormalOf normalOf) {
    const int64_t dims[3] = {frame.width(), frame.height(), frame.depth()};
    const Vec3d b{std::floor(g.x - 0.5), std::floor(g.y - 0.5), std::floor(g.z - 0.5)};
    const Vec3d f = g - Vec3d{0.5, 0.5, 0.5} - b;
    Vec3d sum{0, 0, 0};
    for (int k = 0; k < 8; ++k) {
        const int64_t c[3] = {int64_t(b.x) + (k & 1), int64_t(b.y) + ((k >> 1) & 1),
                              int64_t(b.z) + ((k >> 2) & 1)};
        if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= dims[0] || c[1] >= dims[1] || c[2] >= dims[2])
            continue;
        const Vec3d n = normalOf((c[1] * dims[0] + c[0]) * dims[2] + c[2]);
        if (!(length(n) > 0) || dot(n, own) < kCosBlend) continue;
        const double w =
            ((k & 1) ? f.x : 1 - f.x) * (((k >> 1) & 1) ? f.y : 1 - f.y) * (((k >> 2) & 1) ? f.z : 1 - f.z);
        sum = sum + n * w;
    }
    const double len = length(sum);
    return len > 1e-12 ? sum / len : own;
}

// trilinearNormal over the written voxels of `material`.
Vec3d normalAt(const AttributeGrid& grid, const Vec3d& g, uint32_t material, const Vec3d& own) {
    return trilinearNormal(grid.frame, g, own, [&](int64_t i) {
        if (!grid.written(i) || (!grid.material.empty() && grid.material[size_t(i)] != material))
            return Vec3d{0, 0, 0};
        return Vec3d(grid.normal(i));
    });
}
} // namespace voxel_glass_detail

using voxel_glass_detail::VoxelKind;

// As normalAt, for the face between two touching media: lo's normal over the face's voxels of the
// same two media around g.
Vec3d VoxelGlass::interfaceNormalAt(const Vec3d& g, const Interface& own) const {
    return voxel_glass_detail::trilinearNormal(grid_.frame, g, Vec3d(own.normalLo), [&](int64_t i) {
        const Interface* near = interfaceAt(i);
        return near && near->between && near->lo == own.lo && near->hi == own.hi ? Vec3d(near->normalLo)
                                                                                 : Vec3d{0, 0, 0};
    });
}

// One ray's march: its state between the voxels it walks.
struct VoxelGlass::March {
    // What a voxel did to the ray: nothing special (it goes on through the voxel, attenuated by the
    // medium it is in), passed (the voxel's attenuation is accounted for), turned (an event changed
    // its direction: the walk starts again from pos), or truncated at maxEvents (p is final).
    enum class Step : uint8_t { Through, Passed, Turned, Truncated };

    // The voxel the walk is in and what was written there.
    struct Cell {
        int axis;      // the axis the walk leaves it by
        double tLeave; // where it leaves it (grid units along d from g)
        int64_t i;
        bool written;
        uint32_t material;    // its medium (0 where nothing was written)
        Vec3d sum;            // its sum of unit normals
        VoxelKind kind;       // what was written (voxelKind)
        const Interface* two; // where two materials wrote it: their interface, else null
        bool insideMaterial;  // the ray is in its material (for `two`: in either of the two)
    };

    March(const VoxelGlass& glass, uint32_t medium, const VoxelGlassOptions& options, bool twoSurface)
        : glass(glass), grid(glass.grid_), options(options), twoSurface(twoSurface),
          medium(uint32_t(std::min<size_t>(medium, glass.media_.size() - 1))),
          cosThreshold(std::cos(options.angleThreshold)), stack(glass.media_) {
        dims[0] = grid.frame.width();
        dims[1] = grid.frame.height();
        dims[2] = grid.frame.depth();
    }

    GlassPath run(const Vec3d& entry, const Vec3d& normal, const Vec3d& dir);
    void enter(const Vec3d& entry, const Vec3d& normal, const Vec3d& dir);
    Step walkSegment();
    Cell cellAt(int axis) const;
    Step throughSheet(const Cell& c, double tEnter);
    Step throughFace(const Cell& c, double tEnter);
    Step atSurface(const Cell& c, double tEnter);
    bool crosses(const Cell& c, const Vec3d& nv) const;
    template <class Visit> void alongRay(const Cell& c, Visit&& visit) const;
    bool creaseCrossing(const Cell& c, bool leaving, Vec3d& n) const;
    bool touchedAtCornerOnly(const Cell& c, bool leaving, const Vec3d& n) const;
    Step refract(const Cell& c, double tEnter, bool leaving, const Vec3d& n);
    int64_t index(const Dda& at) const { return (at.cell[1] * dims[0] + at.cell[0]) * dims[2] + at.cell[2]; }
    Vec3d world(double t) const { return glass.origin_ + (g + d * t) * glass.voxel_; }
    Step truncate(double t) {
        p.truncate(world(t), d, thr);
        return Step::Truncated;
    }

    const VoxelGlass& glass;
    const AttributeGrid& grid;
    const VoxelGlassOptions& options;
    const bool twoSurface;
    const uint32_t medium; // the entry medium, every voxel's where the grid has no material channel
    const double cosThreshold;
    int64_t dims[3];

    GlassPath p;
    Vec3d d;   // the ray's direction
    Vec3f thr; // what it carries
    Vec3d pos; // where the current segment starts (world)
    // Where the light leaving the glass is looked up from (the renderer's exact scene cast): the
    // start of the boundary voxel where the ray last left glass, still on the glass's side of the
    // surface, or, while the ray is inside glass, the last event. Never the grid's edge: the grid
    // reaches a voxel beyond the glass, below the ground under glass standing on it, and the cast
    // from there met only the environment.
    Vec3d castFrom;
    // The media the ray is in. Material-id transitions at boundary voxels change it: a voxel whose
    // normal faces the ray enters its material, one whose normal points along the ray leaves it (or,
    // where its material is not one the ray is in, the innermost medium: the boundary still says
    // the ray leaves something).
    detail::MediaStack stack;
    Vec3d lastNormal;      // the outward normal of the surface last crossed (it faced the ray)
    uint32_t lastMaterial; // the material of that surface
    // A sheet thinner than a voxel: its front and back faces write the same voxels, whose normals
    // cancel. The sheet's voxels along the ray, and any other of its material's, are the same sheet
    // until the ray reaches a voxel nothing (or another material) wrote.
    bool inSheet = false;
    uint32_t sheetMaterial = 0;
    bool stop = false; // two-surface: the first back surface was crossed

    // The segment being walked: from grid point g along d, clipped to the grid.
    Vec3d g;
    DdaClip clip;
    Dda walk;
};

GlassPath VoxelGlass::trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir,
                            const VoxelGlassOptions& options, bool twoSurface) const {
    March march(*this, medium, options, twoSurface);
    return march.run(entry, normal, dir);
}

GlassPath VoxelGlass::March::run(const Vec3d& entry, const Vec3d& normal, const Vec3d& dir) {
    enter(entry, normal, dir);
    while (!stop) {
        const Step s = walkSegment();
        if (s == Step::Truncated) return p;
        if (s != Step::Turned) break;
    }
    p.exitPoint = castFrom;
    p.exitDir = d;
    p.throughput = thr;
    return p;
}

// The refraction at the surface the rasterizer found: Fresnel and Snell into the entry medium.
void VoxelGlass::March::enter(const Vec3d& entry, const Vec3d& normal, const Vec3d& dir) {
    p.hit = true;
    d = normalize(dir);
    Vec3d n0 = normalize(normal);
    if (dot(d, n0) > 0) n0 = -n0; // the entry normal faces the ray
    const GlassMedium& m0 = glass.media_[medium];
    const double F0 = fresnelDielectric(-dot(d, n0), 1.0, m0.ior);
    p.reflectDir = reflectDirection(d, n0);
    p.reflectance = float(F0);
    Vec3d r;
    if (!refractDirection(d, n0, 1.0 / m0.ior, r)) r = p.reflectDir;
    d = r;
    thr = m0.tint * float(1 - F0);
    p.events = 1;
    stack.enter(medium);
    lastNormal = n0; // the entry surface's outward normal (it faces the incoming ray)
    lastMaterial = medium;
    pos = entry;
    castFrom = entry;
}

// The walk: voxel after voxel from pos along d until the ray leaves the grid (Passed: done), turns
// at an event (Turned: walk again from the new pos) or reaches maxEvents (Truncated).
VoxelGlass::March::Step VoxelGlass::March::walkSegment() {
    g = (pos - glass.origin_) / glass.voxel_;
    clip = clipToGrid(g, d, dims, 0.0, std::numeric_limits<double>::infinity());
    if (clip.empty()) return Step::Passed;
    walk = Dda::start(g, d, dims, clip.t0);
    double tEnter = clip.t0;
    while (true) {
        const Cell c = cellAt(walk.nextAxis());
        if (!c.written || c.material != sheetMaterial) inSheet = false;
        Step s = Step::Through;
        if (c.kind == VoxelKind::Sheet && !inSheet && !c.insideMaterial)
            s = throughSheet(c, tEnter);
        else if (!inSheet && c.two && c.two->between && c.insideMaterial)
            s = throughFace(c, tEnter);
        else if (c.written && !inSheet)
            s = atSurface(c, tEnter);
        if (s == Step::Turned || s == Step::Truncated) return s;
        if (s == Step::Through) thr = thr * stack.attenuation((c.tLeave - tEnter) * glass.voxel_);
        tEnter = c.tLeave;
        if (c.tLeave >= clip.t1 || !walk.advance(c.axis)) {
            pos = world(c.tLeave);
            return Step::Passed;
        }
    }
}

VoxelGlass::March::Cell VoxelGlass::March::cellAt(int axis) const {
    Cell c;
    c.axis = axis;
    c.tLeave = std::min(walk.tMax[axis], clip.t1);
    c.i = index(walk);
    c.written = grid.written(c.i);
    c.material = c.written
                     ? uint32_t(std::min<size_t>(grid.material.empty() ? medium : grid.material[size_t(c.i)],
                                                 glass.media_.size() - 1))
                     : 0;
    c.sum = c.written ? Vec3d(grid.normalSum[size_t(c.i)]) : Vec3d{0, 0, 0};
    c.kind = voxel_glass_detail::voxelKind(grid, glass.twoMaterials_, c.i);
    // A voxel two materials wrote: where the ray is in either, it is inside the voxel's material
    // (the outer faces of two touching glasses share voxels along the edge of their face).
    c.two = c.written && !glass.twoMaterials_.empty() && glass.twoMaterials_[size_t(c.i)]
                ? glass.interfaceAt(c.i)
                : nullptr;
    c.insideMaterial =
        !stack.empty() && (stack.innermost() == c.material || (c.two && stack.innermost() == c.two->hi));
    return c;
}

// A sheet thinner than a voxel met from outside its material: the ray enters and leaves within the
// voxel (two Fresnel passes, the sheet's attenuation over half a voxel, its direction unchanged: a
// parallel-faced sheet).
VoxelGlass::March::Step VoxelGlass::March::throughSheet(const Cell& c, double tEnter) {
    if (p.events + 2 > options.maxEvents) return truncate(tEnter);
    const GlassMedium& sheet = stack.medium(c.material);
    const double sl = length(c.sum);
    const Vec3d across = sl > 1e-9 ? c.sum / sl : d;
    const double cosIn = std::min(1.0, std::fabs(dot(d, across)));
    const double etaOut = stack.current().ior, etaIn = sheet.ior;
    const double sinT = etaOut / etaIn * std::sqrt(std::max(0.0, 1 - cosIn * cosIn));
    const double cosT = std::sqrt(std::max(0.0, 1 - sinT * sinT));
    // The medium around the sheet over the whole voxel segment, the sheet itself over half a voxel
    // along the refracted direction inside it.
    thr =
        thr * stack.attenuation((c.tLeave - tEnter) * glass.voxel_) * sheet.tint *
        float((1 - fresnelDielectric(cosIn, etaOut, etaIn)) * (1 - fresnelDielectric(cosT, etaIn, etaOut))) *
        beerLambert(sheet.sigma, 0.5 * glass.voxel_ / std::max(cosT, 0.1));
    p.events += 2;
    inSheet = true;
    sheetMaterial = c.material;
    return Step::Passed;
}

// The face between two touching media, met from within one of them: the ray crosses into the other
// where it heads out of the one it is in (n_from / n_to, the tint of the medium entered), and passes
// the face's voxels otherwise (it crossed already, or runs away from the face). Not atSurface's
// test: the voxel's normals cancel.
VoxelGlass::March::Step VoxelGlass::March::throughFace(const Cell& c, double tEnter) {
    const Interface& face = *c.two;
    if (!(length(Vec3d(face.normalLo)) > 0)) return atSurface(c, tEnter);
    const bool fromLo = stack.innermost() == face.lo;
    const uint32_t to = uint32_t(std::min<size_t>(fromLo ? face.hi : face.lo, glass.media_.size() - 1));
    const double tMid = 0.5 * (tEnter + c.tLeave);
    const Vec3d nOut = glass.interfaceNormalAt(g + d * tMid, face) * (fromLo ? 1.0 : -1.0);
    if (!(dot(d, nOut) > 0)) return Step::Through;
    if (p.events >= options.maxEvents) return truncate(tEnter);
    thr = thr * stack.attenuation((tMid - tEnter) * glass.voxel_);
    pos = world(tMid);
    castFrom = pos;
    ++p.events;
    const double etaFrom = stack.current().ior, etaTo = stack.medium(to).ior;
    Vec3d r;
    if (refractDirection(d, -nOut, etaFrom / etaTo, r)) {
        thr = thr * stack.medium(to).tint * float(1 - fresnelDielectric(dot(d, nOut), etaFrom, etaTo));
        d = r;
        stack.replaceInnermost(to);
        lastNormal = -nOut; // the entered medium's outward normal there
        lastMaterial = to;
    } else {
        d = reflectDirection(d, -nOut); // total internal reflection
        lastNormal = nOut;
        lastMaterial = stack.innermost();
    }
    return Step::Turned;
}

// Whether the ray crosses a surface of the voxel's material with normal nv here. Leaving needs a
// medium to leave; entering a material the ray is already in is the same surface seen again. The
// angle threshold guards against refracting twice at one surface spread over neighbouring voxels: a
// surface of another material is another surface (an embedded object's faces can be nearly
// parallel to the one just crossed).
bool VoxelGlass::March::crosses(const Cell& c, const Vec3d& nv) const {
    const double dv = dot(d, nv);
    const bool out = dv > 0 && !stack.empty();
    const bool in = dv < 0 && !c.insideMaterial;
    return length(nv) > 0 && (out || in) &&
           (c.material != lastMaterial || dot(nv, lastNormal) < cosThreshold);
}

// The voxels after c along the ray while they are written with its material (up to kMaxRun of
// them): visit(j, the parameter where the ray leaves j) returns false to stop.
template <class Visit> void VoxelGlass::March::alongRay(const Cell& c, Visit&& visit) const {
    Dda look = walk;
    int lookAxis = c.axis;
    double tLook = c.tLeave;
    for (int k = 0; k < voxel_glass_detail::kMaxRun && tLook < clip.t1 && look.advance(lookAxis); ++k) {
        const int64_t j = index(look);
        if (!grid.written(j) || (!grid.material.empty() && grid.material[size_t(j)] != c.material)) return;
        lookAxis = look.nextAxis();
        tLook = std::min(look.tMax[lookAxis], clip.t1);
        if (!visit(j, tLook)) return;
    }
}

// A boundary voxel of one surface, or of a sheet met from inside its material (its far face):
// the ray enters the voxel's material where the surface faces it, leaves where it faces along the
// ray, unless it is the surface just crossed, or a crease or a corner voxel says the crossing lies
// elsewhere.
VoxelGlass::March::Step VoxelGlass::March::atSurface(const Cell& c, double tEnter) {
    Vec3d n = Vec3d(grid.normal(c.i));
    if (c.kind == VoxelKind::Sheet && c.insideMaterial) {
        // The sheet's far face: parallel to the face the ray entered by, else along the voxel's
        // remaining normal, facing away from the ray.
        const double sl = length(c.sum);
        n = lastMaterial == c.material ? -lastNormal : (sl > 1e-9 ? c.sum / sl : d);
        if (dot(d, n) <= 0) n = -n;
        inSheet = true;
        sheetMaterial = c.material;
    }
    bool candidate = crosses(c, n);
    const bool leaving = dot(d, n) > 0 && !stack.empty();
    if (candidate && c.kind == VoxelKind::Crease) candidate = creaseCrossing(c, leaving, n);
    if (candidate && c.kind == VoxelKind::Surface) candidate = !touchedAtCornerOnly(c, leaving, n);
    if (!candidate) return Step::Through;
    if (p.events >= options.maxEvents) return truncate(tEnter);
    return refract(c, tEnter, leaving, n);
}

// A crease voxel's normal is the mean of two surfaces' (a box's edge: 45 degrees between its side
// and its bottom), a face that is not there: a ray reflected by a glass cube's side towards its
// bottom edge was reflected again there, and left upwards through the far side. Where the ray goes
// on into a voxel of one surface that it crosses, the crossing is there: this voxel is passed
// (false). Otherwise (the ray runs along the edge and out), leaving, it takes the normal n of the
// neighbouring one-surface voxel whose normal is closest to the ray's direction: the face it heads
// into most directly, which it meets first leaving a convex edge from within a voxel of both faces.
bool VoxelGlass::March::creaseCrossing(const Cell& c, bool leaving, Vec3d& n) const {
    bool surfaceAhead = false;
    alongRay(c, [&](int64_t j, double) {
        const VoxelKind kj = voxel_glass_detail::voxelKind(grid, glass.twoMaterials_, j);
        if (kj == VoxelKind::Crease) return true;
        surfaceAhead = kj == VoxelKind::Surface && crosses(c, Vec3d(grid.normal(j)));
        return false;
    });
    if (surfaceAhead) return false;
    if (!leaving) return true;
    double best = 0;
    for (int k = 0; k < 27; ++k) {
        const int64_t at[3] = {walk.cell[0] + k % 3 - 1, walk.cell[1] + (k / 3) % 3 - 1,
                               walk.cell[2] + k / 9 - 1};
        if (k == 13 || at[0] < 0 || at[1] < 0 || at[2] < 0 || at[0] >= dims[0] || at[1] >= dims[1] ||
            at[2] >= dims[2])
            continue;
        const int64_t j = (at[1] * dims[0] + at[0]) * dims[2] + at[2];
        if (voxel_glass_detail::voxelKind(grid, glass.twoMaterials_, j) != VoxelKind::Surface ||
            (!grid.material.empty() && grid.material[size_t(j)] != c.material))
            continue;
        const Vec3d nj(grid.normal(j));
        if (dot(d, nj) > best) {
            best = dot(d, nj);
            n = nj;
        }
    }
    return true;
}

// A voxel the surface touches only at a corner the ray does not pass: the ray goes on into voxels
// nothing wrote (still on this side of the surface) and then meets the same surface again facing
// the same way, with no voxel of its other side between. The crossing is there, not here: leaving a
// curved tube near its rim the event came up to 1.5 voxels early, where the normal had turned 10
// degrees (a false total reflection near the critical angle).
bool VoxelGlass::March::touchedAtCornerOnly(const Cell& c, bool leaving, const Vec3d& n) const {
    Dda look = walk;
    int lookAxis = c.axis;
    double tLook = c.tLeave;
    bool gap = false;
    for (int k = 0; k < 2 * voxel_glass_detail::kMaxRun && tLook < clip.t1 && look.advance(lookAxis); ++k) {
        const int64_t j = index(look);
        lookAxis = look.nextAxis();
        tLook = std::min(look.tMax[lookAxis], clip.t1);
        if (!grid.written(j)) {
            gap = true;
            continue;
        }
        if ((!grid.material.empty() && grid.material[size_t(j)] != c.material) ||
            voxel_glass_detail::voxelKind(grid, glass.twoMaterials_, j) != VoxelKind::Surface)
            return false;
        const Vec3d nj(grid.normal(j));
        if ((dot(d, nj) > 0) != leaving) return false; // the surface's other side: crossed
        if (gap) return !(dot(nj, n) < voxel_glass_detail::kCosBlend);
    }
    return false;
}

// The event at a boundary voxel: the ray enters or leaves c's material (Snell and Fresnel with the
// media on both sides, the tint of a medium entered), or is totally reflected.
VoxelGlass::March::Step VoxelGlass::March::refract(const Cell& c, double tEnter, bool leaving,
                                                   const Vec3d& n) {
    const double tEvent = 0.5 * (tEnter + c.tLeave);
    thr = thr * stack.attenuation((tEvent - tEnter) * glass.voxel_);
    pos = world(tEvent);
    castFrom = leaving ? world(tEnter) : pos;
    ++p.events;
    detail::MediaStack next = stack;
    Vec3f tint{1, 1, 1};
    if (leaving && c.insideMaterial) {
        next.leaveInnermost();
    } else if (leaving) {
        if (!next.leave(c.material)) next.leaveInnermost();
    } else {
        next.enter(c.material);
        tint = stack.medium(c.material).tint;
    }
    const double etaFrom = stack.current().ior, etaTo = next.current().ior;
    // Where the surface crosses the ray: conservative coverage writes every voxel the surface
    // touches, so the ray meets a run of its voxels and the surface lies about the run's middle, up
    // to a few voxels past the first one at a grazing crossing. The normal is taken there, not at
    // this first voxel: leaving a convex surface, the normal before the crossing is tilted further
    // from the ray (at a crossing near the critical angle, a false total reflection). The event
    // itself stays at this voxel (the march and the exit point are unchanged).
    double tRunEnd = c.tLeave;
    alongRay(c, [&](int64_t j, double tOut) {
        const Vec3d nj(grid.normal(j));
        if (!(length(nj) > 0) || (dot(d, nj) > 0) != leaving || dot(nj, n) < voxel_glass_detail::kCosBlend)
            return false;
        tRunEnd = tOut;
        return true;
    });
    // The normal at the crossing: trilinear over the surface's voxels around it (the voxel's own
    // averaged normal is a staircase of the faces that touch it).
    Vec3d ns = voxel_glass_detail::normalAt(grid, g + d * (0.5 * (tEnter + tRunEnd)), c.material, n);
    if ((dot(d, ns) > 0) != leaving) ns = n;
    const Vec3d nf = leaving ? -ns : ns; // facing the ray
    Vec3d r;
    if (refractDirection(d, nf, etaFrom / etaTo, r)) {
        thr = thr * tint * float(1 - fresnelDielectric(-dot(d, nf), etaFrom, etaTo));
        d = r;
        std::swap(stack, next);
    } else {
        d = reflectDirection(d, nf); // total internal reflection
    }
    if (twoSurface && leaving) stop = true; // Wyman: one back surface
    lastNormal = n;
    lastMaterial = c.material;
    return Step::Turned;
}

} // namespace voxfx
