// voxfx — the closest-point query over triangles: the bounding-volume hierarchy (see
// grid/triangle_bvh.hpp). The binned surface area heuristic follows Wald, "On fast construction of
// SAH-based bounding volume hierarchies" (IEEE RT 2007), §3; the nearest-first traversal with
// pruning by box distance is the standard branch-and-bound of nearest-neighbour search.
#include "grid/triangle_bvh.hpp"

#include <algorithm>
#include <array>
#include <numeric>

#include "voxfx/error.hpp"

namespace voxfx::detail {

namespace {

constexpr int kBins = 16;
constexpr uint32_t kMaxLeaf = 4;
// Past this depth the split is the median: the tree's depth stays below kMedianDepth + 32, which
// bounds the traversal stack.
constexpr int kMedianDepth = 48;
constexpr int kStackSize = 96;

double halfArea(const Vec3d& e) { return e.x * e.y + e.y * e.z + e.z * e.x; }

struct BinBox {
    Box3d box;
    uint32_t count = 0;
};

Box3d boxOf(const std::vector<float>& boxes, uint32_t t) {
    const float* b = &boxes[6 * std::size_t(t)];
    return {{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
}

// The largest distance, squared, that a triangle at the best squared distance `best2` may have
// in computed arithmetic: the kernel's rounding (relative 2^-52 of |p - a| <= d + diagonal)
// stays far below the 2^-40 allowed here, so pruning never drops a triangle whose computed
// distance ties or beats the best.
double pruneLimit(double best2, double diagonal) {
    return best2 + 0x1p-40 * (best2 + std::sqrt(best2) * diagonal);
}

} // namespace

DistanceTriangle prepareTriangle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    DistanceTriangle t;
    t.a = a;
    t.ab = b - a;
    t.ac = c - a;
    t.bc = c - b;
    t.n = cross(t.ab, t.ac);
    t.nab = cross(t.n, t.ab);
    t.nac = cross(t.ac, t.n);
    t.nn = dot(t.n, t.n);
    // A triangle whose normal is zero (or underflows) is its three segments.
    t.invNn = t.nn > 0 && std::isfinite(t.nn) ? 1.0 / t.nn : 0.0;
    if (t.invNn == 0) t.nn = 0;
    const auto inv = [](const Vec3d& e) {
        const double l = dot(e, e);
        return l > 0 ? 1.0 / l : 0.0;
    };
    t.invAb = inv(t.ab);
    t.invAc = inv(t.ac);
    t.invBc = inv(t.bc);
    return t;
}

TriangleBvh::TriangleBvh(const MeshView& mesh) {
    const auto n = uint32_t(mesh.triangleCount);
    if (mesh.triangleCount > std::size_t(UINT32_MAX) / 2) fail("too many triangles for the distance query");
    std::vector<float> boxes(6 * std::size_t(n));
    std::vector<Vec3d> centroid(n);
    for (uint32_t t = 0; t < n; ++t) {
        const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                    c = mesh.vertex(mesh.index(t, 2));
        const Vec3d lo = min(min(a, b), c), hi = max(max(a, b), c);
        for (int k = 0; k < 3; ++k) {
            boxes[6 * std::size_t(t) + k] = float(lo[k]); // exact: the corners are floats
            boxes[6 * std::size_t(t) + 3 + k] = float(hi[k]);
        }
        centroid[t] = (lo + hi) * 0.5;
        bounds_.extend(lo);
        bounds_.extend(hi);
    }
    diagonal_ = n ? length(bounds_.extent()) : 0.0;
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    if (n) {
        nodes_.reserve(std::size_t(n) * 2 / kMaxLeaf + 16);
        build(order, centroid, 0, n, boxes, 0);
    }
    triangles_.resize(n);
    faces_ = order;
    boxes_.resize(boxes.size());
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t t = order[i];
        triangles_[i] = prepareTriangle(mesh.vertex(mesh.index(t, 0)), mesh.vertex(mesh.index(t, 1)),
                                        mesh.vertex(mesh.index(t, 2)));
        std::copy_n(&boxes[6 * std::size_t(t)], 6, &boxes_[6 * std::size_t(i)]);
    }
}

// Where to split the triangles [begin, end) of `order` (a position strictly inside), or `begin`
// for a leaf: the binned SAH along the widest centroid axis, the median past kMedianDepth or when
// the heuristic finds no split (all centroids in one bin).
uint32_t TriangleBvh::split(std::vector<uint32_t>& order, const std::vector<Vec3d>& centroid, uint32_t begin,
                            uint32_t end, const std::vector<float>& boxes, const Box3d& box,
                            int depth) const {
    const uint32_t count = end - begin;
    Box3d cbox;
    for (uint32_t i = begin; i < end; ++i) cbox.extend(centroid[order[i]]);
    const Vec3d ce = cbox.extent();
    const int axis = ce.x >= ce.y && ce.x >= ce.z ? 0 : (ce.y >= ce.z ? 1 : 2);
    if (count <= 2 && count <= kMaxLeaf) return begin;
    uint32_t mid = begin;
    if (depth < kMedianDepth && ce[axis] > 0) {
        std::array<BinBox, kBins> bins;
        const double scale = kBins / ce[axis];
        const auto binOf = [&](uint32_t t) {
            return std::min(kBins - 1, int((centroid[t][axis] - cbox.lo[axis]) * scale));
        };
        for (uint32_t i = begin; i < end; ++i) {
            BinBox& b = bins[size_t(binOf(order[i]))];
            b.box.extend(boxOf(boxes, order[i]));
            ++b.count;
        }
        // Cost of the right part of every split (bins b.. kBins-1), then a sweep from the left.
        std::array<double, kBins> rightCost{};
        Box3d acc;
        uint32_t accCount = 0;
        for (int b = kBins - 1; b > 0; --b) {
            acc.extend(bins[size_t(b)].box);
            accCount += bins[size_t(b)].count;
            rightCost[size_t(b)] = accCount ? halfArea(acc.extent()) * accCount : 0;
        }
        acc = Box3d();
        accCount = 0;
        double bestCost = std::numeric_limits<double>::infinity();
        int bestSplit = -1;
        for (int b = 0; b + 1 < kBins; ++b) {
            acc.extend(bins[size_t(b)].box);
            accCount += bins[size_t(b)].count;
            if (accCount == 0 || accCount == count) continue;
            const double cost = halfArea(acc.extent()) * accCount + rightCost[size_t(b + 1)];
            if (cost < bestCost) {
                bestCost = cost;
                bestSplit = b;
            }
        }
        // A leaf when visiting its triangles is cheaper than a box test plus the split's triangles.
        if (count <= kMaxLeaf &&
            (bestSplit < 0 || 0.5 * halfArea(box.extent()) + bestCost >= halfArea(box.extent()) * count))
            return begin;
        if (bestSplit >= 0)
            mid = uint32_t(std::stable_partition(order.begin() + begin, order.begin() + end,
                                                 [&](uint32_t t) { return binOf(t) <= bestSplit; }) -
                           order.begin());
    }
    if (mid == begin || mid == end) {
        if (count <= kMaxLeaf) return begin;
        mid = begin + count / 2;
        std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                         [&](uint32_t x, uint32_t y) {
                             return centroid[x][axis] < centroid[y][axis] ||
                                    (centroid[x][axis] == centroid[y][axis] && x < y);
                         });
    }
    return mid;
}

uint32_t TriangleBvh::build(std::vector<uint32_t>& order, const std::vector<Vec3d>& centroid, uint32_t begin,
                            uint32_t end, const std::vector<float>& boxes, int depth) {
    const auto index = uint32_t(nodes_.size());
    nodes_.push_back({});
    Box3d box;
    for (uint32_t i = begin; i < end; ++i) box.extend(boxOf(boxes, order[i]));
    BvhNode node;
    for (int k = 0; k < 3; ++k) {
        node.lo[k] = float(box.lo[k]); // exact: float corners
        node.hi[k] = float(box.hi[k]);
    }
    const uint32_t mid = split(order, centroid, begin, end, boxes, box, depth);
    if (mid == begin) {
        node.first = begin;
        node.count = end - begin;
    } else {
        build(order, centroid, begin, mid, boxes, depth + 1);
        node.first = build(order, centroid, mid, end, boxes, depth + 1);
        node.count = 0;
    }
    nodes_[index] = node;
    return index;
}

NearestHit TriangleBvh::nearest(const Vec3d& p, double maxDistance2) const {
    NearestHit hit;
    if (nodes_.empty() || !isFinite(p)) return hit;
    hit.distance2 = maxDistance2;
    uint32_t bestTri = UINT32_MAX;
    double limit = pruneLimit(hit.distance2, diagonal_);
    struct Entry {
        uint32_t node;
        double lb;
    };
    Entry stack[kStackSize];
    int sp = 0;
    stack[sp++] = {0, boxDistance2(nodes_[0].lo, nodes_[0].hi, p)};
    while (sp > 0) {
        const Entry e = stack[--sp];
        if (e.lb > limit) continue;
        uint32_t ni = e.node;
        for (;;) {
            const BvhNode& node = nodes_[ni];
            if (node.count) {
                for (uint32_t i = node.first; i < node.first + node.count; ++i) {
                    double u, v;
                    const double d2 = triangleDistance2(triangles_[i], p, u, v);
                    // Ties go to the smallest face index, whatever order the tree visits them in.
                    if (d2 < hit.distance2 ||
                        (d2 == hit.distance2 && (bestTri == UINT32_MAX || faces_[i] < faces_[bestTri]))) {
                        hit.distance2 = d2;
                        hit.u = u;
                        hit.v = v;
                        bestTri = i;
                        limit = pruneLimit(d2, diagonal_);
                    }
                }
                break;
            }
            const uint32_t l = ni + 1, r = node.first;
            const double dl = boxDistance2(nodes_[l].lo, nodes_[l].hi, p);
            const double dr = boxDistance2(nodes_[r].lo, nodes_[r].hi, p);
            const bool leftFirst = dl <= dr;
            const uint32_t nearNode = leftFirst ? l : r, farNode = leftFirst ? r : l;
            const double nearLb = leftFirst ? dl : dr, farLb = leftFirst ? dr : dl;
            if (farLb <= limit) stack[sp++] = {farNode, farLb};
            if (nearLb > limit) break;
            ni = nearNode;
        }
    }
    if (bestTri != UINT32_MAX) {
        hit.face = faces_[bestTri];
        hit.index = bestTri;
    }
    return hit;
}

void TriangleBvh::gather(const Vec3d& lo, const Vec3d& hi, double radius, std::vector<uint32_t>& out) const {
    if (nodes_.empty()) return;
    const double r2 = radius * radius;
    uint32_t stack[kStackSize];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const BvhNode& node = nodes_[stack[--sp]];
        if (boxBoxDistance2(node.lo, node.hi, lo, hi) > r2) continue;
        if (node.count) {
            for (uint32_t i = node.first; i < node.first + node.count; ++i)
                if (boxBoxDistance2(boxLo(i), boxHi(i), lo, hi) <= r2) out.push_back(i);
            continue;
        }
        // Right first on the stack, so the left subtree (lower indices) comes out first.
        stack[sp++] = node.first;
        stack[sp++] = uint32_t(&node - nodes_.data()) + 1;
    }
}

} // namespace voxfx::detail
