// Tests of src/sim/particles.cpp: no particle ends a step inside a filled cell (checked through
// the frame's own world-to-grid map, not the simulator's), energy never grows for restitution
// <= 1, hand-derived bounces on a flat floor, moving obstacles, determinism across thread
// counts. The allocation-free step loop is tested in tests/alloc/ (its own program: it replaces
// the global operator new).
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/particles.hpp"
#include "voxfx/particles_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

// Independent inside test: the frame's gridFromWorld, floor, and the bit.
bool insideFilled(const VoxelGrid& g, const Vec3f& p) {
    const Vec3d q = g.frame.gridFromWorld(Vec3d(p));
    if (!(q.x >= 0 && q.y >= 0 && q.z >= 0 && q.x < double(g.bits.width()) && q.y < double(g.bits.height()) &&
          q.z < double(g.bits.depth())))
        return false;
    return g.bits.get(int64_t(q.x), int64_t(q.y), int64_t(q.z));
}

int64_t particlesInside(const VoxelGrid& g, const Particles& ps) {
    int64_t n = 0;
    for (size_t i = 0; i < ps.size(); ++i) n += insideFilled(g, ps.position(i));
    return n;
}

// A torus lying over a floor slab, in a 64 x 64 x 48 grid of unit cells.
VoxelGrid torusScene(Axis axis = Axis::Z) {
    Mesh m = test::makeTorus({32, 32, 20}, 16, 6, 48, 24);
    test::appendBox(m, {2, 2, 1}, {62, 62, 5});
    const Frame f = Frame::orthographic(
        {{0, 0, 0}, {64, 64, 48}}, axis, axis == Axis::Z ? 64 : (axis == Axis::X ? 64 : 48),
        axis == Axis::Z ? 64 : (axis == Axis::X ? 48 : 64), axis == Axis::Z ? 48 : 64);
    return voxelize(m.view(), f);
}

TEST(ParticlesTest, NoParticleEndsAStepInsideAFilledCell) {
    for (const Axis axis : {Axis::Z, Axis::X}) {
        const ParticleCollider collider(torusScene(axis));
        Particles ps = emitParticles(collider, 20000, {{1, 1, 28}, {63, 63, 47}}, 3);
        ASSERT_EQ(ps.size(), 20000u);
        ParticleOptions o;
        o.gravity = {0, 0, -200}; // cells per s^2: fast enough to cross several cells per step
        o.dt = 1.0 / 60;
        o.restitution = 0.8;
        o.friction = 0.05;
        int64_t bounces = 0;
        for (int step = 0; step < 150; ++step) {
            bounces += stepParticles(ps, collider, o).bounces;
            ASSERT_EQ(particlesInside(collider.grid(), ps), 0)
                << "step " << step << " axis " << toString(axis);
        }
        EXPECT_GT(bounces, 20000) << toString(axis);
    }
}

TEST(ParticlesTest, EnergyNeverGrowsWithRestitutionAtMostOne) {
    const ParticleCollider collider(torusScene());
    for (const double e : {0.0, 0.5, 1.0}) {
        Particles ps = emitParticles(collider, 5000, {{1, 1, 30}, {63, 63, 47}}, 4);
        ParticleOptions o;
        o.gravity = {0, 0, -200};
        o.dt = 1.0 / 60;
        o.restitution = e;
        o.boxWalls = true;
        double previous = particleEnergy(ps, o.gravity);
        const double initial = previous;
        for (int step = 0; step < 200; ++step) {
            stepParticles(ps, collider, o);
            const double now = particleEnergy(ps, o.gravity);
            // Positions and velocities are floats: each step may round by ~1e-7 of the energy.
            ASSERT_LE(now, previous + 1e-6 * std::fabs(initial)) << "restitution " << e << " step " << step;
            previous = now;
        }
        EXPECT_LT(previous, initial) << "restitution " << e;
    }
    // The check can fail: restitution above 1 pumps energy in.
    Particles ps = emitParticles(collider, 2000, {{1, 1, 30}, {63, 63, 47}}, 5);
    ParticleOptions o;
    o.gravity = {0, 0, -200};
    o.dt = 1.0 / 60;
    o.restitution = 1.5;
    o.boxWalls = true;
    const double before = particleEnergy(ps, o.gravity);
    for (int step = 0; step < 200; ++step) stepParticles(ps, collider, o);
    EXPECT_GT(particleEnergy(ps, o.gravity), before);
}

TEST(ParticlesTest, BounceOnAFlatFloorReflectsTheNormalVelocity) {
    // Floor: the lower 8 of 16 slices, grid of unit cells; away from the grid's sides its density
    // normal is exactly +z (the counts only change along z).
    VoxelGrid g{Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 16, 16), BitGrid(16, 16, 16)};
    for (int64_t y = 0; y < 16; ++y)
        for (int64_t x = 0; x < 16; ++x)
            for (int64_t s = 0; s < 8; ++s) g.bits.set(x, y, s);
    const ParticleCollider collider(g);
    ParticleOptions o;
    o.gravity = {0, 0, 0};
    o.dt = 0.1;
    o.restitution = 0.5;
    o.friction = 0.25;
    Particles ps;
    ps.push({8.3, 7.6, 8.2}, {1.0f, 0.0f, -4.0f}); // reaches z = 7.8 within the step: enters slice 7
    ps.push({5.5, 5.5, 9.0}, {0.0f, 0.0f, -1.0f}); // stays above: z = 8.9
    const StepStats s = stepParticles(ps, collider, o);
    EXPECT_EQ(s.bounces, 1);
    // Normal component x -e, tangential x (1 - friction); stopped at the floor's top (z = 8),
    // a hair inside the free cell, half way along the path (z 8.2 -> 7.8 crosses 8 at t = 0.5).
    EXPECT_FLOAT_EQ(ps.vz[0], 2.0f);
    EXPECT_FLOAT_EQ(ps.vx[0], 0.75f);
    EXPECT_NEAR(ps.pz[0], 8.0, 2e-3);
    EXPECT_GE(ps.pz[0], 8.0f);
    EXPECT_NEAR(ps.px[0], 8.35, 1e-5);
    EXPECT_FLOAT_EQ(ps.pz[1], 8.9f);
    EXPECT_FLOAT_EQ(ps.vz[1], -1.0f);
}

TEST(ParticlesTest, MovingObstaclePushesParticlesOut) {
    VoxelGrid g{Frame::orthographic({{0, 0, 0}, {16, 16, 16}}, Axis::Z, 16, 16, 16), BitGrid(16, 16, 16)};
    ParticleCollider collider(g);
    Particles ps;
    ps.push({8.5, 8.5, 8.5});
    ps.push({2.5, 2.5, 2.5});
    // The obstacle now covers the first particle's cell and its neighbours: a 3^3 block.
    BitGrid moved(16, 16, 16);
    for (int64_t y = 7; y <= 9; ++y)
        for (int64_t x = 7; x <= 9; ++x)
            for (int64_t s = 7; s <= 9; ++s) moved.set(x, y, s);
    collider.update(moved);
    ParticleOptions o;
    o.gravity = {0, 0, 0};
    const StepStats s = stepParticles(ps, collider, o);
    EXPECT_EQ(s.pushedOut, 1);
    EXPECT_EQ(s.stuck, 0);
    EXPECT_EQ(particlesInside(collider.grid(), ps), 0);
    // The nearest free space is 1.5 cells away from the block's centre.
    EXPECT_NEAR(length(Vec3d(ps.position(0)) - Vec3d{8.5, 8.5, 8.5}), 1.5, 2e-3);
    EXPECT_THROW(collider.update(BitGrid(8, 8, 8)), Error);
}

TEST(ParticlesTest, ResultsAreIdenticalForAnyThreadCount) {
    const ParticleCollider collider(torusScene());
    Particles a = emitParticles(collider, 30000, {}, 9), b = a;
    ParticleOptions o;
    o.gravity = {0, 0, -150};
    o.dt = 1.0 / 60;
    for (int step = 0; step < 40; ++step) {
        o.threads = 1;
        const StepStats sa = stepParticles(a, collider, o);
        o.threads = 2;
        const StepStats sb = stepParticles(b, collider, o);
        ASSERT_EQ(sa.bounces, sb.bounces);
    }
    EXPECT_EQ(a.px, b.px);
    EXPECT_EQ(a.pz, b.pz);
    EXPECT_EQ(a.vz, b.vz);
}

TEST(ParticlesTest, FilesAndPicture) {
    test::TempDir dir;
    const ParticleCollider collider(torusScene());
    Particles ps = emitParticles(collider, 500, {}, 11);
    writeParticles(ps, dir.file("p.csv"));
    writeParticles(ps, dir.file("p.ply"));
    std::ifstream csv(dir.file("p.csv"));
    std::string line;
    int lines = 0;
    while (std::getline(csv, line)) ++lines;
    EXPECT_EQ(lines, 501);
    EXPECT_GT(std::filesystem::file_size(dir.file("p.ply")), 500u * 24u); // six floats per particle + header
    EXPECT_THROW(writeParticles(ps, dir.file("p.txt")), Error);
    ParticleImageOptions io;
    io.width = 128;
    const Image img = renderParticles(ps, collider, io);
    EXPECT_EQ(img.width, 128);
    EXPECT_EQ(img.height, 96); // box 64 x 48 along x and z
    int64_t particlePixels = 0, solidPixels = 0;
    for (const Vec3f& p : img.pixels) {
        particlePixels += p == io.particleColor;
        solidPixels += !(p == io.particleColor) && !(p == io.background);
    }
    EXPECT_GT(particlePixels, 100);
    EXPECT_GT(solidPixels, 1000);
    writePng(img, dir.file("p.png"));
}

TEST(ParticlesTest, PictureDrawsEachParticleWhereAnOrthographicViewAlongYPutsIt) {
    // Three particles in front of the torus scene (world y < 1, before any filled cell), each
    // alone in the picture: its disc centre must be the pixel that x and z map to by the box's
    // proportions (image x = world x, image rows = world z from the top), 2 pixels per unit.
    const ParticleCollider collider(torusScene());
    ParticleImageOptions io;
    io.width = 128;
    io.particleRadius = 1.0f;
    for (const Vec3f p : {Vec3f{10.3f, 0.5f, 40.6f}, Vec3f{50.9f, 0.2f, 7.1f}, Vec3f{31.2f, 0.7f, 24.4f}}) {
        Particles ps;
        ps.push(p);
        const Image img = renderParticles(ps, collider, io);
        const int64_t px = int64_t(std::floor(p.x / 64.0 * 128.0)),
                      py = int64_t(std::floor((48.0 - p.z) / 48.0 * 96.0));
        EXPECT_EQ(img.at(px, py), io.particleColor) << "particle at " << p.x << ", " << p.z;
        // Nothing of the colour far from it.
        for (int64_t y = 0; y < img.height; ++y)
            for (int64_t x = 0; x < img.width; ++x)
                if (std::abs(x - px) > 2 || std::abs(y - py) > 2) {
                    ASSERT_FALSE(img.at(x, y) == io.particleColor) << x << ", " << y;
                }
    }
}

TEST(ParticlesTest, CommandLineWritesFramesAndAPicture) {
    test::TempDir dir;
    const VoxelGrid scene = torusScene();
    writeGrid(scene, dir.file("scene.binvox"));
    const test::CommandRun run = test::runVoxfx(
        dir, "particles " + dir.file("scene.binvox") + " -n 2000 --steps 20 --every 10 --walls -q -o " +
                 dir.file("p_%02d.csv") + " --png " + dir.file("final.png"));
    ASSERT_EQ(run.exitCode, 0) << run.err;
    for (const char* f : {"p_00.csv", "p_10.csv", "p_20.csv", "final.png"})
        EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
    // The last frame holds every particle, none inside the solid.
    std::ifstream in(dir.file("p_20.csv"));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "x,y,z,vx,vy,vz");
    // Checked against the grid in memory (the file's bytes are grid_io's tests' business).
    int rows = 0, inside = 0;
    while (std::getline(in, line)) {
        float x, y, z;
        ASSERT_EQ(std::sscanf(line.c_str(), "%f,%f,%f", &x, &y, &z), 3) << line;
        inside += insideFilled(scene, {x, y, z});
        ++rows;
    }
    EXPECT_EQ(rows, 2000);
    EXPECT_EQ(inside, 0);
    EXPECT_NE(
        test::runVoxfx(dir, "particles " + dir.file("scene.binvox") + " -o " + dir.file("p_%s.csv")).exitCode,
        0);
}

} // namespace
} // namespace voxfx
