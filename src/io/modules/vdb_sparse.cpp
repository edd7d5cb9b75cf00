// voxfx_vdb — sparse grids (voxfx/sparse_grid.hpp): OpenVDB's bool tree fed brick by brick
// (voxelizeSparse), its topology operations (CSG, morphology, fill, clip), and its files.
#include <algorithm>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/ValueAccessor.h>

#include "io/modules/vdb_internal.hpp"

namespace voxfx::detail::vdbmodule {

namespace {

struct SparseHandle {
    openvdb::BoolGrid::Ptr grid;
    std::mutex mutex; // sparseAddBrick's insertions
};
SparseHandle& handle(void* g) { return *static_cast<SparseHandle*>(g); }
const SparseHandle& handle(const void* g) { return *static_cast<const SparseHandle*>(g); }

// Transposes an 8 x 8 bit matrix (byte r = row r, bit c = column c): bit 8r + c <-> bit 8c + r.
uint64_t transpose8(uint64_t x) {
    uint64_t t = (x ^ (x >> 7)) & 0x00AA00AA00AA00AAull;
    x ^= t ^ (t << 7);
    t = (x ^ (x >> 14)) & 0x0000CCCC0000CCCCull;
    x ^= t ^ (t << 14);
    t = (x ^ (x >> 28)) & 0x00000000F0F0F0F0ull;
    x ^= t ^ (t << 28);
    return x;
}

// The value mask of the 8 x 8 x 8 block of a brick whose first column is (bx, by) and first slice
// bs (brick cells), in OpenVDB's leaf order (offset = i << 6 | j << 3 | k, world axes).
//   bytes[lx][ly] = slices bs .. bs + 7 of brick column (bx + lx, by + ly)
//   axis z: (i, j, k) = (lx, ly, slice): word lx, byte ly is bytes[lx][ly] as it is;
//   axis x: (i, j, k) = (slice, lx, ly): word slice, byte lx, bit ly: the transpose of the eight
//           bytes of one lx (row ly, bit slice);
//   axis y: (i, j, k) = (ly, slice, lx): word ly, byte slice, bit lx: the transpose of the eight
//           bytes of one ly (row lx, bit slice).
void blockMask(const SparseBrick& b, int64_t bx, int64_t by, int64_t bs, uint64_t m[8]) {
    uint8_t bytes[8][8] = {};
    for (int64_t lx = 0; lx < 8 && bx + lx < b.width; ++lx)
        for (int64_t ly = 0; ly < 8 && by + ly < b.height; ++ly) {
            const uint64_t* col = b.words + ((by + ly) * b.width + bx + lx) * b.wordsPerColumn;
            bytes[lx][ly] = uint8_t(col[bs >> 6] >> (bs & 63));
        }
    auto word = [&](int64_t fixed, bool byLx) {
        uint64_t w = 0;
        for (int r = 0; r < 8; ++r) w |= uint64_t(byLx ? bytes[fixed][r] : bytes[r][fixed]) << (8 * r);
        return w;
    };
    std::fill(m, m + 8, 0);
    for (int k = 0; k < 8; ++k) {
        if (b.axis == 2) {
            m[k] = word(k, true);
        } else if (b.axis == 1) {
            m[k] = transpose8(word(k, false));
        } else {
            const uint64_t t = transpose8(word(k, true)); // byte = slice, bit = ly
            for (int sl = 0; sl < 8; ++sl) m[sl] |= ((t >> (8 * sl)) & 0xFF) << (8 * k);
        }
    }
}

// The world index of brick cell (x, y, slice).
openvdb::Coord brickCoord(const SparseBrick& b, int64_t x, int64_t y, int64_t s) {
    int64_t c[3];
    c[(b.axis + 1) % 3] = b.origin[(b.axis + 1) % 3] + x;
    c[(b.axis + 2) % 3] = b.origin[(b.axis + 2) % 3] + y;
    c[b.axis] = b.origin[b.axis] + s;
    return openvdb::Coord(int(c[0]), int(c[1]), int(c[2]));
}

// Bytes a leaf and a lowest internal node take (with the allocator's share), for the budget.
constexpr uint64_t kLeafBytes = sizeof(BoolLeaf) + 16;
constexpr uint64_t kNodeBytes = sizeof(BoolTree::RootNodeType::ChildNodeType::ChildNodeType) + 16;

void addBrick(SparseHandle& h, const SparseBrick& b, uint64_t* bytes) {
    const openvdb::Coord lo = brickCoord(b, 0, 0, 0);
    int64_t size[3];
    size[(b.axis + 1) % 3] = b.width;
    size[(b.axis + 2) % 3] = b.height;
    size[b.axis] = b.depth;
    // A brick that is one whole node of the lowest internal level: one tile of that node's size.
    const bool node = size[0] == 128 && size[1] == 128 && size[2] == 128 && (lo.x() & 127) == 0 &&
                      (lo.y() & 127) == 0 && (lo.z() & 127) == 0;
    *bytes = 0;
    if (!b.words) {
        if (!b.value) return;
        std::lock_guard<std::mutex> lock(h.mutex);
        if (node)
            h.grid->tree().addTile(2, lo, true, true);
        else
            h.grid->tree().fill(openvdb::CoordBBox(lo, lo + openvdb::Coord(int(size[0] - 1), int(size[1] - 1),
                                                                           int(size[2] - 1))),
                                true, true);
        *bytes = node ? 0 : kNodeBytes;
        return;
    }
    std::vector<std::unique_ptr<BoolLeaf>> leaves;
    std::vector<openvdb::Coord> full;
    // Blocks of 8 x 8 columns, one column word (eight blocks of eight slices) at a time: the OR and
    // the AND of the 64 columns' words tell the empty bytes (blocks) and the full ones, so only
    // mixed blocks are gathered (most blocks of a brick the surface crosses are uniform).
    for (int64_t by = 0; by < b.height; by += 8)
        for (int64_t bx = 0; bx < b.width; bx += 8) {
            const bool whole = bx + 8 <= b.width && by + 8 <= b.height;
            for (int64_t w = 0; w < b.wordsPerColumn; ++w) {
                uint64_t any = 0, all = whole ? ~uint64_t(0) : 0;
                for (int64_t ly = 0; ly < 8 && by + ly < b.height; ++ly)
                    for (int64_t lx = 0; lx < 8 && bx + lx < b.width; ++lx) {
                        const uint64_t word = b.words[((by + ly) * b.width + bx + lx) * b.wordsPerColumn + w];
                        any |= word;
                        all &= word;
                    }
                for (int64_t k = 0; k < 8 && 64 * w + 8 * k < b.depth; ++k) {
                    if (((any >> (8 * k)) & 0xFF) == 0) continue;
                    const int64_t bs = 64 * w + 8 * k;
                    const openvdb::Coord origin = brickCoord(b, bx, by, bs);
                    if (((all >> (8 * k)) & 0xFF) == 0xFF && bs + 8 <= b.depth) {
                        full.push_back(origin);
                        continue;
                    }
                    uint64_t m[8];
                    blockMask(b, bx, by, bs, m);
                    auto leaf = std::make_unique<BoolLeaf>(origin, false, false);
                    BoolLeaf::NodeMaskType mask;
                    for (int i = 0; i < 8; ++i) mask.template getWord<uint64_t>(openvdb::Index(i)) = m[i];
                    leaf->setValueMask(mask);
                    std::copy(m, m + 8, leaf->buffer().data()); // value true exactly where active
                    leaves.push_back(std::move(leaf));
                }
            }
        }
    const int64_t blocks = ((size[0] + 7) / 8) * ((size[1] + 7) / 8) * ((size[2] + 7) / 8);
    std::lock_guard<std::mutex> lock(h.mutex);
    if (node && int64_t(full.size()) == blocks) {
        h.grid->tree().addTile(2, lo, true, true);
        return;
    }
    openvdb::tree::ValueAccessor<BoolTree> acc(h.grid->tree());
    for (auto& leaf : leaves) acc.addLeaf(leaf.release());
    for (const openvdb::Coord& origin : full) acc.addTile(1, origin, true, true);
    *bytes = kNodeBytes + uint64_t(leaves.size()) * kLeafBytes;
}

// Active voxels hold true and inactive ones false (topology operations and dilation leave the
// background's false in newly active voxels), then uniform nodes become tiles.
void normalize(BoolTree& tree) {
    for (auto leaf = tree.beginLeaf(); leaf; ++leaf) {
        const auto& mask = leaf->getValueMask();
        for (int i = 0; i < 8; ++i)
            leaf->buffer().data()[i] = mask.template getWord<uint64_t>(openvdb::Index(i));
    }
    auto tile = tree.beginValueAll();
    tile.setMaxDepth(BoolTree::ValueAllIter::LEAF_DEPTH - 1);
    for (; tile; ++tile) tile.setValue(tile.isValueOn());
    tree.prune();
}

// A tree's filled voxels as an index box; false when empty.
bool treeBounds(const BoolTree& tree, int64_t lo[3], int64_t hi[3]) {
    openvdb::CoordBBox box;
    if (!tree.evalActiveVoxelBoundingBox(box)) return false;
    for (int a = 0; a < 3; ++a) {
        lo[a] = box.min()[a];
        hi[a] = box.max()[a];
    }
    return true;
}

} // namespace

void* sparseCreate(std::string* error) {
    SparseHandle* h = nullptr;
    guarded(error, [&] {
        initializeOpenVdb();
        auto owned = std::make_unique<SparseHandle>();
        owned->grid = openvdb::BoolGrid::create(false);
        h = owned.release();
    });
    return h;
}

void sparseDestroy(void* g) { delete static_cast<SparseHandle*>(g); }

void* sparseCopy(const void* g, std::string* error) {
    SparseHandle* h = nullptr;
    guarded(error, [&] {
        auto owned = std::make_unique<SparseHandle>();
        owned->grid = handle(g).grid->deepCopy();
        h = owned.release();
    });
    return h;
}

bool sparseAddBrick(void* g, const SparseBrick& b, uint64_t* bytes, std::string* error) {
    return guarded(error, [&] { addBrick(handle(g), b, bytes); });
}

bool sparseFinish(void* g, std::string* error) {
    return guarded(error, [&] { handle(g).grid->tree().prune(); });
}

bool sparseFromBits(void* g, const VdbBits& bits, ParallelFor parallelFor, std::string* error) {
    return guarded(error, [&] {
        auto grid = openvdb::BoolGrid::create(false);
        fillLeaves(bits, parallelFor, *grid);
        handle(g).grid->tree().topologyUnion(grid->tree());
        normalize(handle(g).grid->tree());
    });
}

bool sparseToBits(const void* g, const int64_t origin[3], int64_t nx, int64_t ny, int64_t nz, int64_t wpc,
                  uint64_t* words, std::string* error) {
    return guarded(error, [&] {
        readTree(*handle(g).grid, openvdb::Coord(int(origin[0]), int(origin[1]), int(origin[2])),
                 Target{nx, ny, nz, wpc, words});
    });
}

int64_t sparseCount(const void* g) { return int64_t(handle(g).grid->tree().activeVoxelCount()); }

bool sparseBounds(const void* g, int64_t lo[3], int64_t hi[3]) {
    return treeBounds(handle(g).grid->tree(), lo, hi);
}

uint64_t sparseMemory(const void* g) { return uint64_t(handle(g).grid->tree().memUsage()); }

bool sparseGet(const void* g, const int64_t ijk[3]) {
    return handle(g).grid->tree().isValueOn(openvdb::Coord(int(ijk[0]), int(ijk[1]), int(ijk[2])));
}

bool sparseCombine(void* a, const void* b, SparseOp op, std::string* error) {
    return guarded(error, [&] {
        BoolTree& ta = handle(a).grid->tree();
        const BoolTree& tb = handle(b).grid->tree();
        if (op == SparseOp::Union)
            ta.topologyUnion(tb);
        else if (op == SparseOp::Intersection)
            ta.topologyIntersection(tb);
        else
            ta.topologyDifference(tb);
        normalize(ta);
    });
}

bool sparseMorphology(void* g, bool erode, int iterations, int neighbours, std::string* error) {
    return guarded(error, [&] {
        const openvdb::tools::NearestNeighbors nn = neighbours == 26   ? openvdb::tools::NN_FACE_EDGE_VERTEX
                                                    : neighbours == 18 ? openvdb::tools::NN_FACE_EDGE
                                                                       : openvdb::tools::NN_FACE;
        BoolTree& tree = handle(g).grid->tree();
        if (erode)
            openvdb::tools::erodeActiveValues(tree, iterations, nn, openvdb::tools::PRESERVE_TILES);
        else
            openvdb::tools::dilateActiveValues(tree, iterations, nn, openvdb::tools::PRESERVE_TILES);
        normalize(tree);
    });
}

namespace {

openvdb::CoordBBox indexBox(const int64_t lo[3], const int64_t hi[3]) {
    for (int a = 0; a < 3; ++a)
        if (lo[a] < std::numeric_limits<int32_t>::min() || hi[a] > std::numeric_limits<int32_t>::max())
            fail("the index box [", lo[a], ", ", hi[a], "] along axis ", a, " does not fit OpenVDB's int32");
    return openvdb::CoordBBox(openvdb::Coord(int(lo[0]), int(lo[1]), int(lo[2])),
                              openvdb::Coord(int(hi[0]), int(hi[1]), int(hi[2])));
}

} // namespace

bool sparseFill(void* g, const int64_t lo[3], const int64_t hi[3], std::string* error) {
    return guarded(error, [&] {
        const openvdb::CoordBBox box = indexBox(lo, hi);
        if (box.empty()) return;
        BoolTree& tree = handle(g).grid->tree();
        tree.fill(box, true, true);
        normalize(tree);
    });
}

bool sparseClip(void* g, const int64_t lo[3], const int64_t hi[3], std::string* error) {
    return guarded(error, [&] {
        BoolTree& tree = handle(g).grid->tree();
        const openvdb::CoordBBox box = indexBox(lo, hi);
        if (box.empty())
            tree.clear();
        else
            tree.clip(box);
        normalize(tree);
    });
}

bool sparseCoordinates(const void* g, const int64_t origin[3], int32_t* out, int64_t count,
                       std::string* error) {
    return guarded(error, [&] {
        const BoolTree& tree = handle(g).grid->tree();
        int64_t n = 0;
        auto put = [&](const openvdb::Coord& c) {
            if (n >= count) fail("the grid holds more voxels than the ", count, " counted");
            for (int a = 0; a < 3; ++a) out[3 * n + a] = int32_t(int64_t(c[a]) - origin[a]);
            ++n;
        };
        for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf)
            for (auto on = leaf->cbeginValueOn(); on; ++on) put(on.getCoord());
        auto tile = tree.cbeginValueOn();
        tile.setMaxDepth(BoolTree::ValueOnCIter::LEAF_DEPTH - 1);
        for (; tile; ++tile) {
            const openvdb::CoordBBox bb = tile.getBoundingBox();
            for (int x = bb.min().x(); x <= bb.max().x(); ++x)
                for (int y = bb.min().y(); y <= bb.max().y(); ++y)
                    for (int z = bb.min().z(); z <= bb.max().z(); ++z) put(openvdb::Coord(x, y, z));
        }
        if (n != count) fail("the grid holds ", n, " voxels, not the ", count, " counted");
    });
}

bool sparseWrite(const char* path, const void* g, const int64_t origin[3], const VdbPlacement& placement,
                 const int64_t dims[3], const char* gridName, bool asFloat, std::string* error) {
    return guarded(error, [&] {
        const BoolTree& tree = handle(g).grid->tree();
        openvdb::GridBase::Ptr out;
        if (asFloat) {
            auto fg = openvdb::FloatGrid::create(
                std::make_shared<openvdb::FloatTree>(tree, 0.0f, 1.0f, openvdb::TopologyCopy()));
            fg->setGridClass(openvdb::GRID_FOG_VOLUME);
            out = fg;
        } else {
            out = openvdb::BoolGrid::create(handle(g).grid->treePtr()); // shares the tree: read only
        }
        // The placement names voxel (0, 0, 0): index `origin` of the tree sits there.
        VdbPlacement p = placement;
        for (int a = 0; a < 3; ++a) p.centre0[a] -= double(origin[a]) * p.cell[a];
        out->setTransform(transformFor(p));
        out->setName(gridName);
        out->insertMeta(kDimsMeta,
                        openvdb::Vec3IMetadata(openvdb::Vec3i(int(dims[0]), int(dims[1]), int(dims[2]))));
        writeFile(path, out);
    });
}

namespace {

// The filled voxels of a scalar grid: active and > 0, as a bool topology.
template <class GridT> void filledTopology(const GridT& grid, BoolTree& out) {
    out.topologyUnion(grid.tree());
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf)
        for (auto on = leaf->cbeginValueOn(); on; ++on)
            if (!(*on > 0)) out.setValueOff(on.getCoord(), false);
    auto tile = grid.tree().cbeginValueOn();
    tile.setMaxDepth(GridT::TreeType::ValueOnCIter::LEAF_DEPTH - 1);
    for (; tile; ++tile)
        if (!(*tile > 0)) out.fill(tile.getBoundingBox(), false, false);
}

} // namespace

void* sparseRead(const uint8_t* data, std::size_t size, VdbReadBox* box, int64_t origin[3],
                 std::string* error) {
    SparseHandle* h = nullptr;
    guarded(error, [&] {
        const openvdb::GridBase::Ptr base = firstOccupancyGrid(data, size);
        double cell[3], centre0[3];
        boxTransform(*base, cell, centre0);
        const openvdb::CoordBBox ibox = indexBox(*base);
        const openvdb::Coord o = ibox.min();
        for (int a = 0; a < 3; ++a) {
            box->dims[a] = int64_t(ibox.max()[a]) - o[a] + 1;
            box->lo[a] = centre0[a] + (double(o[a]) - 0.5) * cell[a];
            box->hi[a] = box->lo[a] + double(box->dims[a]) * cell[a];
            origin[a] = o[a];
        }
        auto owned = std::make_unique<SparseHandle>();
        owned->grid = openvdb::BoolGrid::create(false);
        if (auto b = openvdb::GridBase::grid<openvdb::BoolGrid>(base))
            owned->grid->tree().topologyUnion(b->tree());
        else if (auto f = openvdb::GridBase::grid<openvdb::FloatGrid>(base))
            filledTopology(*f, owned->grid->tree());
        else
            filledTopology(*openvdb::GridBase::grid<openvdb::DoubleGrid>(base), owned->grid->tree());
        normalize(owned->grid->tree());
        h = owned.release();
    });
    return h;
}

} // namespace voxfx::detail::vdbmodule
