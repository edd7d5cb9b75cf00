// voxfx — the glass pass: per glass pixel, Fresnel reflection of the environment plus the light
// that comes through (exact tracer or voxel march), mixed with the surface shading by the
// material's transmission.
#include "render/glass_pass.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <type_traits>
#include <vector>

#include "render/antialias.hpp"
#include "render/shading.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/triangle_tracer.hpp"

namespace voxfx::detail {

namespace {

// Removes the glass triangles that have their own medium on both sides: a scene mesh of one glass
// nested in, overlapping or touching face to face another mesh of that glass. Light crosses no
// interface there (the exact tracer would apply the tint again, the voxel march would leave the
// medium into air). A triangle's outer side is a point a hair off its centroid along its normal
// (counter-clockwise); it is inside the glass where the generalized winding number of the other
// meshes of its material is at least 1/2 in magnitude. A material of one mesh costs nothing (faces
// inside one mesh are left as they are).
void dropSameMediumFaces(Mesh& glass, std::vector<uint32_t>& medium, std::vector<uint32_t>& meshOf) {
    const std::size_t n = medium.size();
    const double eps = 1e-5 * std::max(1e-30, length(computeBounds(glass.view()).extent()));
    std::vector<uint8_t> keep(n, 1);
    std::map<uint32_t, std::vector<uint32_t>> meshesOf; // per material, its meshes
    for (std::size_t t = 0; t < n; ++t) {
        std::vector<uint32_t>& m = meshesOf[medium[t]];
        if (std::find(m.begin(), m.end(), meshOf[t]) == m.end()) m.push_back(meshOf[t]);
    }
    const auto corner = [&](std::size_t t, int k) {
        return Vec3d(glass.positions[glass.indices[3 * t + size_t(k)]]);
    };
    for (const auto& [material, meshes] : meshesOf) {
        if (meshes.size() < 2) continue;
        for (const uint32_t mesh : meshes) {
            Mesh others;
            others.positions = glass.positions;
            std::vector<std::size_t> triangles;
            std::vector<Vec3d> outer;
            for (std::size_t t = 0; t < n; ++t) {
                if (medium[t] != material) continue;
                if (meshOf[t] != mesh) {
                    for (int k = 0; k < 3; ++k) others.indices.push_back(glass.indices[3 * t + size_t(k)]);
                    continue;
                }
                const Vec3d a = corner(t, 0), b = corner(t, 1), c = corner(t, 2), nrm = cross(b - a, c - a);
                if (!(length(nrm) > 0)) continue;
                triangles.push_back(t);
                outer.push_back((a + b + c) * (1.0 / 3) + normalize(nrm) * eps);
            }
            std::vector<double> w(outer.size());
            windingNumbers(others.view(), outer, w);
            for (std::size_t i = 0; i < triangles.size(); ++i)
                if (std::abs(w[i]) >= 0.5) keep[triangles[i]] = 0;
        }
    }
    std::size_t out = 0;
    for (std::size_t t = 0; t < n; ++t) {
        if (!keep[t]) continue;
        for (int k = 0; k < 3; ++k) glass.indices[3 * out + size_t(k)] = glass.indices[3 * t + size_t(k)];
        medium[out] = medium[t];
        meshOf[out++] = meshOf[t];
    }
    glass.indices.resize(3 * out);
    medium.resize(out);
}

// The glass method's structures and the opaque scene's tracer (`any` false when no triangle is glass).
std::shared_ptr<const GlassSetup> setUpGlass(const FrameState& frame, const GlassOptions& method) {
    const Scene& scene = frame.scene;
    const SceneGeometry& geometry = frame.geometry;
    auto setup = std::make_shared<GlassSetup>();
    std::vector<uint8_t>& isGlass = setup->isGlass;
    isGlass.resize(scene.materials.size());
    std::vector<GlassMedium> media(scene.materials.size());
    const double absorption = glassAbsorptionConstant(method);
    if (!(absorption >= 0) || !std::isfinite(absorption))
        fail("glass: the absorption constant must be finite and >= 0, got ", absorption);
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        isGlass[m] = scene.materials[m].isGlass();
        media[m] = glassMedium(scene.materials[m]);
        media[m].sigma = media[m].sigma * float(absorption);
    }
    // The glass triangles, on the scene's vertices.
    Mesh glass;
    glass.positions = geometry.mesh.positions;
    Mesh opaque;
    opaque.positions = geometry.mesh.positions;
    std::vector<uint32_t> medium, meshOf;
    for (size_t t = 0; t < geometry.mesh.triangleCount(); ++t) {
        const bool g = isGlass[geometry.triangleMaterial[t]];
        for (int k = 0; k < 3; ++k)
            (g ? glass : opaque).indices.push_back(geometry.mesh.indices[3 * t + size_t(k)]);
        if (g) {
            medium.push_back(geometry.triangleMaterial[t]);
            meshOf.push_back(geometry.triangleMesh[t]);
        } else {
            setup->opaqueTriangle.push_back(uint32_t(t));
        }
    }
    if (medium.empty()) return setup; // no glass: `any` stays false
    dropSameMediumFaces(glass, medium, meshOf);
    setup->any = true;
    setup->built =
        buildGlass(GlassInput{glass.view(), geometry.normals, medium, media, frame.gbuffer.frame}, method);
    // What the light leaving the glass (and the reflection) comes from: the opaque scene, traced
    // exactly for every method, else the environment.
    if (glassSeesSceneBehind(method) && !setup->opaqueTriangle.empty()) {
        setup->behind = std::make_unique<TriangleTracer>(opaque.view());
        const Box3d box = computeBounds(geometry.mesh.view());
        setup->epsilon = std::max(1e-9, 1e-5 * length(box.extent()));
    }
    return setup;
}

// The options the glass is built with: a voxel method's grid as given, or sized from the glass
// objects' size on screen (chooseGlassGrid); the grid and why go to the result.
GlassOptions glassWithGrid(FrameState& frame) {
    GlassOptions method = frame.options.glass;
    std::visit(
        [&]<class O>(O& o) {
            if constexpr (std::is_base_of_v<VoxelGlassOptions, O>) {
                const SceneGeometry& g = frame.geometry;
                std::vector<Box3d> objects;
                Box3d all;
                if (o.gridResolution == kGlassGridAuto)
                    for (size_t t = 0; t < g.mesh.triangleCount(); ++t) {
                        const uint32_t m = g.triangleMaterial[t];
                        if (m >= frame.scene.materials.size() || !frame.scene.materials[m].isGlass())
                            continue;
                        if (g.triangleMesh[t] >= objects.size()) objects.resize(g.triangleMesh[t] + 1);
                        for (int k = 0; k < 3; ++k) {
                            const Vec3d p(g.mesh.positions[g.mesh.indices[3 * t + size_t(k)]]);
                            objects[g.triangleMesh[t]].extend(p);
                            all.extend(p);
                        }
                    }
                const Frame& view = frame.gbuffer.frame;
                const GlassGridChoice c = chooseGlassGrid(o.gridResolution, objects, all, view,
                                                          double(frame.options.width) / double(view.width()));
                o.gridResolution = c.resolution;
                frame.result.glass.grid = c.resolution;
                frame.result.glass.gridReason = c.reason;
            }
        },
        method);
    return method;
}

// Adaptive anti-aliasing at glass edges: every cell's representative traced, then the other samples
// of edge cells, each as the shading pass shaded it: a sample whose shading was an earlier sample's
// of its cell, or a neighbouring cell's representative's (the same triangle: shadeGBuffer), takes
// that sample's light through the glass too, the rest are traced. What an edge cell needs is which
// surface covers each sample; the light through one triangle varies little over a cell. The second
// round reads representatives and its own cell only, so the order of the cells does not matter.
template <class ShowsGlass, class Trace>
void traceCells(FrameState& f, const ShowsGlass& showsGlass, const Trace& trace) {
    const int a = f.adaptive;
    const int64_t W = f.width, cw = W / a, ch = f.height / a;
    const std::vector<uint32_t>& triangle = f.gbuffer.triangle;
    const auto traceAt = [&](size_t i) { trace(int64_t(i % size_t(W)), int64_t(i / size_t(W)), i); };
    parallelFor(0, ch, 4, [&](int64_t y0, int64_t y1) {
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                const size_t rep = representativeSample(f, cx, cy);
                if (showsGlass(rep)) traceAt(rep);
            }
    });
    parallelFor(0, ch, 4, [&](int64_t y0, int64_t y1) {
        std::array<std::size_t, 64> samples;
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                if (f.refined[size_t(cy * cw + cx)] != kEveryRefinedSample) continue;
                const int n = cellSamples(f, cx, cy, samples);
                for (int k = 1; k < n; ++k) {
                    const size_t i = samples[size_t(k)];
                    if (!showsGlass(i)) continue;
                    int same = 0;
                    while (same < k && triangle[samples[size_t(same)]] != triangle[i]) ++same;
                    const size_t from =
                        same < k ? samples[size_t(same)] : neighbourShowing(f, cx, cy, triangle[i]);
                    if (from == kNoSample) {
                        traceAt(i);
                    } else {
                        f.shaded[i] = f.shaded[from];
                        f.glassSamples[i] = f.glassSamples[from];
                    }
                }
            }
    });
}

// Adaptive anti-aliasing inside glass: a glass cell shaded once (no edge) whose light through it
// bends or steps between its neighbours' (curvesAcrossNeighbours, on the traced representatives) gets its
// N-rooks samples, each shaded as a surface and traced. The cells decide on representatives only,
// which no cell changes, so the order does not matter.
template <class ShowsGlass, class Trace>
void addRookSamples(FrameState& f, const ShowsGlass& showsGlass, const Trace& trace) {
    const int a = f.adaptive;
    const int64_t W = f.width, cw = W / a, ch = f.height / a;
    const Vec3d eye = f.gbuffer.frame.eye();
    parallelFor(0, ch, 4, [&](int64_t y0, int64_t y1) {
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                uint8_t& kind = f.refined[size_t(cy * cw + cx)];
                const size_t rep = representativeSample(f, cx, cy);
                if (kind != 0 || !showsGlass(rep) || !curvesAcrossNeighbours(f, cx, cy)) continue;
                kind = kRookSamples;
                const float occlusion =
                    f.screenOcclusion.empty() ? 1.0f : f.screenOcclusion[size_t(cy * cw + cx)];
                for (int dy = 0; dy < a; ++dy) {
                    const int64_t x = cx * a + rookColumn(a, dy), y = cy * a + dy;
                    const size_t i = size_t(y * W + x);
                    if (i == rep) continue;
                    SurfacePoint s;
                    f.shaded[i] = surfaceAt(f.gbuffer, f.geometry, x, y, s)
                                      ? f.shader->shade(s, eye, occlusion)
                                      : f.shaded[rep];
                    if (showsGlass(i)) trace(x, y, i);
                }
            }
    });
}

} // namespace

void shadeGlass(FrameState& frame) {
    using Clock = std::chrono::steady_clock;
    if (std::holds_alternative<NoGlassOptions>(frame.options.glass)) return;
    const GlassOptions method = glassWithGrid(frame);
    const Scene& scene = frame.scene;
    const SceneGeometry& geometry = frame.geometry;
    const GBuffer& gbuffer = frame.gbuffer;
    const RenderOptions& options = frame.options;
    const Environment& env = *frame.environment;
    std::vector<Vec3f>& shaded = frame.shaded;
    std::vector<uint8_t>& sampleMask = frame.glassSamples;
    sampleMask.assign(shaded.size(), 0);

    const auto t0 = Clock::now();
    // Built from the meshes, materials, normals (crease angle) and options, and the camera for a
    // method fitted to the view: reused from the cache while those stay the same.
    Hasher key;
    key.value(frame.meshesKey), key.value(frame.materialsKey), key.value(options.creaseAngle);
    key.options(method);
    if (viewDependent(method)) hashCamera(key, frame.camera);
    std::shared_ptr<const GlassSetup> cached = frame.cache.glass.find(key.get());
    if (cached) {
        frame.cachedPass = true;
    } else {
        cached = setUpGlass(frame, method);
        frame.cache.glass.insert(key.get(), cached);
    }
    if (!cached->any) return;
    const GlassSetup& setup = *cached;
    const std::vector<uint8_t>& isGlass = setup.isGlass;
    const BuiltGlass& built = setup.built;
    const TriangleTracer* behind = setup.behind.get();
    const double epsilon = setup.epsilon;
    const std::vector<uint32_t>& opaqueTriangle = setup.opaqueTriangle;
    auto incoming = [&](const Vec3d& from, const Vec3d& dir, double blur) -> Vec3f {
        if (behind) {
            // The opaque scene holds no glass triangle, so `from` (on the glass) left none of its
            // triangles: a hit within epsilon counts, on either side (a glass box standing on the
            // ground leaves through its bottom into the ground at t = 0 up to rounding; skipping
            // it showed the sky below the ground through the box).
            TriangleTracer::Hit h =
                behind->intersect(from - dir * epsilon, dir, 0, std::numeric_limits<double>::infinity());
            h.t -= epsilon;
            if (h.hit) {
                const size_t t = opaqueTriangle[h.triangle];
                const uint32_t ia = geometry.mesh.indices[3 * t], ib = geometry.mesh.indices[3 * t + 1],
                               ic = geometry.mesh.indices[3 * t + 2];
                const Vec3d a(geometry.mesh.positions[ia]), b(geometry.mesh.positions[ib]),
                    c(geometry.mesh.positions[ic]);
                SurfacePoint s;
                s.position = from + dir * h.t;
                s.geometricNormal = normalize(cross(b - a, c - a));
                if (dot(s.geometricNormal, dir) > 0) s.geometricNormal = -s.geometricNormal;
                s.normal = normalize(Vec3d(geometry.normals[ia]) * (1 - h.u - h.v) +
                                     Vec3d(geometry.normals[ib]) * h.u + Vec3d(geometry.normals[ic]) * h.v);
                if (!(length(s.normal) > 0)) s.normal = s.geometricNormal;
                if (dot(s.normal, s.geometricNormal) < 0) s.normal = -s.normal;
                s.material = geometry.triangleMaterial[t];
                // shadePoint applies the exposure; the caller applies it to the whole glass radiance.
                return shadePoint(frame, s, from) * (1.0f / options.exposure);
            }
        }
        return env.lookup(dir, blur);
    };
    const auto t1 = Clock::now();
    frame.result.glass.prepareMs += std::chrono::duration<double, std::milli>(t1 - t0).count();

    const int64_t W = gbuffer.frame.width(), H = gbuffer.frame.height();
    const Vec3d eye = gbuffer.frame.eye();
    // The light through the glass at sample (x, y) (index i) mixed into its shading.
    const auto trace = [&](int64_t x, int64_t y, size_t i) {
        SurfacePoint s;
        if (!surfaceAt(gbuffer, geometry, x, y, s)) return;
        const Vec3d d = normalize(s.position - eye);
        const GlassPath p = traceGlass(built, GlassHit{eye, d, s.position, s.normal, s.material});
        if (!p.hit) return;
        // Frosted light is the blurred environment (ED06's pre-filtered map), never the scene.
        const Vec3f through =
            incoming(s.position, p.reflectDir, 0) * p.reflectance +
            (p.blurAngle > 0 ? env.lookup(p.exitDir, p.blurAngle) : incoming(p.exitPoint, p.exitDir, 0)) *
                p.throughput;
        const float tr = std::clamp(scene.materials[s.material].transmission, 0.0f, 1.0f);
        shaded[i] = shaded[i] * (1 - tr) + through * (tr * options.exposure);
        sampleMask[i] = 1;
    };
    const auto showsGlass = [&](size_t i) {
        const uint32_t tri = gbuffer.triangle[i];
        return tri != GBuffer::kNone && isGlass[geometry.triangleMaterial[tri]];
    };
    if (frame.adaptive > 1) {
        traceCells(frame, showsGlass, trace);
        addRookSamples(frame, showsGlass, trace);
    } else {
        parallelFor(0, H, 4, [&](int64_t y0, int64_t y1) {
            for (int64_t y = y0; y < y1; ++y)
                for (int64_t x = 0; x < W; ++x)
                    if (showsGlass(size_t(y * W + x))) trace(x, y, size_t(y * W + x));
        });
    }
    frame.result.glass.traceMs += std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
}

} // namespace voxfx::detail
