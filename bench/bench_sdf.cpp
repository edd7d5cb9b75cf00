// Narrow-band signed distance fields (#23 item 4): voxfx's signedDistanceField against OpenVDB's
// meshToLevelSet with the same band (3 voxels each side) on the same voxel centres, in one run.
//
//   ./build/bench_sdf --benchmark_filter='Sdf/bunny00/.*/256'
//   ./build/bench_sdf                                  (every mesh, method and resolution)
//
// Sdf/<mesh>/<method>/<resolution>: each measurement runs in a fresh process (this program,
// re-executed with --child), so that its peak memory is its own. The child loads the mesh, notes
// its resident memory, builds the field (timed: the iteration time), notes its peak resident
// memory, and only then measures the result. Counters:
//   peak_MB      peak resident memory minus what the process held before the field (mesh loaded)
//   active       active voxels
//   max_err, mean_err  |value| against the exact distance at every active voxel, in voxels (cell
//                sizes): the exact distance is voxfx's closest-point query in double, checked
//                against CGAL's AABB tree on 20,000 of the voxels (cgal_diff: the largest
//                difference, in voxels; it should be ~1e-12 or below)
//   sign_err     active voxels whose sign differs from voxfx's solid voxelization (parity, the
//                exact inside test, for closed meshes; gwn for open ones, as the field's Auto fill)
//   missing      voxels closer than the band width to the surface (exactly) that are not active
// Meshes: bunny00 (75K triangles), armadillo (52K), dragon (ChineseDragon-10kv, 20K, open), bunny1m (1.2M,
// bench_meshes.hpp). Frames: resolution R along the longest side, 3 cells of margin, cubic cells; OpenVDB
// gets the transform that maps index (i, j, k) to voxfx's voxel centre lo + (i + 0.5) * cell.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <sys/resource.h>
#include <unistd.h>

#include "bench_meshes.hpp"
#include "voxfx/distance.hpp"
#include "voxfx/sdf.hpp"
#include "voxfx/voxfx.hpp"

namespace {

using namespace voxfx;

std::string gSelf; // this program, for the children

double residentMB() {
    std::ifstream f("/proc/self/statm");
    long pages = 0, resident = 0;
    f >> pages >> resident;
    return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1 << 20);
}

double peakMB() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

Frame benchFrame(const Mesh& m, int64_t resolution) {
    FitOptions fo;
    fo.resolution = resolution;
    fo.marginCells = 3;
    return fitFrame(computeBounds(m.view()), fo);
}

/// An active voxel of a result: index and value.
struct Voxel {
    int32_t i, j, k;
    float value;
};

std::vector<Voxel> runVoxfx(const Mesh& m, const Frame& frame) {
    const SignedDistanceField f = signedDistanceField(m.view(), frame);
    std::vector<std::array<int32_t, 3>> idx;
    std::vector<float> values;
    f.activeVoxels(idx, values);
    std::vector<Voxel> out(idx.size());
    for (std::size_t a = 0; a < idx.size(); ++a) out[a] = {idx[a][0], idx[a][1], idx[a][2], values[a]};
    return out;
}

std::vector<Voxel> runOpenVdb(const Mesh& m, const Frame& frame) {
    openvdb::initialize();
    const Vec3d cell = frame.cellSize(), c0 = frame.box().lo + cell * 0.5;
    auto xform = openvdb::math::Transform::createLinearTransform(cell.x);
    xform->postTranslate(openvdb::Vec3d(c0.x, c0.y, c0.z));
    std::vector<openvdb::Vec3s> points(m.positions.size());
    for (std::size_t v = 0; v < points.size(); ++v)
        points[v] = openvdb::Vec3s(m.positions[v].x, m.positions[v].y, m.positions[v].z);
    std::vector<openvdb::Vec3I> tris(m.triangleCount());
    for (std::size_t t = 0; t < tris.size(); ++t)
        tris[t] = openvdb::Vec3I(m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]);
    const openvdb::FloatGrid::Ptr grid =
        openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, points, tris, 3.0f);
    std::vector<Voxel> out;
    out.reserve(grid->activeVoxelCount());
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        out.push_back({c.x(), c.y(), c.z(), *it});
    }
    return out;
}

/// The child: one field, its time and memory, then its errors; one line of key=value on stdout.
int child(const std::string& method, const std::string& mesh, int64_t resolution) {
    const Mesh* m = bench::mesh(mesh);
    if (!m) return 2;
    const Frame frame = benchFrame(*m, resolution);
    const double before = residentMB();
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<Voxel> vox = method == "voxfx" ? runVoxfx(*m, frame) : runOpenVdb(*m, frame);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double peak = peakMB() - before;

    // Errors against the exact distance at every active voxel, signs against the exact solid.
    const Vec3d lo = frame.box().lo, cell = frame.cellSize();
    std::vector<Vec3d> centres(vox.size());
    for (std::size_t a = 0; a < vox.size(); ++a)
        centres[a] = {lo.x + (vox[a].i + 0.5) * cell.x, lo.y + (vox[a].j + 0.5) * cell.y,
                      lo.z + (vox[a].k + 0.5) * cell.z};
    const ClosestPointQuery query(m->view());
    std::vector<double> exact(vox.size());
    query.distance(centres, exact);
    VoxelizeOptions vo;
    vo.mode = VoxelizeMode::Solid;
    vo.fill = analyzeTopology(m->view()).closed() ? Fill::Parity : Fill::Gwn; // the SDF's Auto
    const Frame frameZ =
        Frame::orthographic(frame.box(), Axis::Z, frame.width(), frame.height(), frame.depth());
    const VoxelGrid solid = voxelize(m->view(), frameZ, vo);
    double maxErr = 0, sumErr = 0;
    int64_t signErr = 0;
    for (std::size_t a = 0; a < vox.size(); ++a) {
        const double e = std::abs(std::abs(double(vox[a].value)) - exact[a]) / cell.x;
        maxErr = std::max(maxErr, e);
        sumErr += e;
        const bool in = vox[a].i >= 0 && vox[a].j >= 0 && vox[a].k >= 0 && vox[a].i < frame.width() &&
                        vox[a].j < frame.height() && vox[a].k < frame.depth() &&
                        solid.bits.get(vox[a].i, vox[a].j, vox[a].k);
        signErr += std::signbit(vox[a].value) != in;
    }
    // Band voxels that are missing: the exact band from voxfx's own field, whose values the
    // errors above check.
    int64_t missing = 0;
    if (method != "voxfx") {
        const std::vector<Voxel> band = runVoxfx(*m, frame);
        std::map<std::tuple<int32_t, int32_t, int32_t>, char> have;
        for (const Voxel& v : vox) have[{v.i, v.j, v.k}] = 1;
        for (const Voxel& v : band) missing += !have.count({v.i, v.j, v.k});
    }
    // The reference against CGAL on a sample.
    using K = CGAL::Exact_predicates_inexact_constructions_kernel;
    using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<K::Triangle_3>::const_iterator>;
    std::vector<K::Triangle_3> tris;
    const MeshView mv = m->view();
    for (std::size_t t = 0; t < mv.triangleCount; ++t) {
        const Vec3d a = mv.vertex(mv.index(t, 0)), b = mv.vertex(mv.index(t, 1)),
                    c = mv.vertex(mv.index(t, 2));
        tris.emplace_back(K::Point_3(a.x, a.y, a.z), K::Point_3(b.x, b.y, b.z), K::Point_3(c.x, c.y, c.z));
    }
    CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>> tree(tris.begin(), tris.end());
    tree.accelerate_distance_queries();
    std::mt19937_64 rng(5);
    double cgalDiff = 0;
    for (int s = 0; s < 20000 && !vox.empty(); ++s) {
        const std::size_t a = rng() % vox.size();
        const double d =
            std::sqrt(tree.squared_distance(K::Point_3(centres[a].x, centres[a].y, centres[a].z)));
        cgalDiff = std::max(cgalDiff, std::abs(d - exact[a]) / cell.x);
    }
    std::printf("seconds=%.6f peak_MB=%.1f active=%zu max_err=%.9g mean_err=%.9g sign_err=%lld missing=%lld "
                "cgal_diff=%.3g\n",
                seconds, peak, vox.size(), maxErr, vox.empty() ? 0.0 : sumErr / double(vox.size()),
                (long long)signErr, (long long)missing, cgalDiff);
    return 0;
}

void sdfBench(benchmark::State& state, const std::string& mesh, const std::string& method) {
    if (!bench::mesh(mesh)) {
        state.SkipWithError("missing data: run scripts/fetch-data.sh");
        return;
    }
    std::map<std::string, double> r;
    for (auto _ : state) {
        const std::string cmd =
            gSelf + " --child " + method + " " + mesh + " " + std::to_string(state.range(0));
        FILE* p = popen(cmd.c_str(), "r");
        char line[1024] = {};
        const bool got = p && std::fgets(line, sizeof line, p);
        if (p) pclose(p);
        if (!got) {
            state.SkipWithError("the child failed");
            return;
        }
        std::istringstream in(line);
        std::string kv;
        while (in >> kv) r[kv.substr(0, kv.find('='))] = std::stod(kv.substr(kv.find('=') + 1));
        state.SetIterationTime(r["seconds"]);
    }
    for (const char* k : {"peak_MB", "active", "max_err", "mean_err", "sign_err", "missing", "cgal_diff"})
        state.counters[k] = r[k];
}

} // namespace

int main(int argc, char** argv) {
    gSelf = argv[0];
    if (argc == 5 && std::string(argv[1]) == "--child") return child(argv[2], argv[3], std::stoll(argv[4]));
    for (const char* mesh : {"bunny00", "armadillo", "dragon", "bunny1m"})
        for (const char* method : {"voxfx", "openvdb"})
            benchmark::RegisterBenchmark((std::string("Sdf/") + mesh + "/" + method).c_str(), sdfBench, mesh,
                                         method)
                ->Arg(256)
                ->Arg(512)
                ->Arg(1024)
                ->Arg(2048)
                ->Iterations(1)
                ->UseManualTime()
                ->Unit(benchmark::kMillisecond);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    return 0;
}
