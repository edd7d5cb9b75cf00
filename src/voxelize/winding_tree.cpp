// voxfx — the generalized winding number after Barill et al. 2018 (see winding_tree.hpp).
#include "voxelize/winding_tree.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>

#include "voxelize/consumers.hpp"
#include "voxfx/fragment_list.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

void WindingTree::build(const MeshView& mesh, double betaValue) {
    beta = betaValue;
    const std::size_t T = mesh.triangleCount;
    std::vector<std::array<Vec3d, 3>> tris(T);
    std::vector<Vec3d> centroid(T);
    std::vector<uint32_t> order(T);
    for (std::size_t t = 0; t < T; ++t) {
        for (int k = 0; k < 3; ++k) tris[t][std::size_t(k)] = mesh.vertex(mesh.index(t, k));
        centroid[t] = (tris[t][0] + tris[t][1] + tris[t][2]) * (1.0 / 3.0);
        order[t] = uint32_t(t);
    }
    nodes.clear();
    nodes.reserve(2 * T / 4 + 1);
    split(tris, centroid, order, 0, uint32_t(T));
    triangles.resize(T);
    for (std::size_t i = 0; i < T; ++i) triangles[i] = tris[order[i]];
}

int32_t WindingTree::split(const std::vector<std::array<Vec3d, 3>>& tris, const std::vector<Vec3d>& centroid,
                           std::vector<uint32_t>& order, uint32_t begin, uint32_t end) {
    const auto index = int32_t(nodes.size());
    nodes.emplace_back();
    WindingNode n;
    n.begin = begin;
    n.end = end;
    double totalArea = 0;
    Vec3d weighted{0, 0, 0}, lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = begin; i < end; ++i) {
        const auto& t = tris[order[i]];
        const Vec3d a = cross(t[1] - t[0], t[2] - t[0]) * 0.5;
        n.area = n.area + a;
        const double len = length(a);
        totalArea += len;
        weighted = weighted + centroid[order[i]] * len;
        lo = min(lo, centroid[order[i]]);
        hi = max(hi, centroid[order[i]]);
    }
    n.centre = totalArea > 0 ? weighted * (1.0 / totalArea) : (lo + hi) * 0.5;
    for (uint32_t i = begin; i < end; ++i)
        for (const Vec3d& v : tris[order[i]]) n.radius = std::max(n.radius, length(v - n.centre));
    if (end - begin > 8) {
        const Vec3d ext = hi - lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const uint32_t mid = begin + (end - begin) / 2;
        std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                         [&](uint32_t a, uint32_t b) { return centroid[a][axis] < centroid[b][axis]; });
        n.left = split(tris, centroid, order, begin, mid);
        n.right = split(tris, centroid, order, mid, end);
    }
    nodes[std::size_t(index)] = n;
    return index;
}

double WindingTree::at(const Vec3d& p) const {
    if (nodes.empty()) return 0;
    double sum = 0; // solid angles
    int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const WindingNode& n = nodes[std::size_t(stack[--top])];
        const Vec3d d = n.centre - p;
        const double dist = length(d);
        if (beta > 0 && dist > beta * n.radius) {
            sum += dot(d, n.area) / (dist * dist * dist); // dipole: solid angle of a far patch
        } else if (n.left < 0 || top + 2 > 128) {
            for (uint32_t i = n.begin; i < n.end; ++i) {
                const auto& t = triangles[i];
                const Vec3d a = t[0] - p, b = t[1] - p, c = t[2] - p;
                const double la = length(a), lb = length(b), lc = length(c);
                const double det = dot(a, cross(b, c));
                const double den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
                sum += 2.0 * std::atan2(det, den);
            }
        } else {
            stack[top++] = n.left;
            stack[top++] = n.right;
        }
    }
    return sum / (4.0 * std::numbers::pi);
}

namespace {

// Blocks of cells refine from kGwnBlock cells wide down to single cells.
constexpr int64_t kGwnBlock = 16;

// The edges of the mesh's boundary chain: the triangles' oriented edges that do not cancel, with
// vertices at the same position taken as one (so a mesh split into pieces along shared positions
// is closed there). Edges of inconsistently oriented neighbours count, as they should: the
// winding number is not constant across their surface.
std::vector<std::array<Vec3d, 2>> gwnBoundaryEdges(const MeshView& mesh) {
    const std::size_t V = mesh.vertexCount;
    std::vector<uint32_t> order(V), canon(V);
    std::vector<Vec3d> pos(V);
    for (std::size_t i = 0; i < V; ++i) {
        order[i] = uint32_t(i);
        pos[i] = mesh.vertex(i);
    }
    const auto less = [&](uint32_t a, uint32_t b) {
        const Vec3d &p = pos[a], &q = pos[b];
        return p.x != q.x ? p.x < q.x : (p.y != q.y ? p.y < q.y : (p.z != q.z ? p.z < q.z : a < b));
    };
    std::sort(order.begin(), order.end(), less);
    for (std::size_t i = 0; i < V; ++i) {
        const bool same = i > 0 && pos[order[i]].x == pos[order[i - 1]].x &&
                          pos[order[i]].y == pos[order[i - 1]].y && pos[order[i]].z == pos[order[i - 1]].z;
        canon[order[i]] = same ? canon[order[i - 1]] : order[i];
    }
    std::vector<std::pair<uint64_t, int32_t>> edges;
    edges.reserve(3 * mesh.triangleCount);
    for (std::size_t t = 0; t < mesh.triangleCount; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint64_t a = canon[mesh.index(t, k)], b = canon[mesh.index(t, (k + 1) % 3)];
            if (a != b) edges.emplace_back(a < b ? (a << 32 | b) : (b << 32 | a), a < b ? 1 : -1);
        }
    std::sort(edges.begin(), edges.end());
    std::vector<std::array<Vec3d, 2>> out;
    for (std::size_t i = 0; i < edges.size();) {
        int32_t sum = 0;
        std::size_t j = i;
        for (; j < edges.size() && edges[j].first == edges[i].first; ++j) sum += edges[j].second;
        if (sum != 0) out.push_back({pos[edges[i].first >> 32], pos[edges[i].first & 0xffffffffu]});
        i = j;
    }
    return out;
}

// What the tiles share: the crossings of every column (CSR by column) and, per column, where the
// boundary edges near it lie (GwnCurtains). Both come with a margin of a cell from the edges,
// where the winding number turns fast.
struct GwnCrossings {
    /// The columns' crossings with the surface, as the centre-sampled rasterizer finds them (the
    /// tie rule of the parity fill); a front fragment raises the winding number by one.
    FragmentLists lists;
    FrameView view;
    GwnCurtains curtains;
};

GwnCrossings gwnCrossings(const Frame& frame, const MeshView& mesh,
                          const std::vector<std::array<Vec3d, 2>>& edges, Progress* progress) {
    GwnCrossings g;
    g.view = frame.view();
    g.curtains = gwnCurtains(frame, mesh, edges, 0, 0, frame.width(), frame.height());
    if (g.curtains.usable) g.lists = FragmentLists::build(frame, mesh, progress);
    return g;
}

// One tile of kGwnBlock x kGwnBlock columns of a region, one block of kGwnBlock slices at a time:
// the winding numbers evaluated so far in the block (NaN: not yet), the crossing counts of the
// tile's columns, and the block refinement. Coordinates are the frame's; the region maps them to
// its own cells.
class GwnTile {
public:
    GwnTile(const Frame& frame, const WindingTree& tree, const GwnRegion& region)
        : frame_(frame), tree_(tree), r_(region), cache_(size_t(kGwnBlock * kGwnBlock * kGwnBlock)) {
        if (r_.curtains->usable) {
            count_.resize(size_t(kGwnBlock * kGwnBlock * r_.out.depth));
            total_.resize(size_t(kGwnBlock * kGwnBlock));
        }
    }

    // The tile whose first column is (x0, y0) (frame coordinates, inside the region).
    void run(int64_t x0, int64_t y0) {
        const int64_t x1 = std::min(x0 + kGwnBlock, r_.x0 + r_.out.width),
                      y1 = std::min(y0 + kGwnBlock, r_.y0 + r_.out.height);
        o_ = {x0, y0, 0};
        if (r_.curtains->usable) countCrossings(x0, x1, y0, y1);
        const int64_t zEnd = r_.z0 + r_.out.depth;
        for (int64_t z0 = r_.z0; z0 < zEnd; z0 += kGwnBlock) {
            std::fill(cache_.begin(), cache_.end(), std::numeric_limits<float>::quiet_NaN());
            o_[2] = z0;
            decide(x0, x1, y0, y1, z0, std::min(z0 + kGwnBlock, zEnd));
        }
    }

private:
    // N: per cell of the tile, the signed count of crossings in front of its centre; per column,
    // the count over the whole line.
    void countCrossings(int64_t x0, int64_t x1, int64_t y0, int64_t y1) {
        const int64_t d = r_.out.depth;
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x) {
                int32_t* n = &count_[size_t(((y - y0) * kGwnBlock + (x - x0)) * d)];
                total_[size_t((y - y0) * kGwnBlock + (x - x0))] = r_.counts(x, y, n);
            }
    }
    int32_t count(int64_t x, int64_t y, int64_t z) const {
        return count_[size_t(((y - o_[1]) * kGwnBlock + (x - o_[0])) * r_.out.depth + (z - r_.z0))];
    }
    // Minus the count of crossings behind the centre: N less the column's total.
    int32_t countFromFar(int64_t x, int64_t y, int64_t z) const {
        return count(x, y, z) - total_[size_t((y - o_[1]) * kGwnBlock + (x - o_[0]))];
    }
    uint64_t* outColumn(int64_t x, int64_t y) const { return r_.out.column(x - r_.x0, y - r_.y0); }
    void setCell(int64_t x, int64_t y, int64_t z) const {
        const int64_t s = z - r_.z0;
        outColumn(x, y)[s >> 6] |= uint64_t(1) << (s & 63);
    }
    int64_t columnOf(int64_t x, int64_t y) const { return (y - r_.y0) * r_.out.width + (x - r_.x0); }

    // Sets slices [z0, z1) of a column.
    void setSlices(uint64_t* col, int64_t z0, int64_t z1) const {
        z0 -= r_.z0;
        z1 -= r_.z0;
        for (int64_t w = z0 >> 6; w <= (z1 - 1) >> 6; ++w) {
            const int64_t lo = std::max(z0, w * 64) - w * 64, hi = std::min(z1, w * 64 + 64) - w * 64;
            col[w] |= (hi - lo == 64 ? ~uint64_t(0) : ((uint64_t(1) << (hi - lo)) - 1)) << lo;
        }
    }

    // The winding number at a cell's centre (evaluated once per block).
    float winding(int64_t x, int64_t y, int64_t z) {
        float& w = cache_[size_t(((z - o_[2]) * kGwnBlock + (y - o_[1])) * kGwnBlock + (x - o_[0]))];
        if (std::isnan(w)) w = float(tree_.at(frame_.cellCenter(x, y, z)));
        return w;
    }
    // Which side of the threshold |w| = 0.5 a centre lies on: 1 (w >= 0.5), -1 (w <= -0.5, inside
    // a mesh oriented inward), 0 outside.
    int side(int64_t x, int64_t y, int64_t z) {
        const float w = winding(x, y, z);
        return w >= 0.5f ? 1 : w <= -0.5f ? -1 : 0;
    }
    bool insideAt(int64_t x, int64_t y, int64_t z) { return side(x, y, z) != 0; }

    // Whether no curtain reaches into the block: the count N then changes only across the
    // surface, by exactly what the winding number jumps there. The same holds for the count from
    // the far end, whose curtains lie in front of the edges.
    bool curtainFree(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z1) const {
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x)
                if (r_.curtains->curtainBottom[size_t(columnOf(x, y))] < z1) return false;
        return true;
    }
    bool frontCurtainFree(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z0) const {
        if (!r_.curtains->bothWays) return false;
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x)
                if (r_.curtains->edgeTop[size_t(columnOf(x, y))] >= z0) return false;
        return true;
    }

    // Whether a surface cell lies in [x0, x1) x [y0, y1) x [z0, z1) grown by `grow` cells (and
    // clipped to the grid; the region's surface covers that much around the region).
    bool surfaceNear(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z0, int64_t z1,
                     int64_t grow) const {
        x0 = std::max<int64_t>(x0 - grow, 0), y0 = std::max<int64_t>(y0 - grow, 0);
        z0 = std::max<int64_t>(z0 - grow, 0);
        x1 = std::min(x1 + grow, frame_.width()), y1 = std::min(y1 + grow, frame_.height());
        z1 = std::min(z1 + grow, frame_.depth());
        x0 -= r_.sx0, x1 -= r_.sx0, y0 -= r_.sy0, y1 -= r_.sy0, z0 -= r_.sz0, z1 -= r_.sz0;
        const int64_t w0 = z0 >> 6, w1 = (z1 - 1) >> 6;
        const uint64_t m0 = ~uint64_t(0) << (z0 & 63), m1 = ~uint64_t(0) >> (63 - ((z1 - 1) & 63));
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x) {
                const uint64_t* col = r_.surface.column(x, y);
                for (int64_t w = w0; w <= w1; ++w) {
                    const uint64_t m = (w == w0 ? m0 : ~uint64_t(0)) & (w == w1 ? m1 : ~uint64_t(0));
                    if (col[w] & m) return true;
                }
            }
        return false;
    }

    // Across the surface the winding number jumps by exactly the crossing's sign, so
    // C = w - N is continuous there; off the curtains it is harmonic (zero for a closed mesh).
    // When C stays within kGwnSlack of one integer k at the block's corners, every cell of the
    // block is inside exactly when N + k != 0 (|w| >= 0.5 for w = N + C with |C - k| < 0.5).
    static constexpr double kGwnSlack = 0.4;
    bool decideByCrossings(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z0, int64_t z1) {
        if (!r_.curtains->usable) return false;
        if (curtainFree(x0, x1, y0, y1, z1))
            return decideByCount(x0, x1, y0, y1, z0, z1,
                                 [&](int64_t x, int64_t y, int64_t z) { return count(x, y, z); });
        if (frontCurtainFree(x0, x1, y0, y1, z0))
            return decideByCount(x0, x1, y0, y1, z0, z1,
                                 [&](int64_t x, int64_t y, int64_t z) { return countFromFar(x, y, z); });
        return false;
    }
    template <class Count>
    bool decideByCount(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z0, int64_t z1, Count n) {
        double k = 0;
        for (int c = 0; c < 8; ++c) {
            const int64_t x = c & 1 ? x1 - 1 : x0, y = c & 2 ? y1 - 1 : y0, z = c & 4 ? z1 - 1 : z0;
            const double rest = double(winding(x, y, z)) - double(n(x, y, z));
            if (c == 0) k = std::round(rest);
            if (!(std::abs(rest - k) < kGwnSlack)) return false;
        }
        const auto outside = int32_t(-k); // N + k == 0
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x)
                for (int64_t z = z0; z < z1; ++z)
                    if (n(x, y, z) != outside) setCell(x, y, z);
        return true;
    }

    // Along one column no curtain is ever crossed (curtains run along the columns), so C is
    // continuous on cells [z0, z1] of a column away from its edges: the same test on the ends of
    // the run, halving it until it passes, down to single cells.
    void decideRun(int64_t x, int64_t y, int64_t z0, int64_t z1) {
        if (z0 == z1) {
            if (insideAt(x, y, z0)) setCell(x, y, z0);
            return;
        }
        const auto c = size_t(columnOf(x, y));
        if (z1 < r_.curtains->curtainBottom[c] || z0 > r_.curtains->edgeTop[c]) {
            const double r0 = double(winding(x, y, z0)) - double(count(x, y, z0));
            const double r1 = double(winding(x, y, z1)) - double(count(x, y, z1));
            const double k = std::round(r0);
            if (std::abs(r0 - k) < kGwnSlack && std::abs(r1 - k) < kGwnSlack) {
                const auto outside = int32_t(-k);
                for (int64_t z = z0; z <= z1; ++z)
                    if (count(x, y, z) != outside) setCell(x, y, z);
                return;
            }
        }
        const int64_t zm = z0 + (z1 - z0) / 2;
        decideRun(x, y, z0, zm);
        decideRun(x, y, zm + 1, z1);
    }

    void decide(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z0, int64_t z1) {
        if (x1 - x0 == 1 && y1 - y0 == 1 && z1 - z0 == 1) {
            if (insideAt(x0, y0, z0)) setCell(x0, y0, z0);
            return;
        }
        if (decideByCrossings(x0, x1, y0, y1, z0, z1)) return;
        const int first = side(x0, y0, z0);
        bool agree = true;
        for (int k = 1; k < 8 && agree; ++k)
            agree = side(k & 1 ? x1 - 1 : x0, k & 2 ? y1 - 1 : y0, k & 4 ? z1 - 1 : z0) == first;
        // Blocks of 8 cells and more keep a cell of margin from the surface; smaller ones only
        // need none inside (near the surface, most cells lie in such blocks).
        const int64_t grow = std::max({x1 - x0, y1 - y0, z1 - z0}) >= 8 ? 1 : 0;
        if (agree && !surfaceNear(x0, x1, y0, y1, z0, z1, grow)) {
            if (first != 0)
                for (int64_t y = y0; y < y1; ++y)
                    for (int64_t x = x0; x < x1; ++x) setSlices(outColumn(x, y), z0, z1);
            return;
        }
        // Small blocks that a curtain crosses: column by column.
        if (r_.curtains->usable && std::max(x1 - x0, y1 - y0) <= 4) {
            for (int64_t y = y0; y < y1; ++y)
                for (int64_t x = x0; x < x1; ++x) decideRun(x, y, z0, z1 - 1);
            return;
        }
        const int64_t xm = x0 + (x1 - x0 + 1) / 2, ym = y0 + (y1 - y0 + 1) / 2, zm = z0 + (z1 - z0 + 1) / 2;
        for (int k = 0; k < 8; ++k) {
            const int64_t a0 = k & 1 ? xm : x0, a1 = k & 1 ? x1 : xm;
            const int64_t b0 = k & 2 ? ym : y0, b1 = k & 2 ? y1 : ym;
            const int64_t c0 = k & 4 ? zm : z0, c1 = k & 4 ? z1 : zm;
            if (a0 < a1 && b0 < b1 && c0 < c1) decide(a0, a1, b0, b1, c0, c1);
        }
    }

    const Frame& frame_;
    const WindingTree& tree_;
    const GwnRegion& r_;
    std::vector<float> cache_;
    std::vector<int32_t> count_, total_;
    std::array<int64_t, 3> o_{};
};

} // namespace

std::vector<std::array<Vec3d, 2>> gwnEdges(const MeshView& mesh) { return gwnBoundaryEdges(mesh); }

GwnCurtains gwnCurtains(const Frame& frame, const MeshView& mesh,
                        const std::vector<std::array<Vec3d, 2>>& edges, int64_t x0, int64_t y0, int64_t width,
                        int64_t height) {
    GwnCurtains g;
    g.x0 = x0;
    g.y0 = y0;
    g.width = width;
    g.height = height;
    // Exact counts along straight columns from the grid's near end: an orthographic frame with
    // uniform slicing, and no geometry in front of the near plane.
    if (frame.isPerspective() || frame.slicing() != Slicing::Uniform) return g;
    const FrameView view = frame.view();
    const int64_t W = frame.width(), H = frame.height(), D = frame.depth();
    g.bothWays = true;
    for (std::size_t i = 0; i < mesh.vertexCount; ++i) {
        const Vec3d p = frame.projection().gridFromVertex(mesh.vertex(i));
        const double t = view.uniform(p.z);
        if (!(t >= 0) || !std::isfinite(t) || !std::isfinite(p.x) || !std::isfinite(p.y)) {
            g.bothWays = false;
            return g;
        }
        g.bothWays &= t <= double(D);
    }
    // Every column whose cell square grown by a cell a boundary edge's projection touches: its
    // curtain from two slices in front of the edge's lowest point, and the edge up to two slices
    // behind its highest. Only the window's columns are kept; the steps along each edge are those
    // of the whole grid, so a window marks exactly the whole grid's marks in it.
    g.curtainBottom.assign(std::size_t(width * height), int32_t(D));
    g.edgeTop.assign(std::size_t(width * height), -1);
    for (const auto& e : edges) {
        Vec3d a = frame.projection().gridFromVertex(e[0]), b = frame.projection().gridFromVertex(e[1]);
        // Edges whose columns (grown by the margins below) miss the window mark nothing in it.
        if (std::max(a.x, b.x) + 4 < double(x0) || std::min(a.x, b.x) - 4 > double(x0 + width) ||
            std::max(a.y, b.y) + 4 < double(y0) || std::min(a.y, b.y) - 4 > double(y0 + height))
            continue;
        a.z = view.uniform(a.z);
        b.z = view.uniform(b.z);
        const double zLow = std::min(a.z, b.z), zHigh = std::max(a.z, b.z);
        if (!(zLow < double(D) + 2)) continue;
        const auto bottom = int32_t(std::max<double>(0, std::floor(zLow) - 2));
        const auto top = int32_t(std::clamp<double>(std::floor(zHigh) + 2, 0, double(D - 1)));
        // The part of the edge over the grid's columns (grown by two cells), in steps of at most
        // half a cell.
        double u0 = 0, u1 = 1;
        const double lo[2] = {-2, -2}, hi[2] = {double(W) + 2, double(H) + 2};
        const double from[2] = {a.x, a.y}, delta[2] = {b.x - a.x, b.y - a.y};
        for (int k = 0; k < 2; ++k) {
            if (delta[k] == 0) {
                if (from[k] < lo[k] || from[k] > hi[k]) u1 = -1;
                continue;
            }
            const double e0 = (lo[k] - from[k]) / delta[k], e1 = (hi[k] - from[k]) / delta[k];
            u0 = std::max(u0, std::min(e0, e1));
            u1 = std::min(u1, std::max(e0, e1));
        }
        if (!(u0 <= u1)) continue;
        const double len = std::hypot(delta[0], delta[1]) * (u1 - u0);
        const int64_t steps = int64_t(std::ceil(len / 0.5)) + 1;
        constexpr double m = 1.0;
        for (int64_t i = 0; i < steps; ++i) {
            const double t0 = u0 + (u1 - u0) * double(i) / double(steps),
                         t1 = u0 + (u1 - u0) * double(i + 1) / double(steps);
            const double xa = a.x + (b.x - a.x) * t0, xb = a.x + (b.x - a.x) * t1;
            const double ya = a.y + (b.y - a.y) * t0, yb = a.y + (b.y - a.y) * t1;
            const int64_t cx0 = std::max<int64_t>(x0, int64_t(std::floor(std::min(xa, xb) - m)));
            const int64_t cx1 = std::min<int64_t>(x0 + width - 1, int64_t(std::floor(std::max(xa, xb) + m)));
            const int64_t cy0 = std::max<int64_t>(y0, int64_t(std::floor(std::min(ya, yb) - m)));
            const int64_t cy1 = std::min<int64_t>(y0 + height - 1, int64_t(std::floor(std::max(ya, yb) + m)));
            for (int64_t y = cy0; y <= cy1; ++y)
                for (int64_t x = cx0; x <= cx1; ++x) {
                    const auto c = std::size_t((y - y0) * width + (x - x0));
                    g.curtainBottom[c] = std::min(g.curtainBottom[c], bottom);
                    g.edgeTop[c] = std::max(g.edgeTop[c], top);
                }
        }
    }
    g.usable = true;
    return g;
}

void gwnFillRegion(const Frame& frame, const WindingTree& tree, const GwnRegion& region) {
    const int64_t x1 = region.x0 + region.out.width, y1 = region.y0 + region.out.height;
    GwnTile tile(frame, tree, region);
    for (int64_t y = region.y0; y < y1; y += kGwnBlock)
        for (int64_t x = region.x0; x < x1; x += kGwnBlock) tile.run(x, y);
}

BitGrid gwnFillInside(const Frame& frame, const MeshView& mesh, const WindingTree& tree,
                      const BitGrid& surface, Progress* progress) {
    BitGrid out(frame.width(), frame.height(), frame.depth());
    if (tree.nodes.empty()) return out;
    const GwnCrossings crossings = gwnCrossings(frame, mesh, gwnBoundaryEdges(mesh), progress);
    const int64_t tx = (frame.width() + kGwnBlock - 1) / kGwnBlock,
                  ty = (frame.height() + kGwnBlock - 1) / kGwnBlock;
    const int64_t D = frame.depth();
    GwnRegion whole;
    whole.out = out.view();
    whole.surface = const_cast<BitGrid&>(surface).view(); // read only
    whole.curtains = &crossings.curtains;
    // The counts of one column from its fragment list.
    whole.counts = [&](int64_t x, int64_t y, int32_t* n) {
        std::fill(n, n + D, 0);
        const DepthToSlice toSlice = crossings.view.depthToSlice(y * frame.width() + x);
        int32_t total = 0;
        for (const ListFragment& f : crossings.lists.column(x, y)) {
            const int32_t sign = f.front ? 1 : -1;
            const int64_t slice = firstSliceBehind(toSlice(f.depth), D); // D: behind every centre
            if (slice < D) n[slice] += sign;
            total += sign;
        }
        for (int64_t z = 1; z < D; ++z) n[z] += n[z - 1];
        return total;
    };
    // Polled after each tile, one call at a time (as the rasterizer does); once it says stop,
    // the remaining tiles are skipped.
    ProgressSteps steps(progress, tx * ty);
    // Tiles own whole columns, so no two threads write the same word.
    parallelFor(0, tx * ty, 1, [&](int64_t t0, int64_t t1) {
        GwnTile tile(frame, tree, whole);
        for (int64_t t = t0; t < t1 && !steps.cancelled(); ++t) {
            tile.run(t % tx * kGwnBlock, t / tx * kGwnBlock);
            steps.step();
        }
    });
    if (steps.cancelled()) fail("cancelled");
    return out;
}

} // namespace voxfx::detail
