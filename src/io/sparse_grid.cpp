// voxfx — SparseGrid (voxfx/sparse_grid.hpp): OpenVDB's tree behind the voxfx_vdb module, and the
// tiled voxelization into it. In io/ because the module is io's (module_api.hpp).
#include "voxfx/sparse_grid.hpp"

#include <atomic>
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
        fail(why, ": a ", frame.width(), " x ", frame.height(), " x ", frame.depth(), " grid needs ",
             detail::memoryText(need), " to voxelize and convert, but the memory budget is ",
             detail::memoryText(budget), " (the parity, winding and gwn fills work tile by tile)");
    return SparseGrid::fromDense(voxelize(mesh, frame, o));
}

} // namespace

SparseGrid voxelizeSparse(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& given,
                          const TileOptions& tiles) {
    validateMesh(mesh, "mesh");
    // Fill::Auto decided once, here (the report is the caller's; the calls below see the fill).
    VoxelizeOptions options = given;
    options.fill = resolveFill(mesh, frame, given);
    options.report = nullptr;
    const uint64_t budget = tiles.memoryBytes ? tiles.memoryBytes : availableMemoryBytes();
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
        if (total > treeBudget)
            fail("the sparse grid outgrew the memory budget (", detail::memoryText(budget),
                 ", of which the tiles take ", detail::memoryText(working), ") at ",
                 detail::memoryText(total),
                 " of tree; raise the budget (--memory, VOXFX_MEMORY_LIMIT) or lower the resolution");
    });
    std::string error;
    checkSparse(sparseModule().sparseFinish(tree, &error), error, "cannot build the sparse grid");
    return out;
}

} // namespace voxfx
