// voxfx — ED06 §3.3 frosted glass: front- and back-face slicemaps from the eye, the per-column count
// of inside cells, and the thickness driving a refraction offset, attenuation and blur
// (voxfx/frosted_glass.hpp).
#include "voxfx/frosted_glass.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

std::span<const OptionField<FrostedGlassOptions>> FrostedGlassOptions::fields() {
    using O = FrostedGlassOptions;
    static const std::vector<OptionField<O>> table = {
        numberOption<O, &O::gridResolution>("glassGrid", "frosted glass: slicemap columns across and slices",
                                            2, 4096),
        numberOption<O, &O::blur>(
            "frostedBlur", "frosted glass: blur cone (radians) through a thickness of the glass's diagonal",
            0, 3.2),
        flagOption<O, &O::sceneBehind>(
            "sceneBehind", "glass: the light leaving it comes from the opaque scene (off: the environment)")};
    return table;
}

FrostedGlass FrostedGlass::build(const GlassInput& input, const FrostedGlassOptions& options) {
    return FrostedGlass(input.mesh, input.triangleMedium, input.media, input.camera, options);
}

FrostedGlass::FrostedGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium,
                           std::vector<GlassMedium> media, const Frame& camera,
                           const FrostedGlassOptions& options)
    : media_(std::move(media)), blur_(options.blur) {
    validateMesh(mesh, "glass mesh");
    if (!camera.isPerspective()) fail("frosted glass needs the camera's perspective frame");
    if (triangleMedium.size() != mesh.triangleCount) fail("frosted glass: one medium per triangle expected");
    for (const uint32_t m : triangleMedium)
        if (m >= media_.size()) fail("frosted glass: medium index ", m, " out of range");
    if (options.gridResolution < 2 || options.gridResolution > 4096)
        fail("glass grid resolution must be between 2 and 4096, got ", options.gridResolution);
    const Vec3d eye = camera.eye();
    // Split by facing as seen from the eye; the depth range of the glass bounds the slices.
    Mesh front, back;
    front.positions.resize(mesh.vertexCount);
    for (size_t i = 0; i < mesh.vertexCount; ++i) front.positions[i] = Vec3f(mesh.vertex(i));
    back.positions = front.positions;
    double nearD = std::numeric_limits<double>::infinity(), farD = 0;
    for (size_t t = 0; t < mesh.triangleCount; ++t) {
        const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                    c = mesh.vertex(mesh.index(t, 2));
        const bool facing = dot(cross(b - a, c - a), eye - a) > 0;
        for (int k = 0; k < 3; ++k) (facing ? front : back).indices.push_back(mesh.index(t, k));
        for (const Vec3d& p : {a, b, c}) {
            const double d = dot(p - eye, camera.forward());
            nearD = std::min(nearD, d);
            farD = std::max(farD, d);
        }
    }
    const Box3d box = computeBounds(mesh);
    diagonal_ = std::max(1e-12, length(box.extent()));
    farD += 1e-3 * diagonal_;
    nearD = std::max(nearD - 1e-3 * diagonal_, 1e-4 * farD);
    if (!(farD > nearD)) fail("frosted glass: the glass is behind the camera");
    const int64_t W = options.gridResolution;
    const int64_t H = std::max<int64_t>(
        1, int64_t(std::lround(double(W) * double(camera.height()) / double(camera.width()))));
    frame_ = Frame::perspective(eye, eye + camera.forward(), camera.up(), 2 * std::atan(camera.tanHalfFovY()),
                                W, H, nearD, farD, options.gridResolution);
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Surface;
    front_ = front.indices.empty() ? BitGrid(W, H, frame_.depth()) : voxelize(front.view(), frame_, vo).bits;
    back_ = back.indices.empty() ? BitGrid(W, H, frame_.depth()) : voxelize(back.view(), frame_, vo).bits;
}

int64_t FrostedGlass::insideCells(const Vec3d& p) const {
    const Vec3d g = frame_.gridFromWorld(p);
    const int64_t x = std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, frame_.width() - 1);
    const int64_t y = std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, frame_.height() - 1);
    const int64_t D = frame_.depth();
    const int64_t s0 =
        std::clamp<int64_t>(int64_t(std::floor(frame_.depthToSlice(y * frame_.width() + x)(g.z))), 0, D - 1);
    int64_t count = 0;
    bool inside = false;
    for (int64_t s = s0; s < D; ++s) {
        const bool f = front_.get(x, y, s), b = back_.get(x, y, s);
        if (f && !b) { // enters
            inside = true;
            ++count;
        } else if (b && !f) { // leaves (a stray back face outside is ignored)
            count += inside;
            inside = false;
        } else if (f && b) { // ambiguous: a sliver from outside; from inside the way out (a surface
            ++count;         // folded within one cell), so that a missed exit cannot fill the column
            inside = false;
        } else {
            count += inside;
        }
    }
    return count;
}

double FrostedGlass::thickness(const Vec3d& p) const {
    const Vec3d ray = normalize(p - frame_.eye());
    const double slice = (frame_.farDepth() - frame_.nearDepth()) / double(frame_.depth());
    return double(insideCells(p)) * slice / std::max(1e-6, dot(ray, frame_.forward()));
}

GlassPath FrostedGlass::trace(const Vec3d& entry, const Vec3d& normal, uint32_t medium,
                              const Vec3d& dir) const {
    GlassPath p;
    p.hit = true;
    const Vec3d d = normalize(dir);
    Vec3d n0 = normalize(normal);
    if (dot(d, n0) > 0) n0 = -n0;
    const GlassMedium& m = media_[std::min<size_t>(medium, media_.size() - 1)];
    const double F = fresnelDielectric(-dot(d, n0), 1.0, m.ior);
    p.reflectDir = reflectDirection(d, n0);
    p.reflectance = float(F);
    Vec3d t;
    if (!refractDirection(d, n0, 1.0 / m.ior, t)) t = d;
    const double L = thickness(entry);
    // The refraction offset: the light comes from the refracted direction, displaced by the length
    // crossed; two interfaces at the front surface's Fresnel factor.
    p.exitPoint = entry + t * L;
    p.exitDir = t;
    p.throughput = m.tint * beerLambert(m.sigma, L) * float((1 - F) * (1 - F));
    p.blurAngle = blur_ * std::min(1.0, L / diagonal_);
    p.events = 2;
    return p;
}

} // namespace voxfx
