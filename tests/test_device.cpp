// voxfx — the CUDA back end (voxfx/device.hpp): its grids against the CPU's, bit for bit, on the
// CGAL meshes in every mode and kind of frame, and against CGAL itself; and the fallback.
//
// The GPU tests skip visibly where no GPU can be used (CI): the skip message carries
// cudaStatus().reason. The fallback tests run there instead: --device cuda gives the CPU's grid
// and says why. On a machine with a GPU it is the other way round.
#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cgal_oracle.hpp"
#include "test_util.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/device.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

#define VOXFX_REQUIRE_GPU()                                                                                  \
    do {                                                                                                     \
        if (!cudaStatus().available) GTEST_SKIP() << "no usable GPU: " << cudaStatus().reason;               \
    } while (false)

constexpr VoxelizeMode kModes[] = {VoxelizeMode::Surface, VoxelizeMode::Conservative, VoxelizeMode::Solid,
                                   VoxelizeMode::SolidConservative, VoxelizeMode::Interior};

VoxelGrid onCpu(const MeshView& mesh, const Frame& frame, VoxelizeMode mode) {
    VoxelizeOptions o;
    o.mode = mode;
    o.fill = Fill::Parity;
    return voxelize(mesh, frame, o);
}

Frame fitted(const MeshView& mesh, int64_t resolution, Axis axis = Axis::Z, int64_t margin = 0) {
    FitOptions fit;
    fit.resolution = resolution;
    fit.axis = axis;
    fit.marginCells = margin;
    return fitFrame(computeBounds(mesh), fit);
}

// Equal bits; else how many words differ and the first differing cell.
::testing::AssertionResult sameBits(const BitGrid& gpu, const BitGrid& cpu) {
    if (gpu.width() != cpu.width() || gpu.height() != cpu.height() || gpu.depth() != cpu.depth())
        return ::testing::AssertionFailure() << "the grids' sizes differ";
    int64_t words = 0, first = -1;
    for (int64_t i = 0; i < cpu.wordCount(); ++i)
        if (gpu.words()[i] != cpu.words()[i]) {
            ++words;
            if (first < 0) first = i;
        }
    if (words == 0) return ::testing::AssertionSuccess();
    const int64_t column = first / cpu.wordsPerColumn();
    const int bit = std::countr_zero(gpu.words()[first] ^ cpu.words()[first]);
    return ::testing::AssertionFailure()
           << words << " of " << cpu.wordCount() << " words differ; first at cell (" << column % cpu.width()
           << ", " << column / cpu.width() << ", " << (first % cpu.wordsPerColumn()) * 64 + bit << "); GPU "
           << gpu.count() << " cells, CPU " << cpu.count();
}

// The mesh on the GPU in every mode, each against the CPU. `filled`: the grids of the surface
// modes and solid are not empty (false for frames that hold no surface).
void expectEveryModeMatches(CudaVoxelizer& gpu, const MeshView& mesh, const Frame& frame,
                            const std::string& what, bool filled = true) {
    for (VoxelizeMode mode : kModes) {
        SCOPED_TRACE(what + ", " + toString(mode));
        gpu.voxelize(frame, mode);
        const BitGrid bits = gpu.download();
        const VoxelGrid cpu = onCpu(mesh, frame, mode);
        EXPECT_TRUE(sameBits(bits, cpu.bits));
        EXPECT_EQ(gpu.count(), cpu.bits.count());
        EXPECT_TRUE(test::paddingIsZero(bits));
        if (filled && mode != VoxelizeMode::Interior) { EXPECT_GT(cpu.bits.count(), 0); }
    }
}

std::string meshFile(const std::string& name) { return "meshes/" + name + ".off"; }

// --- Without a usable GPU ------------------------------------------------------------------------

TEST(DeviceTest, DeviceNamesParseAndBadOnesAreListed) {
    EXPECT_EQ(parseDevice("CUDA"), Device::Cuda);
    EXPECT_EQ(parseDevice("cpu"), Device::Cpu);
    EXPECT_EQ(parseDevice("auto"), Device::Auto);
    try {
        parseDevice("gpu");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cpu, cuda, auto"), std::string::npos) << e.what();
    }
}

TEST(DeviceTest, StatusIsUsableOrSaysWhyNot) {
    const CudaStatus& s = cudaStatus();
    EXPECT_NE(s.available, !s.reason.empty()) << s.reason;
    if (s.available) { EXPECT_TRUE(s.built); }
    if (!s.built) { EXPECT_NE(s.reason.find("without CUDA"), std::string::npos) << s.reason; }
}

TEST(DeviceTest, CudaRequestWithoutUsableGpuRunsOnTheCpuAndSaysWhy) {
    if (cudaStatus().available) GTEST_SKIP() << "a GPU is usable here (" << cudaStatus().device << ")";
    const Mesh torus = test::makeTorus({0.1, 0.2, 0.3}, 1.0, 0.4, 48, 24);
    const Frame frame = fitted(torus.view(), 40);
    for (Device device : {Device::Cuda, Device::Auto}) {
        VoxelizeOptions o;
        o.mode = VoxelizeMode::SolidConservative;
        o.device = device;
        std::string note = "stale";
        o.deviceNote = &note;
        const VoxelGrid grid = voxelize(torus.view(), frame, o);
        EXPECT_TRUE(sameBits(grid.bits, onCpu(torus.view(), frame, o.mode).bits));
        EXPECT_NE(note.find(cudaStatus().reason), std::string::npos) << note;
        EXPECT_NE(note.find("voxelized on the CPU"), std::string::npos) << note;
    }
    try {
        CudaVoxelizer gpu;
        FAIL() << "a CudaVoxelizer was made without a usable GPU";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(cudaStatus().reason), std::string::npos) << e.what();
    }
    try {
        CudaGrid grid(test::randomBits(4, 4, 4, 0.5, 1));
        FAIL() << "a CudaGrid was made without a usable GPU";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(cudaStatus().reason), std::string::npos) << e.what();
    }
}

TEST(DeviceTest, CommandLineDeviceCudaWritesTheCpuGridAndSaysWhereItRan) {
    test::TempDir dir;
    const Mesh torus = test::makeTorus({0.1, 0.2, 0.3}, 1.0, 0.4, 48, 24);
    std::ostringstream off;
    off << "OFF\n" << torus.positions.size() << " " << torus.triangleCount() << " 0\n";
    for (const Vec3f& p : torus.positions) off << p.x << " " << p.y << " " << p.z << "\n";
    for (std::size_t t = 0; t < torus.triangleCount(); ++t)
        off << "3 " << torus.indices[3 * t] << " " << torus.indices[3 * t + 1] << " "
            << torus.indices[3 * t + 2] << "\n";
    const std::string mesh = test::writeFile(dir.file("torus.off"), off.str());
    const test::CommandRun cpu =
        test::runVoxfx(dir, "voxelize " + mesh + " -r 48 -o " + dir.file("cpu.binvox"));
    ASSERT_EQ(cpu.exitCode, 0) << cpu.err;
    const test::CommandRun gpu =
        test::runVoxfx(dir, "voxelize " + mesh + " -r 48 --device cuda -o " + dir.file("gpu.binvox"));
    ASSERT_EQ(gpu.exitCode, 0) << gpu.err;
    EXPECT_EQ(test::readFileBytes(dir.file("gpu.binvox")), test::readFileBytes(dir.file("cpu.binvox")));
    if (cudaStatus().available) {
        EXPECT_NE(gpu.out.find(" on " + cudaStatus().device), std::string::npos) << gpu.out;
        EXPECT_EQ(gpu.err.find("--device cuda:"), std::string::npos) << gpu.err;
    } else {
        EXPECT_NE(gpu.err.find("--device cuda: " + cudaStatus().reason), std::string::npos) << gpu.err;
    }
    const test::CommandRun devices = test::runVoxfx(dir, "devices");
    ASSERT_EQ(devices.exitCode, 0) << devices.err;
    EXPECT_NE(devices.out.find(cudaStatus().available ? cudaStatus().device : cudaStatus().reason),
              std::string::npos)
        << devices.out;
    const test::CommandRun bad =
        test::runVoxfx(dir, "voxelize " + mesh + " --device gpu -o " + dir.file("x.binvox"));
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("cpu, cuda, auto"), std::string::npos) << bad.err;
}

// --- On the GPU ----------------------------------------------------------------------------------

TEST(CudaTest, EveryModeEqualsTheCpuOnCgalMeshesAt128And512) {
    VOXFX_REQUIRE_GPU();
    CudaVoxelizer gpu;
    for (const char* name : {"bunny00", "armadillo", "ChineseDragon-10kv", "elephant", "knot1"}) {
        VOXFX_REQUIRE_DATA(meshFile(name));
        const Mesh mesh = loadMesh(test::dataPath(meshFile(name)));
        gpu.setMesh(mesh.view());
        for (int64_t resolution : {128, 512})
            expectEveryModeMatches(gpu, mesh.view(), fitted(mesh.view(), resolution),
                                   std::string(name) + " at " + std::to_string(resolution));
    }
}

TEST(CudaTest, EveryModeEqualsTheCpuOnEverySlicingAxisWithMargins) {
    VOXFX_REQUIRE_GPU();
    VOXFX_REQUIRE_DATA(meshFile("armadillo"));
    const Mesh mesh = loadMesh(test::dataPath(meshFile("armadillo")));
    CudaVoxelizer gpu;
    gpu.setMesh(mesh.view());
    for (Axis axis : {Axis::X, Axis::Y, Axis::Z})
        expectEveryModeMatches(gpu, mesh.view(), fitted(mesh.view(), 200, axis, 3),
                               std::string("axis ") + toString(axis));
}

TEST(CudaTest, EveryModeEqualsTheCpuAt1024And2048Slow) {
    VOXFX_REQUIRE_GPU();
    CudaVoxelizer gpu;
    for (const char* name : {"bunny00", "ChineseDragon-10kv", "armadillo"}) {
        VOXFX_REQUIRE_DATA(meshFile(name));
        const Mesh mesh = loadMesh(test::dataPath(meshFile(name)));
        gpu.setMesh(mesh.view());
        for (int64_t resolution : {1024, 2048}) {
            if (resolution == 2048 && std::string(name) != "bunny00") continue;
            expectEveryModeMatches(gpu, mesh.view(), fitted(mesh.view(), resolution),
                                   std::string(name) + " at " + std::to_string(resolution));
        }
    }
}

TEST(CudaTest, LightSpaceFramesAndLocalSlicingEqualTheCpu) {
    VOXFX_REQUIRE_GPU();
    VOXFX_REQUIRE_DATA(meshFile("bunny00"));
    const Mesh mesh = loadMesh(test::dataPath(meshFile("bunny00")));
    const Box3d b = computeBounds(mesh.view());
    const Vec3d c = b.center(), e = b.extent();
    const double r = 0.5 * std::sqrt(dot(e, e));
    CudaVoxelizer gpu;
    gpu.setMesh(mesh.view());
    // A spot light above and to the side (perspective: depth is view distance, near plane inside
    // nothing) and one whose near plane cuts the mesh (depth clamping).
    expectEveryModeMatches(gpu, mesh.view(),
                           Frame::perspective(c + Vec3d{1.7 * r, -2.1 * r, 1.3 * r}, c, {0, 0, 1}, 0.8, 300,
                                              260, 1.0 * r, 5.0 * r, 200),
                           "spot light");
    expectEveryModeMatches(gpu, mesh.view(),
                           Frame::perspective(c + Vec3d{0.3 * r, -1.2 * r, 0.2 * r}, c, {0, 0, 1}, 1.1, 256,
                                              256, 0.6 * r, 3.0 * r, 128),
                           "spot light, near plane through the mesh");
    // A directional light: an oriented orthographic frame along a slanted direction.
    Vec3d forward{0.36, -0.48, -0.8};
    forward = forward / std::sqrt(dot(forward, forward));
    Vec3d right = cross(forward, Vec3d{0, 0, 1});
    right = right / std::sqrt(dot(right, right));
    const Vec3d up = cross(forward, right);
    const Vec3d rr = cross(up, forward);
    Box3d local;
    for (int k = 0; k < 8; ++k) {
        const Vec3d p{k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z};
        local.extend({dot(p, rr), dot(p, up), dot(p, forward)});
    }
    expectEveryModeMatches(gpu, mesh.view(), Frame::orthographic(local, rr, up, forward, 320, 288, 256),
                           "directional light");
    // ED06's local slicing: the D slices of each column spread over its own depth range.
    for (VoxelizeMode mode : kModes) {
        SCOPED_TRACE(std::string("local slicing, ") + toString(mode));
        VoxelizeOptions o;
        o.mode = mode;
        o.slicing = Slicing::Local;
        const Frame frame = fitted(mesh.view(), 160);
        const VoxelGrid cpu = voxelize(mesh.view(), frame, o);
        o.device = Device::Cuda;
        std::string note;
        o.deviceNote = &note;
        const VoxelGrid onGpu = voxelize(mesh.view(), frame, o);
        EXPECT_EQ(note, "");
        ASSERT_TRUE(onGpu.frame.sameGrid(cpu.frame));
        EXPECT_TRUE(sameBits(onGpu.bits, cpu.bits));
    }
}

TEST(CudaTest, EdgeCasesEqualTheCpu) {
    VOXFX_REQUIRE_GPU();
    CudaVoxelizer gpu;
    // A box whose faces lie on cell boundaries and whose edges and corners meet cell centres'
    // columns exactly: the tie rules decide every fragment.
    Mesh aligned;
    test::appendBox(aligned, {2, 3, 1}, {9, 7, 11});
    test::appendBox(aligned, {9, 3, 1}, {12, 5, 4}); // touches the first box along a face
    gpu.setMesh(aligned.view());
    expectEveryModeMatches(gpu, aligned.view(),
                           Frame::orthographic({{0, 0, 0}, {14, 10, 13}}, Axis::Z, 14, 10, 13),
                           "cell-aligned boxes");
    expectEveryModeMatches(gpu, aligned.view(),
                           Frame::orthographic({{0, 0, 0}, {14, 10, 13}}, Axis::Z, 28, 20, 26), "half cells");
    // Triangles far larger than the grid (the block-per-triangle pass), slicing depths that are
    // no multiple of 64 (padding) and more than 32 words per column (the prefix loop over lanes).
    Mesh big;
    test::appendBox(big, {-1, -2, -3}, {5.3, 4.1, 3.7});
    gpu.setMesh(big.view());
    expectEveryModeMatches(gpu, big.view(),
                           Frame::orthographic({{0, 0, 0}, {6, 5, 4}}, Axis::Z, 300, 300, 100),
                           "box through the grid");
    expectEveryModeMatches(gpu, big.view(),
                           Frame::orthographic({{-0.5, -3, -4}, {4, 3, 3}}, Axis::Y, 96, 80, 3000),
                           "3000 slices");
    // The grid inside the box: the surfaces are empty, solid is full.
    expectEveryModeMatches(gpu, big.view(), Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::X, 1, 1, 1),
                           "one cell", false);
    // A mesh entirely outside the frame, and one without triangles.
    expectEveryModeMatches(gpu, big.view(),
                           Frame::orthographic({{10, 10, 10}, {12, 12, 12}}, Axis::Z, 8, 8, 8), "outside",
                           false);
    Mesh none;
    gpu.setMesh(none.view());
    gpu.voxelize(Frame::orthographic({{0, 0, 0}, {1, 1, 1}}, Axis::Z, 8, 8, 70),
                 VoxelizeMode::SolidConservative);
    EXPECT_EQ(gpu.download().count(), 0);
}

TEST(CudaTest, BuffersAreReusedAcrossFramesAndMeshes) {
    VOXFX_REQUIRE_GPU();
    const Mesh torus = test::makeTorus({0.1, 0.2, 0.3}, 1.0, 0.4, 96, 48);
    const Mesh sphere = test::makeUvSphere({0.3, 0.1, -0.2}, 1.2, 40, 80);
    CudaVoxelizer gpu;
    for (const Mesh* mesh : {&torus, &sphere, &torus}) {
        gpu.setMesh(mesh->view());
        for (int64_t resolution : {300, 40, 170}) {
            const Frame frame = fitted(mesh->view(), resolution);
            gpu.voxelize(frame, VoxelizeMode::Solid);
            const VoxelGrid cpu = onCpu(mesh->view(), frame, VoxelizeMode::Solid);
            EXPECT_TRUE(sameBits(gpu.download(), cpu.bits)) << resolution;
            EXPECT_EQ(gpu.count(), cpu.bits.count());
        }
    }
    const DeviceTimings t = gpu.timings();
    EXPECT_GT(t.kernelMs, 0);
    EXPECT_GT(t.downloadMs, 0);
}

TEST(CudaTest, VoxelizeWithDeviceCudaRunsOnTheGpu) {
    VOXFX_REQUIRE_GPU();
    const Mesh torus = test::makeTorus({0.1, 0.2, 0.3}, 1.0, 0.4, 48, 24);
    const Frame frame = fitted(torus.view(), 64);
    VoxelizeOptions o;
    o.mode = VoxelizeMode::Interior;
    o.device = Device::Cuda;
    std::string note = "stale";
    o.deviceNote = &note;
    const VoxelGrid grid = voxelize(torus.view(), frame, o);
    EXPECT_EQ(note, "");
    EXPECT_TRUE(sameBits(grid.bits, onCpu(torus.view(), frame, o.mode).bits));
    // A fill the GPU does not have: the CPU runs it, and the note says so.
    o.mode = VoxelizeMode::Solid;
    o.fill = Fill::Flood;
    (void)voxelize(torus.view(), frame, o);
    EXPECT_NE(note.find("flood"), std::string::npos) << note;
}

TEST(CudaTest, CsgMorphologyAndCountOnTheGpuEqualTheCpu) {
    VOXFX_REQUIRE_GPU();
    struct Dims {
        int64_t w, h, d;
    };
    // Depths below, at and above one word, one with 47 words per column; random fill densities.
    uint64_t seed = 11;
    for (const Dims dims : {Dims{37, 29, 100}, Dims{64, 16, 64}, Dims{23, 41, 3000}, Dims{150, 130, 129}}) {
        SCOPED_TRACE(std::to_string(dims.w) + " x " + std::to_string(dims.h) + " x " +
                     std::to_string(dims.d));
        const BitGrid a = test::randomBits(dims.w, dims.h, dims.d, 0.55, seed++);
        const BitGrid b = test::randomBits(dims.w, dims.h, dims.d, 0.3, seed++);
        const CudaGrid ga(a), gb(b);
        EXPECT_EQ(ga.count(), a.count());
        EXPECT_TRUE(sameBits(ga.download(), a));
        for (CsgOp op : {CsgOp::Union, CsgOp::Intersection, CsgOp::Difference, CsgOp::Xor}) {
            SCOPED_TRACE(toString(op));
            EXPECT_TRUE(sameBits(csg(ga, gb, op).download(), csg(a, b, op)));
        }
        const struct {
            int64_t rx, ry, rz;
        } radii[] = {{1, 1, 1}, {2, 0, 3}, {0, 0, 70}, {5, 3, 0}, {0, 4, 0}, {3, 2, 130}, {200, 1, 5000}};
        for (const auto& r : radii)
            for (MorphOp op : {MorphOp::Erode, MorphOp::Dilate, MorphOp::Open, MorphOp::Close})
                for (MorphBorder border : {MorphBorder::Neutral, MorphBorder::Empty, MorphBorder::Filled}) {
                    SCOPED_TRACE(std::string(toString(op)) + " " + toString(border) + " radii " +
                                 std::to_string(r.rx) + " " + std::to_string(r.ry) + " " +
                                 std::to_string(r.rz));
                    MorphologyOptions o;
                    o.rx = r.rx;
                    o.ry = r.ry;
                    o.rz = r.rz;
                    o.border = border;
                    const CudaGrid out = morphology(ga, op, o);
                    const BitGrid expected = morphology(a, op, o);
                    EXPECT_TRUE(sameBits(out.download(), expected));
                    EXPECT_EQ(out.count(), expected.count());
                }
    }
    // Errors as on the CPU.
    const CudaGrid small(4, 4, 4), other(4, 4, 5);
    EXPECT_THROW(csg(small, other, CsgOp::Union), Error);
    MorphologyOptions negative;
    negative.rz = -1;
    EXPECT_THROW(morphology(small, MorphOp::Dilate, negative), Error);
}

TEST(CudaTest, AVoxelizationStaysOnTheGpuForTheToolkit) {
    VOXFX_REQUIRE_GPU();
    VOXFX_REQUIRE_DATA(meshFile("bunny00"));
    const Mesh mesh = loadMesh(test::dataPath(meshFile("bunny00")));
    const Frame frame = fitted(mesh.view(), 300);
    CudaVoxelizer gpu;
    gpu.setMesh(mesh.view());
    gpu.voxelize(frame, VoxelizeMode::Solid);
    const CudaGrid solid = gpu.grid();
    gpu.voxelize(frame, VoxelizeMode::Conservative);
    const CudaGrid shell = gpu.grid();
    const BitGrid cpuSolid = onCpu(mesh.view(), frame, VoxelizeMode::Solid).bits;
    const BitGrid cpuShell = onCpu(mesh.view(), frame, VoxelizeMode::Conservative).bits;
    // Interior = solid minus the shell, on the GPU, equals the CPU's interior mode.
    EXPECT_TRUE(sameBits(csg(solid, shell, CsgOp::Difference).download(),
                         onCpu(mesh.view(), frame, VoxelizeMode::Interior).bits));
    MorphologyOptions o;
    o.rx = o.ry = o.rz = 3;
    EXPECT_TRUE(
        sameBits(morphology(solid, MorphOp::Close, o).download(), morphology(cpuSolid, MorphOp::Close, o)));
    EXPECT_TRUE(
        sameBits(morphology(shell, MorphOp::Dilate, o).download(), morphology(cpuShell, MorphOp::Dilate, o)));
}

TEST(CudaTest, TransmittanceShadowGridsFromTheGpuEqualTheCpus) {
    VOXFX_REQUIRE_GPU();
    VOXFX_REQUIRE_DATA(meshFile("bunny00"));
    const Mesh mesh = loadMesh(test::dataPath(meshFile("bunny00")));
    const Box3d bounds = computeBounds(mesh.view());
    Light sun;
    sun.direction = Vec3d{0.3, -0.8, -0.52} / std::sqrt(0.09 + 0.64 + 0.2704);
    Light spot;
    spot.type = LightType::Spot;
    spot.position = bounds.center() + Vec3d{0.5, 2.0, 0.7} * bounds.extent().y;
    spot.direction = (bounds.center() - spot.position) /
                     std::sqrt(dot(bounds.center() - spot.position, bounds.center() - spot.position));
    spot.outerConeAngle = 0.9;
    const MeshView groups[1] = {mesh.view()};
    const Vec3f half[1] = {{0.5f, 0.5f, 0.5f}};
    for (const Light& light : {sun, spot})
        for (const LightView& view : makeLightViews(light, bounds, 256, 192))
            for (VoxelizeMode mode : {VoxelizeMode::Surface, VoxelizeMode::Conservative})
                for (Slicing slicing : {Slicing::Uniform, Slicing::Local}) {
                    SCOPED_TRACE(std::string(toString(light.type)) + " " + toString(mode) + " " +
                                 toString(slicing));
                    const TransmittanceShadowMap cpu = TransmittanceShadowMap::build(
                        view, groups, half, mode, slicing, nullptr, Device::Cpu);
                    const TransmittanceShadowMap gpu = TransmittanceShadowMap::build(
                        view, groups, half, mode, slicing, nullptr, Device::Cuda);
                    ASSERT_EQ(gpu.channels().size(), 1u);
                    EXPECT_GT(cpu.channels()[0].grid.bits.count(), 0);
                    EXPECT_TRUE(gpu.channels()[0].grid.frame.sameGrid(cpu.channels()[0].grid.frame));
                    EXPECT_TRUE(sameBits(gpu.channels()[0].grid.bits, cpu.channels()[0].grid.bits));
                }
}

// The GPU's grids against CGAL directly: solid against the exact inside test of the cell
// centres, conservative against exact triangle/box overlap.
TEST(CudaTest, SolidAndConservativeMatchCgal) {
    VOXFX_REQUIRE_GPU();
    for (const char* name : {"bunny00", "knot1"}) {
        VOXFX_REQUIRE_DATA(meshFile(name));
        const Mesh mesh = loadMesh(test::dataPath(meshFile(name)));
        const Frame frame = fitted(mesh.view(), 64);
        CudaVoxelizer gpu;
        gpu.setMesh(mesh.view());
        gpu.voxelize(frame, VoxelizeMode::Solid);
        const VoxelGrid solid{frame, gpu.download()};
        const test::CellGeometry g = test::CellGeometry::of(solid);
        const test::SolidOracle inside = test::oracleSolid(mesh.view(), g);
        ASSERT_TRUE(inside.closed);
        const test::GridDiff d = test::compareGrids(test::toWorldGrid(solid), inside.inside, &inside.leftOut);
        EXPECT_TRUE(d.equal()) << name << ": " << d;
        gpu.voxelize(frame, VoxelizeMode::Conservative);
        const VoxelGrid cons{frame, gpu.download()};
        const test::ConservativeOracle overlap = test::oracleConservative(mesh.view(), g, 2e-9);
        const test::GridDiff dc = test::compareGrids(test::toWorldGrid(cons), overlap.cells, &overlap.near);
        EXPECT_TRUE(dc.equal()) << name << ": " << dc;
    }
}

} // namespace
} // namespace voxfx
