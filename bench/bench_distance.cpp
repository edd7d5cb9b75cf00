// Closest points for a million points (#23 item 5): voxfx's hierarchy (voxfx/distance.hpp) against
// Embree 3's rtcPointQuery and CGAL's AABB tree, each on every core, in one run.
//
//   ./build/bench_distance --benchmark_filter='Closest' --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true      (one command line)
//
// ClosestPoints/<mesh>/<points>/<method>: the time for 1,000,000 queries (items_per_second =
// points per second), the structure built beforehand; ClosestBuild/<mesh>/<method>: the build.
// Methods: voxfx (the library's batch call ClosestPointQuery::distance, which orders the points
// along a Morton curve and starts each query from its predecessor's answer), voxfx_unsorted (the
// same tree queried point by point in the given order, as the others are), embree, cgal.
// Points: "uniform" in the mesh's bounds grown by 10% on every side; "near" surface points (a
// random vertex) moved by a normal offset of 1% of the longest side in each coordinate.
// Every method gives the same answer: Embree's callback runs voxfx's exact double kernel (Embree
// only prunes, in float, with the radius rounded up to cover the rounding of the query point), CGAL
// computes its own in double; `mismatch` counts points whose distance differs from voxfx's by more
// than 1e-12 of the longest side (it should be 0).
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include "bench_meshes.hpp"
#include "grid/triangle_bvh.hpp"
#include "voxfx/distance.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;

constexpr std::size_t kPoints = 1'000'000;

const std::vector<Vec3d>& queryPoints(const std::string& mesh, const std::string& kind) {
    static std::map<std::string, std::vector<Vec3d>> cache;
    const std::string key = mesh + "/" + kind;
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    const Mesh& m = *bench::mesh(mesh);
    const Box3d b = computeBounds(m.view());
    const Vec3d e = b.extent();
    const double longest = std::max({e.x, e.y, e.z});
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> g(0.0, 0.01 * longest);
    std::vector<Vec3d> pts(kPoints);
    for (Vec3d& p : pts) {
        if (kind == "uniform") {
            for (int k = 0; k < 3; ++k) p[k] = b.lo[k] - 0.1 * e[k] + u(rng) * 1.2 * e[k];
        } else {
            const auto v = std::size_t(u(rng) * double(m.positions.size())) % m.positions.size();
            p = Vec3d(m.positions[v]) + Vec3d{g(rng), g(rng), g(rng)};
        }
    }
    return cache.emplace(key, std::move(pts)).first->second;
}

// ---- Embree 3: rtcPointQuery with voxfx's kernel in the callback ---------------------------------

struct EmbreeScene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<detail::DistanceTriangle> tris;
    explicit EmbreeScene(const Mesh& m) {
        device = rtcNewDevice(nullptr);
        scene = rtcNewScene(device);
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
        RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions.size()));
        auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.triangleCount()));
        std::memcpy(v, &m.positions[0].x, m.positions.size() * sizeof(Vec3f));
        std::memcpy(t, m.indices.data(), m.indices.size() * sizeof(uint32_t));
        rtcCommitGeometry(geom);
        rtcAttachGeometry(scene, geom);
        rtcReleaseGeometry(geom);
        rtcCommitScene(scene);
        const MeshView mv = m.view();
        for (std::size_t i = 0; i < mv.triangleCount; ++i)
            tris.push_back(detail::prepareTriangle(mv.vertex(mv.index(i, 0)), mv.vertex(mv.index(i, 1)),
                                                   mv.vertex(mv.index(i, 2))));
    }
    ~EmbreeScene() {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
    }

    struct Query {
        const EmbreeScene* self;
        Vec3d p;
        double slack; ///< |p - float(p)|: the float query sphere must hold the double one
        double best2 = std::numeric_limits<double>::infinity();
        int64_t face = -1;
    };
    static bool callback(RTCPointQueryFunctionArguments* args) {
        auto* q = static_cast<Query*>(args->userPtr);
        double u, v;
        const double d2 = detail::triangleDistance2(q->self->tris[args->primID], q->p, u, v);
        if (d2 < q->best2 || (d2 == q->best2 && int64_t(args->primID) < q->face)) {
            q->best2 = d2;
            q->face = args->primID;
            const float r = float(std::sqrt(d2) + q->slack);
            args->query->radius = std::nextafter(r, std::numeric_limits<float>::infinity());
            return true;
        }
        return false;
    }
    double distance(const Vec3d& p) const {
        RTCPointQuery query;
        query.x = float(p.x);
        query.y = float(p.y);
        query.z = float(p.z);
        query.time = 0;
        query.radius = std::numeric_limits<float>::infinity();
        Query q{this, p, length(p - Vec3d(Vec3f(p)))};
        RTCPointQueryContext context;
        rtcInitPointQueryContext(&context);
        rtcPointQuery(scene, &query, &context, callback, &q);
        return std::sqrt(q.best2);
    }
};

// ---- CGAL's AABB tree (Epick) ----------------------------------------------------------------------

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangle3 = K::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<Triangle3>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

struct CgalTree {
    std::vector<Triangle3> tris;
    Tree tree;
    explicit CgalTree(const Mesh& m) {
        const MeshView mv = m.view();
        for (std::size_t t = 0; t < mv.triangleCount; ++t) {
            K::Point_3 p[3];
            for (int c = 0; c < 3; ++c) {
                const Vec3d v = mv.vertex(mv.index(t, c));
                p[c] = K::Point_3(v.x, v.y, v.z);
            }
            tris.emplace_back(p[0], p[1], p[2]);
        }
        tree.insert(tris.begin(), tris.end());
        tree.build();
        tree.accelerate_distance_queries();
    }
    double distance(const Vec3d& p) const {
        const K::Point_3 q(p.x, p.y, p.z);
        const auto [cp, prim] = tree.closest_point_and_primitive(q);
        return std::sqrt(CGAL::to_double(CGAL::squared_distance(q, *prim)));
    }
};

const std::vector<double>& voxfxDistances(const std::string& mesh, const std::string& kind) {
    static std::map<std::string, std::vector<double>> cache;
    const std::string key = mesh + "/" + kind;
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    const ClosestPointQuery q(bench::mesh(mesh)->view());
    std::vector<double> d(kPoints);
    q.distance(queryPoints(mesh, kind), d);
    return cache.emplace(key, std::move(d)).first->second;
}

template <class Query>
void runQueries(benchmark::State& state, const Query& distanceOf, const std::string& mesh,
                const std::string& kind) {
    const std::vector<Vec3d>& pts = queryPoints(mesh, kind);
    std::vector<double> d(pts.size());
    for (auto _ : state) {
        parallelFor(0, int64_t(pts.size()), 2048, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) d[std::size_t(i)] = distanceOf(pts[std::size_t(i)]);
        });
        benchmark::DoNotOptimize(d.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(pts.size()));
    const std::vector<double>& ref = voxfxDistances(mesh, kind);
    const Vec3d e = computeBounds(bench::mesh(mesh)->view()).extent();
    const double tol = 1e-12 * std::max({e.x, e.y, e.z});
    int64_t mismatch = 0;
    for (std::size_t i = 0; i < d.size(); ++i) mismatch += std::abs(d[i] - ref[i]) > tol;
    state.counters["mismatch"] = double(mismatch);
    state.counters["triangles"] = double(bench::mesh(mesh)->triangleCount());
}

void closestPoints(benchmark::State& state, const std::string& mesh, const std::string& kind,
                   const std::string& method) {
    const Mesh* m = bench::mesh(mesh);
    if (!m) {
        state.SkipWithError("missing data: run scripts/fetch-data.sh");
        return;
    }
    if (method == "voxfx") {
        // The library's batch call: points in Morton order, each query hinted by its predecessor.
        const ClosestPointQuery q(m->view());
        const std::vector<Vec3d>& pts = queryPoints(mesh, kind);
        std::vector<double> d(pts.size());
        for (auto _ : state) {
            q.distance(pts, d);
            benchmark::DoNotOptimize(d.data());
        }
        state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(pts.size()));
        state.counters["triangles"] = double(m->triangleCount());
    } else if (method == "voxfx_unsorted") {
        // One query at a time in the points' own order, as Embree and CGAL are called.
        const ClosestPointQuery q(m->view());
        runQueries(
            state, [&](const Vec3d& p) { return std::sqrt(q.bvh().nearest(p).distance2); }, mesh, kind);
    } else if (method == "embree") {
        const EmbreeScene s(*m);
        runQueries(
            state, [&](const Vec3d& p) { return s.distance(p); }, mesh, kind);
    } else {
        const CgalTree t(*m);
        runQueries(
            state, [&](const Vec3d& p) { return t.distance(p); }, mesh, kind);
    }
}

void closestBuild(benchmark::State& state, const std::string& mesh, const std::string& method) {
    const Mesh* m = bench::mesh(mesh);
    if (!m) {
        state.SkipWithError("missing data: run scripts/fetch-data.sh");
        return;
    }
    for (auto _ : state) {
        if (method == "voxfx") {
            const ClosestPointQuery q(m->view());
            benchmark::DoNotOptimize(&q);
        } else if (method == "embree") {
            const EmbreeScene s(*m);
            benchmark::DoNotOptimize(&s);
        } else {
            const CgalTree t(*m);
            benchmark::DoNotOptimize(&t);
        }
    }
    state.counters["triangles"] = double(m->triangleCount());
}

const bool registered = [] {
    for (const char* mesh : {"bunny00", "armadillo", "dragon", "bunny1m"}) {
        for (const char* method : {"voxfx", "voxfx_unsorted", "embree", "cgal"}) {
            if (std::string(method) != "voxfx_unsorted")
                benchmark::RegisterBenchmark((std::string("ClosestBuild/") + mesh + "/" + method).c_str(),
                                             closestBuild, mesh, method)
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime();
            for (const char* kind : {"uniform", "near"})
                benchmark::RegisterBenchmark(
                    (std::string("ClosestPoints/") + mesh + "/" + kind + "/" + method).c_str(), closestPoints,
                    mesh, kind, method)
                    ->Unit(benchmark::kMillisecond)
                    ->UseRealTime()
                    ->MinTime(0.5);
        }
    }
    return true;
}();

} // namespace

BENCHMARK_MAIN();
