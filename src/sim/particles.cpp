// voxfx — particles colliding with solid grids (Eisemann & Décoret, "Single-Pass GPU Solid
// Voxelization for Real-Time Applications", GI 2008, §7 "Particle collisions": particles query the
// solid grid, bounce with the density-gradient normal on entering a filled cell, and the grid can
// be re-voxelized every frame). Paths are walked with the one 3D DDA (voxfx/dda.hpp).
#include "voxfx/particles.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "voxfx/dda.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

void Particles::resize(std::size_t n) {
    for (auto* a : {&px, &py, &pz, &vx, &vy, &vz}) a->resize(n, 0.0f);
}

void Particles::push(const Vec3f& p, const Vec3f& v) {
    px.push_back(p.x);
    py.push_back(p.y);
    pz.push_back(p.z);
    vx.push_back(v.x);
    vy.push_back(v.y);
    vz.push_back(v.z);
}

namespace {

void requireUniformOrthographic(const Frame& f) {
    if (f.isPerspective() || f.isOriented() || f.slicing() != Slicing::Uniform)
        fail("particle collisions need an axis-aligned orthographic, uniformly sliced grid");
}

// World <-> grid coordinates of an orthographic frame: per grid axis a world axis, an origin and
// a scale (plain numbers, so the kernel does not call into Frame).
struct GridMap {
    int axis[3];        // world axis of grid x, y, slice
    double lo[3];       // world coordinate of grid 0 along that axis
    double perWorld[3]; // grid units per world unit
    double perGrid[3];  // world units per grid unit
    int64_t dims[3];

    explicit GridMap(const Frame& f) {
        const Axis a = f.axis();
        axis[0] = columnXAxis(a);
        axis[1] = columnYAxis(a);
        axis[2] = sliceAxis(a);
        dims[0] = f.width();
        dims[1] = f.height();
        dims[2] = f.depth();
        const Vec3d ext = f.box().extent();
        for (int i = 0; i < 3; ++i) {
            lo[i] = f.box().lo[axis[i]];
            perWorld[i] = double(dims[i]) / ext[axis[i]];
            perGrid[i] = ext[axis[i]] / double(dims[i]);
        }
    }
    Vec3d toGrid(const Vec3d& p) const {
        return {(p[axis[0]] - lo[0]) * perWorld[0], (p[axis[1]] - lo[1]) * perWorld[1],
                (p[axis[2]] - lo[2]) * perWorld[2]};
    }
    Vec3d toWorld(const Vec3d& g) const {
        Vec3d p;
        for (int i = 0; i < 3; ++i) p[axis[i]] = lo[i] + g[i] * perGrid[i];
        return p;
    }
    bool inside(const Vec3d& g) const {
        return g.x >= 0 && g.y >= 0 && g.z >= 0 && g.x < double(dims[0]) && g.y < double(dims[1]) &&
               g.z < double(dims[2]);
    }
};

bool filledCell(const BitGrid& bits, int64_t x, int64_t y, int64_t s) {
    return (bits.column(x, y)[s >> 6] >> (s & 63)) & 1u;
}

// Filled test of a grid point (outside the grid: `outside`). NaN compares false everywhere and
// counts as outside.
bool filledPoint(const BitGrid& bits, const GridMap& m, const Vec3d& g, bool outside) {
    if (!m.inside(g)) return outside;
    return filledCell(bits, std::min<int64_t>(int64_t(g.x), m.dims[0] - 1),
                      std::min<int64_t>(int64_t(g.y), m.dims[1] - 1),
                      std::min<int64_t>(int64_t(g.z), m.dims[2] - 1));
}

struct Hit {
    bool hit = false;
    bool fromOutside = false;    // entered the grid straight into a filled cell
    double t = 1;                // parameter of the entry into the filled cell (or the wall)
    int axis = 0;                // grid axis of the face crossed
    int dir = 0;                 // direction of travel along that axis (+1 / -1)
    int64_t cell[3] = {0, 0, 0}; // last free cell inside the grid (unless fromOutside)
};

// First filled cell (or wall) along a -> b in grid coordinates; the start cell is free.
Hit firstHit(const BitGrid& bits, const GridMap& m, const Vec3d& a, const Vec3d& b, bool walls) {
    Hit h;
    // Most steps end in the cell they start in (a free one): nothing to walk.
    if (m.inside(a) && std::floor(a.x) == std::floor(b.x) && std::floor(a.y) == std::floor(b.y) &&
        std::floor(a.z) == std::floor(b.z))
        return h;
    const Vec3d d = b - a;
    const DdaClip clip = clipToGrid(a, d, m.dims);
    const bool startsInside = m.inside(a);
    if (clip.empty() && !(startsInside && walls)) return h;

    // Inside, the walk starts in the (free) cell that holds the particle; from outside, in the
    // cell it enters first.
    Dda walk = Dda::start(a, d, m.dims, startsInside ? 0.0 : clip.t0,
                          startsInside ? DdaStart::Containing : DdaStart::AlongSegment);
    if (!startsInside && filledCell(bits, walk.cell[0], walk.cell[1], walk.cell[2])) {
        h.hit = true;
        h.fromOutside = true;
        h.t = clip.t0;
        h.axis = clip.entryAxis < 0 ? 0 : clip.entryAxis;
        h.dir = int(walk.step[h.axis]);
        return h;
    }
    for (;;) {
        const int axis = walk.nextAxis();
        const double tNext = walk.tMax[axis];
        if (tNext >= 1.0) return h; // the segment ends in this (free) cell
        const int64_t nextIdx = walk.neighbour(axis);
        if (!walk.inside(axis, nextIdx)) {
            if (!walls) return h; // leaves the grid: free flight
        } else {
            int64_t probe[3] = {walk.cell[0], walk.cell[1], walk.cell[2]};
            probe[axis] = nextIdx;
            if (!filledCell(bits, probe[0], probe[1], probe[2])) {
                walk.advance(axis);
                continue;
            }
        }
        h.hit = true;
        h.t = std::max(0.0, tNext);
        h.axis = axis;
        h.dir = int(walk.step[axis]);
        std::copy(walk.cell, walk.cell + 3, h.cell);
        return h;
    }
}

// Keeps a point a hair inside a cell (so rounding cannot put it on the neighbour's side).
constexpr double kInset = 1e-3;

double clampIntoCell(double g, int64_t c) {
    return std::clamp(g, double(c) + kInset, double(c + 1) - kInset);
}

// Moves a point in a filled cell to the nearest free cell within 4 cells (Chebyshev shells,
// closest point of each free cell, first in scan order on ties). Returns false when none.
bool pushOut(const BitGrid& bits, const GridMap& m, Vec3d& g, bool walls) {
    const int64_t c[3] = {std::clamp<int64_t>(int64_t(std::floor(g.x)), 0, m.dims[0] - 1),
                          std::clamp<int64_t>(int64_t(std::floor(g.y)), 0, m.dims[1] - 1),
                          std::clamp<int64_t>(int64_t(std::floor(g.z)), 0, m.dims[2] - 1)};
    double best = std::numeric_limits<double>::infinity();
    Vec3d bestPoint;
    for (int64_t r = 1; r <= 4 && !std::isfinite(best); ++r)
        for (int64_t dz = -r; dz <= r; ++dz)
            for (int64_t dy = -r; dy <= r; ++dy)
                for (int64_t dx = -r; dx <= r; ++dx) {
                    if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
                    const int64_t q[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
                    const bool in = q[0] >= 0 && q[1] >= 0 && q[2] >= 0 && q[0] < m.dims[0] &&
                                    q[1] < m.dims[1] && q[2] < m.dims[2];
                    if (in ? filledCell(bits, q[0], q[1], q[2]) : walls) continue;
                    Vec3d p;
                    for (int i = 0; i < 3; ++i) p[i] = clampIntoCell(g[i], q[i]);
                    const double dist = dot(p - g, p - g);
                    if (dist < best) {
                        best = dist;
                        bestPoint = p;
                    }
                }
    if (!std::isfinite(best)) return false;
    g = bestPoint;
    return true;
}

struct Kernel {
    const BitGrid& bits;
    const DensityGrid& density;
    const Frame& frame;
    GridMap map;
    Vec3d gravity;
    double dt, restitution, friction;
    bool walls;
    double densityScale; // fine grid -> density grid coordinates

    Vec3d gridNormalToWorld(const Vec3d& n) const {
        Vec3d w;
        for (int i = 0; i < 3; ++i) w[map.axis[i]] = n[i] * map.perWorld[i];
        return normalize(w);
    }

    // Prefetches the grid word holding a particle's cell (a hint; nothing happens outside).
    void prefetch(float fx, float fy, float fz) const {
        const Vec3d g = map.toGrid(Vec3d{fx, fy, fz});
        if (!map.inside(g)) return;
        __builtin_prefetch(bits.column(int64_t(g.x), int64_t(g.y)) + (int64_t(g.z) >> 6));
    }

    // One particle; returns 1 on a bounce. `pushed`/`stuck` count start-of-step repairs.
    int step(float& fx, float& fy, float& fz, float& fvx, float& fvy, float& fvz, int64_t& pushed,
             int64_t& stuck) const {
        Vec3d p{fx, fy, fz}, v{fvx, fvy, fvz};
        Vec3d g = map.toGrid(p);
        if (filledPoint(bits, map, g, false)) {
            if (!pushOut(bits, map, g, walls)) {
                ++stuck;
                return 0;
            }
            ++pushed;
            const Vec3d moved = map.toWorld(g) - p;
            p = map.toWorld(g);
            // Drop the velocity component pointing back into the solid.
            const Vec3d nm = normalize(moved);
            const double vn = dot(v, nm);
            if (vn < 0) v -= nm * vn;
            fx = float(p.x);
            fy = float(p.y);
            fz = float(p.z);
            if (filledPoint(bits, map, map.toGrid(Vec3d{fx, fy, fz}), walls)) {
                ++stuck;
                return 0;
            }
            p = Vec3d{fx, fy, fz};
            g = map.toGrid(p);
        }
        // Semi-implicit Euler.
        v += gravity * dt;
        const Vec3d p1 = p + v * dt;
        const Hit h = firstHit(bits, map, g, map.toGrid(p1), walls);
        Vec3d pNew = p1, n;
        if (h.hit) {
            const Vec3d gHit = g + (map.toGrid(p1) - g) * h.t;
            Vec3d gNew = gHit;
            if (h.fromOutside) {
                // Stop just outside the face it was about to enter.
                gNew[h.axis] = (h.dir > 0 ? 0.0 : double(map.dims[h.axis])) - h.dir * kInset;
            } else {
                for (int i = 0; i < 3; ++i) gNew[i] = clampIntoCell(gNew[i], h.cell[i]);
            }
            pNew = map.toWorld(gNew);
            // The density normal where the particle touches; the crossed face when it is
            // degenerate, points along the motion, or the hit is a wall.
            const bool wallHit = h.axis >= 0 && !h.fromOutside &&
                                 (h.cell[h.axis] + h.dir < 0 || h.cell[h.axis] + h.dir >= map.dims[h.axis]);
            if (!wallHit) n = gridNormalToWorld(Vec3d(sampleNormal(density, gHit * densityScale)));
            if (wallHit || !(dot(n, n) > 0) || dot(n, v) >= 0) {
                Vec3d face;
                face[h.axis] = -double(h.dir);
                n = gridNormalToWorld(face);
            }
        }
        // Store as float; a rounding that lands in a filled cell keeps the previous position.
        float nx = float(pNew.x), ny = float(pNew.y), nz = float(pNew.z);
        if (filledPoint(bits, map, map.toGrid(Vec3d{nx, ny, nz}), walls)) {
            nx = fx;
            ny = fy;
            nz = fz;
        }
        const Vec3d pFinal{nx, ny, nz};
        // Energy budget: stopping short of p1 keeps potential energy -gravity . (pFinal - p1)
        // that the kinetic energy must pay for.
        const double gained = -dot(gravity, pFinal - p1);
        const double k1 = 0.5 * dot(v, v);
        if (gained > 0 && k1 > 0) v *= std::sqrt(std::max(0.0, k1 - gained) / k1);
        if (h.hit) {
            const double vn = dot(v, n);
            if (vn < 0) v = (v - n * vn) * (1.0 - friction) - n * (restitution * vn);
        }
        fx = nx;
        fy = ny;
        fz = nz;
        fvx = float(v.x);
        fvy = float(v.y);
        fvz = float(v.z);
        return h.hit ? 1 : 0;
    }
};

} // namespace

ParticleCollider::ParticleCollider(VoxelGrid grid, int densityLevel) {
    requireUniformOrthographic(grid.frame);
    if (grid.bits.empty()) fail("particle collider: the grid is empty");
    if (grid.bits.width() != grid.frame.width() || grid.bits.height() != grid.frame.height() ||
        grid.bits.depth() != grid.frame.depth())
        fail("particle collider: the grid's bits do not match its frame");
    DensityOptions d;
    d.level = densityLevel;
    density_ = computeDensity(grid.bits, d);
    grid_ = std::move(grid);
}

void ParticleCollider::update(BitGrid bits) {
    if (bits.width() != grid_.bits.width() || bits.height() != grid_.bits.height() ||
        bits.depth() != grid_.bits.depth())
        fail("particle collider update: the new grid is ", bits.width(), " x ", bits.height(), " x ",
             bits.depth(), ", the collider's is ", grid_.bits.width(), " x ", grid_.bits.height(), " x ",
             grid_.bits.depth());
    DensityOptions d;
    d.level = density_.level();
    density_ = computeDensity(bits, d);
    grid_.bits = std::move(bits);
}

bool ParticleCollider::filledAt(const Vec3d& world) const {
    const GridMap m(grid_.frame);
    return filledPoint(grid_.bits, m, m.toGrid(world), false);
}

Vec3d ParticleCollider::normalAt(const Vec3d& world) const {
    const GridMap m(grid_.frame);
    const Vec3d g = m.toGrid(world) / double(density_.kernel());
    return worldFromGridNormal(grid_.frame, Vec3d(sampleNormal(density_, g)));
}

StepStats stepParticles(Particles& ps, const ParticleCollider& collider, const ParticleOptions& o) {
    const std::size_t n = ps.size();
    for (const auto* a : {&ps.py, &ps.pz, &ps.vx, &ps.vy, &ps.vz})
        if (a->size() != n) fail("particles: the six arrays must have the same size");
    if (!(o.dt > 0) || !std::isfinite(o.dt)) fail("particles: time step must be positive, got ", o.dt);
    if (!(o.restitution >= 0 && o.restitution <= 2))
        fail("particles: restitution must lie in [0, 2], got ", o.restitution);
    if (!(o.friction >= 0 && o.friction <= 1))
        fail("particles: friction must lie in [0, 1], got ", o.friction);
    if (!isFinite(o.gravity)) fail("particles: gravity must be finite");
    const VoxelGrid& grid = collider.grid();
    const Kernel k{grid.bits,     collider.density(),
                   grid.frame,    GridMap(grid.frame),
                   o.gravity,     o.dt,
                   o.restitution, o.friction,
                   o.boxWalls,    1.0 / double(collider.density().kernel())};
    // Per-chunk counters combined in chunk order (parallelReduce, no allocation): the totals do
    // not depend on the thread count.
    constexpr int64_t kGrain = 8192;
    StepStats total;
    withThreads(o.threads, [&] {
        total = parallelReduce(
            0, int64_t(n), kGrain, StepStats{},
            [&](int64_t b, int64_t e) {
                StepStats s;
                // Grid words are fetched at random places: ask for the word of a particle a few
                // iterations ahead so the cache misses overlap.
                constexpr int64_t kAhead = 12;
                for (int64_t i = b; i < e; ++i) {
                    if (i + kAhead < e) {
                        const auto a = size_t(i + kAhead);
                        k.prefetch(ps.px[a], ps.py[a], ps.pz[a]);
                    }
                    const auto u = size_t(i);
                    s.bounces += k.step(ps.px[u], ps.py[u], ps.pz[u], ps.vx[u], ps.vy[u], ps.vz[u],
                                        s.pushedOut, s.stuck);
                }
                return s;
            },
            [](StepStats a, const StepStats& b) {
                a.bounces += b.bounces;
                a.pushedOut += b.pushedOut;
                a.stuck += b.stuck;
                return a;
            });
    });
    return total;
}

Particles emitParticles(const ParticleCollider& collider, std::size_t count, const Box3d& region,
                        uint64_t seed) {
    const Box3d& gb = collider.grid().frame.box();
    Box3d r = region;
    if (r.empty()) {
        r = gb;
        r.lo.z = gb.hi.z - 0.25 * (gb.hi.z - gb.lo.z);
    }
    r.lo = max(r.lo, gb.lo);
    r.hi = min(r.hi, gb.hi);
    Particles out;
    if (r.empty()) return out;
    out.px.reserve(count);
    out.py.reserve(count);
    out.pz.reserve(count);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    for (std::size_t i = 0; i < count; ++i)
        for (int attempt = 0; attempt < 64; ++attempt) {
            const Vec3d p{r.lo.x + u01(rng) * (r.hi.x - r.lo.x), r.lo.y + u01(rng) * (r.hi.y - r.lo.y),
                          r.lo.z + u01(rng) * (r.hi.z - r.lo.z)};
            const Vec3f pf(p);
            if (collider.filledAt(Vec3d(pf))) continue;
            out.push(pf);
            break;
        }
    // Neighbours in memory step through neighbouring grid words: far fewer cache misses.
    sortParticles(out, collider);
    return out;
}

void sortParticles(Particles& ps, const ParticleCollider& collider) {
    const std::size_t n = ps.size();
    const VoxelGrid& g = collider.grid();
    const GridMap m(g.frame);
    // Key = position of the cell's word in memory (column, then slice); outside the grid last.
    std::vector<std::pair<uint64_t, uint32_t>> order(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3d q = m.toGrid(Vec3d(ps.position(i)));
        uint64_t key = ~uint64_t(0);
        if (m.inside(q))
            key = (uint64_t(int64_t(q.y) * m.dims[0] + int64_t(q.x)) * uint64_t(m.dims[2])) +
                  uint64_t(int64_t(q.z));
        order[i] = {key, uint32_t(i)};
    }
    std::stable_sort(order.begin(), order.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<float> tmp(n);
    for (auto* a : {&ps.px, &ps.py, &ps.pz, &ps.vx, &ps.vy, &ps.vz}) {
        for (std::size_t i = 0; i < n; ++i) tmp[i] = (*a)[order[i].second];
        a->swap(tmp);
    }
}

double particleEnergy(const Particles& ps, const Vec3d& gravity) {
    double e = 0;
    for (std::size_t i = 0; i < ps.size(); ++i) {
        const Vec3d p(ps.position(i)), v(ps.velocity(i));
        e += 0.5 * dot(v, v) - dot(gravity, p);
    }
    return e;
}

Image renderParticles(const Particles& ps, const ParticleCollider& collider, const ParticleImageOptions& o) {
    const VoxelGrid& grid = collider.grid();
    const Box3d& box = grid.frame.box();
    const Vec3d ext = box.extent();
    const int64_t W = std::max<int64_t>(1, o.width);
    const int64_t H = std::max<int64_t>(1, int64_t(std::lround(double(W) * ext.z / ext.x)));
    Image img(W, H, o.background);
    std::vector<double> depth(size_t(W * H), std::numeric_limits<double>::infinity());

    // The camera is a Frame like every other view: orthographic over the grid's box, looking along
    // +y. Its columns run along (z, x) (columnXAxis(Y) = z), one per pixel: pixel (px, py), y
    // down, is column (H - 1 - py, px); the one slice spans the box's depth.
    const Frame camera = Frame::orthographic(box, Axis::Y, H, W, 1);
    // Sliced along world y, columns run along (z, x) too: the first set bit of a column is the
    // front-most filled cell the camera sees.
    const VoxelGrid front = reslice(grid, Axis::Y);
    const Vec3i dims = grid.worldDims();
    const Vec3d cell = grid.frame.cellSize();
    const Vec3d light = normalize(Vec3d{-0.4, -1.0, 0.7});
    const Vec3f base{0.55f, 0.6f, 0.7f};
    parallelFor(0, H, 8, [&](int64_t b, int64_t e) {
        for (int64_t py = b; py < e; ++py)
            for (int64_t px = 0; px < W; ++px) {
                const Vec3d centre = camera.worldFromGrid({double(H - 1 - py) + 0.5, double(px) + 0.5, 0.0});
                const double wx = centre.x, wz = centre.z;
                const int64_t ix = std::clamp<int64_t>(int64_t((wx - box.lo.x) / cell.x), 0, dims.x - 1);
                const int64_t iz = std::clamp<int64_t>(int64_t((wz - box.lo.z) / cell.z), 0, dims.z - 1);
                const uint64_t* col = front.bits.column(iz, ix);
                for (int64_t w = 0; w < front.bits.wordsPerColumn(); ++w) {
                    if (!col[w]) continue;
                    const int64_t iy = w * 64 + std::countr_zero(col[w]);
                    const double wy = box.lo.y + double(iy) * cell.y;
                    depth[size_t(py * W + px)] = wy;
                    const Vec3d nrm = collider.normalAt({wx, wy + 0.5 * cell.y, wz});
                    const double lambert = dot(nrm, nrm) > 0 ? std::max(0.0, dot(nrm, light)) : 0.5;
                    img.at(px, py) = base * float(0.15 + 0.85 * lambert);
                    break;
                }
            }
    });
    // Particles as discs where the camera projects them, hidden where the solid is in front.
    const double r = std::max(0.5, double(o.particleRadius));
    for (std::size_t i = 0; i < ps.size(); ++i) {
        const Vec3d g = camera.gridFromWorld(Vec3d(ps.position(i)));
        const double sx = g.y, sy = double(H) - g.x;
        if (!(sx > -r && sy > -r && sx < double(W) + r && sy < double(H) + r)) continue;
        const int64_t x0 = std::max<int64_t>(0, int64_t(std::floor(sx - r))),
                      x1 = std::min<int64_t>(W - 1, int64_t(std::ceil(sx + r)));
        const int64_t y0 = std::max<int64_t>(0, int64_t(std::floor(sy - r))),
                      y1 = std::min<int64_t>(H - 1, int64_t(std::ceil(sy + r)));
        for (int64_t y = y0; y <= y1; ++y)
            for (int64_t x = x0; x <= x1; ++x) {
                const double dx = double(x) + 0.5 - sx, dy = double(y) + 0.5 - sy;
                if (dx * dx + dy * dy > r * r || double(ps.py[i]) > depth[size_t(y * W + x)]) continue;
                img.at(x, y) = o.particleColor;
            }
    }
    return img;
}

} // namespace voxfx
