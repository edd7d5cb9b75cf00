// voxfx — deep shadow maps from lights over fragment lists (voxfx/deep_shadow.hpp).
#include "voxfx/deep_shadow.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <tuple>

#include "voxfx/error.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/text.hpp"
#include "voxfx/volume_scene.hpp"

namespace voxfx {

namespace {

double deepShadowMsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// What every texel of one view shares.
struct DeepShadowView {
    const VolumeScene* scene;
    const LightView* view;
    const FlatLeaves* leaves;
    const FragmentLists* lists;
    DeepShadowOptions options;
    double step; // world sample step inside volumes
    /// Per object, the bricks whose samples are transparent; null: sample everywhere (the
    /// reference deepShadowTexel keeps, so that tests compare the skipping build against it).
    const std::vector<EmptySpace>* emptySpace = nullptr;
    /// Per object: its transfer function pre-integrated (Volume objects).
    std::vector<PreintegratedTransfer> preintegrated;

    DeepShadowView(const VolumeScene* s, const LightView* v, const FlatLeaves* l, const FragmentLists* f,
                   const DeepShadowOptions& o, double st, const std::vector<EmptySpace>* e = nullptr)
        : scene(s), view(v), leaves(l), lists(f), options(o), step(st), emptySpace(e),
          preintegrated(s->objects.size()) {
        for (std::size_t i = 0; i < s->objects.size(); ++i)
            if (s->objects[i].kind == ObjectKind::Volume)
                preintegrated[i] = PreintegratedTransfer(s->objects[i].transfer, s->objects[i].opacityLength);
    }
    /// The colour channel this map holds (0: red, or every channel of a grey scene).
    int channel = 0;

    // Glass object o crossed at depth z of a texel's ray (direction `dir`): (1 - F) at the angle
    // between the ray and the normal of its triangle there over the (1 - F0) its transmittance holds
    // (the exact tracer's Fresnel per crossing); 1 for other objects.
    double glassFresnelRatio(std::span<const ListFragment> frags, double z, std::size_t o,
                             const Vec3d& dir) const {
        const VolumeSceneObject& obj = scene->objects[o];
        if (!(obj.ior > 1)) return 1.0;
        const ShapeNode& node = scene->nodes[std::size_t(obj.shape)];
        if (node.op != ShapeOp::Leaf) return 1.0;
        auto it = std::lower_bound(frags.begin(), frags.end(), z,
                                   [](const ListFragment& f, double d) { return f.depth < d; });
        for (; it != frags.end() && it->depth == z; ++it) {
            if (leaves->triangleLeaf[it->triangle] != uint32_t(node.leaf)) continue;
            const Mesh& m = leaves->mesh;
            const std::size_t t = it->triangle;
            const Vec3d a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]),
                c(m.positions[m.indices[3 * t + 2]]);
            const Vec3d n = cross(b - a, c - a);
            const double nl = length(n) * length(dir);
            if (!(nl > 0)) return 1.0;
            const double cosine = std::min(1.0, std::abs(dot(n, dir)) / nl), ior = obj.ior;
            const double f0 = ((ior - 1) / (ior + 1)) * ((ior - 1) / (ior + 1));
            return (1 - fresnelDielectric(cosine, 1.0, ior)) / (1 - f0);
        }
        return 1.0;
    }

    // Feeds texel (x, y) into the builder.
    void texel(int64_t x, int64_t y, VisibilityBuilder& b) const {
        const std::span<const ListFragment> frags = lists->column(x, y);
        if (frags.empty()) return;
        // The texel's ray is affine in the frame depth: world(z) = origin + z * perDepth.
        const Frame& f = view->frame;
        const Vec3d g1 = f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 1.0});
        const Vec3d g2 = f.worldFromGrid({double(x) + 0.5, double(y) + 0.5, 2.0});
        const Vec3d perDepth = g2 - g1, origin = g1 - perDepth;
        const double lengthPerDepth = length(perDepth);
        const double term = options.termination;
        const double jitter = sampleJitter(x, y, 2);
        std::vector<double> value(scene->objects.size(), 0.0), cumulative(scene->objects.size(), 0.0);
        std::vector<uint8_t> haveValue(scene->objects.size(), 0);
        // Glass the ray is inside: the sum of the Beer–Lambert coefficients (this channel, per world
        // unit), applied as a ramp up to each crossing (the chord between a crossing that enters
        // and the next that leaves, as ExactShadow applies it).
        double glassSigma = 0, glassFrom = 0;
        SegmentWalker walker(*scene, leaves->triangleLeaf, true);
        walker.walk(
            frags,
            [&](double z, std::size_t o, bool entering) {
                const VolumeSceneObject& obj = scene->objects[o];
                if (glassSigma > 0 && z > glassFrom)
                    b.ramp(z,
                           beerLambert(Vec3f{float(glassSigma), 0, 0}, (z - glassFrom) * lengthPerDepth).x);
                glassFrom = z;
                const double sigma =
                    obj.kind == ObjectKind::Translucent ? double(obj.attenuation[channel]) : 0;
                if (sigma > 0) glassSigma = entering ? glassSigma + sigma : std::max(0.0, glassSigma - sigma);
                if (glassSigma < 1e-12) glassSigma = 0;
                b.surface(z, obj.kind == ObjectKind::Opaque
                                 ? 1.0
                                 : 1.0 - double(obj.shadowTransmittance()[channel]) *
                                             glassFresnelRatio(frags, z, o, perDepth));
                if (b.visibility() < term) {
                    if (b.visibility() > 0) b.ramp(z, 0.0);
                    return false;
                }
                return true;
            },
            [&](double z0, double z1, std::span<const uint8_t> inside) {
                // Samples at the segment's ends and at z0 + (j + jitter) steps between them (the
                // jitter per texel: no moire where equal steps from each texel's entry would draw
                // it); each interval takes the pre-integrated extinction of the values at its ends.
                const double worldLength = (z1 - z0) * lengthPerDepth;
                const double depthPerLength = (z1 - z0) / worldLength;
                std::fill(haveValue.begin(), haveValue.end(), uint8_t(0));
                b.volumeBegin(z0);
                double l0 = 0;
                for (int64_t j = 0; l0 < worldLength; ++j) {
                    const double l1 = std::min(worldLength, (double(j) + jitter) * step);
                    if (!(l1 > l0)) continue;
                    const double zk = l1 == worldLength ? z1 : z0 + l1 * depthPerLength;
                    const Vec3d p0 = origin + perDepth * (z0 + l0 * depthPerLength),
                                p1 = origin + perDepth * zk;
                    double sigma = 0;
                    for (std::size_t o = 0; o < inside.size(); ++o) {
                        const VolumeSceneObject& obj = scene->objects[o];
                        if (!inside[o] || obj.kind != ObjectKind::Volume) continue;
                        if (emptySpace && (*emptySpace)[o].emptyBetween(p0, p1)) { // adds sigma 0
                            haveValue[o] = 0;
                            continue;
                        }
                        const Volume& volume = *scene->volumes[std::size_t(obj.volume)];
                        const PreintegratedTransfer& pre = preintegrated[o];
                        if (!haveValue[o]) {
                            value[o] = double(volume.sample(p0));
                            cumulative[o] = pre.cumulative(value[o]);
                        }
                        const double a = value[o], ca = cumulative[o];
                        value[o] = double(volume.sample(p1));
                        cumulative[o] = pre.cumulative(value[o]);
                        haveValue[o] = 1;
                        sigma += pre.extinction(a, ca, value[o], cumulative[o]);
                    }
                    // A dense interval in pieces of optical depth at most 0.5 (up to 8): the
                    // map's linear pieces then follow the exponential fall, which a lookup in the
                    // interval (the front of a bone layer) reads; compression drops what it need not.
                    const double dl = l1 - l0;
                    const int64_t pieces = std::clamp<int64_t>(int64_t(std::ceil(sigma * dl / 0.5)), 1, 8);
                    const double zStart = z0 + l0 * depthPerLength;
                    for (int64_t k = 1; k <= pieces; ++k) {
                        const double zp =
                            k == pieces ? zk : zStart + (zk - zStart) * double(k) / double(pieces);
                        b.volumeSample(zp, sigma, dl / double(pieces));
                        if (b.visibility() < term) {
                            b.ramp(zp, 0.0);
                            return false;
                        }
                    }
                    l0 = l1;
                }
                return true;
            });
    }
};

double deepShadowStep(const VolumeScene& scene, const DeepShadowOptions& options) {
    double spacing = std::numeric_limits<double>::infinity();
    for (const auto& v : scene.volumes)
        if (v) spacing = std::min({spacing, v->spacing().x, v->spacing().y, v->spacing().z});
    return std::isfinite(spacing) ? spacing * options.stepVoxels : 1.0;
}

void checkDeepShadowOptions(const DeepShadowOptions& o) {
    if (o.resolution <= 0 || o.resolution > 16384)
        fail("deep shadow map: resolution ", o.resolution, " is not in 1..16384");
    if (!(o.stepVoxels > 0) || !std::isfinite(o.stepVoxels))
        fail("deep shadow map: the volume step must be positive, got ", o.stepVoxels, " voxels");
    if (!(o.termination >= 0 && o.termination < 1))
        fail("deep shadow map: early termination threshold ", o.termination, " is not in [0, 1)");
    if (o.fixedNodes == 1 || o.fixedNodes < 0 || o.fixedNodes > 65535)
        fail("deep shadow map (--fixed-nodes): fixed storage needs 0 (sized by the worst texel) or 2..65535 "
             "nodes per texel "
             "(a surface is a step of two nodes), got ",
             o.fixedNodes);
    if (o.clusters < 0) fail("deep shadow map (--clusters): must be 0 or more, got ", o.clusters);
    if (!(o.clusterThreshold >= 0) || !std::isfinite(o.clusterThreshold))
        fail("deep shadow map (--cluster-threshold): the cluster distance d0 must be a number >= 0, got ",
             o.clusterThreshold);
}

} // namespace

std::vector<int> clusterByDistance(std::size_t n, const std::vector<double>& distances, int maxClusters,
                                   double d0) {
    std::vector<int> cluster(n, -1);
    if (n == 0) return cluster;
    if (distances.size() != n * n)
        fail("clusterByDistance: ", distances.size(), " distances for ", n, " objects");
    maxClusters = std::max(1, maxClusters);
    auto dist = [&](std::size_t a, std::size_t b) { return distances[a * n + b]; };
    // Pairs by increasing distance (ties by index): objects are placed in the order they appear.
    std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
    for (std::size_t a = 0; a < n; ++a)
        for (std::size_t b = a + 1; b < n; ++b) pairs.emplace_back(dist(a, b), a, b);
    std::sort(pairs.begin(), pairs.end());
    std::vector<std::size_t> order;
    for (const auto& [d, a, b] : pairs)
        for (const std::size_t o : {a, b})
            if (std::find(order.begin(), order.end(), o) == order.end()) order.push_back(o);
    if (order.empty()) order.push_back(0);
    std::vector<std::vector<std::size_t>> members;
    for (const std::size_t o : order) {
        int best = -1, nearest = -1;
        double bestD = std::numeric_limits<double>::infinity(), nearestD = bestD;
        for (std::size_t c = 0; c < members.size(); ++c) {
            double worst = 0;
            for (const std::size_t m : members[c]) worst = std::max(worst, dist(o, m));
            if (worst <= d0 && worst < bestD) {
                best = int(c);
                bestD = worst;
            }
            if (worst < nearestD) {
                nearest = int(c);
                nearestD = worst;
            }
        }
        if (best < 0 && int(members.size()) < maxClusters) {
            members.emplace_back();
            best = int(members.size() - 1);
        }
        if (best < 0) best = nearest;
        members[std::size_t(best)].push_back(o);
        cluster[o] = best;
    }
    return cluster;
}

std::vector<int> clusterBoxes(const std::vector<ProjectedBox>& boxes, int maxClusters, double d0) {
    const std::size_t n = boxes.size();
    std::vector<double> dist(n * n, 0.0);
    for (std::size_t a = 0; a < n; ++a)
        for (std::size_t b = 0; b < n; ++b)
            for (int k = 0; k < 2; ++k)
                dist[a * n + b] = std::max({dist[a * n + b], std::abs(boxes[a].lo[k] - boxes[b].lo[k]),
                                            std::abs(boxes[a].hi[k] - boxes[b].hi[k])});
    return clusterByDistance(n, dist, maxClusters, d0);
}

namespace detail_dsmcluster {

// The leaves under `node`.
void leavesOf(const VolumeScene& s, int32_t node, std::vector<int32_t>& out) {
    const ShapeNode& n = s.nodes[std::size_t(node)];
    if (n.op == ShapeOp::Leaf) {
        out.push_back(n.leaf);
        return;
    }
    leavesOf(s, n.a, out);
    leavesOf(s, n.b, out);
}

// A lattice of k^3 points over a box (its corners among them) and the largest distance from a
// point of the box to the nearest lattice point.
constexpr int kLattice = 9;
std::vector<Vec3d> lattice(const Box3d& b, double& reach) {
    std::vector<Vec3d> out;
    const Vec3d e = b.extent() * (1.0 / double(kLattice - 1));
    reach = 0.5 * length(e);
    for (int i = 0; i < kLattice; ++i)
        for (int j = 0; j < kLattice; ++j)
            for (int k = 0; k < kLattice; ++k)
                out.push_back(b.lo + Vec3d{e.x * double(i), e.y * double(j), e.z * double(k)});
    return out;
}

// The cube faces of a point light, in makeLightViews' order: +x, -x, +y, -y, +z, -z. Face f has
// axis f / 2 with sign (f odd: negative); (u, v) are the other two coordinates over the axis one,
// in [-1, 1] inside the face.
struct Faces {
    bool present[6] = {false, false, false, false, false, false};
    ProjectedBox box[6];
};

// Which faces the world box reaches from `eye` (conservative: the lattice test allows for the
// points between lattice points; f = s * d_i - max(|d_j|, |d_k|) changes by at most sqrt(2) per
// unit of distance), and the projected box on each, in fractions of the face's side.
Faces cubeFacesOf(const Box3d& b, const Vec3d& eye) {
    Faces out;
    for (ProjectedBox& pb : out.box) pb = {{1e300, 1e300}, {-1e300, -1e300}};
    double reach = 0;
    for (const Vec3d& q : lattice(b, reach)) {
        const Vec3d d = q - eye;
        for (int f = 0; f < 6; ++f) {
            const int i = f / 2, j = (i + 1) % 3, k = (i + 2) % 3;
            const double axis = f % 2 ? -d[i] : d[i];
            const double side = std::max(std::abs(d[j]), std::abs(d[k]));
            if (axis - side < -1.5 * reach) continue;
            out.present[f] = true;
            // Inside the face's pyramid (up to the tolerance): its (u, v), clamped to the face.
            const double w = std::max(axis, 1e-12);
            const double u = std::clamp(d[j] / w, -1.0, 1.0), v = std::clamp(d[k] / w, -1.0, 1.0);
            ProjectedBox& pb = out.box[f];
            pb.lo[0] = std::min(pb.lo[0], 0.5 * (u + 1));
            pb.hi[0] = std::max(pb.hi[0], 0.5 * (u + 1));
            pb.lo[1] = std::min(pb.lo[1], 0.5 * (v + 1));
            pb.hi[1] = std::max(pb.hi[1], 0.5 * (v + 1));
        }
    }
    return out;
}

double boxDistance(const ProjectedBox& a, const ProjectedBox& b) {
    double d = 0;
    for (int k = 0; k < 2; ++k) d = std::max({d, std::abs(a.lo[k] - b.lo[k]), std::abs(a.hi[k] - b.hi[k])});
    return d;
}

// The largest angle (cosine) between `axis` and the directions from `eye` to the box's corners.
double minCosine(const Box3d& b, const Vec3d& eye, const Vec3d& axis) {
    double c = 1;
    for (int k = 0; k < 8; ++k) {
        const Vec3d q{(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z};
        const double l = length(q - eye);
        if (!(l > 0)) return -1;
        c = std::min(c, dot(q - eye, axis) / l);
    }
    return c;
}

// How the maps of one cluster are made: makeLightViews for `light` fitted to `bounds` (a spot aimed
// at the cluster stands in for a point light where that is enough), keeping only the cube faces
// marked (point lights).
struct ClusterViews {
    Light light;
    Box3d bounds;
    bool keep[6] = {true, true, true, true, true, true};
    std::vector<LightView> make(int64_t columns) const {
        std::vector<LightView> all = makeLightViews(light, bounds, columns, 1), out;
        for (std::size_t i = 0; i < all.size(); ++i)
            if (all.size() == 1 || keep[i]) out.push_back(all[i]);
        return out;
    }
};

int64_t texelsOf(const std::vector<LightView>& views) {
    int64_t t = 0;
    for (const LightView& v : views) t += v.frame.width() * v.frame.height();
    return t;
}

// A point light's cluster is served by one perspective map when every corner of its bounds lies
// within this angle of the direction to its centre (a frame of at most about 120 degrees; wider
// frames spread their texels worse than the cube faces do).
constexpr double kPointClusterHalfAngle = M_PI / 3;

// The casting objects of a scene: their indices and world bounds, and the bounds of them all.
struct Casters {
    std::vector<std::size_t> objects;
    std::vector<Box3d> boxes;
    Box3d all;
};

Casters castersOf(const VolumeScene& scene) {
    Casters c;
    for (std::size_t o = 0; o < scene.objects.size(); ++o) {
        if (!scene.objects[o].castsShadow) continue;
        std::vector<int32_t> leaves;
        leavesOf(scene, scene.objects[o].shape, leaves);
        Box3d wb;
        for (const int32_t l : leaves) wb.extend(computeBounds(scene.leaves[std::size_t(l)].view()));
        if (wb.empty()) continue;
        c.objects.push_back(o);
        c.boxes.push_back(wb);
        c.all.extend(wb);
    }
    return c;
}

// The box of world box wb projected into the light's view `base` (fitted to every caster: a
// corner outside it, behind a spot light, is clamped to the view's border), in fractions of its
// sides.
ProjectedBox projectedBox(const LightView& base, const Box3d& wb) {
    ProjectedBox pb{{1e300, 1e300}, {-1e300, -1e300}};
    for (int k = 0; k < 8; ++k) {
        const Vec3d c{(k & 1) ? wb.hi.x : wb.lo.x, (k & 2) ? wb.hi.y : wb.lo.y, (k & 4) ? wb.hi.z : wb.lo.z};
        Vec3d g = base.frame.isPerspective() && !(base.frame.viewDepth(c) > 0) ? Vec3d{0, 0, 0}
                                                                               : base.gridFromWorld(c);
        const double u = std::clamp(g.x / double(base.frame.width()), 0.0, 1.0),
                     v = std::clamp(g.y / double(base.frame.height()), 0.0, 1.0);
        pb.lo[0] = std::min(pb.lo[0], u);
        pb.hi[0] = std::max(pb.hi[0], u);
        pb.lo[1] = std::min(pb.lo[1], v);
        pb.hi[1] = std::max(pb.hi[1], v);
    }
    return pb;
}

// d(A, B) for every pair of casters (n x n, row-major) in light space: the largest difference of
// the projected boxes' corners, in fractions of the view's side; for a point light the largest over
// the six cube directions (a face that one object reaches and the other does not counts as a whole
// side apart). `base`: the unclustered view (directional and spot lights).
std::vector<double> lightSpaceDistances(const Light& light, const LightView& base,
                                        const std::vector<Box3d>& boxes) {
    const std::size_t n = boxes.size();
    std::vector<double> dist(n * n, 0.0);
    if (light.type == LightType::Point) {
        std::vector<Faces> faces;
        for (const Box3d& b : boxes) faces.push_back(cubeFacesOf(b, light.position));
        for (std::size_t a = 0; a < n; ++a)
            for (std::size_t b = 0; b < n; ++b)
                for (int f = 0; f < 6; ++f) {
                    const bool pa = faces[a].present[f], pb = faces[b].present[f];
                    const double d =
                        pa && pb ? boxDistance(faces[a].box[f], faces[b].box[f]) : (pa || pb ? 1 : 0);
                    dist[a * n + b] = std::max(dist[a * n + b], d);
                }
        return dist;
    }
    std::vector<ProjectedBox> projected;
    for (const Box3d& wb : boxes) projected.push_back(projectedBox(base, wb));
    for (std::size_t a = 0; a < n; ++a)
        for (std::size_t b = 0; b < n; ++b) dist[a * n + b] = boxDistance(projected[a], projected[b]);
    return dist;
}

// The camera: a pair's distance scaled by how much nearer the camera it is than the casters'
// centre (at most 4x), so that objects near the viewer get clusters (and texels) of their own.
void weightByCamera(std::vector<double>& dist, const Casters& casters, const Vec3d& eye) {
    const std::size_t n = casters.boxes.size();
    const double ref = std::max(length(casters.all.center() - eye), 1e-12);
    std::vector<double> weight(n);
    for (std::size_t i = 0; i < n; ++i)
        weight[i] = ref / std::max(length(casters.boxes[i].center() - eye), 0.25 * ref);
    for (std::size_t a = 0; a < n; ++a)
        for (std::size_t b = 0; b < n; ++b) dist[a * n + b] *= std::max(weight[a], weight[b]);
}

// Each cluster's views: a directional light one map fitted to the cluster; spot and point lights
// one map aimed at the cluster where its bounds fit a cone (a spot's own axis would leave a cluster
// off to the side spread over a frame as wide as the unclustered one), else the spot's own frame,
// or the cube faces the cluster reaches.
std::vector<ClusterViews> clusterViewsOf(const Light& light, const Casters& casters,
                                         const std::vector<int>& cluster, int count) {
    const std::size_t n = casters.boxes.size();
    std::vector<ClusterViews> specs(static_cast<std::size_t>(count));
    for (int c = 0; c < count; ++c) {
        ClusterViews& spec = specs[std::size_t(c)];
        spec.light = light;
        for (std::size_t i = 0; i < n; ++i)
            if (cluster[i] == c) spec.bounds.extend(casters.boxes[i]);
        if (light.type == LightType::Directional) continue; // an orthographic frame fitted to the bounds
        const Vec3d toCentre = spec.bounds.center() - light.position;
        const double len = length(toCentre);
        if (len > 0 && minCosine(spec.bounds, light.position, toCentre * (1.0 / len)) >=
                           std::cos(kPointClusterHalfAngle)) {
            spec.light.type = LightType::Spot;
            spec.light.direction = toCentre * (1.0 / len);
            spec.light.outerConeAngle = M_PI / 2; // makeLightViews narrows it to the bounds
            continue;
        }
        if (light.type == LightType::Spot) continue; // too wide to aim at: the spot's own frame
        for (bool& k : spec.keep) k = false;
        for (std::size_t i = 0; i < n; ++i)
            if (cluster[i] == c) {
                const Faces f = cubeFacesOf(casters.boxes[i], light.position);
                for (int k = 0; k < 6; ++k) spec.keep[k] = spec.keep[k] || f.present[k];
            }
    }
    return specs;
}

// Equal texels: the columns of the clustered views so that they share the `budget` texels of the
// unclustered ones, up or down from `columns` (fewer maps than the unclustered views get more
// texels each).
int64_t equalTexelColumns(const std::vector<ClusterViews>& specs, int64_t budget, int64_t columns) {
    auto clusteredTexels = [&](int64_t c) {
        int64_t t = 0;
        for (const ClusterViews& spec : specs) t += texelsOf(spec.make(c));
        return t;
    };
    const int64_t atFull = clusteredTexels(columns);
    columns = std::clamp<int64_t>(
        int64_t(std::floor(double(columns) * std::sqrt(double(budget) / double(atFull)))), 1, 16384);
    while (columns > 1 && clusteredTexels(columns) > budget) --columns;
    return columns;
}

} // namespace detail_dsmcluster

DeepShadow DeepShadow::build(const VolumeScene& scene, const Light& light, const DeepShadowOptions& options,
                             Progress* progress) {
    return build(scene, light, options, BuildContext{}, progress);
}

DeepShadow DeepShadow::build(const VolumeScene& scene, const Light& light, const DeepShadowOptions& options,
                             const BuildContext& context, Progress* progress) {
    namespace dc = detail_dsmcluster;
    checkDeepShadowOptions(options);
    scene.validate();
    std::vector<LightView> all = makeLightViews(light, scene.bounds(true), options.resolution, 1);
    if (options.clusters <= 1) return build(scene, all, options, progress);
    const dc::Casters casters = dc::castersOf(scene);
    const std::size_t n = casters.objects.size();
    std::vector<double> dist = dc::lightSpaceDistances(light, all[0], casters.boxes);
    if (context.camera && n > 0) dc::weightByCamera(dist, casters, context.camera->position);
    const std::vector<int> cluster = clusterByDistance(n, dist, options.clusters, options.clusterThreshold);
    const int count = cluster.empty() ? 0 : *std::max_element(cluster.begin(), cluster.end()) + 1;
    const std::vector<dc::ClusterViews> specs = dc::clusterViewsOf(light, casters, cluster, count);
    const int64_t budget = dc::texelsOf(all);
    const int64_t columns = options.clusterEqualTexels && count > 0
                                ? dc::equalTexelColumns(specs, budget, options.resolution)
                                : int64_t(options.resolution);
    DeepShadow out;
    out.options_ = options;
    out.objectClusters_.assign(scene.objects.size(), -1);
    for (std::size_t i = 0; i < n; ++i) out.objectClusters_[casters.objects[i]] = cluster[i];
    for (int c = 0; c < count; ++c) {
        VolumeScene part = scene;
        for (VolumeSceneObject& o : part.objects) o.castsShadow = false;
        for (std::size_t i = 0; i < n; ++i)
            if (cluster[i] == c) part.objects[casters.objects[i]].castsShadow = true;
        DeepShadow d = build(part, specs[std::size_t(c)].make(columns), options, progress);
        out.groupBegin_.push_back(out.views_.size());
        for (std::size_t i = 0; i < d.views_.size(); ++i) {
            out.views_.push_back(std::move(d.views_[i]));
            out.maps_.push_back(std::move(d.maps_[i]));
            out.greenBlue_.push_back(std::move(d.greenBlue_[i]));
        }
        out.timings_.fragmentsMs += d.timings_.fragmentsMs;
        out.timings_.buildMs += d.timings_.buildMs;
    }
    out.groupBegin_.push_back(out.views_.size());
    DeepShadowStats& cs = out.clusterStats_;
    cs.clusteredLights = 1;
    cs.clusterGroups = count;
    cs.clusterViews = int64_t(out.views_.size());
    cs.unclusteredViewTexels = budget;
    cs.clusteredViewTexels = dc::texelsOf(out.views_);
    cs.singleObjectLights = n == 1;
    return out;
}

DeepShadow DeepShadow::build(const VolumeScene& scene, std::vector<LightView> views,
                             const DeepShadowOptions& options, Progress* progress) {
    checkDeepShadowOptions(options);
    scene.validate();
    DeepShadow out;
    out.options_ = options;
    out.views_ = std::move(views);
    out.groupBegin_ = {0, out.views_.size()};
    const FlatLeaves leaves = flattenLeaves(scene, true);
    const double step = deepShadowStep(scene, options);
    bool coloured = false;
    for (const VolumeSceneObject& o : scene.objects) {
        if (!o.castsShadow || o.kind != ObjectKind::Translucent) continue;
        const Vec3f t = o.shadowTransmittance(), a = o.attenuation;
        coloured = coloured || t.x != t.y || t.y != t.z || a.x != a.y || a.y != a.z;
    }
    const std::vector<EmptySpace> emptySpace =
        options.skipEmptySpace ? emptySpaceOf(scene) : std::vector<EmptySpace>(scene.objects.size());
    for (const LightView& v : out.views_) {
        auto t0 = std::chrono::steady_clock::now();
        // Directional views are oriented orthographic frames: the world mesh rasterizes directly.
        const FragmentLists lists = FragmentLists::build(v.frame, leaves.mesh.view(), progress);
        out.timings_.fragmentsMs += deepShadowMsSince(t0);
        t0 = std::chrono::steady_clock::now();
        DsmBuildOptions bo;
        bo.epsilon = options.epsilon;
        bo.fixedNodes = options.fixedNodes;
        // One map per colour channel where a caster's crossings or glass colour the light (red,
        // then green and blue); one map for every channel of a grey scene.
        auto channelMap = [&](int channel) {
            DeepShadowView ctx{&scene, &v, &leaves, &lists, options, step, &emptySpace};
            ctx.channel = channel;
            return DeepShadowMap::build(
                v.frame.width(), v.frame.height(),
                [&ctx](int64_t x, int64_t y, VisibilityBuilder& b) { ctx.texel(x, y, b); }, options.storage,
                bo);
        };
        out.maps_.push_back(channelMap(0));
        std::vector<DeepShadowMap>& greenBlue = out.greenBlue_.emplace_back();
        if (coloured)
            for (const int channel : {1, 2}) greenBlue.push_back(channelMap(channel));
        out.timings_.buildMs += deepShadowMsSince(t0);
    }
    return out;
}

namespace {

// The view among `count` that covers p (viewIndexFor on a sub-range): one frame, or the cube face
// whose axis is closest to the direction of p.
int deepShadowViewIndex(const LightView* views, std::size_t count, const Vec3d& p) {
    if (count == 1) return views[0].covers(p) ? 0 : -1;
    int best = -1;
    double bestDot = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const double dd = dot(p - views[i].frame.eye(), views[i].frame.forward());
        if (dd > bestDot) {
            bestDot = dd;
            best = int(i);
        }
    }
    return best;
}

// Lookup among views [b, e) (one light's views: one frame, or six cube faces); greenBlue: per view,
// the maps of the green and blue channels, or none (the first map holds every channel). `texelAt`
// (when given): the texel footprint at p of the view that covers it, 0 where none does.
Vec3f deepShadowLookup(const std::vector<LightView>& views, const std::vector<DeepShadowMap>& maps,
                       const std::vector<std::vector<DeepShadowMap>>& greenBlue, std::size_t b, std::size_t e,
                       const Vec3d& p, const Vec3d& n, double normalOffset, double depthBias,
                       DsmFilter filter, double* texelAt = nullptr) {
    const LightView* group = views.data() + b;
    const std::size_t count = e - b;
    int i = deepShadowViewIndex(group, count, p);
    if (texelAt) *texelAt = 0;
    if (i < 0) return {1, 1, 1};
    const double texel = group[i].columnWorldSize(p);
    if (texelAt) *texelAt = texel;
    const Vec3d q = p + n * (normalOffset * texel);
    if (count > 1) {
        const int j = deepShadowViewIndex(group, count, q);
        if (j >= 0) i = j;
    }
    const LightView& v = group[i];
    if (!v.covers(q)) return {1, 1, 1};
    const Vec3d g = v.gridFromWorld(q);
    const double z = g.z - depthBias * texel / v.worldPerDepthUnit();
    const std::size_t k = b + std::size_t(i);
    const float red = maps[k].view().visibilityFiltered(filter, float(g.x), float(g.y), float(z));
    if (greenBlue[k].empty()) return {red, red, red};
    return {red, greenBlue[k][0].view().visibilityFiltered(filter, float(g.x), float(g.y), float(z)),
            greenBlue[k][1].view().visibilityFiltered(filter, float(g.x), float(g.y), float(z))};
}

} // namespace

Vec3f DeepShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    return visibility(p, n, options_.normalOffset, options_.depthBias);
}

Vec3f DeepShadow::visibility(const Vec3d& p, const Vec3d& n, double normalOffset, double depthBias) const {
    Vec3f v{1, 1, 1};
    for (std::size_t g = 0; g + 1 < groupBegin_.size(); ++g)
        v = v * deepShadowLookup(views_, maps_, greenBlue_, groupBegin_[g], groupBegin_[g + 1], p, n,
                                 normalOffset, depthBias, options_.filter);
    return v;
}

Vec3f DeepShadow::visibility(const Vec3d& p, const Vec3d& n, double& texel) const {
    texel = 0;
    if (groupBegin_.size() != 2) { // clusters: the views of all of them, as viewIndexFor sees them
        const int view = viewIndexFor(views_, p);
        if (view >= 0) texel = views_[std::size_t(view)].columnWorldSize(p);
        return visibility(p, n);
    }
    // One group: its views are views(), and the lookup's search is viewIndexFor's.
    return deepShadowLookup(views_, maps_, greenBlue_, groupBegin_[0], groupBegin_[1], p, n,
                            options_.normalOffset, options_.depthBias, options_.filter, &texel);
}

DeepShadowStats DeepShadow::stats() const {
    DeepShadowStats s;
    s.storage = options_.storage;
    s.timings = timings_;
    s.clusteredLights = clusterStats_.clusteredLights;
    s.clusterGroups = clusterStats_.clusterGroups;
    s.clusterViews = clusterStats_.clusterViews;
    s.unclusteredViewTexels = clusterStats_.unclusteredViewTexels;
    s.clusteredViewTexels = clusterStats_.clusteredViewTexels;
    s.singleObjectLights = clusterStats_.singleObjectLights;
    std::vector<const DeepShadowMap*> all;
    for (const DeepShadowMap& m : maps_) all.push_back(&m);
    for (const std::vector<DeepShadowMap>& gb : greenBlue_)
        for (const DeepShadowMap& m : gb) all.push_back(&m);
    for (const DeepShadowMap* m : all) {
        const DsmStats& t = m->stats();
        s.texels += t.texels;
        s.nodes += t.nodes;
        s.maxNodes = std::max(s.maxNodes, t.maxNodes);
        s.bytes += t.bytes;
        s.overflowTexels += t.overflowTexels;
        s.maxEpsilon = std::max(s.maxEpsilon, t.maxEpsilon);
    }
    return s;
}

DeepShadow DeepShadow::build(const Scene& scene, const Light& light, const DeepShadowOptions& options,
                             Progress* progress) {
    return build(scene, light, options, BuildContext{}, progress);
}

DeepShadow DeepShadow::build(const Scene& scene, const Light& light, const DeepShadowOptions& options,
                             const BuildContext& context, Progress* progress) {
    checkDeepShadowOptions(options);
    bool casts = scene.volumeScene != nullptr;
    for (const SceneMesh& m : scene.meshes) casts = casts || (m.castsShadow && !m.mesh.indices.empty());
    if (!casts) { // nothing casts: no maps, visibility 1
        DeepShadow out;
        out.options_ = options;
        return out;
    }
    return build(volumeSceneOf(scene), light, options, context, progress);
}

std::span<const OptionField<DeepShadowOptions>> DeepShadowOptions::fields() {
    using O = DeepShadowOptions;
    static const std::vector<OptionField<O>> table = {
        numberOption<O, &O::resolution>(
            "dsmResolution", "deep shadows: texels along the longer side of a light view", 1, 16384),
        numberOption<O, &O::epsilon>("epsilon", "deep shadows: compression tolerance (0: every node kept)", 0,
                                     1),
        nameOption<O, parseDsmStorage, optionName<DsmStorage>, &O::storage>(
            "dsmStorage", "deep shadows: node storage", "fixed | chunked"),
        numberOption<O, &O::fixedNodes>(
            "fixedNodes",
            "deep shadows, --dsm-storage fixed: nodes each texel holds (the paper's 3D texture depth); a "
            "texel needing more is rebuilt with a doubled epsilon until it fits (counted in the summary); 0: "
            "as many as the worst texel needs",
            0, 65535),
        numberOption<O, &O::stepVoxels>(
            "dsmStep",
            "deep shadows: volume sample step along a light ray, in smallest voxel spacings (smaller: "
            "finer volume shadows, slower maps)",
            1e-3, 1000),
        numberOption<O, &O::termination>(
            "termination",
            "deep shadows: early ray termination; a light ray whose visibility falls below this stops "
            "and is 0 beyond (0: never stop early)",
            0, 0.999999),
        numberOption<O, &O::clusters>(
            "clusters",
            "deep shadows: at most this many clusters of casting objects per light, each with its own "
            "maps fitted to it (point lights too: one aimed map or the cube faces it reaches); 0 or 1: off",
            0, 64),
        numberOption<O, &O::clusterThreshold>(
            "clusterThreshold",
            "deep shadows, --clusters: d0, objects whose light-space projected boxes differ by at most this "
            "(a fraction of the light view's side) may share a cluster; smaller: more clusters",
            0, 100),
        flagOption<O, &O::clusterEqualTexels>(
            "clusterEqualTexels",
            "deep shadows, --clusters: the clustered maps share the texels of the unclustered ones (the "
            "paper's 4 x 128^2 against 256^2)"),
        nameOption<O, parseDsmFilter, optionName<DsmFilter>, &O::filter>(
            "dsmFilter",
            "deep shadows: lookups between texels, bilinear over the four around the point (2x2 PCF) or "
            "none (the texel the point falls in: stair-stepped edges)",
            "bilinear | none"),
        flagOption<O, &O::skipEmptySpace>(
            "emptySpaceSkipping",
            "volumes: skip the bricks the transfer function leaves transparent (same image)"),
        numberOption<O, &O::normalOffset>(
            "normalOffset", "lookup offset along the surface normal, in texel footprints", 0, 1000),
        numberOption<O, &O::depthBias>("depthBias", "deep shadow depth bias, in texel footprints", 0, 1000)};
    return table;
}

DeepShadowStats& DeepShadowStats::operator+=(const DeepShadowStats& o) {
    texels += o.texels;
    nodes += o.nodes;
    maxNodes = std::max(maxNodes, o.maxNodes);
    bytes += o.bytes;
    overflowTexels += o.overflowTexels;
    maxEpsilon = std::max(maxEpsilon, o.maxEpsilon);
    storage = o.storage;
    timings.fragmentsMs += o.timings.fragmentsMs;
    timings.buildMs += o.timings.buildMs;
    clusteredLights += o.clusteredLights;
    clusterGroups += o.clusterGroups;
    clusterViews += o.clusterViews;
    unclusteredViewTexels += o.unclusteredViewTexels;
    clusteredViewTexels += o.clusteredViewTexels;
    singleObjectLights += o.singleObjectLights;
    return *this;
}

std::string DeepShadowStats::summary() const {
    if (texels == 0) return {};
    const double fixedMiB = double(texels) * double(maxNodes * int64_t(sizeof(DsmNode)) + 2) / 1048576.0;
    return countText(texels) + " texels, nodes per texel mean " + numberText(meanNodes()) + " max " +
           countText(maxNodes) + ", " + numberText(double(bytes) / 1048576.0) + " MiB " + toString(storage) +
           " (fixed layout sized by the worst texel: " + numberText(fixedMiB) + " MiB)" +
           (clusteredLights > 0
                ? ", " + countText(clusterGroups) + " clusters in " + countText(clusterViews) + " maps (" +
                      countText(clusteredViewTexels) + " texels per channel against " +
                      countText(unclusteredViewTexels) + " unclustered)"
                : "") +
           (singleObjectLights > 0 ? ", clusters asked but " + countText(singleObjectLights) +
                                         " light(s) have one casting object: one cluster"
                                   : "");
}

std::vector<DsmNode> deepShadowTexel(const VolumeScene& scene, const LightView& view, int64_t x, int64_t y,
                                     const DeepShadowOptions& options) {
    checkDeepShadowOptions(options);
    scene.validate();
    const FlatLeaves leaves = flattenLeaves(scene, true);
    // One column only: a frame of the same camera would change the rasterization; rasterize the
    // whole view (tests use small views).
    const FragmentLists lists = FragmentLists::build(view.frame, leaves.mesh.view());
    const DeepShadowView ctx{&scene, &view, &leaves, &lists, options, deepShadowStep(scene, options)};
    std::vector<DsmNode> out;
    VisibilityBuilder b(-1.0, out);
    ctx.texel(x, y, b);
    b.finish();
    return out;
}

} // namespace voxfx
