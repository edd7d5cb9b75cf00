// voxfx — surface meshes of grids by marching cubes (W. E. Lorensen and H. E. Cline, "Marching
// Cubes: A High Resolution 3D Surface Construction Algorithm", SIGGRAPH 1987, §3), with the
// face ambiguity resolved by the asymptotic decider (G. M. Nielson and B. Hamann, "The Asymptotic
// Decider", IEEE Visualization 1991, §3). Instead of the 256-case triangle table, each cube's
// polygons are assembled from its face segments (the table's content, derived per cube), which
// makes neighbouring cubes agree on shared faces by construction. Field = GI08 §6 density.
#include "voxfx/surface_mesh.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <functional>

#include "voxfx/parallel.hpp"

namespace voxfx {

const char* toString(SurfaceSource s) { return enumName(s, kSurfaceSourceNames); }

SurfaceSource parseSurfaceSource(const std::string& name) {
    return parseEnum<SurfaceSource>(name, "surface source", kSurfaceSourceNames);
}

namespace {

// Cube corner c sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1). Edge e = axis * 4 + idx joins
// the corner `edgeLower(e)` (bit `axis` clear) to the corner with that bit set.
struct CubeTables {
    int faceCorners[6][4]; // counter-clockwise seen from outside the cube
    int edgeOf[8][8];      // edge joining two corners that differ in one bit, else -1
    int edgeLower[12];
    int edgeFaces[12]; // bit f set when edge e lies on face f (two faces per edge)
    CubeTables() {
        for (auto& row : edgeOf)
            for (int& e : row) e = -1;
        for (int axis = 0; axis < 3; ++axis) {
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            for (int idx = 0; idx < 4; ++idx) {
                const int lower = ((idx & 1) << u) | (((idx >> 1) & 1) << w);
                const int e = axis * 4 + idx;
                edgeLower[e] = lower;
                edgeFaces[e] = (1 << (u * 2 + ((lower >> u) & 1))) | (1 << (w * 2 + ((lower >> w) & 1)));
                edgeOf[lower][lower | (1 << axis)] = edgeOf[lower | (1 << axis)][lower] = e;
            }
            // Face with outward normal +axis: (u, w) = (0,0) (1,0) (1,1) (0,1) is counter-clockwise
            // about +axis since (e_u, e_w, e_axis) is right-handed; the -axis face runs reversed.
            static const int ccw[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
            for (int side = 0; side < 2; ++side)
                for (int m = 0; m < 4; ++m) {
                    const int* uw = ccw[side ? m : (4 - m) % 4];
                    faceCorners[axis * 2 + side][m] = (uw[0] << u) | (uw[1] << w) | (side << axis);
                }
        }
    }
};
const CubeTables kCube;

// The polygons of one cube as loops of local edges. `in` bit c = corner c inside, `v` the values.
// On every face, crossings are visited counter-clockwise (seen from outside); a segment runs
// from an entry (outside -> inside corner) to an exit (inside -> outside), which puts the inside
// on a fixed side and makes the joined loops face outwards. On an ambiguous face (inside corners
// on a diagonal) the asymptotic decider compares the bilinear saddle value (ac - bd) / (a + c -
// b - d) with iso: above, the inside corners connect and the segments cut off the outside ones.
// Returns the number of loops; loops are written to `loopEdges` with lengths in `loopLen`.
int cubeLoops(unsigned in, const float v[8], float iso, int loopEdges[12], int loopLen[4]) {
    int next[12];
    std::fill(next, next + 12, -1);
    for (const auto& face : kCube.faceCorners) {
        int x[4], crossings = 0;
        bool entry[4];
        for (int m = 0; m < 4; ++m) {
            const int p = face[m], q = face[(m + 1) & 3];
            const bool ip = (in >> p) & 1u, iq = (in >> q) & 1u;
            x[m] = ip != iq ? kCube.edgeOf[p][q] : -1;
            entry[m] = !ip && iq;
            crossings += ip != iq;
        }
        if (crossings == 2) {
            int from = -1, to = -1;
            for (int m = 0; m < 4; ++m)
                if (x[m] >= 0) (entry[m] ? from : to) = x[m];
            next[from] = to;
        } else if (crossings == 4) {
            // Inside corners are face[0] and face[2], or face[1] and face[3].
            const int i0 = ((in >> face[0]) & 1u) ? 0 : 1;
            const float a = v[face[i0]], c = v[face[i0 + 2]], b = v[face[i0 + 1]], d = v[face[(i0 + 3) & 3]];
            // Symmetric in (a, c) and (b, d), so both cubes sharing the face decide alike.
            const bool connected = a * c - b * d > iso * ((a + c) - (b + d));
            for (int m = 0; m < 4; ++m)
                if (entry[m]) next[x[m]] = connected ? x[(m + 3) & 3] : x[(m + 1) & 3];
        }
    }
    bool used[12] = {};
    int loops = 0, n = 0;
    for (int e = 0; e < 12; ++e) {
        if (next[e] < 0 || used[e]) continue;
        int len = 0;
        for (int cur = e; !used[cur]; cur = next[cur]) {
            used[cur] = true;
            loopEdges[n + len++] = cur;
        }
        loopLen[loops++] = len;
        n += len;
    }
    return loops;
}

// A field of samples at cell centres, 0 outside [0, n): value(i, j, k) in [0, 1]. Sample i sits
// at fine-grid coordinate (i + 0.5) * spacing.
struct Field {
    int64_t nx = 0, ny = 0, nz = 0;
    double spacing = 1;
    std::function<float(int64_t, int64_t, int64_t)> valueInside; // called only inside the grid
    float value(int64_t i, int64_t j, int64_t k) const {
        return (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) ? 0.0f : valueInside(i, j, k);
    }
    Vec3d gradient(int64_t i, int64_t j, int64_t k) const {
        return {0.5 * (value(i + 1, j, k) - value(i - 1, j, k)),
                0.5 * (value(i, j + 1, k) - value(i, j - 1, k)),
                0.5 * (value(i, j, k + 1) - value(i, j, k - 1))};
    }
};

SurfaceMesh marchingCubes(const Field& f, const Frame& frame, float iso) {
    SurfaceMesh mesh;
    // Samples -1 .. n along each axis (the outer ring is the zero border): layer arrays of
    // (nx + 2) x (ny + 2), index (j + 1) * sx + (i + 1).
    const int64_t sx = f.nx + 2, sy = f.ny + 2, layer = sx * sy;
    std::vector<float> values[2] = {std::vector<float>(size_t(layer)), std::vector<float>(size_t(layer))};
    // Vertex ids of edges: x and y edges per sample layer (two layers), z edges of the cube layer.
    std::vector<int64_t> ex[2], ey[2], ez(size_t(layer), -1);
    for (int p = 0; p < 2; ++p) {
        ex[p].assign(size_t(layer), -1);
        ey[p].assign(size_t(layer), -1);
    }
    auto fillLayer = [&](int64_t k, std::vector<float>& dst) {
        parallelFor(0, sy, 64, [&](int64_t b, int64_t e) {
            for (int64_t jj = b; jj < e; ++jj)
                for (int64_t ii = 0; ii < sx; ++ii) dst[size_t(jj * sx + ii)] = f.value(ii - 1, jj - 1, k);
        });
    };
    auto gridPoint = [&](int64_t i, int64_t j, int64_t k) {
        return Vec3d{(double(i) + 0.5) * f.spacing, (double(j) + 0.5) * f.spacing,
                     (double(k) + 0.5) * f.spacing};
    };

    fillLayer(-1, values[0]);
    for (int64_t k = -1; k < f.nz; ++k) {
        const int lo = int((k + 1) & 1), hi = lo ^ 1; // parity slots of sample layers k, k + 1
        fillLayer(k + 1, values[hi]);
        std::fill(ex[hi].begin(), ex[hi].end(), -1);
        std::fill(ey[hi].begin(), ey[hi].end(), -1);
        std::fill(ez.begin(), ez.end(), -1);
        const float* v0 = values[lo].data();
        const float* v1 = values[hi].data();

        // Vertex of local edge e of cube (i, j, k): created once, shared by the cubes around it.
        auto vertex = [&](int64_t i, int64_t j, int e, const float cv[8]) -> uint32_t {
            const int axis = e >> 2, lower = kCube.edgeLower[e], upper = lower | (1 << axis);
            const int64_t li = i + (lower & 1), lj = j + ((lower >> 1) & 1), lk = k + ((lower >> 2) & 1);
            const size_t slot = size_t((lj + 1) * sx + (li + 1));
            int64_t& id = axis == 0 ? ex[(lower >> 2) ? hi : lo][slot]
                                    : (axis == 1 ? ey[(lower >> 2) ? hi : lo][slot] : ez[slot]);
            if (id >= 0) return uint32_t(id);
            const float a = cv[lower], b = cv[upper];
            // Kept 1% away from the edge's ends, so vertices of different edges never coincide.
            const double t = std::clamp(double(iso - a) / double(b - a), 0.01, 0.99);
            Vec3d g = gridPoint(li, lj, lk);
            g[axis] += t * f.spacing;
            const Vec3d ga = f.gradient(li, lj, lk);
            const Vec3d gb = f.gradient(li + (axis == 0), lj + (axis == 1), lk + (axis == 2));
            Vec3d n = -(ga + (gb - ga) * t);
            if (!(length(n) > 0)) n[axis] = a > iso ? 1.0 : -1.0; // flat field: from inside to outside
            id = int64_t(mesh.positions.size());
            mesh.positions.push_back(Vec3f(frame.worldFromGrid(g)));
            mesh.normals.push_back(Vec3f(worldFromGridNormal(frame, n)));
            return uint32_t(id);
        };

        for (int64_t j = -1; j < f.ny; ++j)
            for (int64_t i = -1; i < f.nx; ++i) {
                const size_t s00 = size_t((j + 1) * sx + (i + 1));
                const float cv[8] = {v0[s00], v0[s00 + 1], v0[s00 + sx], v0[s00 + sx + 1],
                                     v1[s00], v1[s00 + 1], v1[s00 + sx], v1[s00 + sx + 1]};
                unsigned in = 0;
                for (int c = 0; c < 8; ++c) in |= unsigned(cv[c] > iso) << c;
                if (in == 0 || in == 0xFF) continue;
                int loopEdges[12], loopLen[4];
                const int loops = cubeLoops(in, cv, iso, loopEdges, loopLen);
                for (int l = 0, base = 0; l < loops; base += loopLen[l++]) {
                    const int len = loopLen[l];
                    const int* e = loopEdges + base;
                    uint32_t ids[12];
                    for (int m = 0; m < len; ++m) ids[m] = vertex(i, j, e[m], cv);
                    // A fan from v_start whose diagonals never join two vertices of one cube
                    // face: such an edge could be chosen by the neighbour across that face as
                    // well and end up shared by four triangles. Loops through an ambiguous face
                    // may have no such start; they get a vertex at their centroid instead.
                    int start = -1;
                    for (int st = 0; st < len && start < 0; ++st) {
                        bool ok = true;
                        for (int m = 2; m + 1 < len && ok; ++m)
                            ok = !(kCube.edgeFaces[e[st]] & kCube.edgeFaces[e[(st + m) % len]]);
                        if (ok) start = st;
                    }
                    if (start >= 0) {
                        for (int m = 1; m + 1 < len; ++m)
                            mesh.indices.insert(mesh.indices.end(), {ids[start], ids[(start + m) % len],
                                                                     ids[(start + m + 1) % len]});
                        continue;
                    }
                    Vec3d centre, normal;
                    for (int m = 0; m < len; ++m) {
                        centre += Vec3d(mesh.positions[ids[m]]);
                        normal += Vec3d(mesh.normals[ids[m]]);
                    }
                    const auto c = uint32_t(mesh.positions.size());
                    mesh.positions.push_back(Vec3f(centre / double(len)));
                    mesh.normals.push_back(Vec3f(normalize(normal)));
                    for (int m = 0; m < len; ++m)
                        mesh.indices.insert(mesh.indices.end(), {c, ids[m], ids[(m + 1) % len]});
                }
            }
    }
    return mesh;
}

void requireUniformOrthographic(const Frame& frame) {
    if (frame.isPerspective() || frame.isOriented() || frame.slicing() != Slicing::Uniform)
        fail("surface extraction needs an axis-aligned orthographic, uniformly sliced grid");
}

void checkIso(float iso) {
    if (!(iso > 0.0f && iso < 1.0f)) fail("surface iso value must lie in (0, 1), got ", iso);
}

} // namespace

SurfaceMesh extractSurface(const DensityGrid& density, const Frame& fineFrame, float iso) {
    requireUniformOrthographic(fineFrame);
    checkIso(iso);
    if (density.empty()) return {};
    Field f;
    f.nx = density.width();
    f.ny = density.height();
    f.nz = density.depth();
    f.spacing = double(density.kernel());
    const float scale = 1.0f / float(density.maxCount());
    f.valueInside = [&](int64_t i, int64_t j, int64_t k) { return float(density.count(i, j, k)) * scale; };
    return marchingCubes(f, fineFrame, iso);
}

SurfaceMesh extractSurface(const VoxelGrid& grid, const SurfaceOptions& options) {
    requireUniformOrthographic(grid.frame);
    checkIso(options.iso);
    if (grid.bits.empty()) return {};
    if (options.source == SurfaceSource::Density) {
        DensityOptions d;
        d.level = options.level;
        d.threads = options.threads;
        const DensityGrid density = computeDensity(grid.bits, d);
        SurfaceMesh out;
        withThreads(options.threads, [&] { out = extractSurface(density, grid.frame, options.iso); });
        return out;
    }
    Field f;
    f.nx = grid.bits.width();
    f.ny = grid.bits.height();
    f.nz = grid.bits.depth();
    f.valueInside = [&](int64_t i, int64_t j, int64_t k) { return grid.bits.get(i, j, k) ? 1.0f : 0.0f; };
    SurfaceMesh out;
    withThreads(options.threads, [&] { out = marchingCubes(f, grid.frame, options.iso); });
    return out;
}

} // namespace voxfx
