// voxfx — LightShadow: the shadow data of one light for one ShadowKind, built from a scene's casters
// (standard map; ED06 §3.1 transmittance = map for opaque casters + slicemap channels for partial
// occluders; CHANG §3 absorption = attribute grid of every caster), and the per-point lookup.
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "voxfx/deep_shadow.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/shadow_volume.hpp"

namespace voxfx {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Casters of a scene split by how they shadow.
struct CasterSets {
    Mesh all, opaque;
    std::vector<uint32_t> allMaterialIndex;       // per triangle of `all`
    std::map<std::array<float, 3>, Mesh> partial; // by crossing transmittance: one channel each
};

void append(Mesh& to, const Mesh& from) {
    const auto base = uint32_t(to.positions.size());
    to.positions.insert(to.positions.end(), from.positions.begin(), from.positions.end());
    for (const uint32_t i : from.indices) to.indices.push_back(base + i);
}

CasterSets collectCasters(const Scene& scene) {
    CasterSets s;
    for (const SceneMesh& m : scene.meshes) {
        if (!m.castsShadow) continue;
        const Material& mat = scene.materials[m.material];
        append(s.all, m.mesh);
        s.allMaterialIndex.insert(s.allMaterialIndex.end(), m.mesh.triangleCount(), m.material);
        if (mat.isOpaque()) {
            append(s.opaque, m.mesh);
        } else {
            const Vec3f t = mat.shadowCrossingTransmittance();
            append(s.partial[{t.x, t.y, t.z}], m.mesh);
        }
    }
    return s;
}

Box3d boundsOf(const Mesh& m) { return computeBounds(m.view()); }

} // namespace

const char* toString(ShadowKind k) { return enumName(k, kShadowKindNames); }

ShadowKind parseShadowKind(const std::string& name) {
    return parseEnum<ShadowKind>(name, "shadow kind", kShadowKindNames);
}

float absorptionPerCrossing(const Material& m, float opaqueAbsorption) {
    if (m.isOpaque()) return opaqueAbsorption;
    const Vec3f t = m.shadowCrossingTransmittance();
    const float luminance = 0.2126f * t.x + 0.7152f * t.y + 0.0722f * t.z;
    return std::min(opaqueAbsorption, -std::log(std::max(luminance, 1e-30f)));
}

LightShadow LightShadow::build(const Scene& scene, const Light& light, const ShadowOptions& options,
                               ShadowBuildTimings* timings, Progress* progress) {
    LightShadow out;
    out.options_ = options;
    if (options.kind == ShadowKind::None) return out;
    if (options.kind == ShadowKind::Volumes)
        fail("shadow volumes are counted per pixel of a G-buffer: render() builds them (buildVolumeShadow)");
    if (options.mapResolution <= 0 || options.gridResolution <= 0 || options.gridDepth <= 0 ||
        options.pcfRadius < 0 || options.skipCells < 0)
        fail("shadow options: resolutions must be positive, PCF radius and skipped cells >= 0");
    ShadowBuildTimings local;
    ShadowBuildTimings& t = timings ? *timings : local;
    const CasterSets casters = collectCasters(scene);
    // Nothing casts: visibility 1 (deep shadows also see the scene's volume objects).
    if (casters.all.indices.empty() && !(options.kind == ShadowKind::Deep && scene.volumeScene)) return out;

    auto buildMaps = [&](const Mesh& mesh) {
        const auto t0 = std::chrono::steady_clock::now();
        out.mapViews_ = makeLightViews(light, boundsOf(mesh), options.mapResolution, 1);
        for (const LightView& v : out.mapViews_)
            out.maps_.push_back(ShadowMap::build(mesh.view(), v, progress));
        t.mapMs += msSince(t0);
    };

    switch (options.kind) {
    case ShadowKind::None:
        break;
    case ShadowKind::Volumes:
        break;
    case ShadowKind::Map:
        buildMaps(casters.all);
        break;
    case ShadowKind::Deep: {
        const auto t0 = std::chrono::steady_clock::now();
        DeepShadowOptions d;
        d.resolution = options.dsmResolution;
        d.epsilon = options.dsmEpsilon;
        d.storage = options.dsmStorage;
        d.clusters = options.dsmClusters;
        d.skipEmptySpace = options.dsmSkipEmptySpace;
        out.deep_ =
            std::make_shared<const DeepShadow>(DeepShadow::build(volumeSceneOf(scene), light, d, progress));
        t.mapMs += msSince(t0);
        break;
    }
    case ShadowKind::Transmittance: {
        if (!casters.opaque.indices.empty()) buildMaps(casters.opaque);
        if (casters.partial.empty()) break;
        const auto t0 = std::chrono::steady_clock::now();
        Box3d bounds;
        std::vector<MeshView> groups;
        std::vector<Vec3f> transmittances;
        for (const auto& [key, mesh] : casters.partial) {
            bounds.extend(boundsOf(mesh));
            groups.push_back(mesh.view());
            transmittances.push_back({key[0], key[1], key[2]});
        }
        out.gridViews_ = makeLightViews(light, bounds, options.gridResolution, options.gridDepth);
        for (const LightView& v : out.gridViews_)
            out.transmittance_.push_back(TransmittanceShadowMap::build(
                v, groups, transmittances, options.voxelMode, options.slicing, progress, options.device));
        t.voxelizeMs += msSince(t0);
        break;
    }
    case ShadowKind::Absorption: {
        const auto t0 = std::chrono::steady_clock::now();
        std::vector<float> perTriangle(casters.allMaterialIndex.size());
        std::vector<float> perMaterial(scene.materials.size());
        for (std::size_t i = 0; i < scene.materials.size(); ++i)
            perMaterial[i] = absorptionPerCrossing(scene.materials[i], options.opaqueAbsorption);
        for (std::size_t i = 0; i < perTriangle.size(); ++i)
            perTriangle[i] = perMaterial[casters.allMaterialIndex[i]];
        out.gridViews_ =
            makeLightViews(light, boundsOf(casters.all), options.gridResolution, options.gridDepth);
        for (const LightView& v : out.gridViews_)
            out.absorption_.push_back(AbsorptionShadowMap::build(
                v, casters.all.view(), perTriangle, options.absorptionCoverage, options.slicing, progress));
        t.voxelizeMs += msSince(t0);
        break;
    }
    case ShadowKind::Exact: {
        const auto t0 = std::chrono::steady_clock::now();
        out.exact_ = std::make_shared<const ExactShadow>(
            ExactShadow::fromMaterials(casters.all.view(), casters.allMaterialIndex, scene.materials));
        out.light_ = light;
        t.mapMs += msSince(t0);
        break;
    }
    }
    return out;
}

namespace {

// The view to look p up in, and the lookup point q = p + n * offset (offset in column footprints
// of the view at p). For point lights the offset can carry q across a cube-face seam, out of the
// frustum of p's face (which would then report "outside the view": full light); q picks its own face.
int lookupView(const std::vector<LightView>& views, const Vec3d& p, const Vec3d& n, double offset, Vec3d& q) {
    int i = viewIndexFor(views, p);
    if (i < 0) return i;
    q = p + n * (offset * views[size_t(i)].columnWorldSize(p));
    if (views.size() > 1) {
        const int j = viewIndexFor(views, q);
        if (j >= 0) i = j;
    }
    return i;
}

} // namespace

LightShadow LightShadow::fromVolumes(const ShadowOptions& options,
                                     std::shared_ptr<const ShadowVolumeMask> mask) {
    LightShadow out;
    out.options_ = options;
    out.options_.kind = ShadowKind::Volumes;
    out.volumes_ = std::move(mask);
    return out;
}

Vec3f LightShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    Vec3f v{1, 1, 1};
    if (options_.kind == ShadowKind::None) return v;
    if (volumes_) {
        const float lit = volumes_->visibility(p);
        return {lit, lit, lit};
    }
    if (deep_) {
        const float d = deep_->visibility(p, n, options_.normalOffset, options_.depthBias);
        return {d, d, d};
    }
    Vec3d q;
    if (!maps_.empty()) {
        const int i = lookupView(mapViews_, p, n, options_.normalOffset, q);
        if (i >= 0) {
            const double texel = mapViews_[size_t(i)].columnWorldSize(p);
            v = v * maps_[size_t(i)].visibility(q, options_.pcfRadius, options_.depthBias * texel);
        }
    }
    if (exact_) {
        // Towards the light from p, offset along n against self-intersection.
        Vec3d l;
        double distance = std::numeric_limits<double>::infinity();
        if (light_.type == LightType::Directional) {
            l = -normalize(light_.direction);
        } else {
            l = light_.position - p;
            distance = length(l);
            l = l / std::max(distance, 1e-300);
        }
        const Vec3d o = p + n * (exact_->epsilon() * 10);
        v = v * exact_->transmittance(o, l, distance);
    }
    if (!transmittance_.empty() || !absorption_.empty()) {
        const int i = lookupView(gridViews_, p, n, options_.normalOffset, q);
        if (i >= 0) {
            const int64_t skip = options_.skipCells;
            if (!transmittance_.empty()) {
                const TransmittanceShadowMap& m = transmittance_[size_t(i)];
                v = v * (options_.bilinear ? m.transmittanceBilinear(q, skip) : m.transmittance(q, skip));
            } else {
                const AbsorptionShadowMap& m = absorption_[size_t(i)];
                v = v * (options_.bilinear ? m.transmittanceBilinear(q, skip) : m.transmittance(q, skip));
            }
        }
    }
    return v;
}

} // namespace voxfx
