// voxfx — volume ray casting over fragment lists, composited over the shaded G-buffer, with the
// visible surfaces of Boolean-shaped opaque and translucent objects (render/volume_pass.hpp).
#include "render/volume_pass.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <variant>

#include "render/antialias.hpp"
#include "render/shading.hpp"
#include "render/volume_light_grid.hpp"
#include "voxfx/deep_shadow.hpp"
#include "voxfx/triangle_tracer.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {

const char* toString(VolumeShading v) { return enumName(v, kVolumeShadingNames); }
VolumeShading parseVolumeShading(const std::string& name) {
    return parseEnum<VolumeShading>(name, "volume shading", kVolumeShadingNames);
}

} // namespace voxfx

namespace voxfx::detail {

namespace {

std::atomic<bool> prelitSwitch{true};

Vec3d volumePassCorner(const Mesh& m, uint32_t t, int k) {
    return Vec3d(m.positions[m.indices[3 * std::size_t(t) + std::size_t(k)]]);
}

} // namespace

bool volumePrelit() { return prelitSwitch.load(std::memory_order_relaxed); }
void setVolumePrelit(bool on) { prelitSwitch.store(on, std::memory_order_relaxed); }

ObjectSurfaces::ObjectSurfaces(const VolumeScene& s) : scene(&s), flat(flattenLeaves(s, false)) {
    objectLeaves.reserve(s.objects.size());
    for (const VolumeSceneObject& o : s.objects) {
        std::vector<uint8_t> used(s.leaves.size(), 0);
        markShapeLeaves(s, o.shape, used);
        objectLeaves.push_back(std::move(used));
    }
    // Area-weighted vertex normals (the cross product's length is twice the area).
    const Mesh& m = flat.mesh;
    vertexNormals.assign(m.positions.size(), Vec3d{0, 0, 0});
    for (uint32_t t = 0; t < uint32_t(m.triangleCount()); ++t) {
        const Vec3d a = volumePassCorner(m, t, 0);
        const Vec3d n = cross(volumePassCorner(m, t, 1) - a, volumePassCorner(m, t, 2) - a);
        for (int k = 0; k < 3; ++k) vertexNormals[m.indices[3 * std::size_t(t) + std::size_t(k)]] += n;
    }
    for (Vec3d& n : vertexNormals)
        if (length(n) > 0) n = normalize(n);
}

ObjectSurfaceHit ObjectSurfaces::hit(const Frame& frame, int64_t x, int64_t y,
                                     std::span<const ListFragment> fragments, double z, std::size_t o,
                                     bool entering) const {
    ObjectSurfaceHit h;
    h.depth = z;
    h.object = uint32_t(o);
    h.entering = entering;
    // The fragments at depth z are sorted by triangle: the first whose leaf the object uses.
    auto it = std::lower_bound(fragments.begin(), fragments.end(), z,
                               [](const ListFragment& f, double d) { return f.depth < d; });
    h.triangle = it != fragments.end() ? it->triangle : 0;
    for (; it != fragments.end() && it->depth == z; ++it)
        if (objectLeaves[o][flat.triangleLeaf[it->triangle]]) {
            h.triangle = it->triangle;
            break;
        }
    const Vec3d eye = frame.eye();
    const Vec3d dir = frame.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - eye;
    h.position = eye + dir * z;
    const Vec3d a = volumePassCorner(flat.mesh, h.triangle, 0);
    Vec3d n =
        cross(volumePassCorner(flat.mesh, h.triangle, 1) - a, volumePassCorner(flat.mesh, h.triangle, 2) - a);
    n = length(n) > 0 ? normalize(n) : -normalize(dir);
    // Entering, the outside is towards the eye; leaving, away from it. Which way the leaf's triangle
    // faces does not matter: a subtracted leaf's surface points into that leaf.
    if ((dot(n, dir) < 0) != entering) n = -n;
    h.outwardNormal = n;
    return h;
}

Vec3d ObjectSurfaces::shadingNormal(const ObjectSurfaceHit& h, const Vec3d& facing) const {
    const Mesh& m = flat.mesh;
    const Vec3d a = volumePassCorner(m, h.triangle, 0), b = volumePassCorner(m, h.triangle, 1),
                c = volumePassCorner(m, h.triangle, 2);
    Vec3d ng = cross(b - a, c - a);
    const double area2 = dot(ng, ng);
    if (!(area2 > 0)) return dot(h.outwardNormal, facing) < 0 ? -h.outwardNormal : h.outwardNormal;
    ng = ng / std::sqrt(area2);
    const Vec3d& p = h.position;
    const double w[3] = {std::max(0.0, dot(cross(b - p, c - p), ng) / std::sqrt(area2)),
                         std::max(0.0, dot(cross(c - p, a - p), ng) / std::sqrt(area2)), 0};
    const double weights[3] = {w[0], w[1], std::max(0.0, 1.0 - w[0] - w[1])};
    Vec3d n{0, 0, 0};
    for (int k = 0; k < 3; ++k) {
        const Vec3d& v = vertexNormals[m.indices[3 * std::size_t(h.triangle) + std::size_t(k)]];
        // Across a crease (a box's edge, a Boolean's seam) the face normal, not an average.
        n += (dot(v, ng) > 0.766 ? v : ng) * weights[k];
    }
    n = length(n) > 0 ? normalize(n) : ng;
    return dot(ng, facing) < 0 ? -n : n;
}

std::vector<std::vector<ObjectSurfaceHit>> objectSurfaceHits(const VolumeScene& vs, const Frame& frame) {
    const ObjectSurfaces surfaces(vs);
    const FragmentLists lists = FragmentLists::build(frame, surfaces.flat.mesh.view());
    const int64_t W = frame.width(), H = frame.height();
    std::vector<std::vector<ObjectSurfaceHit>> out(std::size_t(W * H));
    parallelFor(0, H, 4, [&](int64_t y0, int64_t y1) {
        SegmentWalker walker(vs, surfaces.flat.triangleLeaf);
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = 0; x < W; ++x) {
                const auto col = lists.column(x, y);
                auto& hits = out[std::size_t(y * W + x)];
                walker.walk(
                    col,
                    [&](double z, std::size_t o, bool entering) {
                        if (z < frame.nearDepth()) return true;
                        hits.push_back(surfaces.hit(frame, x, y, col, z, o, entering));
                        return vs.objects[o].kind != ObjectKind::Opaque;
                    },
                    [](double, double, std::span<const uint8_t>) { return true; });
            }
    });
    return out;
}

namespace {

// One volume object along the current interval of a pixel's walk.
struct ObjectInterval {
    /// The value sampled at the interval's end and its PreintegratedTransfer::cumulative (reused as
    /// the next interval's start), and whether they are there (empty intervals skip the sample).
    double value = 0, cumulative = 0;
    bool have = false;
    /// The volume's voxel coordinates (VolumeView::voxelCoordinates) of the interval's end and the
    /// length along the segment they are at (NaN: none yet): the next interval's start reuses them.
    Vec3d u{0, 0, 0};
    double uAt = std::numeric_limits<double>::quiet_NaN();
    double sigma = 0; ///< the interval's extinction (0: transparent or not inside)
    Vec3f color;      ///< its pre-integrated colour
    double alpha = 0; ///< the opacity of each of the interval's pieces
};

// One light as a volume sample receives it: irradiance times shadow, and the direction to it.
struct LightSample {
    Vec3f irradiance;
    Vec3d toLight;
};

// The ray of one pixel: eye + perDepth * z for frame depth z, and what its walk has gathered.
struct PixelRay {
    int64_t x, y;
    std::span<const ListFragment> column;
    Vec3d eye, perDepth;
    double lengthPerDepth;
    double zMax;   ///< the G-buffer's depth: the walk stops at the surface it shows
    double jitter; ///< sampleJitter of the pixel: where its first volume sample falls in a step
    Vec3f color{0, 0, 0};
    double transmittance = 1;
    int64_t samples = 0;
    /// The frame depth where the transmittance first fell to one half (+inf: not yet): where the
    /// ray's matter shows, compared between the cells of refinement's lattice.
    double firstHit = std::numeric_limits<double>::infinity();
    std::vector<ObjectInterval>* objects = nullptr; ///< per object of the scene
    std::vector<LightSample>* lights = nullptr;     ///< per light of the scene, at the current sample
};

} // namespace

// What the volume pass builds from the scene alone, kept in the RenderCache across frames (the
// volume scene's objects and blended meshes, how each surface is shaded, the bricks each volume
// skips, the pre-integrated transfer functions, the sample step): a frame of a static scene
// rebuilds none of it.
struct VolumeSetup {
    std::shared_ptr<const VolumeScene> owner; ///< the scene's volume scene, or one with the blended meshes
    const VolumeScene& vs;
    std::vector<Material> materials; ///< per object: how its surface is shaded
    ObjectSurfaces surfaces;
    std::vector<EmptySpace> emptySpace;
    std::vector<PreintegratedTransfer> preintegrated; ///< per Volume object
    std::vector<VolumeView> views;                    ///< per Volume object, its volume's (else empty)
    /// World length between the samples of the shadow lookup's step towards the light: the smallest
    /// volume's (volumeStep of the smallest voxel spacing of any volume).
    double step;
    /// Per object: world length between its samples, volumeStep of its volume's smallest voxel
    /// spacing (+inf for other kinds); a segment inside several volumes takes the smallest.
    std::vector<double> objectStep;
    /// Per object: a Volume object whose shape is its volume's box (addVolumeBox), which the box
    /// clips exactly.
    std::vector<uint8_t> boxShape;
    /// Under deep shadows, with a Volume object of another shape: the leaves, to find where the step
    /// towards the light leaves the shape (ownTransmittance).
    std::unique_ptr<TriangleTracer> leafTracer;
    /// Per Volume object, phong: the gradient magnitude (value per world unit) from which a sample
    /// is fully shaded; +inf for a constant volume (never shaded).
    std::vector<double> fullGradient;
    /// Phong: a change of this fraction of the volume's value range per voxel shades fully.
    static constexpr double kFullShadingChange = 0.05;
    std::vector<Vec3f> faceNormals; ///< unit, per flattened triangle (zero when degenerate)
    /// Per Volume object, its volume's gradient at the voxel centres (phong's normals; GradientGrid).
    std::vector<GradientGrid> gradients;

    VolumeSetup(const Scene& scene, std::shared_ptr<const VolumeScene> chosen, const RenderOptions& options,
                bool deep)
        : owner(std::move(chosen)), vs(*owner), materials(objectMaterials(scene, vs)), surfaces(vs),
          emptySpace(options.skipEmptySpace ? emptySpaceOf(vs) : std::vector<EmptySpace>(vs.objects.size())),
          preintegrated(preintegrate(vs)), views(volumeViews(vs)), step(sampleStep(vs) * options.volumeStep),
          objectStep(objectSteps(vs, options.volumeStep)), boxShape(boxShapes(vs)),
          fullGradient(fullGradients(vs)) {
        bool otherShape = false;
        for (std::size_t o = 0; o < vs.objects.size(); ++o)
            otherShape |= vs.objects[o].kind == ObjectKind::Volume && !boxShape[o];
        if (deep && otherShape && surfaces.flat.mesh.triangleCount() > 0)
            leafTracer = std::make_unique<TriangleTracer>(surfaces.flat.mesh.view());
        const Mesh& m = surfaces.flat.mesh;
        faceNormals.resize(m.triangleCount());
        for (std::size_t t = 0; t < faceNormals.size(); ++t) {
            const Vec3d p = volumePassCorner(m, uint32_t(t), 0);
            const Vec3d n =
                cross(volumePassCorner(m, uint32_t(t), 1) - p, volumePassCorner(m, uint32_t(t), 2) - p);
            faceNormals[t] = length(n) > 0 ? Vec3f(normalize(n)) : Vec3f{0, 0, 0};
        }
        gradients.resize(vs.objects.size());
        for (std::size_t o = 0; o < vs.objects.size(); ++o)
            if (vs.objects[o].kind == ObjectKind::Volume)
                gradients[o] = GradientGrid(*vs.volumes[std::size_t(vs.objects[o].volume)]);
    }

    // The transmittance of the volume objects `inside` (those holding p) along the segment from p
    // to q that the shadow lookup leaves out: per object, the part of the segment inside its
    // volume's box and, where its shape is not that box, up to the first surface of the volume
    // scene's leaves, with the smaller of the extinctions at its two ends. A homogeneous medium
    // passes its Beer–Lambert (a uniform slab is the closed form within the map's epsilon); a
    // dense layer the sample lies at the front of passes what lies in front of it, so the layer
    // does not shadow its own surface (the lookup's step is there for that; the pre-integrated
    // mean of the two ends, between bone and skin, lit each sample by where its jittered start
    // fell: speckle on the DSM demo's skull).
    double ownTransmittance(const Vec3d& p, const Vec3d& q, std::span<const uint8_t> inside) const {
        double depth = 0;
        for (std::size_t o = 0; o < inside.size(); ++o) {
            const VolumeSceneObject& obj = vs.objects[o];
            if (!inside[o] || obj.kind != ObjectKind::Volume) continue;
            const Volume& volume = *vs.volumes[std::size_t(obj.volume)];
            const VolumeView v = volume.view();
            // The segment's parameter range inside the box: 0 <= voxel coordinate <= n on each axis.
            const int64_t n[3] = {v.nx, v.ny, v.nz};
            double t1 = 1;
            for (int a = 0; a < 3 && t1 > 0; ++a) {
                const double wp = v.voxelCoordinate(p, a), dw = v.voxelCoordinate(q, a) - wp;
                if (dw > 0) t1 = std::min(t1, (double(n[a]) - wp) / dw);
                if (dw < 0) t1 = std::min(t1, -wp / dw);
            }
            if (!(t1 > 0)) continue;
            if (!boxShape[o] && leafTracer) {
                const double len = length(q - p);
                const TriangleTracer::Hit h = leafTracer->intersect(p, (q - p) * (1 / len), 0, t1 * len);
                if (h.hit) t1 = h.t / len;
            }
            const Vec3d c = p + (q - p) * t1;
            if (emptySpace[o].emptyBetween(p, c)) continue;
            const double a = volume.sample(p), b = volume.sample(c);
            // The smaller of the two ends' extinctions (one logarithm, no cumulative integrals).
            depth += preintegrated[o].smallerPointExtinction(a, b) * length(c - p);
        }
        return std::exp(-depth);
    }

    static std::vector<uint8_t> boxShapes(const VolumeScene& vs) {
        std::vector<uint8_t> out(vs.objects.size(), 0);
        for (std::size_t o = 0; o < vs.objects.size(); ++o) {
            const VolumeSceneObject& obj = vs.objects[o];
            if (obj.kind != ObjectKind::Volume) continue;
            const ShapeNode& n = vs.nodes[std::size_t(obj.shape)];
            if (n.op != ShapeOp::Leaf) continue;
            const Mesh& leaf = vs.leaves[std::size_t(n.leaf)];
            const Volume& v = *vs.volumes[std::size_t(obj.volume)];
            const Box3d a = computeBounds(leaf.view()), b = v.box();
            const double tol = 1e-6 * length(b.extent());
            bool same = leaf.triangleCount() == 12;
            for (int k = 0; k < 3; ++k)
                same = same && std::abs(a.lo[k] - b.lo[k]) <= tol && std::abs(a.hi[k] - b.hi[k]) <= tol &&
                       std::abs(v.axis(k)[k] - 1) <= 1e-12;
            out[o] = same;
        }
        return out;
    }

    static std::vector<double> fullGradients(const VolumeScene& vs) {
        std::vector<double> out(vs.objects.size(), std::numeric_limits<double>::infinity());
        for (std::size_t o = 0; o < vs.objects.size(); ++o)
            if (vs.objects[o].kind == ObjectKind::Volume) {
                const Volume& v = *vs.volumes[std::size_t(vs.objects[o].volume)];
                const double range = double(v.maxValue()) - double(v.minValue());
                const Vec3d h = v.spacing();
                if (range > 0) out[o] = kFullShadingChange * range / std::min({h.x, h.y, h.z});
            }
        return out;
    }

    static std::vector<VolumeView> volumeViews(const VolumeScene& vs) {
        std::vector<VolumeView> out(vs.objects.size());
        for (std::size_t o = 0; o < vs.objects.size(); ++o)
            if (vs.objects[o].kind == ObjectKind::Volume)
                out[o] = vs.volumes[std::size_t(vs.objects[o].volume)]->view();
        return out;
    }

    static std::vector<PreintegratedTransfer> preintegrate(const VolumeScene& vs) {
        std::vector<PreintegratedTransfer> out(vs.objects.size());
        for (std::size_t o = 0; o < vs.objects.size(); ++o)
            if (vs.objects[o].kind == ObjectKind::Volume)
                out[o] = PreintegratedTransfer(vs.objects[o].transfer, vs.objects[o].opacityLength);
        return out;
    }

    // Opaque and translucent objects are shaded as meshes of their colour and opacity (a blended
    // mesh with its own material).
    static std::vector<Material> objectMaterials(const Scene& scene, const VolumeScene& vs) {
        std::vector<Material> materials(vs.objects.size());
        for (std::size_t o = 0; o < vs.objects.size(); ++o) {
            const VolumeSceneObject& obj = vs.objects[o];
            materials[o].opacity = obj.kind == ObjectKind::Translucent ? obj.opacity : 1.0f;
            if (obj.material >= 0) {
                // The mesh's own material; the eye sees its coverage (opacity), whatever its tissue
                // passes to the shadows.
                materials[o] = scene.materials[std::size_t(obj.material)];
                if (obj.kind != ObjectKind::Translucent) materials[o].opacity = 1;
            }
            materials[o].name = obj.name;
            materials[o].baseColor = obj.color;
        }
        return materials;
    }

    // The smallest voxel spacing of the volumes (+inf without volumes).
    static double sampleStep(const VolumeScene& vs) {
        double spacing = std::numeric_limits<double>::infinity();
        for (const double s : objectSteps(vs, 1.0)) spacing = std::min(spacing, s);
        return spacing;
    }

    // Per object, `volumeStep` times its volume's smallest voxel spacing (+inf for other kinds).
    static std::vector<double> objectSteps(const VolumeScene& vs, double volumeStep) {
        std::vector<double> out(vs.objects.size(), std::numeric_limits<double>::infinity());
        for (std::size_t o = 0; o < vs.objects.size(); ++o)
            if (vs.objects[o].kind == ObjectKind::Volume) {
                const Vec3d s = vs.volumes[std::size_t(vs.objects[o].volume)]->spacing();
                out[o] = std::min({s.x, s.y, s.z}) * volumeStep;
            }
        return out;
    }
};

namespace {

// What the pass composites in this frame: the cached setup, shaded under the frame's lights.
struct VolumeComposite {
    const FrameState& frame;
    const VolumeSetup& setup;
    const VolumeScene& vs;
    const std::vector<Material>& materials;
    const ObjectSurfaces& surfaces;
    const std::vector<EmptySpace>& emptySpace;
    const std::vector<PreintegratedTransfer>& preintegrated;
    double step;
    const std::vector<uint8_t>& boxShape;
    const TriangleTracer* leafTracer;
    static constexpr double kPieceDepth = 0.5; ///< optical depth of the pieces of a dense interval
    /// Early ray termination inside volumes: a walk whose transmittance falls below this stops, and
    /// the light it would still have let through is that of the piece it stops at (the matter
    /// behind, in the layer's own shadow, lit like its front: dropping it would show what lies
    /// behind by up to this fraction).
    static constexpr double kOpaque = 1e-2;
    /// Phong shading of volume samples (RenderOptions::volumeShading) with lights to shade by.
    bool shaded;
    const std::vector<double>& fullGradient;
    std::vector<LightCone> cones; ///< per light of the frame
    /// Per light under deep shadows, its visibility grids per volume object (lightGrids); else null.
    std::vector<const VolumeLightGrids*> grids;
    /// Whether pieces inside one volume take their light from the pre-lit grids (volumePrelit()).
    bool prelit = volumePrelit();

    VolumeComposite(const FrameState& f, const VolumeSetup& s, std::vector<const VolumeLightGrids*> g)
        : frame(f), setup(s), vs(s.vs), materials(s.materials), surfaces(s.surfaces),
          emptySpace(s.emptySpace), preintegrated(s.preintegrated), step(s.step), boxShape(s.boxShape),
          leafTracer(s.leafTracer.get()),
          shaded(f.options.volumeShading == VolumeShading::Phong && !f.lights.empty()),
          fullGradient(s.fullGradient), grids(std::move(g)) {
        for (const Light& l : f.lights) cones.emplace_back(l);
        grids.resize(f.lights.size(), nullptr);
    }

    // A surface of object o at depth z: shaded and composited; false stops the walk.
    bool surface(PixelRay& r, double z, std::size_t o, bool entering) const {
        const Frame& f = frame.gbuffer.frame;
        if (z >= r.zMax) return false;
        if (z < f.nearDepth()) return true;
        const ObjectSurfaceHit h = surfaces.hit(f, r.x, r.y, r.column, z, o, entering);
        SurfacePoint s;
        s.position = h.position;
        s.geometricNormal = dot(h.outwardNormal, r.perDepth) < 0 ? h.outwardNormal : -h.outwardNormal;
        s.normal = surfaces.shadingNormal(h, -r.perDepth);
        const Material& m = materials[o];
        const double a = m.opacity;
        r.color += shadePoint(frame, s, m, r.eye) * float(a * r.transmittance);
        r.transmittance *= 1.0 - a;
        if (r.transmittance <= 0.5 && std::isinf(r.firstHit)) r.firstHit = z;
        return r.transmittance >= 1e-3;
    }

    // Light arriving at volume sample p inside the volume objects `inside`: returns the ambient
    // light (the constant and the sky's mean radiance, its order-0 harmonic) and sets `lights` to
    // every light's irradiance times its shadow (shadowAt), looked up at p moved one sample step
    // towards the light (and given that direction as the lookup's normal, so the technique adds its
    // own offset): a shadow map samples the volume in steps of its own, and a dense layer the sample
    // lies at the front of (bone under skin) must not shadow its own surface by the step over which
    // the map's visibility falls. Under deep and exact shadows the medium over that step and the
    // offsets, which the lookup leaves out, is put back (ownTransmittance; without it a uniform slab
    // was brighter by exp(sigma * the offset), 8 %). `unshaded` is the ambient plus every light's
    // irradiance / pi: the light a sample takes without a normal.
    //
    // Where p lies inside volume objects (`first`, the first of them, else -1; `several`: more than
    // one) and a deep-shadowed light's grids hold the pre-lit volume of each (LightVisibilityGrid::
    // lookupLight, built for volumes whose shape is their box: irradiance, the map's lookup and the
    // volume's own transmittance made at the voxel corners), that light's term is read from them
    // instead (prelitLight).
    // `u`: p's voxel coordinates in the first volume's (when first >= 0).
    Vec3f lightAt(const Vec3d& p, const Vec3d& u, std::span<const uint8_t> inside, int first, bool several,
                  std::vector<LightSample>& lights, Vec3f& unshaded) const {
        const std::span<const Light> sceneLights = frame.lights;
        const Vec3f ambient = frame.options.ambient + frame.environment->sphericalHarmonics()[0] *
                                                          float(0.282095 * frame.options.skyLight);
        unshaded = ambient;
        lights.clear();
        for (std::size_t l = 0; l < sceneLights.size(); ++l) {
            Vec3d toLight;
            Vec3f ev;
            if (first >= 0 && prelit && grids[l] &&
                prelitLight(*grids[l], p, u, inside, first, several, ev)) {
                if (ev.x <= 0 && ev.y <= 0 && ev.z <= 0) continue;
                unshaded += ev * float(1.0 / M_PI);
                lights.push_back({ev, directionToLight(sceneLights[l], p)});
                continue;
            }
            const Vec3f e = lightIrradiance(sceneLights[l], cones[l], p, toLight);
            if (e.x <= 0 && e.y <= 0 && e.z <= 0) continue;
            const Vec3f vis = l < frame.shadows.size()
                                  ? shadowAt(*frame.shadows[l], grids[l], p, toLight, inside)
                                  : Vec3f{1, 1, 1};
            ev = e * vis;
            unshaded += ev * float(1.0 / M_PI);
            lights.push_back({ev, toLight});
        }
        return ambient;
    }

    // The pre-lit light at p inside the volume objects `inside`, the first of them `first` (`u`: p's
    // voxel coordinates in it): one trilinear lookup of its pre-lit grid (its light, the map's lookup
    // and its own transmittance). Where p lies inside other volumes too (`several`), the light of the
    // first of them whose grid has a value at p (the per-piece path's visibility is the first grid's
    // that covers p) times each other's own transmittance: from its grid, or 1 where p lies in one of
    // its empty bricks, where its grid is not filled (the per-piece path takes the smaller extinction
    // of the step's two ends, 0 at p). False where that is not known (a volume of another shape, or
    // no grid has a value): the caller lights the piece itself.
    bool prelitLight(const VolumeLightGrids& g, const Vec3d& p, const Vec3d& u,
                     std::span<const uint8_t> inside, int first, bool several, Vec3f& light) const {
        if (!several) return g.objects[std::size_t(first)].lookupLightVoxel(u, light);
        bool lit = false;
        float own = 1;
        for (std::size_t o = std::size_t(first); o < inside.size(); ++o) {
            if (!inside[o] || vs.objects[o].kind != ObjectKind::Volume) continue;
            const LightVisibilityGrid& grid = g.objects[o];
            if (!grid.prelit()) return false; // a volume lit per piece
            Vec3f l;
            float t = 1;
            const bool found = int(o) == first ? grid.lookupLightVoxel(u, l, &t) : grid.lookupLight(p, l, &t);
            if (found && !lit)
                light = l, lit = true;
            else if (found)
                own *= t;
            else if (!emptySpace[o].empty(p))
                return false;
        }
        if (!lit) return false;
        light = light * own;
        return true;
    }

    // The shadow of volume sample p (see lightAt): looked up at q, a step towards the light; under
    // deep and exact shadows times ownTransmittance from p to where the lookup starts (deep: q
    // moved towards the light by the normal offset and the depth bias, a texel footprint each by
    // default; exact: the shadow ray's start, 10 epsilons beyond q; without it a uniform slab was
    // 4 % brighter than Beer-Lambert under exact shadows). Under deep shadows the map's lookup (its
    // visibility and texel footprint) is read from the light's grid of the first volume inside
    // that covers p (`grids`, LightVisibilityGrid: the same lookup at the volume's voxel corners,
    // interpolated), else made here.
    Vec3f shadowAt(const LightShadow& shadow, const VolumeLightGrids* grids, const Vec3d& p,
                   const Vec3d& toLight, std::span<const uint8_t> inside) const {
        const Vec3d q = p + toLight * step;
        if (const ExactShadow* exact = std::get_if<ExactShadow>(&shadow))
            return exact->visibility(q, toLight) *
                   float(ownTransmittance(p, q + toLight * (10 * exact->epsilon()), inside));
        const DeepShadow* deep = std::get_if<DeepShadow>(&shadow);
        if (!deep) return shadowVisibility(shadow, q, toLight);
        const DeepShadowOptions* o = std::get_if<DeepShadowOptions>(&frame.options.shadow);
        const double offsets = o ? o->normalOffset + o->depthBias : 2.0;
        double texel = 0;
        Vec3f visibility;
        bool cached = false;
        if (grids)
            for (std::size_t k = 0; k < inside.size() && !cached; ++k)
                cached = inside[k] && grids->objects[k].lookup(p, visibility, texel);
        if (!cached) visibility = deep->visibility(q, toLight, texel);
        return visibility * float(ownTransmittance(p, q + toLight * (offsets * texel), inside));
    }

    double ownTransmittance(const Vec3d& p, const Vec3d& q, std::span<const uint8_t> inside) const {
        return setup.ownTransmittance(p, q, inside);
    }

    // Phong (DSM §3.2) at sample p of volume object o: the diffuse light (times the sample's colour)
    // and the specular radiance (white), blended with the unshaded light by the gradient's
    // magnitude: s = min(1, |g| / fullGradient); diffuse = ambient + sum E ((1 - s) + s max(0, n.l)) / pi,
    // specular = s sum E ks (m + 8) / (8 pi) max(0, n.h)^m max(0, n.l) with n = -g / |g|.
    // `u`: p's voxel coordinates in o's volume, where the caller has them (else null).
    void phong(const Vec3d& p, const Vec3d* u, std::size_t o, const Vec3d& eye,
               const std::vector<LightSample>& lights, const Vec3f& ambient, const Vec3f& unshaded,
               Vec3f& diffuse, Vec3f& specular) const {
        Vec3d g;
        const GradientGrid& grid = setup.gradients[o];
        if (!(u ? grid.lookupVoxel(*u, g) : grid.lookup(p, g)))
            g = vs.volumes[std::size_t(vs.objects[o].volume)]->gradient(p);
        const double gm = length(g);
        const double s = std::min(1.0, gm / fullGradient[o]);
        specular = {0, 0, 0};
        if (!(s > 0)) {
            diffuse = unshaded;
            return;
        }
        const Vec3d n = g * (-1.0 / gm);
        const Vec3d toEye = normalize(eye - p);
        const Material& m = materials[o];
        const double ks = double(m.specular) * (m.shininess + 8) / (8 * M_PI);
        diffuse = ambient;
        for (const LightSample& l : lights) {
            const double ndl = std::max(0.0, dot(n, l.toLight));
            diffuse += l.irradiance * float(((1 - s) + s * ndl) / M_PI);
            if (ndl > 0 && ks > 0) {
                const Vec3d h = normalize(l.toLight + toEye);
                specular += l.irradiance *
                            float(s * ks * std::pow(std::max(0.0, dot(n, h)), double(m.shininess)) * ndl);
            }
        }
    }

    // Empty-space leaping: after an interval every volume inside skipped (its ends in empty
    // bricks), the index of the last sample before the ray, from p1 at length l1 of the segment,
    // enters a brick of one of them that is not empty (EmptySpace::emptyRun), less a millionth of
    // a step; j (the index of l1's sample) where that is no further. The intervals up to it lie in
    // empty bricks, which touch while the step is at most a brick (4 voxels): each would have been
    // skipped one by one, so leaping over them changes no pixel. The caller's next interval starts
    // at that sample, computed as the loop computes it.
    int64_t lastEmptySample(const PixelRay& r, const Vec3d& p1, double l1, double worldLength,
                            double segmentStep, std::span<const uint8_t> inside, int64_t j) const {
        const Vec3d dir = r.perDepth * (1 / r.lengthPerDepth);
        double run = worldLength - l1;
        for (std::size_t o = 0; o < inside.size() && run > 0; ++o)
            if (inside[o] && vs.objects[o].kind == ObjectKind::Volume)
                run = std::min(run, emptySpace[o].emptyRun(p1, dir, run));
        const double until = l1 + run - 1e-6 * segmentStep;
        const double last = std::floor(until / segmentStep - r.jitter);
        return last > double(j) ? int64_t(last) : j;
    }

    // Volume object o's interval from p0 to p1 (lengths l0, l1 along the segment): its extinction
    // and colour into the ray's ObjectInterval (sigma 0: transparent), its end sampled. False where
    // both ends lie in empty bricks (nothing sampled). The ends' voxel coordinates are computed once
    // for the empty bricks and the samples: the start's are the last interval's end's (the same
    // point, bit for bit) where it was computed.
    bool sampleInterval(PixelRay& r, std::size_t o, const Vec3d& p0, const Vec3d& p1, double l0,
                        double l1) const {
        ObjectInterval& w = (*r.objects)[o];
        const VolumeView& view = setup.views[o];
        const Vec3d u0 = w.uAt == l0 ? w.u : view.voxelCoordinates(p0);
        const Vec3d u1 = view.voxelCoordinates(p1);
        w.u = u1, w.uAt = l1;
        if (emptySpace[o].emptyBetweenVoxel(u0, u1)) { // would be transparent
            w.have = false;
            return false;
        }
        // Transparent lattice cells (not a whole brick): the interval's extinction is exactly 0
        // without its samples (the next interval samples its start again: the same value).
        if (emptySpace[o].transparentBetweenVoxel(u0, u1)) {
            w.have = false;
            return true;
        }
        const PreintegratedTransfer& pre = preintegrated[o];
        if (!w.have) {
            w.value = view.sampleVoxel(u0);
            w.cumulative = pre.cumulative(w.value);
            ++r.samples;
        }
        const double a = w.value, ca = w.cumulative;
        w.value = view.sampleVoxel(u1);
        w.cumulative = pre.cumulative(w.value);
        w.have = true;
        ++r.samples;
        w.sigma = pre.extinction(a, ca, w.value, w.cumulative);
        if (w.sigma > 0) {
            const Vec3d c = pre.color(a, w.value);
            w.color = Vec3f{float(c.x), float(c.y), float(c.z)};
        }
        return true;
    }

    // The segment [z0, z1) inside the volume objects `inside`, composited front to back; false
    // stops the walk. Its samples lie at the segment's ends and at z0 + (j + jitter) steps between
    // them, the step of the finest volume inside (segmentStep: the smoke, 48³ over 1.8 units, is not
    // marched at the skull's spacing, 1.6 samples per voxel); each interval between two samples takes the
    // pre-integrated extinction and colour of the values at its ends (exact for a homogeneous volume:
    // Beer-Lambert over its length) and the light at its middle.
    bool segment(PixelRay& r, double z0, double z1, std::span<const uint8_t> inside) const {
        if (z0 >= r.zMax) return false;
        z1 = std::min(z1, r.zMax);
        const double worldLength = (z1 - z0) * r.lengthPerDepth;
        const double depthPerLength = (z1 - z0) / worldLength;
        for (ObjectInterval& w : *r.objects) w.have = false, w.uAt = std::numeric_limits<double>::quiet_NaN();
        double segmentStep = std::numeric_limits<double>::infinity();
        for (std::size_t o = 0; o < inside.size(); ++o)
            if (inside[o]) segmentStep = std::min(segmentStep, setup.objectStep[o]);
        if (!(segmentStep < std::numeric_limits<double>::infinity())) segmentStep = step; // no volume
        int first = -1; // the first volume object inside, if any
        bool several = false;
        for (std::size_t o = 0; o < inside.size(); ++o)
            if (inside[o] && vs.objects[o].kind == ObjectKind::Volume) {
                several = first >= 0;
                if (first < 0) first = int(o);
            }
        double l0 = 0;
        for (int64_t j = 0; l0 < worldLength; ++j) {
            const double l1 = std::min(worldLength, (double(j) + r.jitter) * segmentStep);
            if (!(l1 > l0)) continue;
            const Vec3d p0 = r.eye + r.perDepth * (z0 + l0 * depthPerLength);
            const Vec3d p1 = r.eye + r.perDepth * (z0 + l1 * depthPerLength);
            const double dl = l1 - l0;
            // Each object's extinction over the interval (opacity first: the colour only where
            // something shows).
            double sigmaSum = 0;
            bool allEmpty = true; // every volume inside is in empty bricks over the interval
            for (std::size_t o = 0; o < inside.size(); ++o) {
                ObjectInterval& w = (*r.objects)[o];
                w.sigma = 0;
                if (!inside[o] || vs.objects[o].kind != ObjectKind::Volume) continue;
                if (sampleInterval(r, o, p0, p1, l0, l1)) allEmpty = false;
                sigmaSum += w.sigma;
            }
            if (!(sigmaSum > 0)) {
                l0 = l1;
                if (allEmpty && l1 < worldLength) {
                    const int64_t last = lastEmptySample(r, p1, l1, worldLength, segmentStep, inside, j);
                    if (last > j) j = last, l0 = std::min(worldLength, (double(j) + r.jitter) * segmentStep);
                }
                continue;
            }
            // A dense interval in pieces of optical depth at most kPieceDepth (up to 8), each lit
            // where its matter shows on average (its opacity-weighted depth: the middle of a thin
            // piece, 1/sigma behind the start of a dense one): the light falls fast across a dense
            // layer, and one lookup per step would weigh it by where the step happened to start.
            const int64_t pieces = std::clamp<int64_t>(int64_t(std::ceil(sigmaSum * dl / kPieceDepth)), 1, 8);
            const double pl = dl / double(pieces), x = sigmaSum * pl;
            const double lightDepth = x < 1e-6 ? 0.5 * pl : (1 - x / std::expm1(x)) / sigmaSum;
            for (std::size_t o = 0; o < inside.size(); ++o) {
                ObjectInterval& w = (*r.objects)[o];
                if (w.sigma > 0) w.alpha = -std::expm1(-w.sigma * pl); // the same for every piece
            }
            for (int64_t k = 0; k < pieces && r.transmittance >= kOpaque; ++k) {
                const Vec3d p = p0 + (p1 - p0) * ((double(k) * pl + lightDepth) / dl);
                // p's voxel coordinates in the first volume inside, for its grids' lookups.
                const Vec3d u =
                    first >= 0 ? setup.views[std::size_t(first)].voxelCoordinates(p) : Vec3d{0, 0, 0};
                Vec3f unshaded;
                const Vec3f ambient = lightAt(p, u, inside, first, several, *r.lights, unshaded);
                Vec3f lit{0, 0, 0}; // the last object's light per unit opacity
                for (std::size_t o = 0; o < inside.size(); ++o) {
                    const ObjectInterval& w = (*r.objects)[o];
                    if (!(w.sigma > 0)) continue;
                    const double alpha = w.alpha;
                    const float weight = float(alpha * r.transmittance * frame.options.exposure);
                    if (shaded) {
                        Vec3f diffuse, specular;
                        phong(p, int(o) == first ? &u : nullptr, o, r.eye, *r.lights, ambient, unshaded,
                              diffuse, specular);
                        lit = w.color * diffuse + specular;
                    } else {
                        lit = w.color * unshaded;
                    }
                    r.color += lit * weight;
                    r.transmittance *= 1.0 - alpha;
                }
                if (r.transmittance <= 0.5 && std::isinf(r.firstHit))
                    r.firstHit = z0 + (l0 + double(k) * pl + lightDepth) * depthPerLength;
                if (r.transmittance < kOpaque) { // terminated: the rest lit like this piece
                    r.color += lit * float(r.transmittance * frame.options.exposure);
                    r.transmittance = 0;
                }
            }
            if (r.transmittance < kOpaque) return false;
            l0 = l1;
        }
        return true;
    }
};

// The faces a column's fragments nearer than z cross, in order: leaves and face normals, compared
// between the samples of a cell (a volume's, a Boolean's or a blended mesh's edge).
struct ColumnCrossings {
    const std::vector<uint32_t>& leaf;
    const std::vector<Vec3f>& faceNormal; ///< unit, per flattened triangle (zero when degenerate)

    // Whether columns a (up to depth za) and b (up to zb) cross the same leaves in the same order,
    // with faces within 30 degrees where they cross different triangles.
    bool same(std::span<const ListFragment> a, double za, std::span<const ListFragment> b, double zb,
              double nearDepth) const {
        const float cos30 = 0.866f;
        auto first = [&](std::span<const ListFragment> c) {
            std::size_t i = 0;
            while (i < c.size() && c[i].depth < nearDepth) ++i;
            return i;
        };
        std::size_t i = first(a), j = first(b);
        for (; i < a.size() && a[i].depth < za && j < b.size() && b[j].depth < zb; ++i, ++j) {
            const uint32_t ta = a[i].triangle, tb = b[j].triangle;
            if (ta == tb) continue;
            if (leaf[ta] != leaf[tb] || std::abs(dot(faceNormal[ta], faceNormal[tb])) < cos30) return false;
        }
        return !(i < a.size() && a[i].depth < za) && !(j < b.size() && b[j].depth < zb);
    }
};

// The camera's rays through the volume scene: one sample's walk composited over what the passes
// before shaded there.
struct SampleCaster {
    const FrameState& frame;
    const VolumeComposite& pass;
    const FragmentLists& lists;
    const VolumeScene& scene;

    struct Walker { // per thread
        SegmentWalker walker;
        std::vector<ObjectInterval> objects;
        std::vector<LightSample> lights;
        int64_t samples = 0;
    };
    Walker walker() const {
        Walker w{SegmentWalker(scene, pass.surfaces.flat.triangleLeaf),
                 std::vector<ObjectInterval>(scene.objects.size()),
                 {},
                 0};
        w.lights.reserve(frame.lights.size());
        return w;
    }
    // The G-buffer's depth at sample i: the walk stops at the surface it shows.
    double zMax(std::size_t i) const {
        const GBuffer& g = frame.gbuffer;
        return g.triangle[i] != GBuffer::kNone ? double(g.depth[i]) : std::numeric_limits<double>::infinity();
    }
    // What the volumes along one sample's ray give: their light (composited front to back) and the
    // transmittance that passes the light behind them.
    struct Gathered {
        Vec3f color{0, 0, 0};
        double transmittance = 1;
        double firstHit = std::numeric_limits<double>::infinity(); ///< PixelRay::firstHit
        // Composited over `behind`.
        Vec3f over(const Vec3f& behind) const {
            return transmittance < 1.0 ? color + behind * float(transmittance) : behind;
        }
    };
    // The ray of sample (x, y) walked through the volume scene up to the G-buffer's surface.
    Gathered gather(Walker& w, int64_t x, int64_t y) const {
        const auto col = lists.column(x, y);
        if (col.empty()) return {};
        const Frame& f = frame.gbuffer.frame;
        const std::size_t i = std::size_t(y * f.width() + x);
        PixelRay r{x, y, col, f.eye(), {}, 0, 0, sampleJitter(x, y, 1)};
        r.objects = &w.objects;
        r.lights = &w.lights;
        r.perDepth = f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0}) - r.eye;
        r.lengthPerDepth = length(r.perDepth);
        r.zMax = zMax(i);
        w.walker.walk(
            col, [&](double z, std::size_t o, bool entering) { return pass.surface(r, z, o, entering); },
            [&](double z0, double z1, std::span<const uint8_t> inside) {
                return pass.segment(r, z0, z1, inside);
            });
        w.samples += r.samples;
        return {r.color, r.transmittance, r.firstHit};
    }
    // Sample (x, y) composited over `behind` into `out`.
    void cast(Walker& w, int64_t x, int64_t y, const Vec3f& behind, Vec3f& out) const {
        out = gather(w, x, y).over(behind);
    }
};

// Whether adaptive anti-aliasing shades every sample of cell (cx, cy), shaded once so far, for what
// the volume pass draws there: its samples' rays cross different faces of the volume scene (the
// edge of a volume's box, of a Boolean's shape, of a blended mesh; a crease), or the rays cross
// something and the cell's composited light bends or steps between its neighbours' by more than
// the post-process would leave (curvesAcrossNeighbours: an edge inside a volume, the bone under
// skin).
bool volumeEdge(const FrameState& f, const SampleCaster& c, const ColumnCrossings& crossings,
                std::span<const float> lumas, int64_t cx, int64_t cy) {
    const int a = f.adaptive;
    const std::size_t rep = representativeSample(f, cx, cy);
    const int64_t W = f.width, rx = int64_t(rep % std::size_t(W)), ry = int64_t(rep / std::size_t(W));
    const auto own = c.lists.column(rx, ry);
    const double near = f.gbuffer.frame.nearDepth();
    bool crossed = !own.empty();
    for (int dy = 0; dy < a; ++dy)
        for (int dx = 0; dx < a; ++dx) {
            const int64_t x = cx * a + dx, y = cy * a + dy;
            const std::size_t i = std::size_t(y * W + x);
            if (i == rep) continue;
            const auto col = c.lists.column(x, y);
            crossed |= !col.empty();
            if ((!col.empty() || !own.empty()) && !crossings.same(own, c.zMax(rep), col, c.zMax(i), near))
                return true;
        }
    if (!crossed) return false;
    // curvesAcrossNeighbours(f, cx, cy), its shown lumas read from `lumas` (per cell, its
    // representative's: the round changes no representative).
    const int64_t cw = W / a;
    const auto luma = [&](int64_t x, int64_t y) { return lumas[std::size_t(y * cw + x)]; };
    return curvesAcross(luma, cx, cy, cw, f.height / a, kRefineContrast);
}

// The volume pass's setup for this frame's scene and options: from the cache while the meshes,
// materials, volume scene and the options it reads stay the same; null when the camera sees no
// volume scene object and no blended mesh.
std::shared_ptr<const VolumeSetup> volumeSetup(FrameState& frame, uint64_t& setupKey) {
    const Scene& scene = frame.scene;
    const RenderOptions& options = frame.options;
    // What the camera draws here: the volume scene's objects, and the meshes of blended materials
    // (left out of the G-buffer) as translucent objects.
    const bool anyBlended = std::any_of(scene.meshes.begin(), scene.meshes.end(), [&](const SceneMesh& m) {
        return m.material < scene.materials.size() && scene.materials[m.material].blend;
    });
    if (!anyBlended && !(scene.volumeScene && !scene.volumeScene->objects.empty())) return nullptr;
    const bool deep = std::any_of(frame.shadows.begin(), frame.shadows.end(),
                                  [](const auto& s) { return std::holds_alternative<DeepShadow>(*s); });
    Hasher key;
    key.value(frame.meshesKey), key.value(frame.materialsKey), key.value(options.skipEmptySpace);
    key.value(options.volumeStep), key.value(deep);
    setupKey = key.get();
    std::shared_ptr<const VolumeSetup> setup = frame.cache.volume.find(key.get());
    if (setup) {
        frame.cachedPass = true;
    } else {
        std::shared_ptr<const VolumeScene> chosen =
            anyBlended ? std::make_shared<const VolumeScene>(volumeSceneOf(scene, SceneMeshes::Blended))
                       : scene.volumeScene;
        setup = std::make_shared<const VolumeSetup>(scene, std::move(chosen), options, deep);
        frame.cache.volume.insert(key.get(), setup);
    }
    return setup->vs.objects.empty() ? nullptr : setup;
}

// Per light of the frame under deep shadows, its LightVisibilityGrid of every volume object of the
// setup's scene (null for other lights): from the cache while the setup (`setupKey`) and the light's
// shadow (FrameState::shadowKeys: its meshes, materials, light and options) stay the same, else
// built, which the first frame pays (the pass's time is then not "cached"). `lights` keeps them.
std::vector<const VolumeLightGrids*>
lightGrids(FrameState& frame, const VolumeSetup& setup, uint64_t setupKey,
           std::vector<std::shared_ptr<const VolumeLightGrids>>& lights) {
    const std::size_t n = frame.lights.size();
    std::vector<const VolumeLightGrids*> out(n, nullptr);
    lights.assign(n, nullptr);
    frame.cache.volumeLight.setCapacity(std::max<std::size_t>(4, 2 * n));
    const VolumeScene& vs = setup.vs;
    for (std::size_t l = 0; l < n && l < frame.shadows.size() && l < frame.shadowKeys.size(); ++l) {
        const DeepShadow* deep = std::get_if<DeepShadow>(frame.shadows[l].get());
        if (!deep) continue;
        Hasher key;
        key.value(setupKey), key.value(frame.shadowKeys[l]);
        std::shared_ptr<const VolumeLightGrids> g = frame.cache.volumeLight.find(key.get());
        if (!g) {
            frame.cachedPass = false;
            auto built = std::make_shared<VolumeLightGrids>();
            built->objects.resize(vs.objects.size());
            const LightCone cone(frame.lights[l]);
            const DeepShadowOptions* d = std::get_if<DeepShadowOptions>(&frame.options.shadow);
            const double offsets = d ? d->normalOffset + d->depthBias : 2.0; // as shadowAt's
            for (std::size_t o = 0; o < vs.objects.size(); ++o)
                if (vs.objects[o].kind == ObjectKind::Volume) {
                    // The pre-lit volume: the own transmittance of this volume alone, as shadowAt
                    // takes it from a sample inside it alone. Only for a volume whose shape is its
                    // box: elsewhere corners outside the shape would weigh in with a medium the
                    // march never sees (a dense ball's rim was drawn as rings).
                    std::vector<uint8_t> inside(vs.objects.size(), 0);
                    inside[o] = 1;
                    const LightVisibilityGrid::OwnTransmittance own =
                        [&](const Vec3d& c, const Vec3d& toLight, double texel) {
                            return setup.ownTransmittance(c, c + toLight * (setup.step + offsets * texel),
                                                          inside);
                        };
                    built->objects[o] =
                        LightVisibilityGrid::build(*vs.volumes[std::size_t(vs.objects[o].volume)], *deep,
                                                   frame.lights[l], cone, setup.step, &setup.emptySpace[o],
                                                   setup.objectStep[o], setup.boxShape[o] ? &own : nullptr);
                }
            g = std::move(built);
            frame.cache.volumeLight.insert(key.get(), g);
        }
        out[l] = g.get();
        lights[l] = std::move(g);
    }
    return out;
}

// Adaptive image-space refinement (RenderOptions::volumeRefinement; after Levoy 1990) on a lattice of
// kLevels levels: the cells whose cx and cy are multiples of kCoarse (4) are cast first; then, level by
// level, the cells whose coordinates are multiples of h (2, then 1) and not of 2h take their volumes'
// light, transmittance and first-hit depth from the cells h away that the levels before gave (the two
// along x, along y, or the four at its corners), or are cast, and keep what they got for the next
// level. A cell is interpolated only where nothing the interpolation would smooth over lies between:
// its representative's ray crosses the same faces of the volume scene as its neighbours' (ColumnCrossings:
// the edge of a volume's box, a Boolean's shape or a blended mesh), the G-buffer's depths are within
// 2 % of its own (a mesh in front of or inside a volume: G-buffer refinement's bound), the neighbours'
// rays all reach opacity one half within 2 % of the same depth or none does (a silhouette of the
// volume's matter against what lies behind, an edge of matter in front of matter further away), and
// their light composited over the cell's own background departs from a straight line by at most the
// threshold in shown luma: half the largest second difference of the lattice's lumas along the
// interpolation's axes (the neighbours and the cells 3h away beyond them), which a step between the
// neighbours of J raises to J / 2 and a smooth ramp, however steep, leaves near 0; where no second
// difference can be taken (the image's side, edge cells) the neighbours' own range. Next to a cell
// the G-buffer refined (an edge of the meshes) it is cast. Each level reads only what the levels
// before wrote: the same image whatever the thread count.
struct LatticeInterpolation {
    const FrameState& frame;
    const SampleCaster& caster;
    const ColumnCrossings& crossings;
    /// Per cell (cy * cw + cx): its representative's gathered light, transmittance and first-hit depth,
    /// written by the cell's own level.
    std::vector<Vec3f>& color;
    std::vector<double>& transmittance;
    std::vector<float>& firstHit;
    float threshold;

    static constexpr int kLevels = 2;                ///< levels interpolated: spacings 2 and 1
    static constexpr int64_t kCoarse = 1 << kLevels; ///< the spacing of the cells cast first

    /// 0 for a cell of the coarsest lattice (cast), else the spacing h its level interpolates at.
    static int64_t spacing(int64_t cx, int64_t cy) {
        if (cx % kCoarse == 0 && cy % kCoarse == 0) return 0;
        int64_t h = kCoarse / 2;
        while (cx % h != 0 || cy % h != 0) h /= 2;
        return h;
    }

    int64_t cellsWide() const { return frame.width / frame.adaptive; }
    int64_t cellsHigh() const { return frame.height / frame.adaptive; }
    // Whether cell (x, y) holds a value a level can read (inside the image, not an edge cell, which
    // the first round cast at every sample instead).
    bool usable(int64_t x, int64_t y) const {
        if (x < 0 || y < 0 || x >= cellsWide() || y >= cellsHigh()) return false;
        return !(frame.adaptive > 1 && frame.refined[std::size_t(y * cellsWide() + x)] != 0);
    }
    void store(int64_t cx, int64_t cy, const SampleCaster::Gathered& g) {
        const std::size_t c = std::size_t(cy * cellsWide() + cx);
        color[c] = g.color, transmittance[c] = g.transmittance, firstHit[c] = float(g.firstHit);
    }
    // Whether the volume scene gave nothing (transmittance exactly 1, no light) in cell (cx, cy) and
    // the eight around it inside the image, cast or interpolated: an edge of the volume scene there
    // (a volume's box in air, where its bricks are empty) changes no sample, so adaptive
    // anti-aliasing's volume round gives its samples the light behind without walking their rays.
    // A G-buffer edge cell (stored as transmittance -1) counts as something.
    bool nothingAround(int64_t cx, int64_t cy) const {
        for (int64_t y = std::max<int64_t>(0, cy - 1); y <= std::min(cellsHigh() - 1, cy + 1); ++y)
            for (int64_t x = std::max<int64_t>(0, cx - 1); x <= std::min(cellsWide() - 1, cx + 1); ++x) {
                const std::size_t c = std::size_t(y * cellsWide() + x);
                if (transmittance[c] != 1.0 || color[c].x != 0 || color[c].y != 0 || color[c].z != 0)
                    return false;
            }
        return true;
    }
    SampleCaster::Gathered at(int64_t x, int64_t y) const {
        const std::size_t c = std::size_t(y * cellsWide() + x);
        return {color[c], transmittance[c], double(firstHit[c])};
    }

    // Whether cell (cx, cy), of spacing h, is interpolated over `behind` (its own background); `out` is
    // then what its volumes give.
    bool interpolate(int64_t cx, int64_t cy, int64_t h, const Vec3f& behind,
                     SampleCaster::Gathered& out) const {
        // The neighbours, and the axes along which second differences are taken below.
        const LatticeNeighbours around = latticeNeighbours(cx, cy, h);
        const int64_t *nx = around.x, *ny = around.y;
        const int n = around.n;
        const bool alongX = around.alongX, alongY = around.alongY;
        const std::size_t own = representativeSample(frame, cx, cy);
        const int64_t W = frame.width;
        const auto ownColumn =
            caster.lists.column(int64_t(own % std::size_t(W)), int64_t(own / std::size_t(W)));
        const double ownDepth = caster.zMax(own), near = frame.gbuffer.frame.nearDepth();
        const ToneMap tm = frame.options.toneMap;
        // A cell that let all the light through (transmittance 1: over() gives the background) shows
        // the cell's own background: its luma is taken once.
        float behindLuma = -1;
        const auto lumaOver = [&](const SampleCaster::Gathered& g) {
            if (!(g.transmittance < 1.0)) {
                if (behindLuma < 0) behindLuma = shownLuma(behind, tm);
                return behindLuma;
            }
            return shownLuma(g.over(behind), tm);
        };
        const auto luma = [&](int64_t x, int64_t y) { return lumaOver(at(x, y)); };
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        float nl[4]; // the neighbours' lumas
        double hitLo = std::numeric_limits<double>::infinity(), hitHi = -hitLo;
        int hits = 0;
        Vec3f sumColor{0, 0, 0};
        double sumTransmittance = 0, sumHit = 0;
        for (int k = 0; k < n; ++k) {
            if (!usable(nx[k], ny[k])) return false; // outside, or a G-buffer edge: cast
            const std::size_t rep = representativeSample(frame, nx[k], ny[k]);
            const double depth = caster.zMax(rep);
            if (std::isinf(depth) != std::isinf(ownDepth)) return false;
            if (!std::isinf(depth) && std::abs(depth - ownDepth) > 0.02 * std::min(depth, ownDepth))
                return false;
            const auto column =
                caster.lists.column(int64_t(rep % std::size_t(W)), int64_t(rep / std::size_t(W)));
            if (!crossings.same(ownColumn, ownDepth, column, depth, near)) return false;
            const SampleCaster::Gathered g = at(nx[k], ny[k]);
            if (!std::isinf(g.firstHit)) {
                ++hits, sumHit += g.firstHit;
                hitLo = std::min(hitLo, g.firstHit), hitHi = std::max(hitHi, g.firstHit);
            }
            const float l = nl[k] = lumaOver(g);
            lo = std::min(lo, l), hi = std::max(hi, l);
            sumColor += g.color;
            sumTransmittance += g.transmittance;
        }
        // The matter's silhouette or a jump in its depth: cast.
        if (hits != 0 && (hits != n || hitHi - hitLo > 0.02 * hitLo)) return false;
        // Departure from the line (plane) through the neighbours: second differences of the lattice's
        // lumas at spacing 2h along each axis of the interpolation, through each neighbour line.
        int differences = 0;
        // Along the line (x0, y0) + t (dx, dy), t = -3, -1, 1, 3 (in steps of h), whose cells at -1
        // and 1 are neighbours of lumas l1 and l2: whether either second difference (centred on -1 and
        // on 1) departs by more than the threshold.
        const auto departs = [&](int64_t x0, int64_t y0, int64_t dx, int64_t dy, float l1, float l2) {
            for (const int64_t t : {-3, 3}) {
                const int64_t x = x0 + t * dx, y = y0 + t * dy;
                if (!usable(x, y)) continue;
                ++differences;
                const float l = luma(x, y);
                if (0.5f * std::abs(t < 0 ? l - 2 * l1 + l2 : l1 - 2 * l2 + l) > threshold) return true;
            }
            return false;
        };
        if (alongX   ? departs(cx, cy, h, 0, nl[0], nl[1])
            : alongY ? departs(cx, cy, 0, h, nl[0], nl[1])
                     : departs(cx, cy - h, h, 0, nl[0], nl[1]) || departs(cx, cy + h, h, 0, nl[2], nl[3]) ||
                           departs(cx - h, cy, 0, h, nl[0], nl[2]) || departs(cx + h, cy, 0, h, nl[1], nl[3]))
            return false;
        if (differences == 0 && hi - lo > threshold) return false; // no second difference: the range
        out.color = sumColor * (1.0f / float(n));
        out.transmittance = sumTransmittance / double(n);
        out.firstHit = hits == 0 ? std::numeric_limits<double>::infinity() : sumHit / double(hits);
        return true;
    }
};

} // namespace

// Every sample the passes shaded (antialias.hpp's shadedSample) cast and composited; with adaptive
// image-space refinement (RenderOptions::volumeRefinement > 0) the representatives of cells shaded
// once and off the coarsest lattice only after it, level by level, each cast or interpolated from the
// levels before (LatticeInterpolation). Then, with adaptive anti-aliasing, the cells shaded once where the
// volume scene draws an edge (volumeEdge) get every sample (with refinement, where the volumes gave nothing
// in the cell and the eight around it, LatticeInterpolation::nothingAround, the light behind without a walk):
// each over the light the passes before gave the cell (one mesh and material shows in all its samples, or the
// G-buffer would have refined it), as the shading pass shares a cell's shading among its samples. Each round
// reads only what the rounds before wrote (the lattice's light; representatives, which the last round does
// not change): the order of the cells does not matter.
void compositeVolumes(FrameState& frame) {
    uint64_t setupKey = 0;
    std::shared_ptr<const VolumeSetup> setup = volumeSetup(frame, setupKey);
    if (!setup) return;
    std::vector<std::shared_ptr<const VolumeLightGrids>> keptGrids;
    const VolumeComposite pass(frame, *setup, lightGrids(frame, *setup, setupKey, keptGrids));
    const VolumeScene* chosen = &setup->vs;
    const Frame& f = frame.gbuffer.frame;
    FragmentLists& lists = frame.cache.volumeLists;
    lists.rebuild(f, pass.surfaces.flat.mesh.view());
    const SampleCaster caster{frame, pass, lists, *chosen};
    const int a = frame.adaptive;
    const int64_t W = frame.width, cw = W / a, ch = frame.height / a;
    const bool refine = frame.options.volumeRefinement > 0;
    // The light behind each cell shaded once, before its representative is composited (round 3).
    std::vector<Vec3f>& behind = frame.cache.volumeBehind;
    if (a > 1) behind.resize(std::size_t(cw * ch));
    // Per cell, what its volumes gave (the lattice's levels).
    if (refine) {
        const std::size_t cells = std::size_t(cw * ch);
        frame.cache.volumeColor.resize(cells);
        frame.cache.volumeTransmittance.resize(cells);
        frame.cache.volumeFirstHit.resize(cells);
    }
    const ColumnCrossings crossings{pass.surfaces.flat.triangleLeaf, setup->faceNormals};
    LatticeInterpolation lattice{frame,
                                 caster,
                                 crossings,
                                 frame.cache.volumeColor,
                                 frame.cache.volumeTransmittance,
                                 frame.cache.volumeFirstHit,
                                 float(frame.options.volumeRefinement)};
    const auto edgeCell = [&](int64_t cx, int64_t cy) {
        return a > 1 && frame.refined[std::size_t(cy * cw + cx)] != 0;
    };
    std::atomic<int64_t> samples{0}, interpolated{0};
    parallelFor(0, ch, 2, [&](int64_t y0, int64_t y1) {
        SampleCaster::Walker w = caster.walker();
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                const std::size_t c = std::size_t(cy * cw + cx);
                const bool edge = edgeCell(cx, cy);
                const std::size_t rep = representativeSample(frame, cx, cy);
                if (a > 1 && !edge) behind[c] = frame.shaded[rep];
                if (refine && edge) lattice.store(cx, cy, {{0, 0, 0}, -1}); // nothing known: cast
                const bool coarsest = LatticeInterpolation::spacing(cx, cy) == 0;
                if (refine && !edge && !coarsest) continue; // a later level
                for (int64_t y = cy * a; y < (cy + 1) * a; ++y)
                    for (int64_t x = cx * a; x < (cx + 1) * a; ++x) {
                        if (!shadedSample(frame, x, y)) continue;
                        const std::size_t i = std::size_t(y * W + x);
                        Vec3f& out = frame.shaded[i];
                        if (refine && !edge && i == rep) {
                            const SampleCaster::Gathered g = caster.gather(w, x, y);
                            lattice.store(cx, cy, g);
                            out = g.over(out);
                        } else {
                            caster.cast(w, x, y, out, out);
                        }
                    }
            }
        samples += w.samples;
    });
    // The levels, coarse to fine: each cell of spacing h interpolated from, or cast beside, the
    // cells the levels before gave.
    for (int64_t h = LatticeInterpolation::kCoarse / 2; refine && h >= 1; h /= 2)
        parallelFor(0, ch, 2, [&](int64_t y0, int64_t y1) {
            SampleCaster::Walker w = caster.walker();
            int64_t n = 0;
            for (int64_t cy = y0; cy < y1; ++cy)
                for (int64_t cx = 0; cx < cw; ++cx) {
                    if (edgeCell(cx, cy) || LatticeInterpolation::spacing(cx, cy) != h) continue;
                    const std::size_t rep = representativeSample(frame, cx, cy);
                    const int64_t x = int64_t(rep % std::size_t(W)), y = int64_t(rep / std::size_t(W));
                    if (lists.column(x, y).empty()) { // nothing to composite
                        lattice.store(cx, cy, {});
                        continue;
                    }
                    Vec3f& out = frame.shaded[rep];
                    SampleCaster::Gathered g;
                    if (lattice.interpolate(cx, cy, h, out, g))
                        ++n;
                    else
                        g = caster.gather(w, x, y);
                    lattice.store(cx, cy, g);
                    out = g.over(out);
                }
            samples += w.samples;
            interpolated += n;
        });
    if (a > 1) {
        // Each cell's representative's shown luma, once (volumeEdge's test of the light's curve).
        std::vector<float>& lumas = frame.cache.volumeLuma;
        lumas.resize(std::size_t(cw * ch));
        const ToneMap tm = frame.options.toneMap;
        parallelFor(0, ch, 8, [&](int64_t y0, int64_t y1) {
            for (int64_t cy = y0; cy < y1; ++cy)
                for (int64_t cx = 0; cx < cw; ++cx)
                    lumas[std::size_t(cy * cw + cx)] =
                        shownLuma(frame.shaded[representativeSample(frame, cx, cy)], tm);
        });
        parallelFor(0, ch, 2, [&](int64_t y0, int64_t y1) {
            SampleCaster::Walker w = caster.walker();
            for (int64_t cy = y0; cy < y1; ++cy)
                for (int64_t cx = 0; cx < cw; ++cx) {
                    uint8_t& kind = frame.refined[std::size_t(cy * cw + cx)];
                    if (kind != 0 || !volumeEdge(frame, caster, crossings, lumas, cx, cy)) continue;
                    kind = kEveryRefinedSample;
                    const std::size_t rep = representativeSample(frame, cx, cy);
                    // Nothing of the volumes in or around the cell: its samples keep the light behind
                    // (what a cast that gathers nothing gives), without the walk.
                    const bool nothing = refine && lattice.nothingAround(cx, cy);
                    const Vec3f& under = behind[std::size_t(cy * cw + cx)];
                    for (int64_t y = cy * a; y < (cy + 1) * a; ++y)
                        for (int64_t x = cx * a; x < (cx + 1) * a; ++x)
                            if (std::size_t(y * W + x) != rep) {
                                Vec3f& out = frame.shaded[std::size_t(y * W + x)];
                                if (nothing)
                                    out = under;
                                else
                                    caster.cast(w, x, y, under, out);
                            }
                }
            samples += w.samples;
        });
    }
    frame.result.volumeSamples = samples.load();
    frame.result.volumeInterpolated = interpolated.load();
}

} // namespace voxfx::detail
