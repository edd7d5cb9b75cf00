// voxfx — mesh checks: bounds, validation, degenerate triangles and edge topology.
//
// The exact collinearity test follows the idea of Shewchuk, "Adaptive Precision Floating-Point
// Arithmetic and Fast Robust Geometric Predicates" (1997): a cheap filter with an error bound
// (section 4.3), then an exact expansion sum (section 2, Grow-Expansion with zero elimination)
// when the filter cannot decide.
#include "voxfx/mesh.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <vector>

#include "core/scratch.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

namespace {

// Position of vertex i as floats, read through the view's stride.
inline const float* vertexPtr(const MeshView& mesh, std::size_t i) {
    return reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(mesh.positions) +
                                          i * mesh.positionStride);
}

// Knuth's Two-Sum: s + err == a + b exactly.
inline void twoSum(double a, double b, double& s, double& err) {
    s = a + b;
    double bv = s - a;
    double av = s - bv;
    err = (a - av) + (b - bv);
}

// Exact test of a*b + c*d + e*f + g*h + i*j + k*l == 0 for float inputs: every product of two
// floats is exact in double (24 + 24 bits <= 53, exponent range far inside double's), and the
// sum is accumulated as a nonoverlapping expansion, whose value is zero iff it has no nonzero
// component. Products being exact also makes any FMA contraction harmless.
bool exactSumIsZero(const std::array<double, 6>& terms) {
    std::array<double, 6> e{};
    int n = 0;
    for (double t : terms) {
        double q = t;
        int m = 0;
        for (int i = 0; i < n; ++i) {
            double s, err;
            twoSum(q, e[i], s, err);
            if (err != 0) e[m++] = err;
            q = s;
        }
        if (q != 0) e[m++] = q;
        n = m;
    }
    return n == 0;
}

// Exact orientation of the 2D points (a0,a1), (b0,b1), (c0,c1) projected on one coordinate plane:
// true when they are collinear.
bool collinear2d(float a0, float a1, float b0, float b1, float c0, float c1) {
    // Filter: the determinant in double with Shewchuk's bound for orient2d (his ccwerrboundA is
    // (3 + 16 eps) eps; we take 8 eps to leave room for a contracted multiply-add).
    double left = (double(b0) - a0) * (double(c1) - a1);
    double right = (double(b1) - a1) * (double(c0) - a0);
    double det = left - right;
    constexpr double kEps = 1.1102230246251565e-16; // 2^-53
    if (std::fabs(det) > 8 * kEps * (std::fabs(left) + std::fabs(right))) return false;
    // det = b0 c1 - b0 a1 - a0 c1 - b1 c0 + b1 a0 + a1 c0, each product exact in double.
    return exactSumIsZero({double(b0) * c1, -(double(b0) * a1), -(double(a0) * c1), -(double(b1) * c0),
                           double(b1) * a0, double(a1) * c0});
}

// Exactly zero area: the cross product of (b - a) and (c - a) vanishes in all three components.
bool zeroArea(const float* a, const float* b, const float* c) {
    return collinear2d(a[0], a[1], b[0], b[1], c[0], c[1]) &&
           collinear2d(a[1], a[2], b[1], b[2], c[1], c[2]) && collinear2d(a[2], a[0], b[2], b[0], c[2], c[0]);
}

constexpr std::size_t kMaxMergedVertices = 0xFFFFFFFFu;

// Maps each of the first n vertices to the first vertex with a bit-identical position (after
// turning -0 into +0, the same point), in O(n) with an open-addressing hash table.
detail::PageVector<uint32_t> mergeIdenticalPositions(const MeshView& mesh, std::size_t n) {
    detail::PageVector<uint32_t> remap = detail::Scratch<uint32_t>::take(n);
    remap.resize(n);
    auto key = [&](std::size_t v) {
        const float* p = vertexPtr(mesh, v);
        std::array<uint32_t, 3> k;
        for (int i = 0; i < 3; ++i) k[i] = std::bit_cast<uint32_t>(p[i] + 0.0f); // -0 + 0 = +0
        return k;
    };
    const std::size_t capacity = std::bit_ceil(2 * n);
    const std::size_t mask = capacity - 1;
    constexpr uint32_t kEmpty = ~uint32_t(0);
    detail::PageVector<uint32_t> table = detail::Scratch<uint32_t>::take(capacity);
    table.assign(capacity, kEmpty);
    for (std::size_t v = 0; v < n; ++v) {
        const auto k = key(v);
        // Multiplicative hash of the 96 bits (odd 64-bit constants of xxHash), high bits folded in.
        uint64_t h = (uint64_t(k[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(k[1]) * 0xC2B2AE3D27D4EB4Full) ^
                     (uint64_t(k[2]) * 0x165667B19E3779F9ull);
        h ^= h >> 29;
        std::size_t slot = std::size_t(h) & mask;
        for (;;) {
            uint32_t other = table[slot];
            if (other == kEmpty) {
                table[slot] = uint32_t(v);
                remap[v] = uint32_t(v);
                break;
            }
            if (key(other) == k) {
                remap[v] = other;
                break;
            }
            slot = (slot + 1) & mask;
        }
    }
    detail::Scratch<uint32_t>::give(std::move(table));
    return remap;
}

// Classifies the edges whose smaller endpoint is vertex v: [begin, end) holds, per directed use
// of such an edge, (larger endpoint << 1 | backward), in any order. Without sorting: the uses of
// an edge are summed at its larger endpoint w (sums[w] = uses << 32 | backward uses), which
// mark[w] stamps with v + 1 while the sum is v's (0: free); a second pass classifies each edge
// at its first use and frees the stamp. Both arrays hold n entries.
template <class Entry>
void classifyEdgesOfVertex(std::size_t v, const Entry* begin, const Entry* end, uint32_t* mark,
                           uint64_t* sums, MeshTopology& topo) {
    const auto stamp = uint32_t(v + 1);
    for (const Entry* i = begin; i != end; ++i) {
        const std::size_t w = std::size_t(*i >> 1);
        if (mark[w] != stamp) {
            mark[w] = stamp;
            sums[w] = 0;
        }
        sums[w] += (uint64_t(1) << 32) | uint64_t(*i & 1);
    }
    for (const Entry* i = begin; i != end; ++i) {
        const std::size_t w = std::size_t(*i >> 1);
        if (mark[w] != stamp) continue;
        mark[w] = 0;
        const uint64_t uses = sums[w] >> 32, backward = sums[w] & 0xFFFFFFFFu;
        ++topo.edges;
        if (uses == 1)
            ++topo.boundaryEdges;
        else if (uses >= 3)
            ++topo.nonManifoldEdges;
        else if (backward != 1)
            ++topo.misorientedEdges;
    }
}

// Edge classification in O(V + T): directed edges are bucketed by
// their smaller endpoint with a counting sort (count, prefix sum, fill), as meshoptimizer builds
// its adjacency. Entry is uint32_t while vertex ids fit 31 bits, uint64_t beyond.
template <class Entry>
void classifyEdges(const MeshView& mesh, const detail::PageVector<uint32_t>& remap, MeshTopology& topo) {
    const std::size_t n = remap.size();
    // Calls f(smaller, larger, backward) for the three edges of every usable triangle: in range,
    // and with three distinct positions (a triangle with two corners at one point has no edge).
    auto forEachEdge = [&](auto&& f) {
        for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
            const uint32_t* tri = mesh.indices + 3 * t;
            if (std::max({tri[0], tri[1], tri[2]}) >= n) continue;
            const uint32_t v[3] = {remap[tri[0]], remap[tri[1]], remap[tri[2]]};
            if ((v[0] == v[1]) | (v[1] == v[2]) | (v[0] == v[2])) continue;
            for (int c = 0; c < 3; ++c) {
                const uint32_t p = v[c], q = v[(c + 1) % 3];
                f(std::min(p, q), std::max(p, q), p > q);
            }
        }
    };
    // After the fill, start[v] is where vertex v's bucket ends and start[v - 1] where it begins.
    detail::PageVector<uint64_t> start = detail::Scratch<uint64_t>::take(n + 1);
    start.assign(n + 1, 0);
    forEachEdge([&](uint32_t lo, uint32_t, bool) { ++start[lo + 1]; });
    for (std::size_t v = 0; v < n; ++v) start[v + 1] += start[v];
    detail::PageVector<Entry> entries = detail::Scratch<Entry>::take(start[n]);
    entries.resize(start[n]);
    forEachEdge([&](uint32_t lo, uint32_t hi, bool backward) {
        entries[start[lo]++] = Entry(hi) << 1 | Entry(backward);
    });
    detail::PageVector<uint32_t> mark = detail::Scratch<uint32_t>::take(n);
    mark.assign(n, 0);
    detail::PageVector<uint64_t> sums = detail::Scratch<uint64_t>::take(n);
    sums.resize(n);
    for (std::size_t v = 0; v < n; ++v)
        classifyEdgesOfVertex(v, entries.data() + (v == 0 ? 0 : start[v - 1]), entries.data() + start[v],
                              mark.data(), sums.data(), topo);
    detail::Scratch<uint64_t>::give(std::move(start));
    detail::Scratch<Entry>::give(std::move(entries));
    detail::Scratch<uint32_t>::give(std::move(mark));
    detail::Scratch<uint64_t>::give(std::move(sums));
}

} // namespace

Box3d computeBounds(const MeshView& mesh) {
    Box3d box;
    const std::size_t corners = 3 * mesh.triangleCount;
    for (std::size_t i = 0; i < corners; ++i) {
        const uint32_t v = mesh.indices[i];
        if (v >= mesh.vertexCount) continue; // invalid meshes must not read out of bounds
        const float* p = vertexPtr(mesh, v);
        box.extend(Vec3d{p[0], p[1], p[2]});
    }
    return box;
}

void validateMesh(const MeshView& mesh, const std::string& source) {
    if (mesh.triangleCount > 0 && mesh.indices == nullptr)
        fail(source, ": mesh has ", mesh.triangleCount, " triangles but no index array");
    if (mesh.vertexCount > 0 && mesh.positions == nullptr)
        fail(source, ": mesh has ", mesh.vertexCount, " vertices but no position array");
    if (mesh.positionStride < 3 * sizeof(float))
        fail(source, ": position stride ", mesh.positionStride, " bytes is smaller than 3 floats");
    // Fast path: one linear pass over the indices (a max reduction) and one over the vertices;
    // the per-triangle loop below only runs to name the first offender.
    uint32_t maxIndex = 0;
    for (std::size_t i = 0; i < 3 * mesh.triangleCount; ++i) maxIndex = std::max(maxIndex, mesh.indices[i]);
    bool finite = true;
    for (std::size_t v = 0; v < mesh.vertexCount; ++v) {
        const float* p = vertexPtr(mesh, v);
        for (int c = 0; c < 3; ++c) {
            uint32_t bits;
            std::memcpy(&bits, p + c, sizeof bits);
            finite &= (bits & 0x7f800000u) != 0x7f800000u;
        }
    }
    if (finite && (mesh.triangleCount == 0 || maxIndex < mesh.vertexCount)) return;
    for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
        for (int c = 0; c < 3; ++c) {
            const uint32_t v = mesh.indices[3 * t + c];
            if (v >= mesh.vertexCount)
                fail(source, ": triangle ", t, " uses vertex index ", v, " but the mesh has only ",
                     mesh.vertexCount, " vertices");
            const float* p = vertexPtr(mesh, v);
            if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
                fail(source, ": vertex ", v, " (used by triangle ", t, ") has a non-finite coordinate (",
                     p[0], " ", p[1], " ", p[2], ")");
        }
    }
}

std::size_t removeDegenerateTriangles(Mesh& mesh) {
    const std::size_t triangles = mesh.triangleCount();
    const std::size_t vertexCount = mesh.positions.size();
    uint32_t* idx = mesh.indices.data();
    std::size_t kept = 0;
    for (std::size_t t = 0; t < triangles; ++t) {
        const uint32_t a = idx[3 * t], b = idx[3 * t + 1], c = idx[3 * t + 2];
        bool degenerate = a == b || b == c || a == c;
        // Out-of-range triangles are left for validateMesh to report, never read here.
        if (!degenerate && a < vertexCount && b < vertexCount && c < vertexCount)
            degenerate = zeroArea(&mesh.positions[a].x, &mesh.positions[b].x, &mesh.positions[c].x);
        if (degenerate) continue;
        idx[3 * kept] = a;
        idx[3 * kept + 1] = b;
        idx[3 * kept + 2] = c;
        ++kept;
    }
    mesh.indices.resize(3 * kept);
    return triangles - kept;
}

MeshTopology analyzeTopology(const MeshView& mesh) {
    MeshTopology topo;
    // Indices are 32-bit, so at most 2^32 - 1 vertices can be told apart (one value marks empty).
    const std::size_t n = std::min<std::size_t>(mesh.vertexCount, kMaxMergedVertices);
    if (mesh.triangleCount == 0 || n == 0) return topo;
    detail::PageVector<uint32_t> remap = mergeIdenticalPositions(mesh, n);
    if (n <= (std::size_t(1) << 31))
        classifyEdges<uint32_t>(mesh, remap, topo);
    else
        classifyEdges<uint64_t>(mesh, remap, topo);
    detail::Scratch<uint32_t>::give(std::move(remap));
    return topo;
}

} // namespace voxfx
