// voxfx — the exact reference for shadows through partial occluders: the product of the crossing
// transmittances of every caster triangle between a point and the light, ray traced on the actual
// triangles with Embree (voxfx/triangle_tracer.hpp). Shadow technique "exact" (voxfx/shadow.hpp).
//
// Glass (Material::isGlass: transmission > 0, opacity 1) is a volume, not a sheet: each crossing
// passes the Fresnel-transmitted fraction 1 - F (exact unpolarized dielectric F at the shadow ray's
// angle to the face, taken from the outside: by reciprocity the same fraction leaves a parallel
// slab as enters it), the tint (the material's crossing transmittance) applies once where the ray
// enters, and Beer–Lambert exp(-sigma * length) applies over the straight length between entering
// and leaving (a front face, CCW towards the ray, enters). The shadow ray is not bent: light focused
// or spread by refraction (caustics) is not modelled. The ray starts 10 epsilons off the surface
// along its normal (epsilon: 1e-5 of the casters' diagonal, or of the largest volume-scene leaf's).
//
// The scene's volume scene (Scene::volumeScene: Boolean shapes and volumes seen through transfer
// functions, voxfx/volume_scene.hpp), what the deep shadow map sees besides the meshes, is crossed
// along the same ray: every leaf a casting object's shape uses is traced on its own (Embree), its
// crossings along the whole line through the leaves' bounds (so those behind the point say which
// shapes it lies inside) walked in depth order by the deep shadow map's SegmentWalker. Where an
// opaque object's shape is crossed the light is stopped; a translucent one passes its
// shadowTransmittance per crossing and, glass, Beer–Lambert with its attenuation over the chord
// inside. Inside volume objects the ray is marched at the midpoints of equal steps of at most
// `volumeStep` smallest voxel spacings (default a quarter voxel), each step of length dl passing
// exp(-sigma dl) with sigma the sum over the volumes there of -ln(1 - alpha(value)) / opacityLength
// (alpha the transfer function's opacity at the trilinear sample, clamped to 1 - 1e-7): the
// extinction the deep shadow map's pre-integrated intervals average, so the two agree as their steps
// shrink. Samples in bricks whose opacity is certainly 0 (EmptySpace) are skipped: they add nothing.
// A ray whose light falls to 1e-6 in every channel stops there.
//
// Thread-safety: read-only after construction; transmittance and visibility may run from any
// number of threads.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voxfx/glass_optics.hpp"
#include "voxfx/mesh.hpp"
#include "voxfx/options.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/shadow_options.hpp"

namespace voxfx {

class TriangleTracer;
struct VolumeScene;

class ExactShadow {
public:
    using Options = ExactShadowOptions;
    using Stats = ExactShadowStats;
    /// How glass triangles pass light (see the file comment).
    /// (ior, Beer–Lambert coefficient per world unit, tint applied once per entering crossing: the
    /// medium every glass method uses).
    using Glass = GlassMedium;
    static constexpr uint32_t kNotGlass = 0xffffffffu;

    ExactShadow() = default; ///< no casters: visibility 1
    /// `casters` in world space; one RGB crossing transmittance per triangle (0 for opaque ones);
    /// optionally, per triangle, an index into `glass` or kNotGlass (empty: no glass).
    ExactShadow(const MeshView& casters, std::vector<Vec3f> triangleTransmittance,
                std::vector<uint32_t> triangleGlass = {}, std::vector<Glass> glass = {});
    /// From scene materials: crossingTransmittance per triangle, and glass for glass materials
    /// (Material::isGlass; ior, KHR_materials_volume attenuation, tint = crossingTransmittance).
    static ExactShadow fromMaterials(const MeshView& casters, std::span<const uint32_t> triangleMaterial,
                                     std::span<const Material> materials);
    /// The scene's casters (SceneMesh::castsShadow) and the casting objects of its volume scene,
    /// traced towards `light`. Throws voxfx::Error for a volume step that is not positive, an
    /// invalid volume scene, or when Embree fails.
    static ExactShadow build(const Scene& scene, const Light& light, const ExactShadowOptions& options,
                             Progress* progress = nullptr);
    /// Light fraction along p + t * dir, t in (epsilon, distance): the product over the crossed
    /// triangles (and glass volumes) and the volume scene's objects described above.
    Vec3f transmittance(const Vec3d& p, const Vec3d& dir, double distance) const;
    /// RGB fraction of the light (the one given to build) reaching p: transmittance from p, moved 10
    /// epsilons along `n` (the unit normal turned towards the light), towards the light.
    Vec3f visibility(const Vec3d& p, const Vec3d& n) const;
    /// The tracer's step over a crossed triangle (TriangleTracer::epsilon).
    double epsilon() const;
    Stats stats() const;

private:
    struct Volumes;
    Vec3f meshTransmittance(const Vec3d& p, const Vec3d& dir, double distance) const;
    Vec3f volumeTransmittance(const Vec3d& p, const Vec3d& dir, double distance) const;
    /// Null when no object of `scene` casts shadows.
    static std::shared_ptr<const Volumes> buildVolumes(std::shared_ptr<const VolumeScene> scene,
                                                       double stepVoxels);

    std::vector<Vec3f> transmittance_;
    std::vector<uint32_t> triangleGlass_;
    std::vector<Glass> glass_;
    std::shared_ptr<const TriangleTracer> tracer_; ///< the casters (null: none)
    std::shared_ptr<const Volumes> volumes_;       ///< the volume scene's casters (null: none)
    Light light_;                                  ///< the light visibility looks towards (build)
};

} // namespace voxfx
