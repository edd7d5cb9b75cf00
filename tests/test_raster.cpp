// voxfx — the fragment rasterizer called directly, against brute-force and CGAL oracles:
// centre coverage counts each crossing of a column's centre line exactly once (shared edges and
// vertices included), conservative spans hold the exact depth range of the triangle in the
// column's closed prism, and the parallel schemes agree.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/error.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {
namespace {

struct Fragment {
    int64_t x, y;
    double depth;
    uint32_t triangle;
    bool front;
    bool operator<(const Fragment& o) const {
        return std::tie(y, x, triangle, depth, front) < std::tie(o.y, o.x, o.triangle, o.depth, o.front);
    }
    bool operator==(const Fragment& o) const = default;
};
struct Span {
    int64_t x, y;
    double lo, hi;
    uint32_t triangle;
    bool operator<(const Span& o) const {
        return std::tie(y, x, triangle, lo, hi) < std::tie(o.y, o.x, o.triangle, o.lo, o.hi);
    }
    bool operator==(const Span& o) const = default;
};

// Collects everything the rasterizer emits (tiles and direct sinks from any thread; sorted after).
struct Collector {
    std::mutex mutex;
    std::vector<Fragment> fragments;
    std::vector<Span> spans;
    int64_t rowsFinished = 0;
    struct Sink {
        Collector& c;
        std::vector<Fragment> f;
        std::vector<Span> s;
        void fragment(int64_t x, int64_t y, double depth, uint32_t t, bool front) {
            f.push_back({x, y, depth, t, front});
        }
        void span(int64_t x, int64_t y, double lo, double hi, uint32_t t) { s.push_back({x, y, lo, hi, t}); }
        void finish() {
            std::lock_guard<std::mutex> lock(c.mutex);
            c.fragments.insert(c.fragments.end(), f.begin(), f.end());
            c.spans.insert(c.spans.end(), s.begin(), s.end());
            f.clear();
            s.clear();
        }
        ~Sink() {
            if (!f.empty() || !s.empty()) finish();
        }
    };
    std::vector<Tile> tiles; // every tile handed out, as the rasterizer gave it
    Sink tile(const Tile& t) {
        {
            std::lock_guard<std::mutex> lock(mutex);
            tiles.push_back(t);
        }
        return {*this, {}, {}};
    }
    void sort() {
        std::sort(fragments.begin(), fragments.end());
        std::sort(spans.begin(), spans.end());
    }
};

// The same, offering the direct path too.
struct DirectCollector : Collector {
    Sink direct() { return {*this, {}, {}}; }
    void finishRows(const Tile& t) {
        std::lock_guard<std::mutex> lock(mutex);
        rowsFinished += t.y1 - t.y0;
    }
};

template <class C>
void rasterizeInto(C& c, const Frame& frame, const Mesh& mesh, Coverage coverage,
                   RasterPath path = RasterPath::Auto, int64_t rowsPerTile = 0) {
    RasterOptions o;
    o.coverage = coverage;
    o.path = path;
    o.rowsPerTile = rowsPerTile;
    rasterize(frame, mesh.view(), o, c);
    c.sort();
}

// --- Meshes ------------------------------------------------------------------------------------

void addTriangle(Mesh& m, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const auto base = uint32_t(m.positions.size());
    for (const Vec3d& p : {a, b, c}) m.positions.push_back(Vec3f(p));
    for (uint32_t k = 0; k < 3; ++k) m.indices.push_back(base + k);
}

// A bipyramid: apexes (cx, cy, z0) and (cx, cy, z1) over a ring of n points at height zm,
// radius r; both apexes are vertices of n triangles (a fan) and project onto (cx, cy).
Mesh bipyramid(double cx, double cy, double z0, double zm, double z1, double r, int n, double phase) {
    Mesh m;
    m.positions.push_back(Vec3f(Vec3d{cx, cy, z0}));
    m.positions.push_back(Vec3f(Vec3d{cx, cy, z1}));
    for (int k = 0; k < n; ++k) {
        const double a = phase + 2 * M_PI * k / n;
        m.positions.push_back(Vec3f(Vec3d{cx + r * std::cos(a), cy + r * std::sin(a), zm}));
    }
    for (uint32_t k = 0; k < uint32_t(n); ++k) {
        const uint32_t p = 2 + k, q = 2 + (k + 1) % uint32_t(n);
        for (uint32_t v : {1u, p, q}) m.indices.push_back(v); // top fan, outward CCW
        for (uint32_t v : {0u, q, p}) m.indices.push_back(v); // bottom fan
    }
    return m;
}

// Where the grid point (px, py) lies relative to the convex hull of the projected vertices
// (grid x, y): +1 strictly inside, 0 on the boundary, -1 outside (exact, CGAL's orientation).
int hullSide(const std::vector<test::Point2d>& hull, double px, double py) {
    int side = 1;
    for (std::size_t k = 0; k < hull.size(); ++k) {
        const test::Point2d &a = hull[k], &b = hull[(k + 1) % hull.size()];
        const int o = test::oracleOrient2d(a[0], a[1], b[0], b[1], px, py);
        if (o < 0) return -1;
        if (o == 0) side = 0;
    }
    return side;
}

std::vector<test::Point2d> projectedHull(const Frame& frame, const Mesh& mesh) {
    std::vector<test::Point2d> points;
    for (const Vec3f& v : mesh.positions) {
        const Vec3d g = frame.gridFromWorld(Vec3d(v));
        points.push_back({g.x, g.y});
    }
    return test::oracleConvexHull2(points); // counter-clockwise
}

// Per column: (fragments, front fragments).
std::vector<std::pair<int, int>> perColumn(const Collector& c, const Frame& f) {
    std::vector<std::pair<int, int>> n(size_t(f.columnCount()));
    for (const Fragment& g : c.fragments) {
        auto& e = n[size_t(g.y * f.width() + g.x)];
        ++e.first;
        e.second += g.front;
    }
    return n;
}

// --- Centre coverage ---------------------------------------------------------------------------

TEST(RasterTest, CentreCoverageOfConvexMeshesCrossesEachInsideCentreExactlyTwice) {
    // Lattice-aligned solids: apexes and fans of triangles around them on column centres, edges
    // through column centres and along column boundaries. A convex solid's centre line crosses its
    // surface twice (once front, once back) where the centre lies strictly inside the projected
    // outline, and never outside it; on the outline both or neither.
    const Frame frame = Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 16, 16);
    const Mesh meshes[] = {test::makeOctahedron({8.5, 8.5, 8}, 5), test::makeOctahedron({8, 8, 8}, 6),
                           bipyramid(6.5, 6.5, 2, 7, 13, 4, 7, 0.3), bipyramid(8.5, 7.5, 3, 8, 12, 5, 6, 0),
                           bipyramid(8, 8, 3, 8.5, 12, 4, 12, 0)};
    int index = 0;
    for (const Mesh& mesh : meshes) {
        SCOPED_TRACE(index++);
        for (RasterPath path : {RasterPath::Binned, RasterPath::Direct}) {
            DirectCollector c;
            rasterizeInto(c, frame, mesh, Coverage::Center, path);
            const auto hull = projectedHull(frame, mesh);
            const auto n = perColumn(c, frame);
            int inside = 0;
            for (int64_t y = 0; y < 16; ++y)
                for (int64_t x = 0; x < 16; ++x) {
                    const auto [count, fronts] = n[size_t(y * 16 + x)];
                    const int side = hullSide(hull, x + 0.5, y + 0.5);
                    inside += side > 0;
                    if (side > 0)
                        EXPECT_EQ(count, 2) << "column " << x << ", " << y;
                    else if (side < 0)
                        EXPECT_EQ(count, 0) << "column " << x << ", " << y;
                    else
                        EXPECT_TRUE(count == 0 || count == 2) << "column " << x << ", " << y;
                    EXPECT_EQ(2 * fronts, count) << "column " << x << ", " << y << ": fronts";
                }
            EXPECT_GT(inside, 20);
        }
    }
}

TEST(RasterTest, CentreCoverageOfAFlatFanAroundACentreCountsTheCentreOnce) {
    // A tilted planar polygon triangulated as a fan around a vertex that sits on a column centre,
    // its spokes through other centres: every centre strictly inside is covered by exactly one
    // triangle, the shared vertex and spokes included.
    for (int n : {3, 4, 6, 8, 11}) {
        SCOPED_TRACE(n);
        const Frame frame = Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 16, 16);
        Mesh m;
        const Vec3d c{7.5, 8.5, 0};
        auto z = [](double x, double y) { return 4 + 0.25 * x + 0.125 * y; };
        std::vector<Vec3d> ring;
        for (int k = 0; k < n; ++k) {
            const double a = 2 * M_PI * k / n;
            // Radius 5 along the axes (through centres), otherwise rounded to the lattice of
            // half cells so that many spokes pass through centres.
            const double x = c.x + std::round(10 * std::cos(a)) / 2,
                         y = c.y + std::round(10 * std::sin(a)) / 2;
            ring.push_back({x, y, z(x, y)});
        }
        for (int k = 0; k < n; ++k)
            addTriangle(m, {c.x, c.y, z(c.x, c.y)}, ring[size_t(k)], ring[size_t((k + 1) % n)]);
        DirectCollector col;
        rasterizeInto(col, frame, m, Coverage::Center, RasterPath::Binned);
        const auto hull = projectedHull(frame, m);
        const auto counts = perColumn(col, frame);
        for (int64_t y = 0; y < 16; ++y)
            for (int64_t x = 0; x < 16; ++x) {
                const int side = hullSide(hull, x + 0.5, y + 0.5);
                const int count = counts[size_t(y * 16 + x)].first;
                if (side > 0) {
                    EXPECT_EQ(count, 1) << "column " << x << ", " << y;
                } else if (side < 0) {
                    EXPECT_EQ(count, 0) << "column " << x << ", " << y;
                } else {
                    EXPECT_LE(count, 1) << "column " << x << ", " << y;
                }
            }
        EXPECT_EQ(counts[size_t(8 * 16 + 7)].first, 1) << "the fan's centre vertex";
        // Fragment depth: the plane's depth at the centre (exact here: dyadic coefficients).
        for (const Fragment& f : col.fragments) EXPECT_DOUBLE_EQ(f.depth, z(f.x + 0.5, f.y + 0.5));
    }
}

TEST(RasterTest, CentreCoverageThroughAPerspectiveFrameCrossesAConvexSolidTwice) {
    const Frame frame = Frame::perspective({0, 0, 10}, {0, 0, 0}, {0, 1, 0}, 0.8, 24, 18, 1, 20, 32);
    const Mesh mesh = bipyramid(0.1, -0.2, -3, 0, 3, 2.5, 9, 0.1);
    for (RasterPath path : {RasterPath::Binned, RasterPath::Direct}) {
        DirectCollector c;
        rasterizeInto(c, frame, mesh, Coverage::Center, path);
        const auto n = perColumn(c, frame);
        const auto hull = projectedHull(frame, mesh);
        int inside = 0;
        for (int64_t y = 0; y < frame.height(); ++y)
            for (int64_t x = 0; x < frame.width(); ++x) {
                const auto [count, fronts] = n[size_t(y * frame.width() + x)];
                EXPECT_EQ(count % 2, 0);
                EXPECT_EQ(2 * fronts, count);
                const int side = hullSide(hull, x + 0.5, y + 0.5);
                // The outline from rounded projections: decide only centres clearly off it.
                double dist = INFINITY;
                for (std::size_t k = 0; k < hull.size(); ++k) {
                    dist = std::min(dist, test::oracleDistanceToSegment2(hull[k], hull[(k + 1) % hull.size()],
                                                                         {x + 0.5, y + 0.5}));
                }
                if (dist < 1e-6) continue;
                inside += side > 0;
                EXPECT_EQ(count, side > 0 ? 2 : 0) << "column " << x << ", " << y;
            }
        EXPECT_GT(inside, 20);
        // Depths are view distances within the solid's depth range.
        for (const Fragment& f : c.fragments) {
            EXPECT_GE(f.depth, 10 - 3 - 1e-9);
            EXPECT_LE(f.depth, 10 + 3 + 1e-9);
        }
    }
}

// --- Conservative spans ------------------------------------------------------------------------

// Random triangles in grid space of a frame whose world box is the grid itself, some of them
// special: parallel to the view (projecting to segments), with corners on column boundaries,
// tiny ones inside one column.
std::vector<std::array<Vec3d, 3>> testTriangles(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(-1, 13), d(0, 8);
    std::uniform_int_distribution<int> lattice(0, 12);
    std::vector<std::array<Vec3d, 3>> out;
    for (int k = 0; k < 60; ++k)
        out.push_back({Vec3d{u(rng), u(rng), d(rng)}, {u(rng), u(rng), d(rng)}, {u(rng), u(rng), d(rng)}});
    for (int k = 0; k < 20; ++k) { // corners on column corners
        auto p = [&] { return Vec3d{double(lattice(rng)), double(lattice(rng)), d(rng)}; };
        out.push_back({p(), p(), p()});
    }
    for (int k = 0; k < 20; ++k) { // parallel to the view: all corners on one vertical plane
        const Vec3d a{u(rng), u(rng), d(rng)}, b{u(rng), u(rng), d(rng)};
        const double s = std::uniform_real_distribution<double>(0, 1)(rng);
        out.push_back({a, b, Vec3d{a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), d(rng)}});
    }
    for (int k = 0; k < 10; ++k) { // tiny
        const Vec3d a{u(rng), u(rng), d(rng)};
        out.push_back({a, a + Vec3d{0.01, 0.002, 0.3}, a + Vec3d{-0.003, 0.02, -0.1}});
    }
    return out;
}

TEST(RasterTest, ConservativeSpansHoldTheExactDepthRangeOfTheTriangleInEachClosedPrism) {
    // World = grid (box [0, 12] x [0, 10] x [0, 8], unit cells). Oracles: dense samples of the
    // triangle (every sample in a closed prism lies within that column's span), and CGAL's exact
    // triangle/box overlap (a column has a span iff the triangle meets its closed prism, up to the
    // rasterizer's 1e-9-cell slack; the span's ends are attained within 1e-7).
    const Frame frame = Frame::orthographic({{0, 0, 0}, {12, 10, 8}}, Axis::Z, 12, 10, 8);
    std::mt19937_64 rng(11);
    const auto tris = testTriangles(rng);
    const double big = 1e3, tol = 1e-7, slack = 2e-9;
    int checkedSpans = 0;
    for (std::size_t t = 0; t < tris.size(); ++t) {
        SCOPED_TRACE(t);
        Mesh mesh;
        addTriangle(mesh, tris[t][0], tris[t][1], tris[t][2]);
        // Corners as the mesh stores them (float).
        Vec3d p[3];
        for (int k = 0; k < 3; ++k) p[k] = Vec3d(mesh.positions[size_t(k)]);
        const std::array<Vec3d, 3> tri{p[0], p[1], p[2]};
        for (RasterPath path : {RasterPath::Binned, RasterPath::Direct}) {
            DirectCollector c;
            rasterizeInto(c, frame, mesh, Coverage::Conservative, path, 3);
            std::vector<const Span*> spanOf(size_t(frame.columnCount()), nullptr);
            for (const Span& s : c.spans) {
                ASSERT_EQ(spanOf[size_t(s.y * 12 + s.x)], nullptr) << "two spans in one column";
                spanOf[size_t(s.y * 12 + s.x)] = &s;
            }
            for (int64_t y = 0; y < 10; ++y)
                for (int64_t x = 0; x < 12; ++x) {
                    auto prism = [&](double grow, double z0, double z1) {
                        return Box3d{{x - grow, y - grow, z0}, {x + 1 + grow, y + 1 + grow, z1}};
                    };
                    const Span* s = spanOf[size_t(y * 12 + x)];
                    if (!s) {
                        EXPECT_FALSE(test::oracleTriangleMeetsBox(tri, prism(0, -big, big)))
                            << "missed column " << x << ", " << y;
                        continue;
                    }
                    ++checkedSpans;
                    EXPECT_TRUE(test::oracleTriangleMeetsBox(tri, prism(slack, -big, big)))
                        << "extra column " << x << ", " << y;
                    EXPECT_LE(s->lo, s->hi);
                    // Tight: the triangle reaches both ends, and nothing of it in the prism lies
                    // beyond them.
                    EXPECT_TRUE(test::oracleTriangleMeetsBox(tri, prism(slack, s->lo - tol, s->lo + tol)));
                    EXPECT_TRUE(test::oracleTriangleMeetsBox(tri, prism(slack, s->hi - tol, s->hi + tol)));
                    EXPECT_FALSE(test::oracleTriangleMeetsBox(tri, prism(0, -big, s->lo - tol)));
                    EXPECT_FALSE(test::oracleTriangleMeetsBox(tri, prism(0, s->hi + tol, big)));
                }
            // Dense samples (barycentric lattice, edges included).
            const int n = 64;
            for (int i = 0; i <= n; ++i)
                for (int j = 0; i + j <= n; ++j) {
                    const double a = double(i) / n, b = double(j) / n;
                    const Vec3d q = p[0] + (p[1] - p[0]) * a + (p[2] - p[0]) * b;
                    for (int64_t x = int64_t(std::floor(q.x)) - 1; x <= int64_t(std::floor(q.x)); ++x)
                        for (int64_t y = int64_t(std::floor(q.y)) - 1; y <= int64_t(std::floor(q.y)); ++y) {
                            if (x < 0 || y < 0 || x >= 12 || y >= 10) continue;
                            if (q.x < x || q.x > x + 1 || q.y < y || q.y > y + 1) continue;
                            const Span* s = spanOf[size_t(y * 12 + x)];
                            ASSERT_NE(s, nullptr) << "sample in column " << x << ", " << y << " has no span";
                            EXPECT_GE(q.z, s->lo - 1e-9);
                            EXPECT_LE(q.z, s->hi + 1e-9);
                        }
                }
        }
    }
    EXPECT_GT(checkedSpans, 500);
}

TEST(RasterTest, PerspectiveConservativeSpansHoldEverySampleOfTheTriangle) {
    const Frame frame = Frame::perspective({0.3, -0.2, 12}, {0, 0, 0}, {0, 1, 0}, 0.7, 20, 16, 2, 30, 32);
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(-5, 5);
    for (int t = 0; t < 40; ++t) {
        SCOPED_TRACE(t);
        Mesh mesh;
        addTriangle(mesh, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)});
        Vec3d p[3];
        for (int k = 0; k < 3; ++k) p[k] = Vec3d(mesh.positions[size_t(k)]);
        DirectCollector c;
        rasterizeInto(c, frame, mesh, Coverage::Conservative);
        std::vector<const Span*> spanOf(size_t(frame.columnCount()), nullptr);
        for (const Span& s : c.spans) spanOf[size_t(s.y * frame.width() + s.x)] = &s;
        const int n = 48;
        for (int i = 0; i <= n; ++i)
            for (int j = 0; i + j <= n; ++j) {
                const Vec3d q = p[0] + (p[1] - p[0]) * (double(i) / n) + (p[2] - p[0]) * (double(j) / n);
                const Vec3d g = frame.gridFromWorld(q);
                const int64_t x = int64_t(std::floor(g.x)), y = int64_t(std::floor(g.y));
                // Stay clear of column boundaries (rounding of the projection).
                if (x < 0 || y < 0 || x >= frame.width() || y >= frame.height()) continue;
                if (g.x - double(x) < 1e-6 || double(x + 1) - g.x < 1e-6 || g.y - double(y) < 1e-6 ||
                    double(y + 1) - g.y < 1e-6)
                    continue;
                const Span* s = spanOf[size_t(y * frame.width() + x)];
                ASSERT_NE(s, nullptr) << "sample in column " << x << ", " << y << " has no span";
                EXPECT_GE(g.z, s->lo * (1 - 1e-9));
                EXPECT_LE(g.z, s->hi * (1 + 1e-9));
            }
    }
}

// --- Parallel schemes --------------------------------------------------------------------------

TEST(RasterTest, TileSizesAndTheDirectPathEmitTheSameFragmentsAndSpans) {
    std::mt19937_64 rng(9);
    const auto tris = testTriangles(rng);
    Mesh mesh;
    for (const auto& t : tris) addTriangle(mesh, t[0], t[1], t[2]);
    const Frame frame = Frame::orthographic({{0, 0, 0}, {12, 10, 8}}, Axis::Z, 12, 10, 8);
    for (Coverage coverage : {Coverage::Center, Coverage::Conservative}) {
        DirectCollector reference;
        rasterizeInto(reference, frame, mesh, coverage, RasterPath::Binned, 1);
        EXPECT_GT(reference.fragments.size() + reference.spans.size(), 100u);
        for (int64_t rows : {2, 3, 7, 10, 0}) {
            DirectCollector c;
            rasterizeInto(c, frame, mesh, coverage, RasterPath::Binned, rows);
            EXPECT_TRUE(c.fragments == reference.fragments) << rows << " rows per tile";
            EXPECT_TRUE(c.spans == reference.spans) << rows << " rows per tile";
        }
        DirectCollector direct;
        rasterizeInto(direct, frame, mesh, coverage, RasterPath::Direct, 3);
        EXPECT_TRUE(direct.fragments == reference.fragments) << "direct";
        EXPECT_TRUE(direct.spans == reference.spans) << "direct";
        EXPECT_EQ(direct.rowsFinished, 10) << "finishRows covers every row once";
    }
}

// The same, taking a row's four neighbours in one call where the rasterizer offers them
// (QuadSink), each expanded to the fragment it stands for.
struct QuadCollector : Collector {
    std::atomic<int64_t> quadCalls{0}; // calls of fragments(), from every tile's sink
    struct Sink4 : Sink {
        std::atomic<int64_t>* calls;
        void fragments(int64_t x, int64_t y, const double* depth, unsigned bits, uint32_t t, bool front) {
            EXPECT_NE(bits, 0u);
            EXPECT_EQ(bits & ~15u, 0u);
            ++*calls;
            for (int k = 0; k < 4; ++k)
                if (bits >> k & 1) fragment(x + k, y, depth[k], t, front);
        }
    };
    Sink4 tile(const Tile& t) {
        Collector::tile(t);
        return {{*this, {}, {}}, &quadCalls};
    }
};

TEST(RasterTest, AQuadSinkGetsTheFragmentsTheOneByOneSinkGets) {
    // The path a G-buffer's vector depth test takes (four neighbours of a row per call) against the
    // one-fragment-at-a-time path: the same fragments, bit for bit (depths too), orthographic and
    // perspective, at several tile sizes.
    std::mt19937_64 rng(21);
    const auto tris = testTriangles(rng);
    Mesh mesh;
    for (const auto& t : tris) addTriangle(mesh, t[0], t[1], t[2]);
    const Frame frames[2] = {
        Frame::orthographic({{0, 0, 0}, {12, 10, 8}}, Axis::Z, 37, 29, 8),
        Frame::perspective({6.3, 5.2, 20}, {6, 5, 4}, {0, 1, 0}, 0.9, 53, 41, 1, 40, 32)};
    for (const Frame& frame : frames)
        for (int64_t rows : {1, 5, 0}) {
            Collector one;
            rasterizeInto(one, frame, mesh, Coverage::Center, RasterPath::Binned, rows);
            ASSERT_GT(one.fragments.size(), 500u);
            QuadCollector quad;
            {
                RasterOptions o;
                o.rowsPerTile = rows;
                rasterize(frame, mesh.view(), o, quad);
                quad.sort();
            }
            EXPECT_TRUE(quad.fragments == one.fragments) << rows << " rows per tile";
            const int64_t calls = quad.quadCalls;
#if defined(__AVX__) && defined(__GNUC__)
            EXPECT_GT(calls, 0) << "the vector path took the quad calls";
#endif
            EXPECT_LE(calls, int64_t(one.fragments.size()));
        }
}

TEST(RasterTest, CancellingThroughProgressFailsWithAnError) {
    struct Stop : Progress {
        bool update(double) override { return false; }
    } stop;
    Mesh mesh = test::makeOctahedron({8, 8, 8}, 6);
    const Frame frame = Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 16, 16);
    RasterOptions o;
    o.progress = &stop;
    DirectCollector c;
    EXPECT_THROW(rasterize(frame, mesh.view(), o, c), Error);
}

// --- The consumer contract -----------------------------------------------------------------------

struct OnlyFragments {
    struct Sink { // tiles run on several threads: the count is shared
        std::atomic<int64_t>* n;
        void fragment(int64_t, int64_t, double, uint32_t, bool) {
            n->fetch_add(1, std::memory_order_relaxed);
        }
        void finish() {}
    };
    std::atomic<int64_t> n = 0;
    Sink tile(const Tile&) { return {&n}; }
};
struct OnlySpans {
    struct Sink {
        void span(int64_t, int64_t, double, double, uint32_t) {}
        void finish() {}
    };
    Sink tile(const Tile&) { return {}; }
};
struct NoMembers {
    struct Sink {
        void finish() {}
    };
    Sink tile(const Tile&) { return {}; }
};
struct NoFinish {
    struct Sink {
        void fragment(int64_t, int64_t, double, uint32_t, bool) {}
    };
    Sink tile(const Tile&) { return {}; }
};
struct OldTileSignature {
    struct Sink {
        void fragment(int64_t, int64_t, double, uint32_t, bool) {}
        void finish() {}
    };
    Sink tile(int64_t, int64_t) { return {}; }
};

// What compiles: checked here at compile time (a consumer that breaks the contract is refused by
// rasterize's constraints instead of silently emitting nothing).
static_assert(TileConsumer<OnlyFragments> && TileConsumer<OnlySpans> && TileConsumer<Collector>);
static_assert(!TileConsumer<NoMembers>, "a sink with neither fragment nor span");
static_assert(!TileConsumer<NoFinish>, "a sink without finish");
static_assert(!TileConsumer<OldTileSignature>, "tile must take the Tile it is handed");
static_assert(DirectConsumer<DirectCollector> && !DirectConsumer<Collector>);
static_assert(sinkSupports<OnlyFragments::Sink>(Coverage::Center));
static_assert(!sinkSupports<OnlyFragments::Sink>(Coverage::Conservative));
static_assert(!sinkSupports<OnlySpans::Sink>(Coverage::Center));

TEST(RasterTest, AConsumerWithoutTheMemberTheCoverageNeedsFailsLoudly) {
    const Mesh mesh = test::makeOctahedron({8, 8, 8}, 6);
    const Frame frame = Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 16, 16);
    RasterOptions o;
    o.coverage = Coverage::Conservative;
    OnlyFragments fragments;
    EXPECT_THROW(rasterize(frame, mesh.view(), o, fragments), Error);
    o.coverage = Coverage::Center;
    OnlySpans spans;
    EXPECT_THROW(rasterize(frame, mesh.view(), o, spans), Error);
    // The supported coverage runs, also with the coverage fixed at compile time.
    EXPECT_NO_THROW(rasterize(frame, mesh.view(), o, fragments));
    EXPECT_GT(fragments.n.load(), 0);
    const int64_t n = fragments.n.load();
    o.coverage = Coverage::Conservative; // ignored by rasterize<C>
    rasterize<Coverage::Center>(frame, mesh.view(), o, fragments);
    EXPECT_EQ(fragments.n.load(), 2 * n);
}

TEST(RasterTest, ConsumersAreHandedEachTileOnceWithItsIndexAndRows) {
    const Mesh mesh = test::makeOctahedron({8, 8, 8}, 6);
    const Frame frame = Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 13, 16);
    for (int64_t rows : {1, 4, 5, 13, 0}) {
        SCOPED_TRACE(rows);
        DirectCollector c;
        rasterizeInto(c, frame, mesh, Coverage::Center, RasterPath::Binned, rows);
        std::sort(c.tiles.begin(), c.tiles.end(),
                  [](const Tile& a, const Tile& b) { return a.index < b.index; });
        ASSERT_FALSE(c.tiles.empty());
        int64_t next = 0;
        for (std::size_t k = 0; k < c.tiles.size(); ++k) {
            EXPECT_EQ(c.tiles[k].index, int64_t(k));
            EXPECT_EQ(c.tiles[k].y0, next);
            EXPECT_GT(c.tiles[k].y1, c.tiles[k].y0);
            if (rows > 0) { EXPECT_LE(c.tiles[k].y1 - c.tiles[k].y0, rows); }
            next = c.tiles[k].y1;
        }
        EXPECT_EQ(next, 13) << "the tiles cover every row once";
    }
}

} // namespace
} // namespace voxfx
