// voxfx — the glass pass: per glass pixel, Fresnel reflection of the environment plus the light
// that comes through (exact tracer or voxel march), mixed with the surface shading by the
// material's transmission.
#include "render/glass_pass.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <type_traits>
#include <unordered_map>
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

// Per triangle of `m`, the triangle across each of its edges (a vertex index pair shared by two
// triangles; GlassSetup::kNoTriangle where none, or where more than two share it past the first two).
std::vector<std::array<uint32_t, 3>> edgeNeighbours(const Mesh& m) {
    const std::size_t n = m.triangleCount();
    std::vector<std::array<uint32_t, 3>> out(
        n, {GlassSetup::kNoTriangle, GlassSetup::kNoTriangle, GlassSetup::kNoTriangle});
    std::unordered_map<uint64_t, uint64_t> open; // edge -> triangle * 3 + its edge, until matched
    open.reserve(3 * n);
    for (std::size_t t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m.indices[3 * t + size_t(k)], b = m.indices[3 * t + size_t((k + 1) % 3)];
            const uint64_t key = uint64_t(std::min(a, b)) << 32 | std::max(a, b);
            const auto [it, fresh] = open.try_emplace(key, 3 * uint64_t(t) + uint64_t(k));
            if (fresh) continue;
            const uint64_t other = it->second;
            if (other == ~uint64_t(0)) continue; // already matched: a third triangle on the edge
            out[t][size_t(k)] = uint32_t(other / 3);
            out[other / 3][other % 3] = uint32_t(t);
            it->second = ~uint64_t(0);
        }
    return out;
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
        setup->behindNeighbours = edgeNeighbours(opaque);
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

// Where a ray from the glass (the light leaving it, or the reflection) lands: the opaque object
// (mesh and material) and its triangle, or the environment (kSky).
struct Landing {
    static constexpr uint64_t kSky = ~uint64_t(0);
    uint64_t object = kSky;
    uint32_t triangle = GlassSetup::kNoTriangle; ///< of GlassSetup::behind
};

// What a lattice cell's representative path found (RenderOptions::glassRefinement).
struct LatticePath {
    bool traced = false; ///< a path that met glass (else nothing below holds)
    bool bends = false;  ///< its shown light departs from the line through its lattice neighbours'
    uint32_t material = 0;
    int events = 0;
    bool truncated = false;
    uint64_t crossed = 0;
    Landing exit, reflection;
    Vec3f exitDir{0, 0, 0};
    Vec3f through{0, 0, 0}; ///< the light through the glass (before the transmission and exposure)

    // Whether the two paths went through the same glass the same way and landed on the same objects
    // (mesh and material), on one triangle or two that share an edge (`neighbours`: a continuous
    // surface between them, so no depth step; else another part of the object, a tile of a checker
    // beyond a corner, may lie between), leaving in directions within kMaxExitTurn: light that
    // varies smoothly between them (their luma decides the rest).
    bool agrees(const LatticePath& o, const std::vector<std::array<uint32_t, 3>>& neighbours) const {
        static const float kCosTurn = float(std::cos(kMaxExitTurn));
        const auto touch = [&](uint32_t a, uint32_t b) {
            if (a == b) return true;
            if (a == GlassSetup::kNoTriangle || b == GlassSetup::kNoTriangle || a >= neighbours.size())
                return false;
            const std::array<uint32_t, 3>& n = neighbours[a];
            return n[0] == b || n[1] == b || n[2] == b;
        };
        return traced && o.traced && material == o.material && events == o.events &&
               truncated == o.truncated && crossed == o.crossed && exit.object == o.exit.object &&
               reflection.object == o.reflection.object && dot(exitDir, o.exitDir) >= kCosTurn &&
               touch(exit.triangle, o.exit.triangle) && touch(reflection.triangle, o.reflection.triangle);
    }
    /// Radians (3 degrees): lattice paths whose light leaves the glass further apart than this in
    /// direction sample the scene behind too coarsely to be interpolated (a crease of the glass, a
    /// strongly minifying curve).
    static constexpr double kMaxExitTurn = 3 * M_PI / 180;
};

// Adaptive image-space refinement of the light through the glass (RenderOptions::glassRefinement,
// after Levoy 1990, as the volume pass does): the cells of the coarse lattice (even cx and cy) are
// traced first; a cell between them takes the light through the glass from the lattice cells around
// it (the two along x, along y, or the four at its corners) where their paths agree
// (LatticePath::agrees: the same glass crossed the same way, the same objects behind, on one triangle
// or two sharing an edge, exit directions within 3 degrees), none of them bends (its shown luma departs from
// the line through its agreeing lattice neighbours' by more than the threshold: bilinear interpolation then
// misses by about as much), none is a cell the G-buffer refined (an edge of the glass: those stay
// exact) and their material is the cell's own. The cell is traced otherwise.
class GlassLattice {
public:
    GlassLattice(const FrameState& f, float threshold, const std::vector<std::array<uint32_t, 3>>& neighbours)
        : f_(f), neighbours_(neighbours), threshold_(threshold), a_(f.adaptive), cw_(f.width / a_),
          ch_(f.height / a_), lw_((cw_ + 1) / 2),
          paths_(threshold > 0 ? std::size_t(lw_ * ((ch_ + 1) / 2)) : 0) {}

    bool enabled() const { return threshold_ > 0; }
    static bool onLattice(int64_t cx, int64_t cy) { return cx % 2 == 0 && cy % 2 == 0; }
    LatticePath& at(int64_t cx, int64_t cy) { return paths_[index(cx, cy)]; }

    // After the lattice is traced: which of its cells bend (rows in parallel; each reads the
    // representatives' shading only).
    void markBends() {
        const ToneMap tm = f_.options.toneMap;
        const int64_t lh = (ch_ + 1) / 2;
        parallelFor(0, lh, 16, [&](int64_t y0, int64_t y1) {
            for (int64_t ly = y0; ly < y1; ++ly)
                for (int64_t lx = 0; lx < lw_; ++lx) {
                    LatticePath& p = paths_[std::size_t(ly * lw_ + lx)];
                    if (!p.traced) continue;
                    const int64_t cx = 2 * lx, cy = 2 * ly;
                    const float own = luma(cx, cy, tm);
                    // A neighbour whose path does not agree (or past the image's side) counts as the
                    // cell itself: what lies beyond a parting is not interpolated over anyway.
                    const auto l = [&](int64_t nx, int64_t ny) {
                        if (nx < 0 || ny < 0 || nx >= cw_ || ny >= ch_ || !p.agrees(at(nx, ny), neighbours_))
                            return own;
                        return luma(nx, ny, tm);
                    };
                    p.bends = std::abs(l(cx - 2, cy) + l(cx + 2, cy) - 2 * own) > threshold_ ||
                              std::abs(l(cx, cy - 2) + l(cx, cy + 2) - 2 * own) > threshold_;
                }
        });
    }

    // Whether cell (cx, cy), off the lattice, of material `material`, takes its light through the
    // glass from the lattice: then `through` is it.
    bool interpolate(int64_t cx, int64_t cy, uint32_t material, Vec3f& through) const {
        const LatticeNeighbours around = latticeNeighbours(cx, cy, 1);
        const int64_t *nx = around.x, *ny = around.y;
        const int n = around.n;
        Vec3f sum{0, 0, 0};
        const LatticePath* p[4];
        for (int k = 0; k < n; ++k) {
            if (nx[k] < 0 || ny[k] < 0 || nx[k] >= cw_ || ny[k] >= ch_) return false;
            if (a_ > 1 && f_.refined[std::size_t(ny[k] * cw_ + nx[k])] != 0) return false; // an edge
            p[k] = &paths_[index(nx[k], ny[k])];
            if (!p[k]->traced || p[k]->bends || p[k]->material != material) return false;
            for (int j = 0; j < k; ++j) // every pair: triangles that touch are not transitive
                if (!p[j]->agrees(*p[k], neighbours_)) return false;
            sum += p[k]->through;
        }
        through = sum * (1.0f / float(n));
        return true;
    }

private:
    std::size_t index(int64_t cx, int64_t cy) const { return std::size_t((cy / 2) * lw_ + cx / 2); }
    float luma(int64_t cx, int64_t cy, ToneMap tm) const {
        return shownLuma(f_.shaded[representativeSample(f_, cx, cy)], tm);
    }

    const FrameState& f_;
    const std::vector<std::array<uint32_t, 3>>& neighbours_;
    float threshold_;
    int a_;
    int64_t cw_, ch_, lw_;
    std::vector<LatticePath> paths_;
};

// Every cell's representative that shows glass: with the lattice (RenderOptions::glassRefinement >
// 0), the lattice cells and the cells the G-buffer refined first (traced), then the others, each
// traced or interpolated (GlassLattice). With adaptive anti-aliasing, then the other samples of edge
// cells, each as the shading pass shaded it: a sample whose shading was an earlier sample's of its
// cell, or a neighbouring cell's representative's (the same triangle: shadeGBuffer), takes that
// sample's light through the glass too, the rest are traced. What an edge cell needs is which surface
// covers each sample; the light through one triangle varies little over a cell. Each round reads
// what the rounds before wrote only (the lattice; representatives), so the order of the cells does
// not matter.
template <class ShowsGlass, class Trace, class Mix>
void traceCells(FrameState& f, const GlassSetup& setup, const ShowsGlass& showsGlass, const Trace& trace,
                const Mix& mix, std::atomic<int64_t>& interpolated) {
    const int a = f.adaptive;
    const int64_t W = f.width, cw = W / a, ch = f.height / a;
    const std::vector<uint32_t>& triangle = f.gbuffer.triangle;
    const auto traceAt = [&](size_t i, LatticePath* into) {
        trace(int64_t(i % size_t(W)), int64_t(i / size_t(W)), i, into);
    };
    const auto edge = [&](int64_t cx, int64_t cy) { return a > 1 && f.refined[size_t(cy * cw + cx)] != 0; };
    GlassLattice lattice(f, float(f.options.glassRefinement), setup.behindNeighbours);
    parallelFor(0, ch, 4, [&](int64_t y0, int64_t y1) {
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                const size_t rep = representativeSample(f, cx, cy);
                if (!showsGlass(rep)) continue;
                if (!lattice.enabled()) {
                    traceAt(rep, nullptr);
                } else if (GlassLattice::onLattice(cx, cy)) {
                    traceAt(rep, &lattice.at(cx, cy));
                } else if (edge(cx, cy)) {
                    traceAt(rep, nullptr);
                }
            }
    });
    if (lattice.enabled()) {
        lattice.markBends();
        const std::vector<uint32_t>& material = f.geometry.triangleMaterial;
        parallelFor(0, ch, 4, [&](int64_t y0, int64_t y1) {
            int64_t n = 0;
            for (int64_t cy = y0; cy < y1; ++cy)
                for (int64_t cx = 0; cx < cw; ++cx) {
                    if (GlassLattice::onLattice(cx, cy) || edge(cx, cy)) continue;
                    const size_t rep = representativeSample(f, cx, cy);
                    if (!showsGlass(rep)) continue;
                    Vec3f through;
                    if (lattice.interpolate(cx, cy, material[triangle[rep]], through)) {
                        mix(rep, through);
                        ++n;
                    } else {
                        traceAt(rep, nullptr);
                    }
                }
            interpolated += n;
        });
    }
    if (a <= 1) return;
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
                        traceAt(i, nullptr);
                    } else {
                        f.shaded[i] = f.shaded[from];
                        f.glassSamples[i] = f.glassSamples[from];
                    }
                }
            }
    });
}

// Adaptive anti-aliasing inside glass: a glass cell shaded once (no edge) whose light through it
// bends or steps between its neighbours' by more than RenderOptions::glassSampleContrast
// (curvesAcrossNeighbours, on the traced representatives) gets its N-rooks samples, each shaded as a
// surface and traced. The cells decide on representatives only,
// which no cell changes, so the order does not matter.
template <class ShowsGlass, class Trace>
void addRookSamples(FrameState& f, const ShowsGlass& showsGlass, const Trace& trace) {
    const int a = f.adaptive;
    const int64_t W = f.width, cw = W / a, ch = f.height / a;
    const Vec3d eye = f.gbuffer.frame.eye();
    const float contrast = float(f.options.glassSampleContrast);
    parallelFor(0, ch, 4, [&](int64_t y0, int64_t y1) {
        for (int64_t cy = y0; cy < y1; ++cy)
            for (int64_t cx = 0; cx < cw; ++cx) {
                uint8_t& kind = f.refined[size_t(cy * cw + cx)];
                const size_t rep = representativeSample(f, cx, cy);
                if (kind != 0 || !showsGlass(rep) || !curvesAcrossNeighbours(f, cx, cy, contrast)) continue;
                kind = kRookSamples;
                const float occlusion =
                    f.screenOcclusion.empty() ? 1.0f : f.screenOcclusion[size_t(cy * cw + cx)];
                for (int dy = 0; dy < a; ++dy) {
                    const int64_t x = cx * a + rookColumn(a, dy), y = cy * a + dy;
                    const size_t i = size_t(y * W + x);
                    if (i == rep) continue;
                    SurfacePoint s;
                    const bool surface = surfaceAt(f.gbuffer, f.geometry, x, y, s);
                    const auto shade = [&] {
                        return surface ? f.shader->shade(s, eye, occlusion) : f.shaded[rep];
                    };
                    if (!showsGlass(i)) {
                        f.shaded[i] = shade();
                    } else if (glassReplacesShading(f, s.material)) {
                        // Mixed in times 0 where a path goes through: shaded only where none does.
                        f.shaded[i] = {0, 0, 0};
                        if (!trace(x, y, i, nullptr)) f.shaded[i] = shade();
                    } else {
                        f.shaded[i] = shade();
                        trace(x, y, i, nullptr);
                    }
                }
            }
    });
}

// The light arriving at `from` (on the glass) along `dir` from behind it: the opaque scene's shading
// where a ray meets it (what it landed on into `landing`), else the environment (blurred by `blur`).
Vec3f lightBehindGlass(FrameState& frame, const GlassSetup& setup, const Vec3d& from, const Vec3d& dir,
                       double blur, Landing& landing) {
    const SceneGeometry& geometry = frame.geometry;
    if (const TriangleTracer* behind = setup.behind.get()) {
        // The opaque scene holds no glass triangle, so `from` (on the glass) left none of its
        // triangles: a hit within epsilon counts, on either side (a glass box standing on the
        // ground leaves through its bottom into the ground at t = 0 up to rounding; skipping
        // it showed the sky below the ground through the box).
        const double epsilon = setup.epsilon;
        TriangleTracer::Hit h =
            behind->intersect(from - dir * epsilon, dir, 0, std::numeric_limits<double>::infinity());
        h.t -= epsilon;
        if (h.hit) {
            const size_t t = setup.opaqueTriangle[h.triangle];
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
            landing.object = uint64_t(geometry.triangleMesh[t]) << 32 | s.material;
            landing.triangle = h.triangle;
            // shadePoint applies the exposure; the caller applies it to the whole glass radiance.
            return shadePoint(frame, s, from) * (1.0f / frame.options.exposure);
        }
    }
    return frame.environment->lookup(dir, blur);
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
    const auto incoming = [&](const Vec3d& from, const Vec3d& dir, double blur, Landing& landing) {
        return lightBehindGlass(frame, setup, from, dir, blur, landing);
    };
    const auto t1 = Clock::now();
    frame.result.glass.prepareMs += std::chrono::duration<double, std::milli>(t1 - t0).count();

    const Vec3d eye = gbuffer.frame.eye();
    // Light through the glass `through` mixed into the shading of sample i.
    const auto mix = [&](size_t i, const Vec3f& through) {
        const uint32_t m = geometry.triangleMaterial[gbuffer.triangle[i]];
        const float tr = std::clamp(scene.materials[m].transmission, 0.0f, 1.0f);
        shaded[i] = shaded[i] * (1 - tr) + through * (tr * options.exposure);
        sampleMask[i] = 1;
    };
    std::atomic<int64_t> paths{0}, interpolated{0};
    const int a = frame.adaptive;
    const int64_t cw = frame.width / a;
    // A cell's representative the shading pass left black (glassReplacesShading) gets its shading
    // where no path goes through it.
    const auto shadeUnlit = [&](int64_t x, int64_t y, size_t i) {
        const int64_t cx = x / a, cy = y / a;
        if (i != representativeSample(frame, cx, cy) || gbuffer.triangle[i] == GBuffer::kNone ||
            !glassReplacesShading(frame, geometry.triangleMaterial[gbuffer.triangle[i]]))
            return;
        shaded[i] = shadeSample(
            frame, i, frame.screenOcclusion.empty() ? 1.0f : frame.screenOcclusion[size_t(cy * cw + cx)]);
    };
    // The light through the glass at sample (x, y) (index i) mixed into its shading; what the path
    // found into `lattice` where one is given. False where no path went through (the shading stays).
    const auto trace = [&](int64_t x, int64_t y, size_t i, LatticePath* lattice) {
        SurfacePoint s;
        GlassPath p;
        if (surfaceAt(gbuffer, geometry, x, y, s)) {
            const Vec3d d = normalize(s.position - eye);
            p = traceGlass(built, GlassHit{eye, d, s.position, s.normal, s.material});
            paths.fetch_add(1, std::memory_order_relaxed);
        }
        if (!p.hit) {
            shadeUnlit(x, y, i);
            return false;
        }
        // Frosted light is the blurred environment (ED06's pre-filtered map), never the scene.
        Landing reflection, exit;
        const Vec3f through = incoming(s.position, p.reflectDir, 0, reflection) * p.reflectance +
                              (p.blurAngle > 0 ? env.lookup(p.exitDir, p.blurAngle)
                                               : incoming(p.exitPoint, p.exitDir, 0, exit)) *
                                  p.throughput;
        mix(i, through);
        if (lattice)
            *lattice = LatticePath{true,      false, s.material, p.events,         p.truncated,
                                   p.crossed, exit,  reflection, Vec3f(p.exitDir), through};
        return true;
    };
    const auto showsGlass = [&](size_t i) {
        const uint32_t tri = gbuffer.triangle[i];
        return tri != GBuffer::kNone && isGlass[geometry.triangleMaterial[tri]];
    };
    traceCells(frame, setup, showsGlass, trace, mix, interpolated);
    if (frame.adaptive > 1) addRookSamples(frame, showsGlass, trace);
    frame.result.glass.paths += paths.load();
    frame.result.glass.interpolated += interpolated.load();
    frame.result.glass.traceMs += std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
}

} // namespace voxfx::detail
