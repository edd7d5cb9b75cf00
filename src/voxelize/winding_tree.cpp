// voxfx — the generalized winding number after Barill et al. 2018 (see winding_tree.hpp).
#include "voxelize/winding_tree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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

// One tile of kGwnBlock x kGwnBlock columns, one block of kGwnBlock slices at a time: the
// winding numbers evaluated so far in the block (NaN: not yet), and the block refinement.
constexpr int64_t kGwnBlock = 16;

class GwnTile {
public:
    GwnTile(const Frame& frame, const WindingTree& tree, const BitGrid& surface, BitGrid& out)
        : frame_(frame), tree_(tree), surface_(surface), out_(out),
          cache_(size_t(kGwnBlock * kGwnBlock * kGwnBlock)) {}

    void run(int64_t x0, int64_t y0) {
        const int64_t x1 = std::min(x0 + kGwnBlock, out_.width()),
                      y1 = std::min(y0 + kGwnBlock, out_.height());
        for (int64_t z0 = 0; z0 < out_.depth(); z0 += kGwnBlock) {
            std::fill(cache_.begin(), cache_.end(), std::numeric_limits<float>::quiet_NaN());
            o_ = {x0, y0, z0};
            decide(x0, x1, y0, y1, z0, std::min(z0 + kGwnBlock, out_.depth()));
        }
    }

private:
    // Sets slices [z0, z1) of a column.
    static void setSlices(uint64_t* col, int64_t z0, int64_t z1) {
        for (int64_t w = z0 >> 6; w <= (z1 - 1) >> 6; ++w) {
            const int64_t lo = std::max(z0, w * 64) - w * 64, hi = std::min(z1, w * 64 + 64) - w * 64;
            col[w] |= (hi - lo == 64 ? ~uint64_t(0) : ((uint64_t(1) << (hi - lo)) - 1)) << lo;
        }
    }

    bool insideAt(int64_t x, int64_t y, int64_t z) {
        float& w = cache_[size_t(((z - o_[2]) * kGwnBlock + (y - o_[1])) * kGwnBlock + (x - o_[0]))];
        if (std::isnan(w)) w = float(tree_.at(frame_.cellCenter(x, y, z)) - 0.5);
        return w >= 0;
    }

    // Whether a surface cell lies in [x0, x1) x [y0, y1) x [z0, z1) grown by `grow` cells.
    bool surfaceNear(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z0, int64_t z1,
                     int64_t grow) const {
        x0 = std::max<int64_t>(x0 - grow, 0), y0 = std::max<int64_t>(y0 - grow, 0);
        z0 = std::max<int64_t>(z0 - grow, 0);
        x1 = std::min(x1 + grow, surface_.width()), y1 = std::min(y1 + grow, surface_.height());
        z1 = std::min(z1 + grow, surface_.depth());
        const int64_t w0 = z0 >> 6, w1 = (z1 - 1) >> 6;
        const uint64_t m0 = ~uint64_t(0) << (z0 & 63), m1 = ~uint64_t(0) >> (63 - ((z1 - 1) & 63));
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x) {
                const uint64_t* col = surface_.column(x, y);
                for (int64_t w = w0; w <= w1; ++w) {
                    const uint64_t m = (w == w0 ? m0 : ~uint64_t(0)) & (w == w1 ? m1 : ~uint64_t(0));
                    if (col[w] & m) return true;
                }
            }
        return false;
    }

    void decide(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int64_t z0, int64_t z1) {
        if (x1 - x0 == 1 && y1 - y0 == 1 && z1 - z0 == 1) {
            if (insideAt(x0, y0, z0)) out_.set(x0, y0, z0);
            return;
        }
        const bool first = insideAt(x0, y0, z0);
        bool agree = true;
        for (int k = 1; k < 8 && agree; ++k)
            agree = insideAt(k & 1 ? x1 - 1 : x0, k & 2 ? y1 - 1 : y0, k & 4 ? z1 - 1 : z0) == first;
        // Blocks of 8 cells and more keep a cell of margin from the surface; smaller ones only
        // need none inside (near the surface, most cells lie in such blocks).
        const int64_t grow = std::max({x1 - x0, y1 - y0, z1 - z0}) >= 8 ? 1 : 0;
        if (agree && !surfaceNear(x0, x1, y0, y1, z0, z1, grow)) {
            if (first)
                for (int64_t y = y0; y < y1; ++y)
                    for (int64_t x = x0; x < x1; ++x) setSlices(out_.column(x, y), z0, z1);
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
    const BitGrid& surface_;
    BitGrid& out_;
    std::vector<float> cache_;
    std::array<int64_t, 3> o_{};
};

} // namespace

BitGrid gwnFillInside(const Frame& frame, const WindingTree& tree, const BitGrid& surface) {
    BitGrid out(frame.width(), frame.height(), frame.depth());
    if (tree.nodes.empty()) return out;
    const int64_t tx = (frame.width() + kGwnBlock - 1) / kGwnBlock,
                  ty = (frame.height() + kGwnBlock - 1) / kGwnBlock;
    // Tiles own whole columns, so no two threads write the same word.
    parallelFor(0, tx * ty, 1, [&](int64_t t0, int64_t t1) {
        GwnTile tile(frame, tree, surface, out);
        for (int64_t t = t0; t < t1; ++t) tile.run(t % tx * kGwnBlock, t / tx * kGwnBlock);
    });
    return out;
}

} // namespace voxfx::detail
