// voxfx particles INPUT — particles falling onto a solid grid (GI08 §7), positions per frame as
// PLY or CSV and a picture of the final state.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/image_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/moving_obstacle.hpp"
#include "voxfx/particles.hpp"
#include "voxfx/particles_io.hpp"

namespace voxfx::cli {
namespace {

struct ParticleArgs {
    GridInput in{128, 2};
    std::string output, png;
    int64_t count = 100000, steps = 240, every = 0;
    double dt = 1.0 / 120.0, restitution = 0.5, friction = 0.1, rotate = 0;
    std::vector<double> gravity{0, 0, -9.81}, emit;
    uint64_t seed = 1;
    bool walls = false;
    int64_t imageWidth = 800;
};

// "frames/p_%04d.ply" -> the name of frame n; a name without a conversion is used as is.
std::string frameName(const std::string& pattern, int64_t n) {
    if (pattern.find('%') == std::string::npos) return pattern;
    char buf[4096];
    std::snprintf(buf, sizeof(buf), pattern.c_str(), int(n));
    return buf;
}

void checkPattern(const std::string& pattern) {
    const size_t p = pattern.find('%');
    if (p == std::string::npos) return;
    size_t q = p + 1;
    while (q < pattern.size() && (std::isdigit(static_cast<unsigned char>(pattern[q])) || pattern[q] == '0'))
        ++q;
    if (q >= pattern.size() || pattern[q] != 'd' || pattern.find('%', q) != std::string::npos)
        fail("output pattern '", pattern, "' must hold exactly one %d (e.g. frames/p_%04d.ply)");
}

int runParticles(const ParticleArgs& a) {
    const auto t0 = Clock::now();
    if (!a.output.empty()) checkPattern(a.output);
    if (!a.output.empty()) requireExtension(a.output, {".ply", ".csv"}, "particle frame");
    if (!a.png.empty()) requireExtension(a.png, {".png"}, "picture");
    ParticleOptions po;
    po.gravity = {a.gravity[0], a.gravity[1], a.gravity[2]};
    po.dt = a.dt;
    po.restitution = a.restitution;
    po.friction = a.friction;
    po.boxWalls = a.walls;
    po.threads = a.in.threads;

    // A mesh input with --rotate is a moving obstacle, re-voxelized every step (sim/).
    std::unique_ptr<MovingObstacle> obstacle;
    VoxelGrid grid;
    if (a.rotate != 0) {
        VoxelizeOptions vo = MovingObstacle::autoSolid();
        vo.threads = a.in.threads;
        obstacle = std::make_unique<MovingObstacle>(loadMesh(a.in.path),
                                                    ObstacleMotion{.spinDegreesPerStep = a.rotate}, a.steps,
                                                    toFitOptions(a.in.fit, a.in.choices), vo);
        grid = obstacle->voxelizeAt(0);
    } else {
        grid = loadGridInput(a.in, /*uniform=*/true);
    }
    ParticleCollider collider(std::move(grid));
    Box3d region;
    if (!a.emit.empty()) {
        region.lo = {a.emit[0], a.emit[1], a.emit[2]};
        region.hi = {a.emit[3], a.emit[4], a.emit[5]};
        if (region.empty()) fail("--emit needs min <= max on every axis");
    }
    Particles ps = emitParticles(collider, size_t(a.count), region, a.seed);
    if (ps.size() == 0) fail("no free space to emit particles in (check --emit)");
    const double setupMs = msSince(t0);

    ProgressLine progress("simulating", !a.in.quiet);
    StepStats total;
    double stepMs = 0, voxelMs = 0, writeMs = 0;
    auto writeFrame = [&](int64_t n) {
        const auto tw = Clock::now();
        writeParticles(ps, frameName(a.output, n));
        writeMs += msSince(tw);
    };
    if (!a.output.empty() && a.every > 0) writeFrame(0);
    for (int64_t step = 1; step <= a.steps; ++step) {
        if (obstacle) {
            const auto tv = Clock::now();
            collider.update(std::move(obstacle->voxelizeAt(step).bits));
            voxelMs += msSince(tv);
        }
        const auto ts = Clock::now();
        const StepStats s = stepParticles(ps, collider, po);
        stepMs += msSince(ts);
        total.bounces += s.bounces;
        total.pushedOut += s.pushedOut;
        total.stuck += s.stuck;
        if (!a.output.empty() && a.every > 0 && step % a.every == 0) writeFrame(step);
        if (!progress.update(double(step) / double(a.steps))) fail("cancelled");
    }
    if (!a.output.empty() && (a.every <= 0 || a.steps % a.every != 0)) writeFrame(a.steps);
    progress.done();
    double imageMs = 0;
    if (!a.png.empty()) {
        const auto ti = Clock::now();
        ParticleImageOptions io;
        io.width = a.imageWidth;
        writePng(renderParticles(ps, collider, io), a.png);
        imageMs = msSince(ti);
    }
    if (!a.in.quiet) {
        const Vec3i d = collider.grid().worldDims();
        std::cout << a.in.path << ": " << d.x << " x " << d.y << " x " << d.z << " grid, "
                  << withCommas(int64_t(ps.size())) << " particles, " << a.steps << " steps of " << fmt(a.dt)
                  << " s" << (a.rotate != 0 ? ", mesh re-voxelized every step" : "") << "\n";
        std::cout << "bounces " << withCommas(total.bounces) << ", pushed out " << withCommas(total.pushedOut)
                  << ", stuck " << withCommas(total.stuck) << "; "
                  << fmt(a.steps > 0 ? double(a.steps) / (stepMs / 1000.0) : 0.0) << " steps/s ("
                  << fmt(double(ps.size()) * double(a.steps) / (stepMs / 1000.0) / 1e6)
                  << " M particle-steps/s)\n";
        std::cout << "time: setup " << fmtMs(setupMs) << ", steps " << fmtMs(stepMs);
        if (a.rotate != 0) std::cout << ", re-voxelize " << fmtMs(voxelMs);
        if (!a.output.empty()) std::cout << ", write " << fmtMs(writeMs) << " -> " << a.output;
        if (!a.png.empty()) std::cout << ", image " << fmtMs(imageMs) << " -> " << a.png;
        std::cout << "\n";
    }
    return 0;
}

const char* kParticlesHelp = R"(
Particles start at rest, uniformly over the free cells of --emit (default: the top quarter of
the grid's box along z), and fall under --gravity with a fixed time step (semi-implicit Euler).
A particle whose path enters a filled cell stops at the entry point and bounces about the
density-map normal there: normal velocity x restitution, tangential x (1 - friction). No
particle ever ends a step inside a filled cell; with restitution <= 1 the energy never grows.
--rotate DEG turns a mesh input about the vertical axis by DEG per step and re-voxelizes it
every step (a moving obstacle). Output: -o frames/p_%04d.ply (or .csv) writes frame 0, every
--every steps and the last; without %d only the final state is written. --png renders the
final state seen along +y.)";

const Command kParticles{
    "particles", "Simulate particles bouncing on a grid or mesh; write frames and a picture",
    [](CLI::App& app) {
        app.footer(kParticlesHelp);
        auto a = std::make_shared<ParticleArgs>();
        app.add_option("-o,--output", a->output, "Positions per frame: PATTERN with %d, .ply or .csv");
        app.add_option("--png", a->png, "Picture of the final state (.png)");
        app.add_option("-n,--count", a->count, "Number of particles (default 100000)")
            ->check(CLI::Range(int64_t(1), int64_t(1) << 32))
            ->default_val(100000);
        app.add_option("--steps", a->steps, "Time steps (default 240)")
            ->check(CLI::NonNegativeNumber)
            ->default_val(240);
        app.add_option("--every", a->every, "Write a frame every N steps (0: only the last)")
            ->check(CLI::NonNegativeNumber)
            ->default_val(0);
        app.add_option("--dt", a->dt, "Time step in seconds (default 1/120)")->check(CLI::PositiveNumber);
        app.add_option("--gravity", a->gravity, "Gravity vector, world units / s^2 (default 0 0 -9.81)")
            ->expected(3);
        app.add_option("--restitution", a->restitution,
                       "Normal velocity kept on a bounce, 0..2 (default 0.5)")
            ->check(CLI::Range(0.0, 2.0));
        app.add_option("--friction", a->friction, "Tangential velocity lost on a bounce, 0..1 (default 0.1)")
            ->check(CLI::Range(0.0, 1.0));
        app.add_flag("--walls", a->walls, "The grid's box is a closed container");
        app.add_option("--emit", a->emit, "Emission box: xmin ymin zmin xmax ymax zmax (world units)")
            ->expected(6);
        app.add_option("--seed", a->seed, "Random seed of the emission (default 1)");
        app.add_option("--rotate", a->rotate, "Mesh input: degrees per step about the vertical axis");
        app.add_option("--image-width", a->imageWidth, "Picture width in pixels (default 800)")
            ->check(CLI::Range(int64_t(16), int64_t(16384)));
        addGridInputOptions(app, a->in);
        return std::function<int()>([a] { return runParticles(*a); });
    }};

} // namespace
} // namespace voxfx::cli
