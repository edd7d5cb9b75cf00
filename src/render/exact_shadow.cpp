// voxfx — exact shadows through partial occluders: every caster triangle between a point and the
// light multiplies the light by its crossing transmittance (Embree finds them in order); glass
// multiplies by the Fresnel-transmitted fraction at each crossing, its tint where the ray enters and
// Beer–Lambert over the length inside; the objects of the scene's volume scene (Bornik et al. §3:
// Boolean shapes, volumes seen through transfer functions) are crossed along the same ray, their
// boundaries found by Embree on each leaf, the volumes marched in fine fixed steps
// (voxfx/exact_shadow.hpp).
#include "voxfx/exact_shadow.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

#include "render/media_stack.hpp"
#include "render/shadow_casters.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/segment_walker.hpp"
#include "voxfx/text.hpp"
#include "voxfx/triangle_tracer.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {

// The casting objects of a scene's volume scene, traced exactly: one Embree tracer per leaf a
// casting object's shape uses (a leaf of its own, so coincident faces of two leaves are both found;
// within a leaf, a hit on an edge shared by two triangles is found once, as a crossing of the
// tracer's nearest-hit walk), the volumes' transparent bricks, and the march step.
struct ExactShadow::Volumes {
    std::shared_ptr<const VolumeScene> scene;
    std::vector<std::unique_ptr<TriangleTracer>> leafTracer; ///< null for leaves no caster uses
    std::vector<uint32_t> leafOfFragment;                    ///< identity: a fragment's triangle is its leaf
    std::vector<EmptySpace> empty;                           ///< per object (Volume objects)
    Box3d bounds;                                            ///< of the leaves traced
    double step = 1;                                         ///< world step of the volume march
    double epsilon = 1e-6;                                   ///< the largest of the leaf tracers'
    bool marches = false;                                    ///< some casting object is a volume
    uint64_t id = 0; ///< distinguishes this set from others for the per-thread walkers
};

namespace {

// Below this (in every channel) the light is taken as stopped: the march ends, the rest of the
// ray could only lower it further.
constexpr float kExactTermination = 1e-6f;

// -ln(1 - alpha) / opacityLength, alpha clamped below 1 as PreintegratedTransfer does: the
// extinction the deep shadow map's pre-integrated intervals average (voxfx/volume_scene.hpp).
double exactPointExtinction(const VolumeSceneObject& object, double value) {
    const double a = std::min(object.transfer.opacity(value), 1.0 - 1e-7);
    return a > 0 ? -std::log1p(-a) / object.opacityLength : 0.0;
}

// The parameter interval [t0, t1] of the line p + t dir inside `box` grown by `margin`; false when
// the line misses it.
bool exactClipLine(const Box3d& box, double margin, const Vec3d& p, const Vec3d& dir, double& t0,
                   double& t1) {
    t0 = -std::numeric_limits<double>::infinity();
    t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        const double lo = box.lo[a] - margin, hi = box.hi[a] + margin;
        if (dir[a] == 0) {
            if (p[a] < lo || p[a] > hi) return false;
            continue;
        }
        double ta = (lo - p[a]) / dir[a], tb = (hi - p[a]) / dir[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

} // namespace

ExactShadow::ExactShadow(const MeshView& casters, std::vector<Vec3f> triangleTransmittance,
                         std::vector<uint32_t> triangleGlass, std::vector<Glass> glass)
    : transmittance_(std::move(triangleTransmittance)), triangleGlass_(std::move(triangleGlass)),
      glass_(std::move(glass)) {
    validateMesh(casters, "shadow casters");
    if (transmittance_.size() != casters.triangleCount)
        fail("exact shadows: ", transmittance_.size(), " transmittances for ", casters.triangleCount,
             " triangles");
    if (!triangleGlass_.empty() && triangleGlass_.size() != casters.triangleCount)
        fail("exact shadows: ", triangleGlass_.size(), " glass indices for ", casters.triangleCount,
             " triangles");
    for (const uint32_t g : triangleGlass_)
        if (g != kNotGlass && g >= glass_.size())
            fail("exact shadows: glass index ", g, " outside the table of ", glass_.size());
    for (const Glass& g : glass_)
        if (!(g.ior >= 1 && std::isfinite(g.ior))) fail("exact shadows: glass ior must be >= 1, got ", g.ior);
    tracer_ = std::make_shared<const TriangleTracer>(casters);
}

ExactShadow ExactShadow::fromMaterials(const MeshView& casters, std::span<const uint32_t> triangleMaterial,
                                       std::span<const Material> materials) {
    if (triangleMaterial.size() != casters.triangleCount)
        fail("exact shadows: ", triangleMaterial.size(), " materials for ", casters.triangleCount,
             " triangles");
    std::vector<uint32_t> glassOf(materials.size(), kNotGlass);
    std::vector<Glass> glass;
    for (size_t m = 0; m < materials.size(); ++m)
        if (materials[m].isGlass()) {
            glassOf[m] = uint32_t(glass.size());
            glass.push_back({std::max(1.0f, materials[m].ior), attenuationCoefficient(materials[m]),
                             materials[m].crossingTransmittance()});
        }
    std::vector<Vec3f> perTriangle(casters.triangleCount);
    std::vector<uint32_t> triangleGlass;
    if (!glass.empty()) triangleGlass.resize(casters.triangleCount);
    for (size_t t = 0; t < casters.triangleCount; ++t) {
        const uint32_t m = triangleMaterial[t];
        if (m >= materials.size()) fail("exact shadows: material ", m, " out of range");
        perTriangle[t] = materials[m].crossingTransmittance();
        if (!glass.empty()) triangleGlass[t] = glassOf[m];
    }
    return ExactShadow(casters, std::move(perTriangle), std::move(triangleGlass), std::move(glass));
}

Vec3f ExactShadow::transmittance(const Vec3d& p, const Vec3d& dir, double distance) const {
    const Vec3f v = tracer_ ? meshTransmittance(p, dir, distance) : Vec3f{1, 1, 1};
    if (!volumes_ || std::max({v.x, v.y, v.z}) <= 0) return v;
    return v * volumeTransmittance(p, dir, distance);
}

Vec3f ExactShadow::volumeTransmittance(const Vec3d& p, const Vec3d& dir, double distance) const {
    const Volumes& vol = *volumes_;
    const VolumeScene& scene = *vol.scene;
    // The whole line through the leaves' box, so that crossings behind p say what p is inside;
    // rays whose segment [0, distance] misses the box cross nothing.
    double b0 = 0, b1 = 0;
    const double margin = 16 * vol.epsilon;
    if (!exactClipLine(vol.bounds, margin, p, dir, b0, b1) || b1 <= 0 || b0 >= distance) return {1, 1, 1};
    const double start = std::min(b0, 0.0) - margin; // the line's parameter at the tracers' origin
    const Vec3d origin = p + dir * start;
    const double far = b1 - start + margin;
    // Every leaf's crossings along the line, as fragments of a column (depth: the line's parameter
    // t, triangle: the leaf), in depth order; the segment walker then classifies them exactly as it
    // does the deep shadow map's fragment lists.
    thread_local std::vector<ListFragment> fragments;
    thread_local std::optional<SegmentWalker> walker;
    thread_local uint64_t walkerOf = 0;
    if (walkerOf != vol.id) {
        walker.emplace(scene, vol.leafOfFragment, true);
        walkerOf = vol.id;
    }
    fragments.clear();
    for (std::size_t leaf = 0; leaf < vol.leafTracer.size(); ++leaf) {
        const TriangleTracer* tracer = vol.leafTracer[leaf].get();
        if (!tracer) continue;
        double tNear = 0;
        for (int crossings = 0; crossings < 100000; ++crossings) {
            const TriangleTracer::Hit h = tracer->intersect(origin, dir, tNear, far);
            if (!h.hit) break;
            fragments.push_back({start + h.t, uint32_t(leaf), false});
            tNear = h.t + tracer->epsilon();
        }
    }
    if (fragments.empty()) return {1, 1, 1};
    std::sort(fragments.begin(), fragments.end(), [](const ListFragment& a, const ListFragment& b) {
        return a.depth < b.depth || (a.depth == b.depth && a.triangle < b.triangle);
    });
    Vec3f v{1, 1, 1};
    // Glass the ray is inside (summed Beer–Lambert coefficients) and where its chord last began.
    Vec3f glassSigma{0, 0, 0};
    double glassFrom = 0;
    auto applyGlass = [&](double upTo) {
        if (upTo > glassFrom && (glassSigma.x > 0 || glassSigma.y > 0 || glassSigma.z > 0))
            v = v * beerLambert(glassSigma, upTo - glassFrom);
        glassFrom = std::max(glassFrom, upTo);
    };
    walker->walk(
        std::span<const ListFragment>(fragments),
        [&](double z, std::size_t o, bool entering) {
            const VolumeSceneObject& obj = scene.objects[o];
            const bool onRay = z > 0 && z < distance;
            if (onRay) applyGlass(z);
            if (obj.kind == ObjectKind::Translucent)
                for (int c = 0; c < 3; ++c)
                    glassSigma[c] = entering ? glassSigma[c] + obj.attenuation[c]
                                             : std::max(0.0f, glassSigma[c] - obj.attenuation[c]);
            if (!onRay) return z < distance;
            if (obj.kind == ObjectKind::Opaque)
                v = {0, 0, 0};
            else
                v = v * obj.shadowTransmittance();
            return std::max({v.x, v.y, v.z}) > kExactTermination;
        },
        [&](double z0, double z1, std::span<const uint8_t> inside) {
            // The part of the segment between p and the light, marched at midpoints of equal steps
            // of at most `step`: each adds the extinction of every volume object inside there.
            const double a = std::max(z0, 0.0), b = std::min(z1, distance);
            if (!(b > a) || !vol.marches) return z1 < distance;
            const int64_t n = std::max<int64_t>(1, int64_t(std::ceil((b - a) / vol.step)));
            const double dl = (b - a) / double(n);
            for (int64_t k = 0; k < n; ++k) {
                const Vec3d q = p + dir * (a + (double(k) + 0.5) * dl);
                double sigma = 0;
                for (std::size_t o = 0; o < inside.size(); ++o) {
                    const VolumeSceneObject& obj = scene.objects[o];
                    if (!inside[o] || obj.kind != ObjectKind::Volume || vol.empty[o].empty(q)) continue;
                    sigma +=
                        exactPointExtinction(obj, double(scene.volumes[std::size_t(obj.volume)]->sample(q)));
                }
                if (sigma > 0) {
                    v = v * float(std::exp(-sigma * dl));
                    if (std::max({v.x, v.y, v.z}) <= kExactTermination) return false;
                }
            }
            return z1 < distance;
        });
    // A light inside glass: attenuated up to the light.
    if (std::isfinite(distance)) applyGlass(distance);
    return v;
}

Vec3f ExactShadow::meshTransmittance(const Vec3d& p, const Vec3d& dir, double distance) const {
    const Mesh& mesh = tracer_->mesh();
    const double epsilon = tracer_->epsilon();
    Vec3f v{1, 1, 1};
    Vec3d o = p;
    double left = distance, travelled = 0;
    // Glass volumes the ray is inside: which one and where it entered (nested objects stack). One
    // stack per thread, reused: this runs once per shadow ray, and a fresh one would allocate on
    // every ray that enters glass.
    thread_local detail::MediaStack inside;
    inside.reset(glass_);
    // Each crossing moves the origin to the hit; epsilon steps over the triangle just crossed.
    for (int crossings = 0; crossings < 100000; ++crossings) {
        const TriangleTracer::Hit h = tracer_->intersect(o, dir, epsilon, left);
        if (!h.hit) break;
        const uint32_t g = triangleGlass_.empty() ? kNotGlass : triangleGlass_[h.triangle];
        const double tHit = travelled + h.t;
        if (g == kNotGlass) {
            v = v * transmittance_[h.triangle];
        } else {
            const Glass& glass = glass_[g];
            const Vec3d a = Vec3d(mesh.positions[mesh.indices[3 * size_t(h.triangle)]]);
            const Vec3d b = Vec3d(mesh.positions[mesh.indices[3 * size_t(h.triangle) + 1]]);
            const Vec3d c = Vec3d(mesh.positions[mesh.indices[3 * size_t(h.triangle) + 2]]);
            const Vec3d n = normalize(cross(b - a, c - a));
            const double cosine = dot(dir, n);
            v = v * float(1 - fresnelDielectric(std::min(1.0, std::abs(cosine)), 1.0, glass.ior));
            if (cosine < 0) { // a front face: the ray enters
                v = v * glass.tint;
                inside.enter(g, tHit);
            } else { // leaves: Beer–Lambert since it entered (or since p, which was inside)
                const std::optional<detail::MediaStack::Entry> entered = inside.leave(g);
                v = v * beerLambert(glass.sigma, tHit - (entered ? entered->t : 0.0));
            }
        }
        if (std::max({v.x, v.y, v.z}) <= 0) return v;
        o = o + dir * h.t;
        left -= h.t;
        travelled = tHit;
    }
    // A light inside glass: attenuated up to the light.
    if (std::isfinite(distance))
        for (const detail::MediaStack::Entry& i : inside.entries())
            v = v * beerLambert(glass_[i.medium].sigma, distance - i.t);
    return v;
}

std::span<const OptionField<ExactShadowOptions>> ExactShadowOptions::fields() {
    using O = ExactShadowOptions;
    static const std::vector<OptionField<O>> table = {numberOption<O, &O::volumeStep>(
        "exactStep",
        "exact shadows: step of the march through volume objects along a shadow ray, in smallest voxel "
        "spacings (smaller: closer to the integral, slower)",
        1e-3, 100)};
    return table;
}

ExactShadowStats& ExactShadowStats::operator+=(const ExactShadowStats& o) {
    triangles += o.triangles;
    volumeObjects += o.volumeObjects;
    volumeStep = std::max(volumeStep, o.volumeStep);
    return *this;
}

std::string ExactShadowStats::summary() const {
    std::string s = countText(triangles) + " caster triangles traced (Embree)";
    if (volumeObjects > 0) {
        s += ", " + countText(volumeObjects) + " volume-scene objects";
        if (volumeStep > 0) s += " (volumes marched every " + formatOption(volumeStep) + " world units)";
    }
    return s;
}

ExactShadow ExactShadow::build(const Scene& scene, const Light& light, const ExactShadowOptions& options,
                               Progress*) {
    if (!(options.volumeStep > 0) || !std::isfinite(options.volumeStep))
        fail("exact shadows (--exact-step): the volume step must be a positive number of voxels, got ",
             options.volumeStep);
    const detail::CasterSets casters = detail::collectCasters(scene);
    ExactShadow out;
    if (!casters.all.indices.empty())
        out = fromMaterials(casters.all.view(), casters.allMaterialIndex, scene.materials);
    if (scene.volumeScene) out.volumes_ = buildVolumes(scene.volumeScene, options.volumeStep);
    out.light_ = light;
    return out;
}

std::shared_ptr<const ExactShadow::Volumes>
ExactShadow::buildVolumes(std::shared_ptr<const VolumeScene> scene, double stepVoxels) {
    scene->validate();
    auto out = std::make_shared<Volumes>();
    const std::vector<uint8_t> used = scene->usedLeaves(true);
    if (std::find(used.begin(), used.end(), uint8_t(1)) == used.end()) return nullptr;
    static std::atomic<uint64_t> ids{0};
    out->id = ++ids;
    out->leafTracer.resize(scene->leaves.size());
    out->leafOfFragment.resize(scene->leaves.size());
    for (std::size_t l = 0; l < scene->leaves.size(); ++l) {
        out->leafOfFragment[l] = uint32_t(l);
        if (!used[l] || scene->leaves[l].indices.empty()) continue;
        out->leafTracer[l] = std::make_unique<TriangleTracer>(scene->leaves[l].view());
        out->epsilon = std::max(out->epsilon, out->leafTracer[l]->epsilon());
        out->bounds.extend(computeBounds(scene->leaves[l].view()));
    }
    if (out->bounds.empty()) return nullptr;
    double spacing = std::numeric_limits<double>::infinity();
    for (const VolumeSceneObject& o : scene->objects)
        if (o.castsShadow && o.kind == ObjectKind::Volume) {
            const Vec3d s = scene->volumes[std::size_t(o.volume)]->spacing();
            spacing = std::min({spacing, s.x, s.y, s.z});
            out->marches = true;
        }
    out->step = std::isfinite(spacing) ? spacing * stepVoxels : 1.0;
    out->empty = emptySpaceOf(*scene);
    out->scene = std::move(scene);
    return out;
}

Vec3f ExactShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    if (!tracer_ && !volumes_) return {1, 1, 1};
    // Towards the light from p offset along n against self-intersection (to a point light from
    // the offset point: a light inside a volume is marched up to exactly where it is).
    const Vec3d o = p + n * (epsilon() * 10);
    Vec3d l = light_.towards(o);
    double distance = std::numeric_limits<double>::infinity();
    if (light_.positioned()) {
        distance = length(l);
        l = l / std::max(distance, 1e-300);
    }
    return transmittance(o, l, distance);
}

ExactShadow::Stats ExactShadow::stats() const {
    Stats s;
    s.triangles = tracer_ ? int64_t(tracer_->mesh().triangleCount()) : 0;
    if (volumes_) {
        for (const VolumeSceneObject& o : volumes_->scene->objects) s.volumeObjects += o.castsShadow;
        s.volumeStep = volumes_->marches ? volumes_->step : 0;
    }
    return s;
}

double ExactShadow::epsilon() const {
    const double mesh = tracer_ ? tracer_->epsilon() : 0;
    const double volumes = volumes_ ? volumes_->epsilon : 0;
    return mesh > 0 || volumes > 0 ? std::max(mesh, volumes) : 1e-6;
}

} // namespace voxfx
