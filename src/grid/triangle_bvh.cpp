// voxfx — the closest-point query over triangles: the bounding-volume hierarchy (see
// grid/triangle_bvh.hpp). The binned surface area heuristic follows Wald, "On fast construction of
// SAH-based bounding volume hierarchies" (IEEE RT 2007), §3; the nearest-first traversal with
// pruning by box distance is the standard branch-and-bound of nearest-neighbour search.
#include "grid/triangle_bvh.hpp"

#include <algorithm>
#include <array>
#include <numeric>

#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

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

TriangleBvh::TriangleBvh(const MeshView& mesh) {
    const auto n = uint32_t(mesh.triangleCount);
    if (mesh.triangleCount > std::size_t(UINT32_MAX) / 2) fail("too many triangles for the distance query");
    std::vector<float> boxes(6 * std::size_t(n));
    std::vector<Vec3d> centroid(n);
    Box3d bounds;
    for (uint32_t t = 0; t < n; ++t) {
        const Vec3d a = mesh.vertex(mesh.index(t, 0)), b = mesh.vertex(mesh.index(t, 1)),
                    c = mesh.vertex(mesh.index(t, 2));
        const Vec3d lo = min(min(a, b), c), hi = max(max(a, b), c);
        for (int k = 0; k < 3; ++k) {
            boxes[6 * std::size_t(t) + k] = float(lo[k]); // exact: the corners are floats
            boxes[6 * std::size_t(t) + 3 + k] = float(hi[k]);
        }
        centroid[t] = (lo + hi) * 0.5;
        bounds.extend(lo);
        bounds.extend(hi);
    }
    diagonal_ = n ? length(bounds.extent()) : 0.0;
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    if (n) {
        nodes_.reserve(std::size_t(n) / 2 + 16);
        BuildState st{order, centroid, boxes, {}, 0};
        buildAll(st, n);
    }
    faces_ = order;
    corners_.resize(9 * std::size_t(n));
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const Vec3d v = mesh.vertex(mesh.index(order[i], k));
            for (int j = 0; j < 3; ++j)
                corners_[9 * std::size_t(i) + 3 * std::size_t(k) + std::size_t(j)] = float(v[j]);
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

BvhRef TriangleBvh::build(BuildState& st, std::vector<BvhNode>& nodes, uint32_t begin, uint32_t end,
                          int depth, bool top) const {
    BvhRef out;
    // Ranges below the cut-off are built later, in parallel: a placeholder for now.
    if (top && end - begin <= st.cutoff) {
        out.ref = uint32_t(st.pending.size());
        out.count = kPendingCount;
        st.pending.push_back({begin, end, depth});
        return out;
    }
    for (uint32_t i = begin; i < end; ++i) out.box.extend(boxOf(st.boxes, st.order[i]));
    const uint32_t mid = split(st.order, st.centroid, begin, end, st.boxes, out.box, depth);
    if (mid == begin) {
        out.ref = begin;
        out.count = end - begin;
        return out;
    }
    const auto index = uint32_t(nodes.size());
    nodes.push_back({});
    const BvhRef children[2] = {build(st, nodes, begin, mid, depth + 1, top),
                                build(st, nodes, mid, end, depth + 1, top)};
    BvhNode& node = nodes[index];
    for (int c = 0; c < 2; ++c) setChild(node, c, children[c]);
    out.ref = index;
    out.count = 0;
    return out;
}

void TriangleBvh::setChild(BvhNode& node, int c, const BvhRef& child) {
    for (int k = 0; k < 3; ++k) {
        node.lo[c][k] = float(child.box.lo[k]); // exact: float corners
        node.hi[c][k] = float(child.box.hi[k]);
    }
    node.ref[c] = child.ref;
    node.count[c] = child.count;
}

// The top of the tree serially down to ranges of about n / 64 triangles, those subtrees in
// parallel (each into its own nodes), then the subtrees appended in a fixed order and linked. The
// tree is the serial build's (every split is a function of its range), numbered differently.
void TriangleBvh::buildAll(BuildState& st, uint32_t n) {
    st.cutoff = std::max<uint32_t>(4096, n / 64);
    root_ = build(st, nodes_, 0, n, 0, true);
    std::vector<std::vector<BvhNode>> parts(st.pending.size());
    std::vector<BvhRef> roots(st.pending.size());
    parallelFor(0, int64_t(st.pending.size()), 1, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i) {
            const Pending& pd = st.pending[std::size_t(i)];
            roots[std::size_t(i)] = build(st, parts[std::size_t(i)], pd.begin, pd.end, pd.depth, false);
        }
    });
    std::vector<uint32_t> base(parts.size());
    for (std::size_t i = 0; i < parts.size(); ++i) {
        base[i] = uint32_t(nodes_.size());
        for (BvhNode node : parts[i]) {
            for (int c = 0; c < 2; ++c)
                if (!node.count[c]) node.ref[c] += base[i];
            nodes_.push_back(node);
        }
    }
    const auto link = [&](const BvhRef& placeholder) {
        BvhRef r = roots[placeholder.ref];
        if (!r.count) r.ref += base[placeholder.ref];
        return r;
    };
    if (root_.count == kPendingCount) root_ = link(root_);
    for (std::size_t i = 0; i < nodes_.size(); ++i)
        for (int c = 0; c < 2; ++c)
            if (nodes_[i].count[c] == kPendingCount) {
                BvhRef placeholder;
                placeholder.ref = nodes_[i].ref[c];
                const BvhRef r = link(placeholder);
                BvhNode& node = nodes_[i];
                node.ref[c] = r.ref;
                node.count[c] = r.count;
                // The box was unknown when the placeholder was made.
                for (int k = 0; k < 3; ++k) {
                    node.lo[c][k] = float(r.box.lo[k]);
                    node.hi[c][k] = float(r.box.hi[k]);
                }
            }
}

double TriangleBvh::triangleBoxDistance2(uint32_t i, const Vec3d& p) const {
    const float* c = &corners_[9 * std::size_t(i)];
    double s = 0;
    for (int k = 0; k < 3; ++k) {
        const double lo = std::min({c[k], c[3 + k], c[6 + k]}), hi = std::max({c[k], c[3 + k], c[6 + k]});
        const double d = std::max({lo - p[k], 0.0, p[k] - hi});
        s += d * d;
    }
    return s;
}

NearestHit TriangleBvh::nearest(const Vec3d& p, double maxDistance2, uint32_t hint) const {
    NearestHit hit;
    if (faces_.empty() || !isFinite(p)) return hit;
    hit.distance2 = maxDistance2;
    uint32_t bestTri = UINT32_MAX;
    double limit = pruneLimit(hit.distance2, diagonal_);
    // A good first guess (the answer of a nearby point) tightens the pruning from the start; the
    // tree is then searched as usual, so the answer is the same with or without it.
    if (hint < faces_.size()) {
        double u, v;
        const double d2 = triangleDistance2(triangle(hint), p, u, v);
        if (d2 <= hit.distance2) {
            hit.distance2 = d2;
            hit.u = u;
            hit.v = v;
            bestTri = hint;
            limit = pruneLimit(d2, diagonal_);
        }
    }
    const auto visitLeaf = [&](uint32_t first, uint32_t count) {
        for (uint32_t i = first; i < first + count; ++i) {
            if (triangleBoxDistance2(i, p) > limit) continue;
            double u, v;
            const double d2 = triangleDistance2(triangle(i), p, u, v);
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
    };
    struct Entry {
        uint32_t ref, count;
        double lb;
    };
    Entry stack[kStackSize];
    int sp = 0;
    stack[sp++] = {root_.ref, root_.count, 0.0};
    while (sp > 0) {
        Entry e = stack[--sp];
        if (e.lb > limit) continue;
        while (!e.count) {
            const BvhNode& node = nodes_[e.ref];
            const double d0 = boxDistance2(node.lo[0], node.hi[0], p),
                         d1 = boxDistance2(node.lo[1], node.hi[1], p);
            const int nearChild = d1 < d0 ? 1 : 0;
            const Entry nearE{node.ref[nearChild], node.count[nearChild], nearChild ? d1 : d0};
            const Entry farE{node.ref[1 - nearChild], node.count[1 - nearChild], nearChild ? d0 : d1};
            if (farE.lb <= limit) stack[sp++] = farE;
            if (nearE.lb > limit) break;
            e = nearE;
        }
        if (e.count && e.lb <= limit) visitLeaf(e.ref, e.count);
    }
    if (bestTri != UINT32_MAX) {
        hit.face = faces_[bestTri];
        hit.index = bestTri;
    }
    return hit;
}

void TriangleBvh::gather(const Vec3d& lo, const Vec3d& hi, double radius, std::vector<uint32_t>& out) const {
    if (faces_.empty()) return;
    const double r2 = radius * radius;
    const auto visitLeaf = [&](uint32_t first, uint32_t count) {
        for (uint32_t i = first; i < first + count; ++i) {
            const float* c = &corners_[9 * std::size_t(i)];
            float tlo[3], thi[3];
            for (int k = 0; k < 3; ++k) {
                tlo[k] = std::min({c[k], c[3 + k], c[6 + k]});
                thi[k] = std::max({c[k], c[3 + k], c[6 + k]});
            }
            if (boxBoxDistance2(tlo, thi, lo, hi) <= r2) out.push_back(i);
        }
    };
    if (root_.count) {
        visitLeaf(root_.ref, root_.count);
        return;
    }
    uint32_t stack[kStackSize];
    int sp = 0;
    stack[sp++] = root_.ref;
    while (sp > 0) {
        const BvhNode& node = nodes_[stack[--sp]];
        for (int c = 0; c < 2; ++c) {
            if (boxBoxDistance2(node.lo[c], node.hi[c], lo, hi) > r2) continue;
            if (node.count[c])
                visitLeaf(node.ref[c], node.count[c]);
            else
                stack[sp++] = node.ref[c];
        }
    }
}

} // namespace voxfx::detail
