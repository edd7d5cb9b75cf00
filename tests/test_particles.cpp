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

// --- Slanted and curved surfaces against the analytic reflection (GI08 §7) ------------------
//
// One bounce per particle, gravity off (the path of a step is then the straight line the closed
// forms use), restitution e and no friction: the analytic velocity after the bounce is
// v - (1 + e) (v . n) n with n the true surface normal at the true contact point Q, the crossing
// of the path with the true surface. The simulator stops the particle where its path enters the
// first filled cell and reflects about the density normal there. Tolerances:
//  - contact point: the stop S lies on the face between the last free cell (centre outside) and
//    the filled one (centre inside), so a segment from either centre to S crosses the surface
//    within the distance between them, sqrt(3)/2 h (h the cell size): |d(S)| < sqrt(3)/2 h for
//    a plane's signed distance d; the particle then sits at most 1e-3 h per axis inside the free
//    cell (particles.cpp's inset). Along a path at angle theta to the normal that is
//    |S - Q| <= (sqrt(3)/2 + sqrt(3) 1e-3) h / cos(theta) + sqrt(3) 1e-3 h.
//  - direction: v - (1 + e) (v . n') n' differs from v - (1 + e) (v . n) n by
//    (1 + e) |(n' n'^T - n n^T) v| <= (1 + e) |v| sin(delta) for normals delta apart (the two
//    projections differ by sin(delta) in norm). delta is the density normal's error:
//    kPlaneNormalDegrees on a plane (measured below over 48 planes at the finest kernel, level 1:
//    the 2 x 2 x 2 blocks' counts are small integers, so a shallow staircase turns the gradient
//    by up to about 20 degrees), plus, on a sphere of radius R, the turn of the true normal
//    between Q and S, |S - Q| / (R - |S - Q|), plus the kernel's reach on a curved surface, the
//    2 x 2 x 2 density cells differenced over two cells each way: 4 h / R.

// The density normal of a centre-sampled plane, level 1, is within this of the true normal
// (measured over the planes of PlaneDensityNormalIsWithinItsMeasuredBound: at most 19.35 degrees).
constexpr double kPlaneNormalDegrees = 20.0;

// Half the world of a unit-cell grid [0, 64]^3 is solid below the plane through `point` with
// unit normal `n`: a slab 24 cells thick and 200 wide, cut by the grid.
Mesh makeSlabBelowPlane(const Vec3d& point, const Vec3d& n) {
    const Vec3d t1 = normalize(std::abs(n.x) < 0.9 ? cross(n, Vec3d{1, 0, 0}) : cross(n, Vec3d{0, 1, 0}));
    const Vec3d t2 = cross(n, t1); // (t1, t2, n) right-handed
    Mesh local = test::makeBox({-100, -100, -24}, {100, 100, 0});
    for (Vec3f& p : local.positions) {
        const Vec3d q(p);
        p = Vec3f(point + t1 * q.x + t2 * q.y + n * q.z);
    }
    return local;
}

Vec3d tiltedNormal(double tiltDegrees, double azimuthDegrees) {
    const double a = tiltDegrees * M_PI / 180, b = azimuthDegrees * M_PI / 180;
    return {std::sin(a) * std::cos(b), std::sin(a) * std::sin(b), std::cos(a)};
}

double angleDegrees(const Vec3d& a, const Vec3d& b) {
    return std::acos(std::clamp(dot(normalize(a), normalize(b)), -1.0, 1.0)) * 180 / M_PI;
}

VoxelGrid slabGrid(const Mesh& m, int64_t n = 64) {
    return voxelize(m.view(),
                    Frame::orthographic({{0, 0, 0}, {double(n), double(n), double(n)}}, Axis::Z, n, n, n));
}

TEST(ParticlesTest, PlaneDensityNormalIsWithinItsMeasuredBound) {
    // The bound the bounce tests rely on: at points of the plane away from the grid's sides,
    // the collider's normal against the plane's, over tilts up to 75 degrees and 8 azimuths.
    double worst = 0;
    for (const double tilt : {0.0, 10.0, 22.5, 35.0, 45.0, 60.0})
        for (const double azimuth : {0.0, 17.0, 45.0, 72.0, 101.0, 160.0, 215.0, 300.0}) {
            const Vec3d n = tiltedNormal(tilt, azimuth);
            const Vec3d c{32.3, 31.8, 32.1};
            const ParticleCollider collider(slabGrid(makeSlabBelowPlane(c, n)));
            for (const Vec3d off :
                 {Vec3d{0, 0, 0}, Vec3d{7.3, -5.1, 0}, Vec3d{-9.4, 8.2, 0}, Vec3d{4.4, 11.9, 0}}) {
                // A point on the plane, moved along it.
                Vec3d p = c + off;
                p -= n * dot(p - c, n);
                worst = std::max(worst, angleDegrees(collider.normalAt(p), n));
            }
        }
    std::cout << "[ particles ] plane density normal: worst " << worst << " degrees\n";
    EXPECT_LE(worst, kPlaneNormalDegrees);
    EXPECT_GT(worst, 0.5); // the staircase is visible: the bound is not vacuous
}

struct Bounce {
    double contactError = 0, contactBound = 0; // |S - Q| and its bound, world units
    double velocityError = 0, velocityBound = 0;
    double turnDegrees = 0; // angle between the velocity after the bounce and the analytic one
};

// One particle from `start` with velocity `v` (gravity off) over one step of `dt` against the
// collider; the analytic contact `q`, normal `n` there, and the bound on the normal's error.
Bounce bounceOnce(const ParticleCollider& collider, const Vec3d& start, const Vec3d& v, double dt, double e,
                  const Vec3d& q, const Vec3d& n, double normalErrorRadians, double h) {
    Particles ps;
    ps.push(Vec3f(start), Vec3f(v));
    ParticleOptions o;
    o.gravity = {0, 0, 0};
    o.dt = dt;
    o.restitution = e;
    o.friction = 0;
    const StepStats stats = stepParticles(ps, collider, o);
    EXPECT_EQ(stats.bounces, 1) << "from (" << start.x << ", " << start.y << ", " << start.z << ")";
    Bounce b;
    const double cosTheta = std::abs(dot(normalize(v), n));
    b.contactError = length(Vec3d(ps.position(0)) - q);
    b.contactBound =
        ((std::sqrt(3.0) / 2 + std::sqrt(3.0) * 1e-3) / cosTheta + std::sqrt(3.0) * 1e-3 + 1e-4) * h;
    const Vec3d expected = v - n * ((1 + e) * dot(v, n));
    b.velocityError = length(Vec3d(ps.velocity(0)) - expected);
    b.velocityBound =
        (1 + e) * length(v) * std::sin(std::min(normalErrorRadians, M_PI / 2)) + 1e-5 * length(v);
    b.turnDegrees = angleDegrees(Vec3d(ps.velocity(0)), expected);
    return b;
}

TEST(ParticlesTest, BallDroppedOnAnInclinedPlaneBouncesAboutThePlaneNormal) {
    // A ball falling straight down onto planes tilted by 15-60 degrees: it must touch the plane
    // where the vertical line meets it, and leave along the mirror image of its fall (2 x tilt
    // from the vertical for e = 1), within the tolerances above.
    const double delta = kPlaneNormalDegrees * M_PI / 180;
    int bounces = 0;
    for (const double tilt : {15.0, 30.0, 45.0, 60.0})
        for (const double azimuth : {20.0, 135.0, 250.0}) {
            const Vec3d n = tiltedNormal(tilt, azimuth), c{32.2, 31.9, 32.4};
            const ParticleCollider collider(slabGrid(makeSlabBelowPlane(c, n)));
            for (const double e : {1.0, 0.5})
                for (const Vec3d off :
                     {Vec3d{0.3, 0.1, 0}, Vec3d{-6.7, 4.9, 0}, Vec3d{8.1, 7.3, 0}, Vec3d{3.3, -9.6, 0}}) {
                    // Q on the plane above (x, y); the ball starts 3 cells above it, falls 6 per step.
                    const Vec3d xy = c + off;
                    const Vec3d q{xy.x, xy.y, c.z - (n.x * (xy.x - c.x) + n.y * (xy.y - c.y)) / n.z};
                    const Bounce b =
                        bounceOnce(collider, q + Vec3d{0, 0, 3}, {0, 0, -60}, 0.1, e, q, n, delta, 1.0);
                    EXPECT_LE(b.contactError, b.contactBound) << "tilt " << tilt << " azimuth " << azimuth;
                    EXPECT_LE(b.velocityError, b.velocityBound) << "tilt " << tilt << " azimuth " << azimuth;
                    ++bounces;
                }
        }
    EXPECT_EQ(bounces, 96);
}

TEST(ParticlesTest, ParticleStreamOntoASphereReflectsAboutTheSphereNormal) {
    // A vertical stream onto a sphere of radius 20 cells (a UV sphere of 96 x 192 quads: its
    // facets stay within R (1 - cos(pi / 96)) = 0.011 cells of the sphere, added to the contact
    // bound), offsets up to 0.8 R from the axis (incidence up to 53 degrees). At twice the
    // resolution the same stream must still meet its (halved) bounds.
    for (const int64_t cells : {64, 128}) {
        const double h = 64.0 / double(cells), R = 20;
        const Vec3d centre{32.1, 31.7, 30.2};
        const Mesh sphere = test::makeUvSphere(centre, R, 96, 192);
        const ParticleCollider collider(voxelize(
            sphere.view(), Frame::orthographic({{0, 0, 0}, {64, 64, 64}}, Axis::Z, cells, cells, cells)));
        double worstContact = 0, worstVelocity = 0;
        int bounces = 0;
        for (int i = -4; i <= 4; ++i)
            for (int j = -4; j <= 4; ++j) {
                const double dx = 0.2 * R * i + 0.37, dy = 0.2 * R * j - 0.21;
                if (dx * dx + dy * dy > 0.64 * R * R) continue;
                const Vec3d q = centre + Vec3d{dx, dy, std::sqrt(R * R - dx * dx - dy * dy)};
                const Vec3d n = (q - centre) / R;
                const double tessellation = R * (1 - std::cos(M_PI / 96));
                // The contact's bound first, then the normal's: the true normal turns by at
                // most |S - Q| / (R - |S - Q|) between the contact and the stop.
                const double cosTheta = n.z;
                const double contact =
                    ((std::sqrt(3.0) / 2 + std::sqrt(3.0) * 1e-3) / cosTheta + std::sqrt(3.0) * 1e-3) * h +
                    tessellation / cosTheta;
                const double delta = kPlaneNormalDegrees * M_PI / 180 + contact / (R - contact) + 4 * h / R;
                Bounce b =
                    bounceOnce(collider, q + Vec3d{0, 0, 3 * h}, {0, 0, -60 * h}, 0.1, 1.0, q, n, delta, h);
                b.contactBound += tessellation / cosTheta;
                EXPECT_LE(b.contactError, b.contactBound) << "offset " << dx << ", " << dy << " at " << cells;
                EXPECT_LE(b.velocityError, b.velocityBound)
                    << "offset " << dx << ", " << dy << " at " << cells;
                worstContact = std::max(worstContact, b.contactError / h);
                worstVelocity = std::max(worstVelocity, b.turnDegrees);
                ++bounces;
            }
        EXPECT_GE(bounces, 40);
        std::cout << "[ particles ] sphere at " << cells << "^3: worst contact " << worstContact
                  << " cells, worst reflection " << worstVelocity << " degrees\n";
    }
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
