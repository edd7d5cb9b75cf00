// voxfx — SparseGrid (voxfx/sparse_grid.hpp): OpenVDB's tree behind the voxfx_vdb module, and the
// tiled voxelization into it. In io/ because the module is io's (module_api.hpp).
#include "voxfx/sparse_grid.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

#include "io/module_api.hpp"
#include "voxelize/memory_text.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace {

const detail::VdbModule& sparseModule() { return detail::vdbModule(); }

void checkSparse(bool ok, const std::string& error, const char* what) {
    if (!ok) fail(what, ": ", error);
}

void requireSparseFrame(const Frame& frame) {
    if (frame.isPerspective() || frame.isOriented() || frame.slicing() != Slicing::Uniform)
        fail("a sparse grid needs an axis-aligned orthographic frame with uniform slicing");
}

void sparseParallelFor(int64_t begin, int64_t end, int64_t grain, void* body,
                       void (*call)(void* body, int64_t b, int64_t e)) {
    parallelFor(begin, end, grain, [&](int64_t b, int64_t e) { call(body, b, e); });
}

// The dims of a frame's grid along world x, y, z.
Vec3i sparseWorldDims(const Frame& frame) {
    Vec3i d;
    d[columnXAxis(frame.axis())] = frame.width();
    d[columnYAxis(frame.axis())] = frame.height();
    d[sliceAxis(frame.axis())] = frame.depth();
    return d;
}

} // namespace

SparseGrid::SparseGrid() = default;

SparseGrid::SparseGrid(const Frame& frame) : frame_(frame) {
    requireSparseFrame(frame);
    std::string error;
    tree_ = sparseModule().sparseCreate(&error);
    checkSparse(tree_ != nullptr, error, "cannot create a sparse grid");
}

SparseGrid::~SparseGrid() {
    if (tree_) sparseModule().sparseDestroy(tree_);
}

SparseGrid::SparseGrid(const SparseGrid& o) : frame_(o.frame_), origin_(o.origin_) {
    if (!o.tree_) return;
    std::string error;
    tree_ = sparseModule().sparseCopy(o.tree_, &error);
    checkSparse(tree_ != nullptr, error, "cannot copy a sparse grid");
}

SparseGrid& SparseGrid::operator=(const SparseGrid& o) {
    if (this != &o) *this = SparseGrid(o);
    return *this;
}

SparseGrid::SparseGrid(SparseGrid&& o) noexcept
    : frame_(std::move(o.frame_)), origin_(o.origin_), tree_(std::exchange(o.tree_, nullptr)) {}

SparseGrid& SparseGrid::operator=(SparseGrid&& o) noexcept {
    if (this != &o) {
        if (tree_) sparseModule().sparseDestroy(tree_);
        frame_ = std::move(o.frame_);
        origin_ = o.origin_;
        tree_ = std::exchange(o.tree_, nullptr);
    }
    return *this;
}

SparseGrid SparseGrid::adopt(const Frame& frame, void* tree, const Vec3i& origin) {
    SparseGrid g;
    g.frame_ = frame;
    g.tree_ = tree;
    g.origin_ = origin;
    return g;
}

SparseGrid SparseGrid::fromDense(const VoxelGrid& grid) {
    const VoxelGrid uniform = grid.frame.slicing() == Slicing::Local ? resampleToUniform(grid) : grid;
    SparseGrid out(uniform.frame);
    const VoxelGrid z = uniform.frame.axis() == Axis::Z ? VoxelGrid{} : reslice(uniform, Axis::Z);
    const BitGrid& bits = uniform.frame.axis() == Axis::Z ? uniform.bits : z.bits;
    const detail::VdbBits view{bits.width(), bits.height(), bits.depth(), bits.wordsPerColumn(),
                               bits.words()};
    std::string error;
    checkSparse(sparseModule().sparseFromBits(out.tree_, view, sparseParallelFor, &error), error,
                "cannot convert to a sparse grid");
    return out;
}

VoxelGrid SparseGrid::toDense() const {
    if (!tree_) return {};
    const Vec3i d = dims();
    BitGrid bits(d.x, d.y, d.z); // checks the memory
    const int64_t origin[3] = {origin_.x, origin_.y, origin_.z};
    std::string error;
    checkSparse(sparseModule().sparseToBits(tree_, origin, d.x, d.y, d.z, bits.wordsPerColumn(), bits.words(),
                                            &error),
                error, "cannot convert a sparse grid to a dense one");
    VoxelGrid z{Frame::orthographic(frame_.box(), Axis::Z, d.x, d.y, d.z), std::move(bits)};
    return frame_.axis() == Axis::Z ? z : reslice(z, frame_.axis());
}

VoxelGrid SparseGrid::toDense(const IndexBox& box) const {
    if (!tree_ || box.empty()) return {};
    const Vec3i d = box.hi - box.lo + Vec3i{1, 1, 1};
    BitGrid bits(d.x, d.y, d.z); // checks the memory
    const int64_t origin[3] = {origin_.x + box.lo.x, origin_.y + box.lo.y, origin_.z + box.lo.z};
    std::string error;
    checkSparse(sparseModule().sparseToBits(tree_, origin, d.x, d.y, d.z, bits.wordsPerColumn(), bits.words(),
                                            &error),
                error, "cannot convert a sparse grid to a dense one");
    const Vec3d cell = frame_.cellSize(), lo = frame_.box().lo;
    const Box3d world{lo + cell * Vec3d(double(box.lo.x), double(box.lo.y), double(box.lo.z)),
                      lo + cell * Vec3d(double(box.hi.x + 1), double(box.hi.y + 1), double(box.hi.z + 1))};
    return {Frame::orthographic(world, Axis::Z, d.x, d.y, d.z), std::move(bits)};
}

Vec3i SparseGrid::dims() const { return tree_ ? sparseWorldDims(frame_) : Vec3i{0, 0, 0}; }

int64_t SparseGrid::count() const { return tree_ ? sparseModule().sparseCount(tree_) : 0; }

IndexBox SparseGrid::bounds() const {
    IndexBox box;
    int64_t lo[3], hi[3];
    if (!tree_ || !sparseModule().sparseBounds(tree_, lo, hi)) return box;
    box.lo = Vec3i{lo[0], lo[1], lo[2]} - origin_;
    box.hi = Vec3i{hi[0], hi[1], hi[2]} - origin_;
    return box;
}

bool SparseGrid::at(int64_t i, int64_t j, int64_t k) const {
    if (!tree_) return false;
    const int64_t ijk[3] = {i + origin_.x, j + origin_.y, k + origin_.z};
    for (int64_t v : ijk)
        if (v < std::numeric_limits<int32_t>::min() || v > std::numeric_limits<int32_t>::max()) return false;
    return sparseModule().sparseGet(tree_, ijk);
}

uint64_t SparseGrid::memoryBytes() const { return tree_ ? sparseModule().sparseMemory(tree_) : 0; }

void SparseGrid::requireSameFrame(const SparseGrid& o, const char* what) const {
    if (!tree_ || !o.tree_ || !frame_.sameGrid(o.frame_) || !(origin_ == o.origin_)) {
        // Frames sliced along other axes are the same cells: compare boxes and world dims.
        const bool sameCells = tree_ && o.tree_ && frame_.box() == o.frame_.box() &&
                               sparseWorldDims(frame_) == sparseWorldDims(o.frame_) && origin_ == o.origin_;
        if (!sameCells) fail("sparse grid ", what, ": the grids have different frames");
    }
}

SparseGrid& SparseGrid::unite(const SparseGrid& o) {
    requireSameFrame(o, "union");
    std::string error;
    checkSparse(sparseModule().sparseCombine(tree_, o.tree_, detail::SparseOp::Union, &error), error,
                "sparse grid union");
    return *this;
}

SparseGrid& SparseGrid::intersect(const SparseGrid& o) {
    requireSameFrame(o, "intersection");
    std::string error;
    checkSparse(sparseModule().sparseCombine(tree_, o.tree_, detail::SparseOp::Intersection, &error), error,
                "sparse grid intersection");
    return *this;
}

SparseGrid& SparseGrid::subtract(const SparseGrid& o) {
    requireSameFrame(o, "difference");
    std::string error;
    checkSparse(sparseModule().sparseCombine(tree_, o.tree_, detail::SparseOp::Difference, &error), error,
                "sparse grid difference");
    return *this;
}

SparseGrid& SparseGrid::dilate(int steps, Neighbours neighbours) {
    if (steps < 0) fail("dilation steps must be >= 0, got ", steps);
    std::string error;
    if (tree_ && steps > 0)
        checkSparse(sparseModule().sparseMorphology(tree_, false, steps, int(neighbours), &error), error,
                    "sparse dilation");
    return *this;
}

SparseGrid& SparseGrid::erode(int steps, Neighbours neighbours) {
    if (steps < 0) fail("erosion steps must be >= 0, got ", steps);
    std::string error;
    if (tree_ && steps > 0)
        checkSparse(sparseModule().sparseMorphology(tree_, true, steps, int(neighbours), &error), error,
                    "sparse erosion");
    return *this;
}

namespace {
void toIndices(const Vec3i& v, const Vec3i& origin, int64_t out[3]) {
    for (int a = 0; a < 3; ++a) out[a] = v[a] + origin[a];
}
} // namespace

SparseGrid& SparseGrid::fill(const IndexBox& box) {
    if (!tree_ || box.empty()) return *this;
    int64_t lo[3], hi[3];
    toIndices(box.lo, origin_, lo);
    toIndices(box.hi, origin_, hi);
    std::string error;
    checkSparse(sparseModule().sparseFill(tree_, lo, hi, &error), error, "sparse grid fill");
    return *this;
}

SparseGrid& SparseGrid::clip(const IndexBox& box) {
    if (!tree_) return *this;
    int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};
    if (!box.empty()) {
        toIndices(box.lo, origin_, lo);
        toIndices(box.hi, origin_, hi);
    }
    std::string error;
    checkSparse(sparseModule().sparseClip(tree_, lo, hi, &error), error, "sparse grid clip");
    return *this;
}

IndexBox SparseGrid::box() const {
    const Vec3i d = dims();
    return {{0, 0, 0}, d - Vec3i{1, 1, 1}};
}

std::vector<int32_t> SparseGrid::coordinates() const {
    const int64_t n = count();
    const IndexBox box = bounds();
    const int64_t limit = std::numeric_limits<int32_t>::max(), low = std::numeric_limits<int32_t>::min();
    if (!box.empty() && (box.lo.x < low || box.lo.y < low || box.lo.z < low || box.hi.x > limit ||
                         box.hi.y > limit || box.hi.z > limit))
        fail("sparse grid coordinates: an index does not fit int32");
    checkMemory(uint64_t(n) * 12, "the coordinates of the sparse grid's cells");
    std::vector<int32_t> out(size_t(3 * n));
    if (n == 0) return out;
    const int64_t origin[3] = {origin_.x, origin_.y, origin_.z};
    std::string error;
    checkSparse(sparseModule().sparseCoordinates(tree_, origin, out.data(), n, &error), error,
                "sparse grid coordinates");
    return out;
}

namespace {

// The cells of a fill that needs the whole grid: the dense grid, converted, when it fits.
SparseGrid sparseOfDense(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& o, uint64_t budget,
                         const std::string& why) {
    const uint64_t one = BitGrid::requiredBytes(frame.width(), frame.height(), frame.depth());
    // The dense grid, the surface it may need, and the conversion's leaves (at most a grid again).
    const uint64_t need = 3 * one;
    if (need > budget)
        failMemory(why, ": a ", frame.width(), " x ", frame.height(), " x ", frame.depth(), " grid needs ",
                   detail::memoryText(need), " to voxelize and convert, but the memory budget is ",
                   detail::memoryText(budget), " (the parity, winding and gwn fills work tile by tile)");
    return SparseGrid::fromDense(voxelize(mesh, frame, o));
}

// A lower bound on the tree's bytes, known before any brick: the surface crosses at least area /
// (sqrt(2) * 8^2) leaves of 8^3 cells (no plane cuts a cube of edge L in more than sqrt(2) L^2),
// area in cells, of the triangles wholly inside the grid; a bool leaf takes more than 128 bytes.
// Coincident triangles count twice (a bound too high for such meshes, by their share of the area).
uint64_t sparseTreeLowerBound(const MeshView& mesh, const Frame& frame) {
    if (frame.isPerspective()) return 0;
    const Vec3d size{double(frame.width()), double(frame.height()), double(frame.depth())};
    const auto inside = [&](const Vec3d& g) {
        return g.x >= 0 && g.y >= 0 && g.z >= 0 && g.x <= size.x && g.y <= size.y && g.z <= size.z;
    };
    double area = 0;
    for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
        const Vec3d a = frame.gridFromWorld(mesh.vertex(mesh.indices[3 * t])),
                    b = frame.gridFromWorld(mesh.vertex(mesh.indices[3 * t + 1])),
                    c = frame.gridFromWorld(mesh.vertex(mesh.indices[3 * t + 2]));
        if (inside(a) && inside(b) && inside(c)) area += 0.5 * length(cross(b - a, c - a));
    }
    const double leaves = std::floor(area / (std::sqrt(2.0) * 64.0));
    return leaves >= 0x1p56 ? ~uint64_t(0) : uint64_t(leaves) * 128;
}

} // namespace

SparseGrid voxelizeSparseUnpadded(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& given,
                                  const TileOptions& tiles);

SparseGrid voxelizeSparse(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& given,
                          const TileOptions& tiles) {
    SparseGrid out = voxelizeSparseUnpadded(mesh, frame, given, tiles);
    // The padding ring stays empty (VoxelizeOptions::emptyBorder; a whole-grid fill kept its
    // surface out of it already, so that a flood entered from the border).
    const int64_t r = given.emptyBorder;
    if (r > 0 && !frame.isPerspective() && !frame.isOriented() && frame.slicing() == Slicing::Uniform &&
        given.slicing == Slicing::Uniform) {
        const Vec3i d = out.dims();
        IndexBox inner{Vec3i{r, r, r}, Vec3i{d.x - 1 - r, d.y - 1 - r, d.z - 1 - r}};
        out.clip(inner);
    }
    return out;
}

SparseGrid voxelizeSparseUnpadded(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& given,
                                  const TileOptions& tiles) {
    validateMesh(mesh, "mesh");
    // Fill::Auto decided once, here (the report is the caller's; the calls below see the fill).
    VoxelizeOptions options = given;
    options.fill = resolveFill(mesh, frame, given);
    options.report = nullptr;
    const uint64_t budget = tiles.memoryBytes ? tiles.memoryBytes : availableMemoryBytes();
    // Refused before the first brick when the surface alone needs more leaves than the budget holds
    // (at a resolution of 100,000 a tree of tens of GiB would otherwise grow until killed).
    if (const uint64_t least = sparseTreeLowerBound(mesh, frame); least > budget)
        failMemory("a sparse ", frame.width(), " x ", frame.height(), " x ", frame.depth(),
                   " grid of this surface needs at least ", detail::memoryText(least),
                   " of tree, but the memory budget is ", detail::memoryText(budget),
                   "; raise the budget (--memory, VOXFX_MEMORY_LIMIT) or lower the resolution");
    if (options.deviceNote) options.deviceNote->clear();
    if (const std::string why = wholeGridReason(frame, options); !why.empty()) {
        if (options.slicing == Slicing::Local || frame.slicing() != Slicing::Uniform)
            fail("a sparse grid needs uniform slicing");
        requireSparseFrame(frame);
        return sparseOfDense(mesh, frame, options, budget, why);
    }
    if (options.device != Device::Cpu && options.deviceNote)
        *options.deviceNote = "tiles for a sparse grid run on the CPU";
    // The tree may take what the tiling leaves of the budget (known before the first brick).
    uint64_t working = 0;
    TileOptions t = tiles;
    t.workingBytes = &working;
    SparseGrid out(frame);
    void* tree = const_cast<void*>(out.handle());
    const Axis axis = frame.axis();
    std::atomic<uint64_t> treeBytes{0};
    // OpenVDB's upper internal nodes (4096^3 cells, 270 KiB each) count once per region a brick
    // fills: a bitmap of the regions, in the frame's (x, y, slice) order.
    const int64_t rx = (frame.width() + 4095) / 4096, ry = (frame.height() + 4095) / 4096,
                  rs = (frame.depth() + 4095) / 4096;
    std::vector<std::atomic<uint64_t>> regions(size_t((rx * ry * rs + 63) / 64));
    constexpr uint64_t kUpperNodeBytes = 270352 + 16;
    voxelizeTiles(mesh, frame, options, t, [&](const GridTile& tile) {
        if (tile.uniform && !tile.value) return;
        const uint64_t treeBudget = budget > working ? budget - working : 0;
        const int64_t region = ((tile.s0 / 4096) * ry + tile.y0 / 4096) * rx + tile.x0 / 4096;
        const uint64_t bit = uint64_t(1) << (region & 63);
        if (!(regions[size_t(region >> 6)].fetch_or(bit) & bit)) treeBytes += kUpperNodeBytes;
        detail::SparseBrick b;
        b.origin[columnXAxis(axis)] = tile.x0;
        b.origin[columnYAxis(axis)] = tile.y0;
        b.origin[sliceAxis(axis)] = tile.s0;
        b.width = tile.width;
        b.height = tile.height;
        b.depth = tile.depth;
        b.wordsPerColumn = tile.bits.wordsPerColumn;
        b.words = tile.bits.words;
        b.value = tile.value;
        b.axis = int(axis);
        uint64_t bytes = 0;
        std::string error;
        checkSparse(sparseModule().sparseAddBrick(tree, b, &bytes, &error), error,
                    "cannot build the sparse grid");
        const uint64_t total = treeBytes += bytes;
        // OpenVDB's count leaves out the allocator's overhead (about a tenth more, measured as
        // the process's growth): the budget holds the tree as the process sees it.
        if (total + total / 8 > treeBudget)
            failMemory("the sparse grid outgrew the memory budget (", detail::memoryText(budget),
                       ", of which the tiles take ", detail::memoryText(working), ") at ",
                       detail::memoryText(total),
                       " of tree; raise the budget (--memory, VOXFX_MEMORY_LIMIT) or lower the resolution");
    });
    std::string error;
    checkSparse(sparseModule().sparseFinish(tree, &error), error, "cannot build the sparse grid");
    return out;
}

} // namespace voxfx

namespace voxfx {
namespace detail_sparse_ops {

// The cells of `box` within `r` of its sides (r > 0).
IndexBox shrunk(const IndexBox& box, int64_t r) { return {box.lo + Vec3i{r, r, r}, box.hi - Vec3i{r, r, r}}; }

void dilateStep(SparseGrid& g, int r, MorphBorder border) {
    const IndexBox box = g.box();
    g.dilate(r).clip(box);
    if (border != MorphBorder::Filled || r == 0) return;
    // Outside filled: every cell within r of a side meets a filled cell.
    for (int a = 0; a < 3; ++a) {
        IndexBox low = box, high = box;
        low.hi[a] = std::min(box.hi[a], box.lo[a] + r - 1);
        high.lo[a] = std::max(box.lo[a], box.hi[a] - r + 1);
        g.fill(low).fill(high);
    }
}

void erodeStep(SparseGrid& g, int r, MorphBorder border) {
    const IndexBox box = g.box();
    if (border != MorphBorder::Empty && r > 0) {
        // Outside filled (Neutral erodes as Filled does): a cell c survives when box(c, r) holds
        // only filled cells; its outside cells matter only when c is filled and within r of a
        // side, and they lie within r of c. So outside cells within r of the filled cells of the
        // band along the sides stand in for the whole filled outside.
        SparseGrid band = g, inner = g;
        band.subtract(inner.clip(shrunk(box, r)));
        band.dilate(r);
        SparseGrid inside = band;
        band.subtract(inside.clip(box));
        g.unite(band);
    }
    // OpenVDB's erosion expands tiles into leaves (a cube filling 1024^3: 62 s, 720 MB); the same
    // cells as X minus the dilation by r of X's outer boundary (the empty cells next to a filled
    // one: a box around c that holds an empty cell holds one next to a filled cell, on the way
    // from c), which touches only the surface's leaves.
    if (r > 0) {
        SparseGrid boundary = g;
        boundary.dilate(1).subtract(g);
        g.subtract(boundary.dilate(r));
    }
    g.clip(box);
}

} // namespace detail_sparse_ops

SparseGrid morphology(const SparseGrid& grid, MorphOp op, int64_t radius, MorphBorder border) {
    if (radius < 0 || radius > (int64_t(1) << 20))
        fail("sparse morphology: the radius must lie in [0, 2^20], got ", radius);
    using namespace detail_sparse_ops;
    SparseGrid g = grid;
    g.clip(g.box());
    const int r = int(radius);
    switch (op) {
    case MorphOp::Dilate:
        dilateStep(g, r, border);
        break;
    case MorphOp::Erode:
        erodeStep(g, r, border);
        break;
    case MorphOp::Open:
        erodeStep(g, r, border);
        dilateStep(g, r, border);
        break;
    case MorphOp::Close:
        dilateStep(g, r, border);
        erodeStep(g, r, border);
        break;
    }
    return g;
}

SparseGrid evaluateCsg(const CsgNode& node, const std::function<SparseGrid(const std::string&)>& leaf) {
    if (node.isMesh) return leaf(node.mesh);
    if (node.args.empty()) fail("CSG: operation '", toString(node.op), "' without arguments");
    SparseGrid acc = evaluateCsg(node.args[0], leaf);
    for (size_t i = 1; i < node.args.size(); ++i) {
        const SparseGrid b = evaluateCsg(node.args[i], leaf);
        switch (node.op) {
        case CsgOp::Union:
            acc.unite(b);
            break;
        case CsgOp::Intersection:
            acc.intersect(b);
            break;
        case CsgOp::Difference:
            acc.subtract(b);
            break;
        case CsgOp::Xor: {
            SparseGrid both = acc;
            both.intersect(b);
            acc.unite(b).subtract(both);
            break;
        }
        }
    }
    return acc;
}

} // namespace voxfx
