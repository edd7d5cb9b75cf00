// voxfx — exact point occupancy (see voxfx/contains.hpp).
#include "voxfx/contains.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <initializer_list>
#include <numbers>

#include "voxelize/winding_tree.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

namespace {

// ---- exact arithmetic: Shewchuk's filters, then expansions (sums of non-overlapping doubles) ----

constexpr double kContainsEps = 0x1p-53; // half an ulp of 1
constexpr double kOrient2dBound = (3.0 + 16.0 * kContainsEps) * kContainsEps;
constexpr double kOrient3dBound = (7.0 + 56.0 * kContainsEps) * kContainsEps;

/// A sum of doubles, non-overlapping and in increasing magnitude (Shewchuk 1997); exact.
struct ContainsExpansion {
    std::vector<double> terms;
    int sign() const {
        for (auto it = terms.rbegin(); it != terms.rend(); ++it)
            if (*it != 0) return *it > 0 ? 1 : -1;
        return 0;
    }
};

inline void containsTwoSum(double a, double b, double& x, double& y) {
    x = a + b;
    const double bv = x - a, av = x - bv;
    y = (a - av) + (b - bv);
}

/// e + b, exactly (Grow-Expansion with zero elimination).
ContainsExpansion containsGrow(const ContainsExpansion& e, double b) {
    ContainsExpansion out;
    out.terms.reserve(e.terms.size() + 1);
    double q = b;
    for (const double t : e.terms) {
        double h;
        containsTwoSum(q, t, q, h);
        if (h != 0) out.terms.push_back(h);
    }
    if (q != 0 || out.terms.empty()) out.terms.push_back(q);
    return out;
}

ContainsExpansion containsAdd(const ContainsExpansion& e, const ContainsExpansion& f) {
    ContainsExpansion out = e;
    for (const double t : f.terms) out = containsGrow(out, t);
    return out;
}

ContainsExpansion containsNegate(ContainsExpansion e) {
    for (double& t : e.terms) t = -t;
    return e;
}

/// a - b as a two-term expansion.
ContainsExpansion containsDiff(double a, double b) {
    double x, y;
    containsTwoSum(a, -b, x, y);
    ContainsExpansion out;
    out.terms = {y, x};
    return out;
}

ContainsExpansion containsMul(const ContainsExpansion& e, const ContainsExpansion& f) {
    ContainsExpansion out;
    for (const double a : e.terms)
        for (const double b : f.terms) {
            const double x = a * b, y = std::fma(a, b, -x); // exact product x + y
            out = containsGrow(containsGrow(out, y), x);
        }
    return out;
}

/// 2^k such that the largest |value| becomes about 2^target: scaling every input by a power of
/// two is exact and keeps the sign of the determinant, and it moves tiny (even subnormal) inputs
/// away from underflow and huge ones away from overflow in the products below.
double containsScale(std::initializer_list<double> values, int target) {
    double m = 0;
    for (const double v : values) m = std::max(m, std::abs(v));
    return m > 0 && std::isfinite(m) ? std::ldexp(1.0, target - std::ilogb(m)) : 1.0;
}

int containsOrient2dExact(double ax, double ay, double bx, double by, double cx, double cy) {
    // (a - c) x (b - c), as Shewchuk's orient2d, on inputs scaled to about 2^450 (products stay
    // below 2^1003).
    const double k = containsScale({ax, ay, bx, by, cx, cy}, 450);
    ax *= k, ay *= k, bx *= k, by *= k, cx *= k, cy *= k;
    const ContainsExpansion l = containsMul(containsDiff(ax, cx), containsDiff(by, cy));
    const ContainsExpansion r = containsMul(containsDiff(ay, cy), containsDiff(bx, cx));
    return containsAdd(l, containsNegate(r)).sign();
}

int containsOrient3dExact(Vec3d a, Vec3d b, Vec3d c, Vec3d d) {
    // Rows u = b - a, v = c - a, w = d - a; det = u.z (v.x w.y - v.y w.x) + v.z (w.x u.y - u.x w.y)
    //                                              + w.z (u.x v.y - v.x u.y), on inputs scaled to
    // about 2^300 (products of three stay below 2^903).
    const double k = containsScale({a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z}, 300);
    a = a * k, b = b * k, c = c * k, d = d * k;
    ContainsExpansion u[3], v[3], w[3];
    for (int i = 0; i < 3; ++i) {
        u[i] = containsDiff(b[i], a[i]);
        v[i] = containsDiff(c[i], a[i]);
        w[i] = containsDiff(d[i], a[i]);
    }
    const auto minor = [](const ContainsExpansion& p, const ContainsExpansion& q, const ContainsExpansion& r,
                          const ContainsExpansion& s) { // p q - r s
        return containsAdd(containsMul(p, q), containsNegate(containsMul(r, s)));
    };
    ContainsExpansion det = containsMul(u[2], minor(v[0], w[1], v[1], w[0]));
    det = containsAdd(det, containsMul(v[2], minor(w[0], u[1], u[0], w[1])));
    det = containsAdd(det, containsMul(w[2], minor(u[0], v[1], v[0], u[1])));
    return det.sign();
}

thread_local int64_t tContainsFilterMisses = 0;

} // namespace

namespace exact {

int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    // Sign of (b - a) x (c - a) = (a - c) x (b - c): Shewchuk's orient2d filter A. Products near
    // underflow (or overflowing) go to the exact path, where the filter's bound does not hold.
    const double detleft = (ax - cx) * (by - cy), detright = (ay - cy) * (bx - cx);
    const double det = detleft - detright;
    const double detsum = std::abs(detleft) + std::abs(detright);
    if (detsum > 0x1p-800 && detsum < 0x1p1000) {
        if ((detleft > 0 && detright <= 0) || (detleft < 0 && detright >= 0)) return detleft > 0 ? 1 : -1;
        const double bound = kOrient2dBound * detsum;
        if (det > bound) return 1;
        if (-det > bound) return -1;
    }
    ++tContainsFilterMisses;
    return containsOrient2dExact(ax, ay, bx, by, cx, cy);
}

int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
    const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
    const double m0 = vx * wy - vy * wx, m1 = wx * uy - ux * wy, m2 = ux * vy - vx * uy;
    const double det = uz * m0 + vz * m1 + wz * m2;
    const double permanent = (std::abs(vx * wy) + std::abs(vy * wx)) * std::abs(uz) +
                             (std::abs(wx * uy) + std::abs(ux * wy)) * std::abs(vz) +
                             (std::abs(ux * vy) + std::abs(vx * uy)) * std::abs(wz);
    if (permanent > 0x1p-700 && permanent < 0x1p1000) {
        const double bound = kOrient3dBound * permanent;
        if (det > bound) return 1;
        if (-det > bound) return -1;
    }
    ++tContainsFilterMisses;
    return containsOrient3dExact(a, b, c, d);
}

} // namespace exact

const char* toString(ContainsMethod m) { return enumName(m, kContainsMethodNames); }

ContainsMethod parseContainsMethod(const std::string& name) {
    return parseEnum<ContainsMethod>(name, "contains method", kContainsMethodNames);
}

int64_t defaultContainsResolution(std::size_t triangles, std::size_t points) {
    // Measured on the CGAL meshes (bunny, armadillo, elephant; 1M uniform points in the bounds):
    // the grid pays for itself up to about 1.3 cbrt(points) cells along the longest side, and
    // dense meshes want enough columns that each holds a few dozen triangles.
    const double byPoints = 1.3 * std::cbrt(double(std::max<std::size_t>(points, 1)));
    const double byTriangles = 0.25 * std::sqrt(double(triangles));
    return std::clamp<int64_t>(int64_t(std::max(byPoints, byTriangles)), 16, 512);
}

double windingNumber(const MeshView& mesh, const Vec3d& p) {
    // Van Oosterom & Strackee: tan(Omega / 2) = det[a b c] / (|a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|).
    double sum = 0;
    for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
        const Vec3d a = mesh.vertex(mesh.index(t, 0)) - p, b = mesh.vertex(mesh.index(t, 1)) - p,
                    c = mesh.vertex(mesh.index(t, 2)) - p;
        const double la = length(a), lb = length(b), lc = length(c);
        const double det = dot(a, cross(b, c));
        const double den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
        sum += 2.0 * std::atan2(det, den);
    }
    return sum / (4.0 * std::numbers::pi);
}

using detail::WindingTree;

void windingNumbers(const MeshView& mesh, std::span<const Vec3d> points, std::span<double> out, double beta,
                    int threads) {
    if (points.size() != out.size())
        fail("windingNumbers: ", points.size(), " points but room for ", out.size());
    validateMesh(mesh, "mesh");
    if (mesh.triangleCount == 0) {
        std::fill(out.begin(), out.end(), 0.0);
        return;
    }
    WindingTree tree;
    tree.build(mesh, beta);
    withThreads(threads, [&] {
        parallelFor(0, int64_t(points.size()), 1024, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) out[std::size_t(i)] = tree.at(points[std::size_t(i)]);
        });
    });
}

struct PointClassifier::Impl {
    ContainsMethod method = ContainsMethod::Parity;
    int threads = 0;
    Mesh mesh; // a copy: the classifier outlives the caller's arrays
    bool emptyMesh = false;
    Frame frame;
    BitGrid solid;   // parity solid, or the flood fill
    BitGrid surface; // conservative surface
    // Per column (y * W + x): the triangles whose xy bounding box touches it (CSR).
    std::vector<int64_t> columnStart;
    std::vector<uint32_t> columnTriangles;
    std::vector<std::array<Vec3d, 3>> triangles;
    std::vector<int8_t> orientXY; // exact sign of each triangle's xy orientation
    WindingTree winding;

    bool parityExact(const Vec3d& p, int64_t column) const;
};

/// The exact parity of triangles strictly below p along z, with the rasterizer's tie rule (see
/// the header), over the triangles of `column`.
bool PointClassifier::Impl::parityExact(const Vec3d& p, int64_t column) const {
    bool inside = false;
    for (int64_t e = columnStart[std::size_t(column)]; e < columnStart[std::size_t(column) + 1]; ++e) {
        const uint32_t t = columnTriangles[std::size_t(e)];
        const int o = orientXY[t];
        if (o == 0) continue; // parallel to z: covers no perturbed point
        const std::array<Vec3d, 3>& v = triangles[t];
        if (p.x < std::min({v[0].x, v[1].x, v[2].x}) || p.x > std::max({v[0].x, v[1].x, v[2].x}) ||
            p.y < std::min({v[0].y, v[1].y, v[2].y}) || p.y > std::max({v[0].y, v[1].y, v[2].y}))
            continue;
        bool covers = true;
        for (int k = 0; k < 3 && covers; ++k) {
            const Vec3d& q0 = v[k];
            const Vec3d& q1 = v[(k + 1) % 3];
            // Canonical (lexicographic) endpoints, as the rasterizer's CanonicalEdge.
            const bool swap = q1.x < q0.x || (q1.x == q0.x && q1.y < q0.y);
            const Vec3d& a = swap ? q1 : q0;
            const Vec3d& b = swap ? q0 : q1;
            int s = exact::orient2d(a.x, a.y, b.x, b.y, p.x, p.y);
            if (s == 0) {
                // E(p + (eps, eps^2)) = E(p) - dy eps + dx eps^2: the first non-zero term decides.
                s = b.y != a.y ? (b.y < a.y ? 1 : -1) : (b.x > a.x ? 1 : -1);
            }
            if (swap) s = -s;
            covers = s == o;
        }
        if (!covers) continue;
        // Strictly below p: sign(n . (p - a)) == sign(n.z), n = (b - a) x (c - a).
        const int d = exact::orient3d(v[0], v[1], v[2], p);
        if (d == o) inside = !inside;
    }
    return inside;
}

PointClassifier::PointClassifier(const MeshView& meshView, const ContainsOptions& options)
    : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.method = options.method;
    m.threads = options.threads;
    if (options.resolution < 0) fail("contains: resolution must be >= 0");
    validateMesh(meshView, "mesh");
    m.mesh.positions.resize(meshView.vertexCount);
    for (std::size_t i = 0; i < meshView.vertexCount; ++i) m.mesh.positions[i] = Vec3f(meshView.vertex(i));
    m.mesh.indices.assign(meshView.indices, meshView.indices + 3 * meshView.triangleCount);
    const MeshView mv = m.mesh.view();
    Box3d bounds = computeBounds(mv);
    if (bounds.empty()) {
        m.emptyMesh = true;
        return;
    }
    if (m.method == ContainsMethod::Winding) {
        if (!(options.windingBeta >= 0)) fail("contains: windingBeta must be >= 0");
        m.winding.build(mv, options.windingBeta);
        return;
    }

    // A flat or point-like mesh still gets a grid: widen degenerate extents.
    const Vec3d ext = bounds.extent();
    const double longest = std::max({ext.x, ext.y, ext.z});
    const double pad = longest > 0 ? longest * 1e-3 : std::max(1.0, std::abs(bounds.lo.x)) * 1e-3;
    for (int k = 0; k < 3; ++k)
        if (ext[k] < pad) {
            bounds.lo[k] -= pad;
            bounds.hi[k] += pad;
        }
    FitOptions fo;
    fo.resolution =
        options.resolution > 0 ? options.resolution : defaultContainsResolution(mv.triangleCount, 0);
    fo.marginCells = 1; // every surface cell lies inside the grid, away from its border
    fo.axis = Axis::Z;
    m.frame = fitFrame(bounds, fo);
    VoxelizeOptions vo;
    vo.threads = options.threads;
    vo.progress = options.progress;
    vo.mode = VoxelizeMode::Conservative;
    m.surface = voxelize(mv, m.frame, vo).bits;
    if (m.method == ContainsMethod::Flood) {
        vo.mode = VoxelizeMode::Solid;
        vo.fill = Fill::Flood;
        m.solid = voxelize(mv, m.frame, vo).bits;
        return;
    }
    vo.mode = VoxelizeMode::Solid;
    vo.fill = Fill::Parity;
    m.solid = voxelize(mv, m.frame, vo).bits;

    // Triangles in double, their exact xy orientation, and the column lists (bounding boxes
    // widened by 1e-6 column so that rounding in gridFromWorld never loses a covering triangle).
    const std::size_t T = mv.triangleCount;
    m.triangles.resize(T);
    m.orientXY.resize(T);
    const int64_t W = m.frame.width(), H = m.frame.height();
    std::vector<std::array<int64_t, 4>> boxes(T);
    parallelFor(0, int64_t(T), 4096, [&](int64_t b, int64_t e) {
        for (int64_t t = b; t < e; ++t) {
            auto& v = m.triangles[std::size_t(t)];
            for (int k = 0; k < 3; ++k) v[k] = mv.vertex(mv.index(std::size_t(t), k));
            m.orientXY[std::size_t(t)] =
                int8_t(exact::orient2d(v[0].x, v[0].y, v[1].x, v[1].y, v[2].x, v[2].y));
            Vec3d lo = min(min(v[0], v[1]), v[2]), hi = max(max(v[0], v[1]), v[2]);
            const Vec3d glo = m.frame.gridFromWorld(lo), ghi = m.frame.gridFromWorld(hi);
            const auto cell = [](double g, int64_t n) {
                return std::clamp<int64_t>(int64_t(std::floor(std::clamp(g, -1.0, double(n)))), 0, n - 1);
            };
            boxes[std::size_t(t)] = {cell(glo.x - 1e-6, W), cell(ghi.x + 1e-6, W), cell(glo.y - 1e-6, H),
                                     cell(ghi.y + 1e-6, H)};
        }
    });
    m.columnStart.assign(std::size_t(W * H + 1), 0);
    for (const auto& b : boxes)
        for (int64_t y = b[2]; y <= b[3]; ++y)
            for (int64_t x = b[0]; x <= b[1]; ++x) ++m.columnStart[std::size_t(y * W + x + 1)];
    for (std::size_t c = 1; c < m.columnStart.size(); ++c) m.columnStart[c] += m.columnStart[c - 1];
    m.columnTriangles.resize(std::size_t(m.columnStart.back()));
    std::vector<int64_t> fillAt(m.columnStart.begin(), m.columnStart.end() - 1);
    for (std::size_t t = 0; t < T; ++t) {
        const auto& b = boxes[t];
        for (int64_t y = b[2]; y <= b[3]; ++y)
            for (int64_t x = b[0]; x <= b[1]; ++x)
                m.columnTriangles[std::size_t(fillAt[std::size_t(y * W + x)]++)] = uint32_t(t);
    }
}

PointClassifier::~PointClassifier() = default;
PointClassifier::PointClassifier(PointClassifier&&) noexcept = default;
PointClassifier& PointClassifier::operator=(PointClassifier&&) noexcept = default;

int64_t PointClassifier::resolution() const {
    const Impl& m = *impl_;
    if (m.solid.empty()) return 0;
    return std::max({m.frame.width(), m.frame.height(), m.frame.depth()}) - 2;
}

void PointClassifier::classify(std::span<const Vec3d> points, std::span<uint8_t> out, ContainsStats* stats,
                               Progress* progress) const {
    if (points.size() != out.size())
        fail("contains: ", points.size(), " points but room for ", out.size(), " answers");
    const Impl& m = *impl_;
    std::atomic<int64_t> fromCells{0}, exactCount{0}, misses{0};
    // With a progress object, chunks of some tens of milliseconds with a poll before each: about
    // a million points, 65,536 for the winding number (a tree walk per point); else one loop.
    const int64_t n = int64_t(points.size());
    const int64_t chunk = !progress                             ? std::max<int64_t>(n, 1)
                          : m.method == ContainsMethod::Winding ? int64_t(1) << 16
                                                                : int64_t(1) << 20;
    const auto run = [&] {
        for (int64_t c0 = 0; c0 < n; c0 += chunk) {
            if (progress && !progress->update(double(c0) / double(n))) fail("contains: cancelled");
            parallelFor(c0, std::min(n, c0 + chunk), 4096, [&](int64_t b, int64_t e) {
                int64_t cells = 0, exacts = 0;
                const int64_t missesBefore = tContainsFilterMisses;
                for (int64_t i = b; i < e; ++i) {
                    const Vec3d& p = points[std::size_t(i)];
                    uint8_t answer = 0;
                    if (m.emptyMesh) {
                    } else if (m.method == ContainsMethod::Winding) {
                        ++exacts;
                        answer = isFinite(p) && std::abs(m.winding.at(p)) >= 0.5 ? 1 : 0;
                    } else {
                        const Vec3d g = m.frame.gridFromWorld(p);
                        const int64_t W = m.frame.width(), H = m.frame.height(), D = m.frame.depth();
                        if (g.x >= 0 && g.x < double(W) && g.y >= 0 && g.y < double(H) && g.z >= 0 &&
                            g.z < double(D)) {
                            const int64_t x = std::min<int64_t>(int64_t(g.x), W - 1),
                                          y = std::min<int64_t>(int64_t(g.y), H - 1),
                                          z = std::min<int64_t>(int64_t(g.z), D - 1);
                            if (m.method == ContainsMethod::Flood || !m.surface.get(x, y, z)) {
                                ++cells;
                                answer = m.solid.get(x, y, z) ? 1 : 0;
                            } else {
                                ++exacts;
                                answer = m.parityExact(p, y * W + x) ? 1 : 0;
                            }
                        } else {
                            ++cells; // outside the grid, which holds the mesh with a cell to spare
                        }
                    }
                    out[std::size_t(i)] = answer;
                }
                fromCells += cells;
                exactCount += exacts;
                misses += tContainsFilterMisses - missesBefore;
            });
        }
    };
    withThreads(m.threads, run);
    if (stats) {
        stats->points = int64_t(points.size());
        stats->fromCells = fromCells;
        stats->exact = exactCount;
        stats->filterMiss = misses;
    }
}

bool PointClassifier::inside(const Vec3d& p) const {
    const Impl& m = *impl_;
    if (m.emptyMesh) return false;
    if (m.method == ContainsMethod::Winding) return isFinite(p) && std::abs(m.winding.at(p)) >= 0.5;
    const Vec3d g = m.frame.gridFromWorld(p);
    const int64_t W = m.frame.width(), H = m.frame.height(), D = m.frame.depth();
    if (!(g.x >= 0 && g.x < double(W) && g.y >= 0 && g.y < double(H) && g.z >= 0 && g.z < double(D)))
        return false;
    const int64_t x = std::min<int64_t>(int64_t(g.x), W - 1), y = std::min<int64_t>(int64_t(g.y), H - 1),
                  z = std::min<int64_t>(int64_t(g.z), D - 1);
    if (m.method == ContainsMethod::Flood || !m.surface.get(x, y, z)) return m.solid.get(x, y, z);
    return m.parityExact(p, y * W + x);
}

void contains(const MeshView& mesh, std::span<const Vec3d> points, std::span<uint8_t> out,
              const ContainsOptions& options) {
    ContainsOptions o = options;
    if (o.resolution == 0) o.resolution = defaultContainsResolution(mesh.triangleCount, points.size());
    const PointClassifier classifier(mesh, o);
    classifier.classify(points, out, nullptr, o.progress);
}

std::vector<uint8_t> contains(const MeshView& mesh, std::span<const Vec3d> points,
                              const ContainsOptions& options) {
    std::vector<uint8_t> out(points.size());
    contains(mesh, points, out, options);
    return out;
}

} // namespace voxfx
