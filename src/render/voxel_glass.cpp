// voxfx — the voxel glass methods: the march through an attribute grid (CHANG §4.1.1 multiple
// refraction; Wyman's two-surface refraction as its baseline), voxfx/voxel_glass.hpp.
#include "voxfx/voxel_glass.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>

#include "voxfx/dda.hpp"
#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"

namespace voxfx {

namespace {

template <class O> std::vector<OptionField<O>> voxelGlassFields() {
    return {
        numberOption<O, &O::gridResolution>("glassGrid", "glass voxels along the glass's longest side", 2,
                                            4096),
        nameOption<O, parseCoverage, optionName<Coverage>, &O::coverage>(
            "glassCoverage",
            "glass voxels: every voxel a triangle touches (CHANG's widened slabs at their limit: no "
            "holes on steep faces), or one per column (thinner boundary, holes where faces are steep)",
            "conservative | center"),
        numberOption<O, &O::angleThreshold>(
            "angleThreshold",
            "glass (CHANG's angle threshold, radians): a boundary voxel of the last surface's material "
            "whose normal is this close to that surface's is the same surface, not a new event (0: "
            "only the media stack guards against refracting twice at one surface)",
            0, 3.2),
        numberOption<O, &O::slabOverlap>(
            "slabOverlap",
            "glass voxels: CHANG's widened slabs, each slab grown by this many slices on both sides "
            "(more voxels written, fewer holes where faces are steep under center coverage)",
            0, 4),
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
}

} // namespace

std::span<const OptionField<MultiGlassOptions>> MultiGlassOptions::fields() {
    static const std::vector<OptionField<MultiGlassOptions>> table = voxelGlassFields<MultiGlassOptions>();
    return table;
}

std::span<const OptionField<TwoSurfaceGlassOptions>> TwoSurfaceGlassOptions::fields() {
    static const std::vector<OptionField<TwoSurfaceGlassOptions>> table =
        voxelGlassFields<TwoSurfaceGlassOptions>();
    return table;
}

template <class O, bool kTwoSurface>
VoxelGlassMethod<O, kTwoSurface> VoxelGlassMethod<O, kTwoSurface>::build(const GlassInput& input,
                                                                         const O& options) {
    return VoxelGlassMethod(
        VoxelGlass(input.mesh, input.triangleMedium, input.media, options, input.vertexNormals), options);
}

template class VoxelGlassMethod<MultiGlassOptions, false>;
template class VoxelGlassMethod<TwoSurfaceGlassOptions, true>;

VoxelGlass::VoxelGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium,
                       std::vector<GlassMedium> media, const VoxelGlassOptions& options,
                       std::span<const Vec3f> vertexNormals)
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
    ao.slabOverlap = options.slabOverlap;
    // Normals and material id, and the write count, which tells a voxel holding both faces of a sheet
    // thinner than itself (its normals cancel) from one surface: 18 bytes per voxel.
    ao.channels = AttributeChannels::glass();
    ao.channels.count = true;
    ao.triangleMaterial = triangleMedium;
    ao.vertexNormals = vertexNormals;
    const Frame frame = Frame::orthographic(grid, Axis::Z, dims[0], dims[1], dims[2]);
    grid_ = voxelizeAttributes(mesh, frame, {}, ao);
    // Where two materials wrote a voxel: its material is that of the lowest-indexed triangle written
    // into it, so the same voxelization with the triangles in reverse order gives the highest one's.
    if (std::adjacent_find(triangleMedium.begin(), triangleMedium.end(), std::not_equal_to<>()) !=
        triangleMedium.end()) {
        std::vector<uint32_t> reversed(mesh.triangleCount * 3);
        std::vector<uint32_t> reversedMedium(mesh.triangleCount);
        for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
            const std::size_t from = mesh.triangleCount - 1 - t;
            for (int c = 0; c < 3; ++c)
                reversed[3 * t + std::size_t(c)] = mesh.indices[3 * from + std::size_t(c)];
            reversedMedium[t] = triangleMedium[from];
        }
        MeshView back = mesh;
        back.indices = reversed.data();
        AttributeOptions last = ao;
        last.channels = {false, false, false, true, false, false}; // material id only
        last.triangleMaterial = reversedMedium;
        const AttributeGrid lastWriter = voxelizeAttributes(back, frame, {}, last);
        twoMaterials_.resize(grid_.material.size());
        for (std::size_t i = 0; i < twoMaterials_.size(); ++i)
            twoMaterials_[i] = grid_.material[i] != lastWriter.material[i];
        // The face between two touching media (CHANG §4.2): its voxels hold both media's faces, whose
        // normals cancel (where they do not, the voxel is no such face: an object inside another
        // touching its boundary, the edge where the face meets the outside). Which way the face
        // points is told by the triangles of one of the two media alone: for the lowest bit in which
        // the two ids differ, a normals-only voxelization of the triangles of the one whose id has
        // that bit set (one pass per bit that is needed: a few for any number of media).
        // side[k]: per medium, whether the pass for bit k voxelizes its triangles (only those of
        // media on a face whose lowest differing bit is k: the pass costs what those faces do).
        std::vector<std::vector<uint8_t>> side(32);
        for (std::size_t i = 0; i < twoMaterials_.size(); ++i) {
            if (!twoMaterials_[i]) continue;
            const uint32_t lo = grid_.material[i], hi = lastWriter.material[i];
            const bool between = length(Vec3d(grid_.normalSum[i])) < 0.5 * double(grid_.count[i]);
            interfaces_.push_back({int64_t(i), lo, hi, between, {0, 0, 0}});
            if (!between) continue;
            const int k = std::countr_zero(lo ^ hi);
            side[size_t(k)].resize(media_.size(), 0);
            side[size_t(k)][((lo >> k) & 1) ? lo : hi] = 1;
        }
        for (int k = 0; k < 32; ++k) {
            if (side[size_t(k)].empty()) continue;
            std::vector<uint32_t> part;
            for (std::size_t t = 0; t < mesh.triangleCount; ++t)
                if (side[size_t(k)][triangleMedium[t]])
                    for (int c = 0; c < 3; ++c) part.push_back(mesh.indices[3 * t + std::size_t(c)]);
            MeshView ofOne = mesh;
            ofOne.indices = part.data();
            ofOne.triangleCount = part.size() / 3;
            AttributeOptions normalsOnly = ao;
            normalsOnly.channels = {false, false, true, false, false, false};
            normalsOnly.triangleMaterial = {};
            const AttributeGrid sideGrid = voxelizeAttributes(ofOne, frame, {}, normalsOnly);
            for (Interface& f : interfaces_) {
                if (!f.between || std::countr_zero(f.lo ^ f.hi) != k) continue;
                const Vec3d nLo =
                    Vec3d(sideGrid.normalSum[size_t(f.voxel)]) * (((f.lo >> k) & 1) ? 1.0 : -1.0);
                const double len = length(nLo);
                if (len > 1e-6) f.normalLo = Vec3f(nLo / len);
            }
        }
    }
}

const VoxelGlass::Interface* VoxelGlass::interfaceAt(int64_t voxel) const {
    const auto it = std::lower_bound(interfaces_.begin(), interfaces_.end(), voxel,
                                     [](const Interface& f, int64_t v) { return f.voxel < v; });
    return it != interfaces_.end() && it->voxel == voxel ? &*it : nullptr;
}

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
// per voxel or empty) is one surface: its normals cancel, but it is no sheet (see trace).
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

// As normalAt, for the face between two touching media: lo's normal over the face's voxels of the
// same two media around g.
Vec3d VoxelGlass::interfaceNormalAt(const Vec3d& g, const Interface& own) const {
    return voxel_glass_detail::trilinearNormal(grid_.frame, g, Vec3d(own.normalLo), [&](int64_t i) {
        const Interface* near = interfaceAt(i);
        return near && near->between && near->lo == own.lo && near->hi == own.hi ? Vec3d(near->normalLo)
                                                                                 : Vec3d{0, 0, 0};
    });
}

GlassPath VoxelGlass::trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium, const Vec3d& dir,
                            const VoxelGlassOptions& options, bool twoSurface) const {
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
    // The media the ray is in, innermost (last entered) on top; empty: air. Material-id transitions
    // at boundary voxels change it: a voxel whose normal faces the ray enters its material, one whose
    // normal points along the ray leaves it (or, where its material is not one the ray is in, the
    // innermost medium: the boundary still says the ray leaves something).
    static const GlassMedium kAir{1.0f, {0, 0, 0}, {1, 1, 1}};
    std::vector<uint32_t> stack{uint32_t(std::min<size_t>(medium, media_.size() - 1))};
    auto current = [&]() -> const GlassMedium& { return stack.empty() ? kAir : media_[stack.back()]; };
    Vec3d lastNormal = n0;                // the entry surface's outward normal (it faces the incoming ray)
    uint32_t lastMaterial = stack.back(); // the material of that surface
    const double cosThreshold = std::cos(options.angleThreshold);
    const int64_t dims[3] = {grid_.frame.width(), grid_.frame.height(), grid_.frame.depth()};
    const int64_t D = dims[2];
    Vec3d pos = entry;
    // Where the light leaving the glass is looked up from (the renderer's exact scene cast): the
    // start of the boundary voxel where the ray last left glass, still on the glass's side of the
    // surface, or, while the ray is inside glass, the last event. Never the grid's edge: the grid
    // reaches a voxel beyond the glass, below the ground under glass standing on it, and the cast
    // from there met only the environment.
    Vec3d castFrom = entry;
    // A sheet thinner than a voxel: its front and back faces write the same voxels, whose normals
    // cancel (|sum of the unit normals| below half the writes). Met from inside its material, such a
    // voxel is where the ray leaves, through a face parallel to the one it entered by; met from
    // outside, the ray enters and leaves within the voxel (two Fresnel passes, the sheet's
    // attenuation over half a voxel, its direction unchanged: a parallel-faced sheet). The sheet's
    // voxels along the ray, and any other of its material's, are the same sheet until the ray
    // reaches a voxel nothing (or another material) wrote.
    bool inSheet = false;
    uint32_t sheetMaterial = 0;
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
            const bool written = grid_.written(i);
            const uint32_t mid =
                written ? uint32_t(std::min<size_t>(
                              grid_.material.empty() ? medium : grid_.material[size_t(i)], media_.size() - 1))
                        : 0;
            const Vec3d sum = written ? Vec3d(grid_.normalSum[size_t(i)]) : Vec3d{0, 0, 0};
            const voxel_glass_detail::VoxelKind kind = voxel_glass_detail::voxelKind(grid_, twoMaterials_, i);
            const bool sheet = kind == voxel_glass_detail::VoxelKind::Sheet;
            if (!written || mid != sheetMaterial) inSheet = false;
            // A voxel two materials wrote: where the ray is in either, it is inside the voxel's material
            // (the outer faces of two touching glasses share voxels along the edge of their face).
            const Interface* two =
                written && !twoMaterials_.empty() && twoMaterials_[size_t(i)] ? interfaceAt(i) : nullptr;
            const bool insideMid =
                !stack.empty() && (stack.back() == mid || (two && stack.back() == two->hi));
            if (sheet && !inSheet && !insideMid) {
                // Through the whole sheet within this voxel.
                if (p.events + 2 > options.maxEvents) {
                    p.truncate(origin_ + (g + d * tEnter) * voxel_, d, thr);
                    return p;
                }
                const double sl = length(sum);
                const Vec3d across = sl > 1e-9 ? sum / sl : d;
                const double cosIn = std::min(1.0, std::fabs(dot(d, across)));
                const double etaOut = current().ior, etaIn = media_[mid].ior;
                const double sinT = etaOut / etaIn * std::sqrt(std::max(0.0, 1 - cosIn * cosIn));
                const double cosT = std::sqrt(std::max(0.0, 1 - sinT * sinT));
                // The medium around the sheet over the whole voxel segment, the sheet itself over
                // half a voxel along the refracted direction inside it.
                thr = thr * beerLambert(current().sigma, (tLeave - tEnter) * voxel_) * media_[mid].tint *
                      float((1 - fresnelDielectric(cosIn, etaOut, etaIn)) *
                            (1 - fresnelDielectric(cosT, etaIn, etaOut))) *
                      beerLambert(media_[mid].sigma, 0.5 * voxel_ / std::max(cosT, 0.1));
                p.events += 2;
                inSheet = true;
                sheetMaterial = mid;
                tEnter = tLeave;
                if (tLeave >= clip.t1 || !walk.advance(axis)) {
                    pos = origin_ + (g + d * tLeave) * voxel_;
                    break;
                }
                continue;
            }
            // The face between two touching media, met from within one of them: the ray crosses
            // into the other where it heads out of the one it is in (n_from / n_to, the tint of the
            // medium entered), and passes the face's voxels otherwise (it crossed already, or runs
            // away from the face). Not the generic test below: the voxel's normals cancel.
            bool throughFace = false;
            if (!inSheet && two && two->between && insideMid) {
                const Interface* face = two;
                if (length(Vec3d(face->normalLo)) > 0) {
                    throughFace = true;
                    const bool fromLo = stack.back() == face->lo;
                    const uint32_t to =
                        uint32_t(std::min<size_t>(fromLo ? face->hi : face->lo, media_.size() - 1));
                    const double tMid = 0.5 * (tEnter + tLeave);
                    const Vec3d nOut = interfaceNormalAt(g + d * tMid, *face) * (fromLo ? 1.0 : -1.0);
                    if (dot(d, nOut) > 0) {
                        if (p.events >= options.maxEvents) {
                            p.truncate(origin_ + (g + d * tEnter) * voxel_, d, thr);
                            return p;
                        }
                        thr = thr * beerLambert(current().sigma, (tMid - tEnter) * voxel_);
                        pos = origin_ + (g + d * tMid) * voxel_;
                        castFrom = pos;
                        ++p.events;
                        const double etaFrom = current().ior, etaTo = media_[to].ior;
                        if (refractDirection(d, -nOut, etaFrom / etaTo, r)) {
                            thr = thr * media_[to].tint *
                                  float(1 - fresnelDielectric(dot(d, nOut), etaFrom, etaTo));
                            d = r;
                            stack.back() = to;
                            lastNormal = -nOut; // the entered medium's outward normal there
                            lastMaterial = to;
                        } else {
                            d = reflectDirection(d, -nOut); // total internal reflection
                            lastNormal = nOut;
                            lastMaterial = stack.back();
                        }
                        restarted = true;
                        break;
                    }
                }
            }
            if (written && !inSheet && !throughFace) {
                Vec3d n = Vec3d(grid_.normal(i));
                if (sheet && insideMid) {
                    // The sheet's far face: parallel to the face the ray entered by, else along the
                    // voxel's remaining normal, facing away from the ray.
                    const double sl = length(sum);
                    n = lastMaterial == mid ? -lastNormal : (sl > 1e-9 ? sum / sl : d);
                    if (dot(d, n) <= 0) n = -n;
                    inSheet = true;
                    sheetMaterial = mid;
                }
                // Whether the ray crosses a surface of this voxel's material with normal nv here.
                // Leaving needs a medium to leave; entering a material the ray is already in is the
                // same surface seen again. The angle threshold guards against refracting twice at one
                // surface spread over neighbouring voxels: a surface of another material is another
                // surface (an embedded object's faces can be nearly parallel to the one just crossed).
                auto crosses = [&](const Vec3d& nv) {
                    const double dv = dot(d, nv);
                    const bool out = dv > 0 && !stack.empty();
                    const bool in = dv < 0 && !insideMid;
                    return length(nv) > 0 && (out || in) &&
                           (mid != lastMaterial || dot(nv, lastNormal) < cosThreshold);
                };
                bool candidate = crosses(n);
                const bool leaving = dot(d, n) > 0 && !stack.empty();
                // The voxels after this one along the ray while they are written with its material (up
                // to kMaxRun of them): visit(j, the parameter where the ray leaves j) returns false to
                // stop.
                auto alongRay = [&](auto&& visit) {
                    Dda look = walk;
                    int lookAxis = axis;
                    double tLook = tLeave;
                    for (int k = 0;
                         k < voxel_glass_detail::kMaxRun && tLook < clip.t1 && look.advance(lookAxis); ++k) {
                        const int64_t j = (look.cell[1] * dims[0] + look.cell[0]) * D + look.cell[2];
                        if (!grid_.written(j) ||
                            (!grid_.material.empty() && grid_.material[size_t(j)] != mid))
                            return;
                        lookAxis = look.nextAxis();
                        tLook = std::min(look.tMax[lookAxis], clip.t1);
                        if (!visit(j, tLook)) return;
                    }
                };
                if (candidate && kind == voxel_glass_detail::VoxelKind::Crease) {
                    // A crease voxel's normal is the mean of two surfaces' (a box's edge: 45 degrees
                    // between its side and its bottom), a face that is not there: a ray reflected by
                    // a glass cube's side towards its bottom edge was reflected again there, and left
                    // upwards through the far side. Where the ray goes on into a voxel of one surface
                    // that it crosses, the crossing is there: this voxel is passed. Otherwise (the
                    // ray runs along the edge and out), leaving, it takes the normal of the
                    // neighbouring one-surface voxel whose normal is closest to the ray's direction:
                    // the face it heads into most directly, which it meets first leaving a convex
                    // edge from within a voxel of both faces.
                    bool surfaceAhead = false;
                    alongRay([&](int64_t j, double) {
                        const voxel_glass_detail::VoxelKind kj =
                            voxel_glass_detail::voxelKind(grid_, twoMaterials_, j);
                        if (kj == voxel_glass_detail::VoxelKind::Crease) return true;
                        surfaceAhead =
                            kj == voxel_glass_detail::VoxelKind::Surface && crosses(Vec3d(grid_.normal(j)));
                        return false;
                    });
                    if (surfaceAhead) {
                        candidate = false;
                    } else if (leaving) {
                        double best = 0;
                        for (int k = 0; k < 27; ++k) {
                            const int64_t c[3] = {walk.cell[0] + k % 3 - 1, walk.cell[1] + (k / 3) % 3 - 1,
                                                  walk.cell[2] + k / 9 - 1};
                            if (k == 13 || c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= dims[0] ||
                                c[1] >= dims[1] || c[2] >= dims[2])
                                continue;
                            const int64_t j = (c[1] * dims[0] + c[0]) * D + c[2];
                            if (voxel_glass_detail::voxelKind(grid_, twoMaterials_, j) !=
                                    voxel_glass_detail::VoxelKind::Surface ||
                                (!grid_.material.empty() && grid_.material[size_t(j)] != mid))
                                continue;
                            const Vec3d nj(grid_.normal(j));
                            if (dot(d, nj) > best) {
                                best = dot(d, nj);
                                n = nj;
                            }
                        }
                    }
                }
                if (candidate && kind == voxel_glass_detail::VoxelKind::Surface) {
                    // A voxel the surface touches only at a corner the ray does not pass: the ray
                    // goes on into voxels nothing wrote (still on this side of the surface) and then
                    // meets the same surface again facing the same way, with no voxel of its other
                    // side between. The crossing is there, not here: leaving a curved tube near its
                    // rim the event came up to 1.5 voxels early, where the normal had turned 10
                    // degrees (a false total reflection near the critical angle).
                    Dda look = walk;
                    int lookAxis = axis;
                    double tLook = tLeave;
                    bool gap = false;
                    for (int k = 0;
                         k < 2 * voxel_glass_detail::kMaxRun && tLook < clip.t1 && look.advance(lookAxis);
                         ++k) {
                        const int64_t j = (look.cell[1] * dims[0] + look.cell[0]) * D + look.cell[2];
                        lookAxis = look.nextAxis();
                        tLook = std::min(look.tMax[lookAxis], clip.t1);
                        if (!grid_.written(j)) {
                            gap = true;
                            continue;
                        }
                        if ((!grid_.material.empty() && grid_.material[size_t(j)] != mid) ||
                            voxel_glass_detail::voxelKind(grid_, twoMaterials_, j) !=
                                voxel_glass_detail::VoxelKind::Surface)
                            break;
                        const Vec3d nj(grid_.normal(j));
                        if ((dot(d, nj) > 0) != leaving) break; // the surface's other side: crossed
                        if (gap) {
                            candidate = dot(nj, n) < voxel_glass_detail::kCosBlend;
                            break;
                        }
                    }
                }
                if (candidate) {
                    if (p.events >= options.maxEvents) {
                        p.truncate(origin_ + (g + d * tEnter) * voxel_, d, thr);
                        return p;
                    }
                    const double tEvent = 0.5 * (tEnter + tLeave);
                    thr = thr * beerLambert(current().sigma, (tEvent - tEnter) * voxel_);
                    pos = origin_ + (g + d * tEvent) * voxel_;
                    castFrom = leaving ? origin_ + (g + d * tEnter) * voxel_ : pos;
                    ++p.events;
                    std::vector<uint32_t> next = stack;
                    Vec3f tint{1, 1, 1};
                    if (leaving && insideMid) {
                        next.pop_back();
                    } else if (leaving) {
                        const auto it = std::find(next.rbegin(), next.rend(), mid);
                        next.erase(it == next.rend() ? next.end() - 1 : std::next(it).base());
                    } else {
                        next.push_back(mid);
                        tint = media_[mid].tint;
                    }
                    const double etaFrom = current().ior,
                                 etaTo = next.empty() ? 1.0 : media_[next.back()].ior;
                    // Where the surface crosses the ray: conservative coverage writes every voxel the
                    // surface touches, so the ray meets a run of its voxels and the surface lies
                    // about the run's middle, up to a few voxels past the first one at a grazing
                    // crossing. The normal is taken there, not at this first voxel: leaving a convex
                    // surface, the normal before the crossing is tilted further from the ray (at a
                    // crossing near the critical angle, a false total reflection). The event itself
                    // stays at this voxel (the march and the exit point are unchanged).
                    double tRunEnd = tLeave;
                    alongRay([&](int64_t j, double tOut) {
                        const Vec3d nj(grid_.normal(j));
                        if (!(length(nj) > 0) || (dot(d, nj) > 0) != leaving ||
                            dot(nj, n) < voxel_glass_detail::kCosBlend)
                            return false;
                        tRunEnd = tOut;
                        return true;
                    });
                    // The normal at the crossing: trilinear over the surface's voxels around it (the
                    // voxel's own averaged normal is a staircase of the faces that touch it).
                    Vec3d ns =
                        voxel_glass_detail::normalAt(grid_, g + d * (0.5 * (tEnter + tRunEnd)), mid, n);
                    if ((dot(d, ns) > 0) != leaving) ns = n;
                    const Vec3d nf = leaving ? -ns : ns; // facing the ray
                    if (refractDirection(d, nf, etaFrom / etaTo, r)) {
                        thr = thr * tint * float(1 - fresnelDielectric(-dot(d, nf), etaFrom, etaTo));
                        d = r;
                        stack.swap(next);
                    } else {
                        d = reflectDirection(d, nf); // total internal reflection
                    }
                    if (twoSurface && leaving) stop = true; // Wyman: one back surface
                    lastNormal = n;
                    lastMaterial = mid;
                    restarted = true;
                    break;
                }
            }
            thr = thr * beerLambert(current().sigma, (tLeave - tEnter) * voxel_);
            tEnter = tLeave;
            if (tLeave >= clip.t1 || !walk.advance(axis)) {
                pos = origin_ + (g + d * tLeave) * voxel_;
                break;
            }
        }
        if (!restarted) break;
    }
    p.exitPoint = castFrom;
    p.exitDir = d;
    p.throughput = thr;
    return p;
}

} // namespace voxfx
