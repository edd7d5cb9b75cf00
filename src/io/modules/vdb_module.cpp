// voxfx_vdb — the OpenVDB module: .vdb reading and writing (see io/module_api.hpp, io/vdb.cpp,
// io/volume_vdb.cpp).
//
// Written grids: a BoolGrid (or a FloatGrid fog volume with 1 in filled voxels) whose index
// (i, j, k) is voxel (i, j, k) of the grid and whose transform maps it to the voxel centre:
// scale by the cell size, then translate by lo + cell / 2 (OpenVDB's cell-centred convention).
// The grid's dimensions travel as Vec3i metadata "voxfx_dims", so empty borders survive a round
// trip; grids without it get the bounding box of their active voxels.
//
// The writer fills leaf nodes straight from the bit columns: with the grid sliced along z, the
// 8 x 8 x 8 leaf at (x0, y0, z0) has value-mask word x & 7 = eight bytes, byte y & 7 being bits
// z0 .. z0+7 of column (x, y) (offset = (x & 7) << 6 | (y & 7) << 3 | (z & 7)).
#include <algorithm>
#include <bit>
#include <cmath>
#include <istream>
#include <limits>
#include <memory>
#include <mutex>
#include <span>
#include <streambuf>
#include <string>
#include <string_view>
#include <vector>

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafNode.h>
#include <openvdb/tree/ValueAccessor.h>

#include "core/bitops.hpp"
#include "io/module_api.hpp"
#include "io/modules/vdb_validate.hpp"
#include "voxfx/error.hpp"

namespace voxfx::detail {

namespace {
constexpr const char* kDimsMeta = "voxfx_dims";

void initializeOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

template <class F>
void forChunks(ParallelFor parallelFor, int64_t begin, int64_t end, int64_t grain, F& body) {
    parallelFor(begin, end, grain, &body, [](void* f, int64_t b, int64_t e) { (*static_cast<F*>(f))(b, e); });
}

using BoolLeaf = openvdb::BoolGrid::TreeType::LeafNodeType;
static_assert(BoolLeaf::LOG2DIM == 3 && BoolLeaf::NodeMaskType::WORD_COUNT == 8);

// Builds the leaves of a z-sliced grid, 8 x 8 leaf columns per task, and hands them to the tree
// in a fixed order (deterministic tree, single-threaded insertion).
template <class GridT> void fillLeaves(const VdbBits& g, ParallelFor parallelFor, GridT& grid) {
    using LeafT = typename GridT::TreeType::LeafNodeType;
    using ValueT = typename LeafT::ValueType;
    const int64_t nx = g.nx, ny = g.ny, nz = g.nz, wpc = g.wordsPerColumn;
    const int64_t lx = (nx + 7) / 8, ly = (ny + 7) / 8, lz = (nz + 7) / 8;
    std::vector<std::vector<std::unique_ptr<LeafT>>> leaves(size_t(lx * ly));
    std::vector<std::vector<openvdb::Coord>> fullLeaves(size_t(lx * ly));
    auto body = [&](int64_t b, int64_t e) {
        std::vector<uint64_t> masks(size_t(lz * 8));
        for (int64_t t = b; t < e; ++t) {
            const int64_t bx = t % lx, by = t / lx;
            std::fill(masks.begin(), masks.end(), 0);
            // Column (x, y) word w holds bits z = 64w .. 64w+63: byte k goes to leaf bz = 8w + k.
            for (int64_t ix = 0; ix < 8 && bx * 8 + ix < nx; ++ix)
                for (int64_t jy = 0; jy < 8 && by * 8 + jy < ny; ++jy) {
                    const uint64_t* col = g.words + ((by * 8 + jy) * nx + bx * 8 + ix) * wpc;
                    for (int64_t w = 0; w < wpc; ++w) {
                        const uint64_t word = col[w];
                        if (!word) continue;
                        for (int64_t k = 0; k < 8 && w * 8 + k < lz; ++k)
                            masks[size_t((w * 8 + k) * 8 + ix)] |= ((word >> (8 * k)) & 0xFF) << (8 * jy);
                    }
                }
            for (int64_t bz = 0; bz < lz; ++bz) {
                const uint64_t* m = &masks[size_t(bz * 8)];
                if (!(m[0] | m[1] | m[2] | m[3] | m[4] | m[5] | m[6] | m[7])) continue;
                const openvdb::Coord origin(int(bx * 8), int(by * 8), int(bz * 8));
                // Full blocks become leaf-sized tiles: no 2 KiB float buffer to allocate and prune.
                if (!~(m[0] & m[1] & m[2] & m[3] & m[4] & m[5] & m[6] & m[7])) {
                    fullLeaves[size_t(t)].push_back(origin);
                    continue;
                }
                typename LeafT::NodeMaskType mask;
                for (int i = 0; i < 8; ++i) mask.template getWord<uint64_t>(openvdb::Index(i)) = m[i];
                auto leaf = std::make_unique<LeafT>(origin, ValueT(0), false);
                leaf->setValueMask(mask);
                if constexpr (std::is_same_v<ValueT, bool>) {
                    std::copy(m, m + 8, leaf->buffer().data()); // value true exactly where active
                } else {
                    auto* values = leaf->buffer().data();
                    for (int i = 0; i < 512; ++i) values[i] = float((m[i >> 6] >> (i & 63)) & 1u);
                }
                leaves[size_t(t)].push_back(std::move(leaf));
            }
        }
    };
    forChunks(parallelFor, 0, lx * ly, 4, body);
    auto& tree = grid.tree();
    for (size_t t = 0; t < leaves.size(); ++t) {
        for (auto& leaf : leaves[t]) tree.addLeaf(leaf.release());
        for (const openvdb::Coord& origin : fullLeaves[t]) tree.addTile(1, origin, ValueT(1), true);
    }
    // Blocks of full tiles merge into larger tiles: smaller files, same voxels.
    tree.prune();
}

openvdb::math::Transform::Ptr transformFor(const VdbPlacement& p) {
    openvdb::math::Transform::Ptr xform;
    if (p.cell[0] == p.cell[1] && p.cell[1] == p.cell[2]) {
        xform = openvdb::math::Transform::createLinearTransform(p.cell[0]);
    } else {
        xform = openvdb::math::Transform::createLinearTransform(1.0);
        xform->preScale(openvdb::Vec3d(p.cell[0], p.cell[1], p.cell[2]));
    }
    xform->postTranslate(openvdb::Vec3d(p.centre0[0], p.centre0[1], p.centre0[2]));
    return xform;
}

void writeFile(const char* path, const openvdb::GridBase::Ptr& grid) {
    try {
        openvdb::io::File f(path);
        f.write({grid});
        f.close();
    } catch (const openvdb::Exception& e) { fail("OpenVDB: ", e.what()); }
}

// Cell size and centre of voxel (0,0,0) of an axis-aligned scale + translate transform.
void boxTransform(const openvdb::GridBase& grid, double cell[3], double centre0[3]) {
    const openvdb::math::MapBase::ConstPtr map = grid.transform().baseMap();
    if (!map->isLinear())
        fail("grid '", grid.getName(), "' has a non-linear (", map->type(), ") transform; only axis-aligned ",
             "scale + translate transforms describe a voxel box");
    const openvdb::Mat4d m = map->getAffineMap()->getMat4(); // row vectors: p' = p * m
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c)
            if (r != c && std::abs(m(r, c)) > 1e-12 * (std::abs(m(r, r)) + std::abs(m(c, c))))
                fail("grid '", grid.getName(), "' has a rotated or sheared transform; only axis-aligned ",
                     "scale + translate transforms describe a voxel box");
        cell[r] = m(r, r);
        centre0[r] = m(3, r);
    }
    bool finite = true;
    for (int i = 0; i < 3; ++i) finite = finite && std::isfinite(cell[i]) && std::isfinite(centre0[i]);
    if (!(cell[0] > 0 && cell[1] > 0 && cell[2] > 0 && finite))
        fail("grid '", grid.getName(), "' has a mirrored or degenerate transform (scale ", cell[0], ", ",
             cell[1], ", ", cell[2], ")");
}

// Cell sizes, unit directions of the index axes and centre of voxel (0,0,0) of a linear transform
// whose index axes are orthogonal (scale, rotation, mirror, translation): what a turned volume is.
void turnedTransform(const openvdb::GridBase& grid, double cell[3], double axes[3][3], double centre0[3]) {
    const openvdb::math::MapBase::ConstPtr map = grid.transform().baseMap();
    if (!map->isLinear())
        fail("grid '", grid.getName(), "' has a non-linear (", map->type(), ") transform; only linear ",
             "transforms with orthogonal axes describe a voxel box");
    const openvdb::Mat4d m = map->getAffineMap()->getMat4(); // row vectors: row r is index axis r's step
    for (int r = 0; r < 3; ++r) {
        cell[r] = std::sqrt(m(r, 0) * m(r, 0) + m(r, 1) * m(r, 1) + m(r, 2) * m(r, 2));
        if (!(std::isfinite(cell[r]) && cell[r] > 0))
            fail("grid '", grid.getName(), "' has a degenerate transform (index axis ", r, " has length ",
                 cell[r], ")");
        for (int c = 0; c < 3; ++c) axes[r][c] = m(r, c) / cell[r];
        centre0[r] = m(3, r);
        if (!std::isfinite(centre0[r])) fail("grid '", grid.getName(), "' has a non-finite translation");
    }
    for (int r = 0; r < 3; ++r)
        for (int q = 0; q < r; ++q) {
            const double d = axes[r][0] * axes[q][0] + axes[r][1] * axes[q][1] + axes[r][2] * axes[q][2];
            if (!(std::abs(d) <= 1e-6))
                fail("grid '", grid.getName(), "' has a sheared transform (index axes ", q, " and ", r,
                     " are not orthogonal); only scale, rotation and translation describe a voxel box");
        }
}

// A z-sliced target: n = index box size, words wpc per column (x, y).
struct Target {
    int64_t nx, ny, nz, wpc;
    uint64_t* words;
    uint64_t* column(int64_t x, int64_t y) const { return words + (y * nx + x) * wpc; }
};

// Sets the bits of a z-sliced grid whose index box starts at `o` from a tree's leaves and tiles:
// active voxels (and, for scalars, value > 0).
template <class GridT> void readTree(const GridT& grid, const openvdb::Coord& o, const Target& g) {
    using TreeT = typename GridT::TreeType;
    using ValueT = typename GridT::ValueType;
    const TreeT& tree = grid.tree();
    const int64_t nx = g.nx, ny = g.ny, nz = g.nz;
    auto filled = [](const ValueT& v) {
        if constexpr (std::is_same_v<ValueT, bool>) {
            (void)v; // bool grids: activity alone marks a filled voxel
            return true;
        } else {
            return v > ValueT(0);
        }
    };
    // Leaves: eight z bits per (x, y) row, shifted to the column's bit position.
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const openvdb::Coord l = leaf->origin();
        const auto& mask = leaf->getValueMask();
        for (int ix = 0; ix < 8; ++ix) {
            uint64_t word = mask.template getWord<uint64_t>(openvdb::Index(ix));
            if constexpr (!std::is_same_v<ValueT, bool>) {
                for (uint64_t bits = word; bits; bits &= bits - 1) {
                    const int b = std::countr_zero(bits);
                    if (!filled(leaf->getValue(openvdb::Index(ix * 64 + b)))) word &= ~(uint64_t(1) << b);
                }
            }
            const int64_t x = int64_t(l.x()) + ix - o.x();
            if (!word || x < 0 || x >= nx) continue;
            for (int jy = 0; jy < 8; ++jy) {
                uint64_t byte = (word >> (8 * jy)) & 0xFF;
                const int64_t y = int64_t(l.y()) + jy - o.y();
                int64_t z = int64_t(l.z()) - o.z();
                if (!byte || y < 0 || y >= ny) continue;
                // The index box holds every active voxel, so bits shifted out below 0 or past nz
                // are empty; clamp anyway so a bad box cannot write outside the column.
                if (z < 0) {
                    byte >>= std::min<int64_t>(8, -z);
                    z = 0;
                }
                if (z >= nz) continue;
                if (nz - z < 8) byte &= (uint64_t(1) << (nz - z)) - 1;
                uint64_t* col = g.column(x, y);
                col[z >> 6] |= byte << (z & 63);
                if ((z & 63) > 56) col[(z >> 6) + 1] |= byte >> (64 - (z & 63));
            }
        }
    }
    // Active tiles (internal and root levels): fill their boxes, clipped to the index box.
    auto it = tree.cbeginValueOn();
    it.setMaxDepth(TreeT::ValueOnCIter::LEAF_DEPTH - 1);
    for (; it; ++it) {
        if (!filled(*it)) continue;
        const openvdb::CoordBBox bb = it.getBoundingBox();
        const int64_t x0 = std::max<int64_t>(0, bb.min().x() - o.x()),
                      x1 = std::min<int64_t>(nx, bb.max().x() - o.x() + 1);
        const int64_t y0 = std::max<int64_t>(0, bb.min().y() - o.y()),
                      y1 = std::min<int64_t>(ny, bb.max().y() - o.y() + 1);
        const int64_t z0 = std::max<int64_t>(0, bb.min().z() - o.z()),
                      z1 = std::min<int64_t>(nz, bb.max().z() - o.z() + 1);
        for (int64_t y = y0; y < y1; ++y)
            for (int64_t x = x0; x < x1; ++x) {
                uint64_t* col = g.column(x, y);
                for (int64_t z = z0; z < z1;) {
                    const int lo = int(z & 63), hi = int(std::min<int64_t>(64, lo + (z1 - z)));
                    col[z >> 6] |= bitRange(lo, hi);
                    z += hi - lo;
                }
            }
    }
}

// An istream's buffer over read-only bytes in memory, seekable within them, that reads a few of
// them as other values (the walker's overrides) without copying the rest: the get area is the
// bytes up to the next override, or the one overriding byte.
class MemoryBuffer : public std::streambuf {
public:
    MemoryBuffer(std::string_view bytes, std::span<const vdbcheck::ByteOverride> overrides)
        : bytes_(bytes), overrides_(overrides) {
        show(0);
    }

protected:
    int_type underflow() override {
        const uint64_t pos = position();
        if (pos >= bytes_.size()) return traits_type::eof();
        show(pos);
        return traits_type::to_int_type(*gptr());
    }
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override {
        const off_type size = off_type(bytes_.size());
        const off_type base = dir == std::ios_base::beg   ? 0
                              : dir == std::ios_base::cur ? off_type(position())
                                                          : size;
        if (off < -base || off > size - base) return pos_type(off_type(-1));
        show(uint64_t(base + off));
        return pos_type(base + off);
    }
    pos_type seekpos(pos_type p, std::ios_base::openmode mode) override {
        return seekoff(off_type(p), std::ios_base::beg, mode);
    }

private:
    uint64_t position() const { return start_ + uint64_t(gptr() - eback()); }

    // Starts the get area at `pos`.
    void show(uint64_t pos) {
        start_ = pos;
        const auto next =
            std::lower_bound(overrides_.begin(), overrides_.end(), pos,
                             [](const vdbcheck::ByteOverride& o, uint64_t p) { return o.at < p; });
        if (next != overrides_.end() && next->at == pos) {
            one_ = next->value;
            setg(&one_, &one_, &one_ + 1);
            return;
        }
        const uint64_t end = next == overrides_.end() ? bytes_.size() : next->at;
        char* p = const_cast<char*>(bytes_.data()); // read only: no put area
        setg(p + pos, p + pos, p + end);
    }

    std::string_view bytes_;
    std::span<const vdbcheck::ByteOverride> overrides_;
    uint64_t start_ = 0; // position of eback()
    char one_ = 0;       // the overriding byte, when the get area is it
};

// Every grid of a .vdb file's bytes, read by OpenVDB after the walker checked them.
openvdb::GridPtrVecPtr readValidatedGrids(const uint8_t* data, std::size_t size) {
    initializeOpenVdb();
    // The whole file, checked by the walker (vdb_validate.hpp) before OpenVDB reads those very
    // bytes from memory, in place: OpenVDB trusts every size and count in a file.
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    const std::vector<vdbcheck::ByteOverride> overrides = vdbcheck::validate(bytes);
    openvdb::GridPtrVecPtr grids;
    try {
        // Exceptions on: a read past the end (which the walker rules out) would otherwise feed
        // OpenVDB zeros or stale bytes.
        MemoryBuffer buffer(bytes, overrides);
        std::istream in(&buffer);
        in.exceptions(std::ios::failbit | std::ios::badbit);
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        grids = stream.getGrids();
    } catch (const Error&) { throw; } catch (const std::ios_base::failure&) {
        fail("the file is truncated or unreadable (OpenVDB read past its end)");
    } catch (const std::exception& e) {
        // OpenVDB reports malformed files with its own exceptions (and the odd std one).
        fail("OpenVDB: ", e.what());
    }
    return grids;
}

// The index box of a grid: its stored dimensions when they cover every active voxel, else the
// bounding box of its active voxels.
openvdb::CoordBBox indexBox(const openvdb::GridBase& grid) {
    openvdb::CoordBBox active;
    const bool any = grid.baseTree().evalActiveVoxelBoundingBox(active);
    const auto dims = grid.getMetadata<openvdb::Vec3IMetadata>(kDimsMeta);
    if (dims && dims->value().x() > 0 && dims->value().y() > 0 && dims->value().z() > 0) {
        const openvdb::CoordBBox box(openvdb::Coord(0), openvdb::Coord(dims->value()) - openvdb::Coord(1));
        return any && !box.isInside(active) ? active : box;
    }
    if (!any) fail("grid '", grid.getName(), "' has no active voxels and no stored dimensions");
    return active;
}

// The file's first bool, float or double grid (what readGrid reads as occupancy); level sets are
// refused.
openvdb::GridBase::Ptr firstOccupancyGrid(const uint8_t* data, std::size_t size) {
    const openvdb::GridPtrVecPtr grids = readValidatedGrids(data, size);
    for (const auto& gp : *grids)
        if (gp && (gp->isType<openvdb::BoolGrid>() || gp->isType<openvdb::FloatGrid>() ||
                   gp->isType<openvdb::DoubleGrid>())) {
            if (gp->getGridClass() == openvdb::GRID_LEVEL_SET)
                fail("grid '", gp->getName(), "' is a level set; convert it to a fog volume or a mask first");
            return gp;
        }
    fail("the file holds no bool, float or double grid");
}

void readBitsImpl(const uint8_t* data, std::size_t size, void* ctx,
                  uint64_t* (*allocate)(void* ctx, const VdbReadBox& box, int64_t* wordsPerColumn)) {
    const openvdb::GridBase::Ptr base = firstOccupancyGrid(data, size);

    double cell[3], centre0[3];
    boxTransform(*base, cell, centre0);

    const openvdb::CoordBBox box = indexBox(*base);
    // Sizes in 64 bits: an index box from -2^31 to 2^31 - 1 has 2^32 voxels along an axis.
    const openvdb::Coord o = box.min();
    const int64_t n[3] = {int64_t(box.max().x()) - o.x() + 1, int64_t(box.max().y()) - o.y() + 1,
                          int64_t(box.max().z()) - o.z() + 1};
    VdbReadBox out;
    for (int a = 0; a < 3; ++a) {
        out.dims[a] = n[a];
        out.lo[a] = centre0[a] + (double(o[a]) - 0.5) * cell[a];
        out.hi[a] = out.lo[a] + double(n[a]) * cell[a];
    }
    int64_t wpc = 0;
    uint64_t* words = allocate(ctx, out, &wpc);
    const Target g{n[0], n[1], n[2], wpc, words};
    if (auto b = openvdb::GridBase::grid<openvdb::BoolGrid>(base))
        readTree(*b, o, g);
    else if (auto f = openvdb::GridBase::grid<openvdb::FloatGrid>(base))
        readTree(*f, o, g);
    else
        readTree(*openvdb::GridBase::grid<openvdb::DoubleGrid>(base), o, g);
}

// A scalar value as a volume sample: finite and within float's range, or an error naming where.
template <class ValueT>
float volumeSample(const openvdb::GridBase& grid, ValueT v, const char* what, const openvdb::Coord& at) {
    if (std::isfinite(v) && std::abs(double(v)) <= double(std::numeric_limits<float>::max())) return float(v);
    fail("grid '", grid.getName(), "': ", what, " at index (", at.x(), ", ", at.y(), ", ", at.z(), ") is ",
         std::isnan(v) ? "NaN" : (std::isinf(v) ? "infinite" : "beyond the range of float"),
         " (volume samples must be finite)");
}

// The dense values of a float or double grid over the index box from `o` of n voxels per axis,
// x fastest. Every voxel has a value, active or not: the background first, then the tiles above
// the leaves (active or not, clipped to the box), then each leaf's 512 values.
template <class GridT>
void readDense(const GridT& grid, const openvdb::Coord& o, const int64_t n[3], float* out) {
    using TreeT = typename GridT::TreeType;
    const TreeT& tree = grid.tree();
    const auto index = [&](int64_t x, int64_t y, int64_t z) {
        return std::size_t((z * n[1] + y) * n[0] + x);
    };
    std::fill(out, out + n[0] * n[1] * n[2], volumeSample(grid, tree.background(), "the background", o));
    auto tile = tree.cbeginValueAll();
    tile.setMaxDepth(TreeT::ValueAllCIter::LEAF_DEPTH - 1);
    for (; tile; ++tile) {
        const openvdb::CoordBBox bb = tile.getBoundingBox();
        int64_t lo[3], hi[3];
        bool empty = false;
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::max<int64_t>(0, int64_t(bb.min()[a]) - o[a]);
            hi[a] = std::min<int64_t>(n[a], int64_t(bb.max()[a]) - o[a] + 1);
            empty = empty || lo[a] >= hi[a];
        }
        if (empty) continue;
        const float v = volumeSample(grid, *tile, "the tile", bb.min());
        for (int64_t z = lo[2]; z < hi[2]; ++z)
            for (int64_t y = lo[1]; y < hi[1]; ++y)
                std::fill(out + index(lo[0], y, z), out + index(hi[0], y, z), v);
    }
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf)
        for (openvdb::Index i = 0; i < TreeT::LeafNodeType::SIZE; ++i) {
            const openvdb::Coord c = leaf->offsetToGlobalCoord(i);
            const int64_t x = int64_t(c.x()) - o.x(), y = int64_t(c.y()) - o.y(), z = int64_t(c.z()) - o.z();
            if (x < 0 || y < 0 || z < 0 || x >= n[0] || y >= n[1] || z >= n[2]) continue;
            out[index(x, y, z)] = volumeSample(grid, leaf->getValue(i), "the value", c);
        }
}

void readFloatsImpl(const uint8_t* data, std::size_t size, const char* gridName, void* ctx,
                    float* (*allocate)(void* ctx, const VdbFloatBox& box)) {
    const openvdb::GridPtrVecPtr grids = readValidatedGrids(data, size);
    const std::string wanted = gridName ? gridName : "";
    auto scalar = [](const openvdb::GridBase& g) {
        return g.isType<openvdb::FloatGrid>() || g.isType<openvdb::DoubleGrid>();
    };
    openvdb::GridBase::Ptr base;
    std::string seen;
    for (const auto& gp : *grids) {
        if (!gp) continue;
        if (wanted.empty() ? scalar(*gp) : gp->getName() == wanted) {
            base = gp;
            break;
        }
        seen += (seen.empty() ? "" : ", ") + ("'" + gp->getName() + "' (" + gp->valueType() + ")");
    }
    const std::string holds = seen.empty() ? std::string(" (it holds no grid)") : " (it holds " + seen + ")";
    if (!base && wanted.empty()) fail("the file holds no float or double grid", holds);
    if (!base) fail("the file holds no grid named '", wanted, "'", holds);
    if (!scalar(*base))
        fail("grid '", base->getName(), "' is a ", base->valueType(),
             " grid; volumes are read from float or double grids");

    VdbFloatBox out;
    double centre0[3];
    turnedTransform(*base, out.spacing, out.axes, centre0);
    const openvdb::CoordBBox box = indexBox(*base);
    const openvdb::Coord o = box.min();
    for (int a = 0; a < 3; ++a) out.dims[a] = int64_t(box.max()[a]) - o[a] + 1;
    // The corner of the box's voxel (0,0,0): index o - 0.5 along every axis.
    for (int c = 0; c < 3; ++c) {
        out.lo[c] = centre0[c];
        for (int r = 0; r < 3; ++r) out.lo[c] += out.axes[r][c] * (double(o[r]) - 0.5) * out.spacing[r];
    }
    out.name = base->getName();
    out.gridClass = openvdb::GridBase::gridClassToString(base->getGridClass());
    out.isDouble = base->isType<openvdb::DoubleGrid>();
    // The caller checks the dense size against the limits and the memory available first.
    float* values = allocate(ctx, out);
    if (!values) fail("no memory for the dense volume");
    if (auto f = openvdb::GridBase::grid<openvdb::FloatGrid>(base))
        readDense(*f, o, out.dims, values);
    else
        readDense(*openvdb::GridBase::grid<openvdb::DoubleGrid>(base), o, out.dims, values);
}

// Runs f, turning any exception into a message for the caller (nothing crosses the boundary).
template <class F> bool guarded(std::string* error, const F& f) {
    try {
        f();
        return true;
    } catch (const std::bad_alloc&) { *error = "out of memory"; } catch (const std::exception& e) {
        *error = e.what();
    } catch (...) { *error = "unknown error in the OpenVDB module"; }
    return false;
}

bool writeBits(const char* path, const VdbBits& bits, const VdbPlacement& placement, const char* gridName,
               bool asFloat, ParallelFor parallelFor, std::string* error) {
    return guarded(error, [&] {
        initializeOpenVdb();
        openvdb::GridBase::Ptr out;
        if (asFloat) {
            auto fg = openvdb::FloatGrid::create(0.0f);
            fillLeaves(bits, parallelFor, *fg);
            fg->setGridClass(openvdb::GRID_FOG_VOLUME);
            out = fg;
        } else {
            auto bg = openvdb::BoolGrid::create(false);
            fillLeaves(bits, parallelFor, *bg);
            out = bg;
        }
        out->setTransform(transformFor(placement));
        out->setName(gridName);
        out->insertMeta(kDimsMeta,
                        openvdb::Vec3IMetadata(openvdb::Vec3i(int(bits.nx), int(bits.ny), int(bits.nz))));
        writeFile(path, out);
    });
}

bool writeFloats(const char* path, const int64_t dims[3], const float* values, const VdbPlacement& placement,
                 const char* gridName, std::string* error) {
    return guarded(error, [&] {
        initializeOpenVdb();
        auto grid = openvdb::FloatGrid::create(0.0f);
        // Non-uniform scale as a pre-scale of the unit transform (the density writer's placement).
        auto xform = openvdb::math::Transform::createLinearTransform(1.0);
        xform->preScale(openvdb::Vec3d(placement.cell[0], placement.cell[1], placement.cell[2]));
        xform->postTranslate(
            openvdb::Vec3d(placement.centre0[0], placement.centre0[1], placement.centre0[2]));
        grid->setTransform(xform);
        grid->setName(gridName);
        grid->setGridClass(openvdb::GRID_FOG_VOLUME);
        // The grid's size travels as metadata (as for bit grids), so empty borders survive.
        grid->insertMeta(kDimsMeta,
                         openvdb::Vec3IMetadata(openvdb::Vec3i(int(dims[0]), int(dims[1]), int(dims[2]))));
        auto acc = grid->getAccessor();
        // Serial insertion in a fixed order keeps the tree (and the file) deterministic.
        const float* v = values;
        for (int64_t k = 0; k < dims[2]; ++k)
            for (int64_t j = 0; j < dims[1]; ++j)
                for (int64_t i = 0; i < dims[0]; ++i, ++v)
                    if (*v != 0.0f) acc.setValue(openvdb::Coord(int(i), int(j), int(k)), *v);
        writeFile(path, grid);
    });
}

// A dense grid's active voxels with their values, inserted serially in a fixed order (a
// deterministic tree and file).
template <class GridT, class Make>
openvdb::GridBase::Ptr denseGrid(const int64_t dims[3], const uint8_t* active, const VdbDenseGrid& in,
                                 const openvdb::math::Transform::Ptr& xform, Make&& value) {
    using V = typename GridT::ValueType;
    auto grid = GridT::create(value(in.background, nullptr));
    grid->setTransform(xform);
    grid->setName(in.name);
    grid->insertMeta(kDimsMeta,
                     openvdb::Vec3IMetadata(openvdb::Vec3i(int(dims[0]), int(dims[1]), int(dims[2]))));
    auto acc = grid->getAccessor();
    std::size_t n = 0;
    for (int64_t k = 0; k < dims[2]; ++k)
        for (int64_t j = 0; j < dims[1]; ++j)
            for (int64_t i = 0; i < dims[0]; ++i, ++n)
                if (active[n]) {
                    const V v = value(0, in.values + n * std::size_t(in.components));
                    acc.setValue(openvdb::Coord(int(i), int(j), int(k)), v);
                }
    return grid;
}

bool writeDenseGrids(const char* path, const int64_t dims[3], const uint8_t* active,
                     const VdbDenseGrid* grids, std::size_t gridCount, const VdbPlacement& placement,
                     std::string* error) {
    return guarded(error, [&] {
        initializeOpenVdb();
        auto xform = openvdb::math::Transform::createLinearTransform(1.0);
        xform->preScale(openvdb::Vec3d(placement.cell[0], placement.cell[1], placement.cell[2]));
        xform->postTranslate(
            openvdb::Vec3d(placement.centre0[0], placement.centre0[1], placement.centre0[2]));
        openvdb::GridPtrVec out;
        for (std::size_t g = 0; g < gridCount; ++g) {
            const VdbDenseGrid& in = grids[g];
            if (in.components == 1)
                out.push_back(denseGrid<openvdb::FloatGrid>(
                    dims, active, in, xform, [](float bg, const float* v) { return v ? *v : bg; }));
            else if (in.components == 3)
                out.push_back(
                    denseGrid<openvdb::Vec3SGrid>(dims, active, in, xform, [](float bg, const float* v) {
                        return v ? openvdb::Vec3s(v[0], v[1], v[2]) : openvdb::Vec3s(bg, bg, bg);
                    }));
            else
                fail("grid '", in.name, "': ", in.components, " components (1 or 3 expected)");
        }
        try {
            openvdb::io::File f(path);
            f.write(out);
            f.close();
        } catch (const openvdb::Exception& e) { fail("OpenVDB: ", e.what()); }
    });
}

// ---- Level sets -----------------------------------------------------------------------------

using FloatLeaf = openvdb::FloatGrid::TreeType::LeafNodeType;
static_assert(FloatLeaf::SIZE == 512 && FloatLeaf::NodeMaskType::WORD_COUNT == 8);

// A copy of a grid's transform with the same numbers: Transform's copy constructor shares the
// (immutable) map, where Transform::copy() and Grid::deepCopy() rebuild it through simplify(),
// which recomputes the scale as the difference of two translated points (off by 1e-12 relative
// for a grid 1000 voxels from the origin, and no longer uniform) so that the copy and the original
// no longer compare equal and CSG between them resampled.
openvdb::math::Transform::Ptr sameTransform(const openvdb::GridBase& grid) {
    return std::make_shared<openvdb::math::Transform>(grid.constTransform());
}

// A deep copy of a level set with its transform unchanged (see sameTransform).
openvdb::FloatGrid::Ptr copyLevelSet(const openvdb::FloatGrid& grid) {
    openvdb::FloatGrid::Ptr copy = grid.deepCopy();
    copy->setTransform(sameTransform(grid));
    return copy;
}

// One leaf at its origin plus `offset` (the level set's indexOffset; multiples of 8).
std::unique_ptr<FloatLeaf> levelSetLeaf(const VdbLevelSetLeaf& in, float background,
                                        const int64_t offset[3] = nullptr) {
    const int64_t zero[3] = {0, 0, 0};
    const int64_t* o = offset ? offset : zero;
    auto leaf = std::make_unique<FloatLeaf>(
        openvdb::Coord(int(in.origin[0] + o[0]), int(in.origin[1] + o[1]), int(in.origin[2] + o[2])),
        background, false);
    typename FloatLeaf::NodeMaskType mask;
    for (int i = 0; i < 8; ++i) mask.template getWord<uint64_t>(openvdb::Index(i)) = in.active[i];
    leaf->setValueMask(mask);
    std::copy(in.values, in.values + 512, leaf->buffer().data());
    return leaf;
}

// Leaf-sized inactive tiles at -background for the inside runs. The tree does not depend on the
// order of addLeaf and addTile calls (disjoint blocks; nodes are made with background tiles), so
// streamed and whole insertion give the same tree.
void addInsideRuns(openvdb::FloatTree& tree, const VdbInsideRun* runs, std::size_t count, float background,
                   const int64_t offset[3] = nullptr) {
    const int64_t zero[3] = {0, 0, 0};
    const int64_t* o = offset ? offset : zero;
    for (std::size_t r = 0; r < count; ++r)
        for (int32_t x = runs[r].x0; x < runs[r].x1; ++x)
            tree.addTile(1,
                         openvdb::Coord(int(8 * int64_t(x) + o[0]), int(8 * int64_t(runs[r].y) + o[1]),
                                        int(8 * int64_t(runs[r].z) + o[2])),
                         -background, false);
}

// Nodes made only of equal inactive tiles (inside: -background) become one tile; then the
// transform, class, name and dimensions, and the file.
void finishLevelSet(openvdb::FloatGrid& grid, const VdbPlacement& placement, const int64_t dims[3],
                    const char* gridName) {
    grid.tree().prune();
    grid.setTransform(transformFor(placement));
    grid.setName(gridName);
    grid.setGridClass(openvdb::GRID_LEVEL_SET);
    grid.insertMeta(kDimsMeta,
                    openvdb::Vec3IMetadata(openvdb::Vec3i(int(dims[0]), int(dims[1]), int(dims[2]))));
}

// The level set a SignedDistanceField describes (see writeLevelSet), kept in memory; with
// `transformOf`, that grid's transform (a copy) and no dimensions (see levelSetBuild).
openvdb::FloatGrid::Ptr buildLevelSet(const VdbLevelSet& ls, const VdbPlacement& placement,
                                      const char* gridName, ParallelFor parallelFor,
                                      const openvdb::FloatGrid* transformOf = nullptr) {
    initializeOpenVdb();
    const int64_t* o = ls.indexOffset;
    for (int a = 0; a < 3; ++a)
        if (o[a] % 8 != 0)
            fail("level set: the index offset (", o[0], ", ", o[1], ", ", o[2], ") is not a multiple of 8");
    // Every index of the tree must fit OpenVDB's int32 coordinates.
    const int64_t limit = int64_t(std::numeric_limits<int32_t>::max()) - 8;
    for (int a = 0; a < 3; ++a)
        if (o[a] < -limit || o[a] + ls.dims[a] > limit)
            fail("level set: index offset ", o[a], " with ", ls.dims[a],
                 " voxels leaves OpenVDB's 32-bit indices");
    auto grid = openvdb::FloatGrid::create(ls.background);
    // The leaves are made on worker threads and handed to the tree in their order (a
    // deterministic tree, single-threaded insertion), as for bit grids.
    std::vector<std::unique_ptr<FloatLeaf>> leaves(ls.leafCount);
    auto body = [&](int64_t b, int64_t e) {
        for (int64_t l = b; l < e; ++l) leaves[std::size_t(l)] = levelSetLeaf(ls.leaves[l], ls.background, o);
    };
    forChunks(parallelFor, 0, int64_t(ls.leafCount), 64, body);
    auto& tree = grid->tree();
    for (auto& leaf : leaves) tree.addLeaf(leaf.release());
    addInsideRuns(tree, ls.insideRuns, ls.insideRunCount, ls.background, o);
    if (!transformOf) {
        finishLevelSet(*grid, placement, ls.dims, gridName);
        return grid;
    }
    grid->tree().prune();
    grid->setTransform(sameTransform(*transformOf));
    grid->setName(gridName);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    return grid;
}

bool writeLevelSet(const char* path, const VdbLevelSet& ls, const VdbPlacement& placement,
                   const char* gridName, ParallelFor parallelFor, std::string* error) {
    return guarded(error, [&] { writeFile(path, buildLevelSet(ls, placement, gridName, parallelFor)); });
}

struct LevelSetHandle {
    openvdb::FloatGrid::Ptr grid;
    std::mutex mutex; // levelSetAdd's insertions
};

void* levelSetCreate(float background, std::string* error) {
    LevelSetHandle* h = nullptr;
    guarded(error, [&] {
        initializeOpenVdb();
        auto owned = std::make_unique<LevelSetHandle>();
        owned->grid = openvdb::FloatGrid::create(background);
        h = owned.release();
    });
    return h;
}

void levelSetDestroy(void* g) { delete static_cast<LevelSetHandle*>(g); }

bool levelSetAdd(void* g, const VdbLevelSetLeaf* leaves, std::size_t leafCount, const VdbInsideRun* runs,
                 std::size_t runCount, std::string* error) {
    return guarded(error, [&] {
        LevelSetHandle& h = *static_cast<LevelSetHandle*>(g);
        const float background = h.grid->background();
        // Made on the calling thread, inserted under the lock.
        std::vector<std::unique_ptr<FloatLeaf>> made(leafCount);
        for (std::size_t l = 0; l < leafCount; ++l) made[l] = levelSetLeaf(leaves[l], background);
        std::lock_guard<std::mutex> lock(h.mutex);
        auto& tree = h.grid->tree();
        for (auto& leaf : made) tree.addLeaf(leaf.release());
        addInsideRuns(tree, runs, runCount, background);
    });
}

bool levelSetStreamWrite(const char* path, void* g, const VdbPlacement& placement, const int64_t dims[3],
                         const char* gridName, std::string* error) {
    return guarded(error, [&] {
        LevelSetHandle& h = *static_cast<LevelSetHandle*>(g);
        finishLevelSet(*h.grid, placement, dims, gridName);
        writeFile(path, h.grid);
    });
}

bool readBits(const uint8_t* data, std::size_t size, void* ctx,
              uint64_t* (*allocate)(void* ctx, const VdbReadBox& box, int64_t* wordsPerColumn),
              std::string* error) {
    return guarded(error, [&] { readBitsImpl(data, size, ctx, allocate); });
}

bool readFloats(const uint8_t* data, std::size_t size, const char* gridName, void* ctx,
                float* (*allocate)(void* ctx, const VdbFloatBox& box), std::string* error) {
    return guarded(error, [&] { readFloatsImpl(data, size, gridName, ctx, allocate); });
}

// ---- Sparse grids ---------------------------------------------------------------------------

using BoolTree = openvdb::BoolGrid::TreeType;

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

openvdb::CoordBBox indexBox(const int64_t lo[3], const int64_t hi[3]) {
    for (int a = 0; a < 3; ++a)
        if (lo[a] < std::numeric_limits<int32_t>::min() || hi[a] > std::numeric_limits<int32_t>::max())
            fail("the index box [", lo[a], ", ", hi[a], "] along axis ", a, " does not fit OpenVDB's int32");
    return openvdb::CoordBBox(openvdb::Coord(int(lo[0]), int(lo[1]), int(lo[2])),
                              openvdb::Coord(int(hi[0]), int(hi[1]), int(hi[2])));
}

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

// ---- Level sets ------------------------------------------------------------------------------

openvdb::FloatGrid& lsGrid(void* g) { return *static_cast<LevelSetHandle*>(g)->grid; }
const openvdb::FloatGrid& lsGrid(const void* g) { return *static_cast<const LevelSetHandle*>(g)->grid; }

const char* gridClassName(openvdb::GridClass c) {
    switch (c) {
    case openvdb::GRID_LEVEL_SET:
        return "level set";
    case openvdb::GRID_FOG_VOLUME:
        return "fog volume";
    case openvdb::GRID_STAGGERED:
        return "staggered";
    default:
        return "unknown";
    }
}

// The first bool, float or double grid of the file, and whether it is a float level set; *what
// describes it otherwise.
openvdb::GridBase::Ptr firstScalarGrid(const uint8_t* data, std::size_t size, bool* levelSet,
                                       std::string* what) {
    const openvdb::GridPtrVecPtr grids = readValidatedGrids(data, size);
    for (const auto& gp : *grids) {
        if (!gp) continue;
        const std::string name = "grid '" + gp->getName() + "'";
        if (gp->isType<openvdb::BoolGrid>()) {
            *levelSet = false;
            *what = name + " is a BoolGrid (occupancy), not a level set";
            return gp;
        }
        if (gp->isType<openvdb::FloatGrid>() || gp->isType<openvdb::DoubleGrid>()) {
            const bool isFloat = gp->isType<openvdb::FloatGrid>();
            *levelSet = isFloat && gp->getGridClass() == openvdb::GRID_LEVEL_SET;
            if (!*levelSet)
                *what = name + " is a " + (isFloat ? "FloatGrid" : "DoubleGrid") + " of class " +
                        gridClassName(gp->getGridClass()) +
                        (isFloat ? ", not a level set" : " (level sets are read as FloatGrids)");
            return gp;
        }
    }
    fail("the file holds no bool, float or double grid");
}

void* levelSetRead(const uint8_t* data, std::size_t size, std::string* error) {
    LevelSetHandle* h = nullptr;
    guarded(error, [&] {
        bool isLevelSet = false;
        std::string what;
        const openvdb::GridBase::Ptr base = firstScalarGrid(data, size, &isLevelSet, &what);
        if (!isLevelSet) fail(what);
        auto owned = std::make_unique<LevelSetHandle>();
        owned->grid = openvdb::GridBase::grid<openvdb::FloatGrid>(base);
        if (!(owned->grid->background() > 0))
            fail("level set '", base->getName(), "' has background ", owned->grid->background(),
                 " (a level set's background is its band width, > 0)");
        h = owned.release();
    });
    return h;
}

int levelSetProbe(const uint8_t* data, std::size_t size, std::string* what, std::string* error) {
    int result = -1;
    guarded(error, [&] {
        bool isLevelSet = false;
        firstScalarGrid(data, size, &isLevelSet, what);
        result = isLevelSet ? 1 : 0;
    });
    return result;
}

void* levelSetBuild(const VdbLevelSet& ls, const VdbPlacement& placement, const void* transformOf,
                    const char* gridName, ParallelFor parallelFor, std::string* error) {
    LevelSetHandle* h = nullptr;
    guarded(error, [&] {
        auto owned = std::make_unique<LevelSetHandle>();
        owned->grid =
            buildLevelSet(ls, placement, gridName, parallelFor, transformOf ? &lsGrid(transformOf) : nullptr);
        h = owned.release();
    });
    return h;
}

void* levelSetCopy(const void* g, std::string* error) {
    LevelSetHandle* h = nullptr;
    guarded(error, [&] {
        auto owned = std::make_unique<LevelSetHandle>();
        owned->grid = copyLevelSet(lsGrid(g));
        h = owned.release();
    });
    return h;
}

bool levelSetInfo(const void* g, VdbLevelSetInfo* info, std::string* error) {
    return guarded(error, [&] {
        const openvdb::FloatGrid& grid = lsGrid(g);
        info->background = grid.background();
        const openvdb::Vec3d vs = grid.voxelSize();
        const openvdb::Vec3d c0 = grid.indexToWorld(openvdb::Vec3d(0, 0, 0));
        for (int a = 0; a < 3; ++a) {
            info->voxelSize[a] = vs[a];
            info->centre0[a] = c0[a];
        }
        const auto map = grid.transform().baseMap();
        info->axisAligned = map->isLinear();
        if (info->axisAligned) {
            // A positive scale per axis: a mirrored axis runs against voxelSize (a length).
            const openvdb::Mat4d m = map->getAffineMap()->getMat4();
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c)
                    if (r != c ? m(r, c) != 0 : !(m(r, c) > 0)) info->axisAligned = false;
        }
        info->activeCount = int64_t(grid.tree().activeVoxelCount());
        openvdb::CoordBBox box;
        info->anyActive = grid.tree().evalActiveVoxelBoundingBox(box);
        for (int a = 0; a < 3; ++a) {
            info->lo[a] = info->anyActive ? box.min()[a] : 0;
            info->hi[a] = info->anyActive ? box.max()[a] : -1;
        }
        info->name = grid.getName();
    });
}

float levelSetValue(const void* g, const int64_t ijk[3]) {
    return lsGrid(g).tree().getValue(openvdb::Coord(int(ijk[0]), int(ijk[1]), int(ijk[2])));
}

bool levelSetValues(const void* g, const int32_t* ijk, std::size_t count, float* out, ParallelFor parallelFor,
                    std::string* error) {
    return guarded(error, [&] {
        const openvdb::FloatTree& tree = lsGrid(g).tree();
        // One accessor per chunk (accessors cache the path to the last leaf: nearby indices are
        // cheap); each chunk writes only its own outputs.
        auto body = [&](int64_t b, int64_t e) {
            openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(tree);
            for (int64_t n = b; n < e; ++n) {
                const int32_t* c = ijk + 3 * n;
                out[n] = acc.getValue(openvdb::Coord(c[0], c[1], c[2]));
            }
        };
        forChunks(parallelFor, 0, int64_t(count), 4096, body);
    });
}

bool levelSetActive(const void* g, std::vector<int32_t>* ijk, std::vector<float>* values,
                    std::string* error) {
    return guarded(error, [&] {
        const openvdb::FloatGrid& grid = lsGrid(g);
        const std::size_t n = std::size_t(grid.tree().activeVoxelCount());
        ijk->clear();
        values->clear();
        ijk->reserve(3 * n);
        values->reserve(n);
        for (auto it = grid.tree().cbeginValueOn(); it; ++it) {
            if (it.isVoxelValue()) {
                const openvdb::Coord c = it.getCoord();
                ijk->insert(ijk->end(), {c.x(), c.y(), c.z()});
                values->push_back(*it);
                continue;
            }
            const openvdb::CoordBBox box = it.getBoundingBox(); // an active tile: each of its voxels
            for (auto c = box.begin(); c; ++c) {
                ijk->insert(ijk->end(), {(*c).x(), (*c).y(), (*c).z()});
                values->push_back(*it);
            }
        }
    });
}

bool levelSetCombine(void* a, const void* b, SparseOp op, bool* resampled, std::string* error) {
    return guarded(error, [&] {
        openvdb::FloatGrid& ga = lsGrid(a);
        const openvdb::FloatGrid& gb = lsGrid(b);
        openvdb::FloatGrid::Ptr copy;
        *resampled = !(ga.constTransform() == gb.constTransform());
        if (!*resampled) {
            copy = copyLevelSet(gb);
        } else {
            copy = openvdb::FloatGrid::create(ga.background());
            copy->setTransform(sameTransform(ga));
            copy->setGridClass(openvdb::GRID_LEVEL_SET);
            openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(gb, *copy);
        }
        try {
            if (op == SparseOp::Union)
                openvdb::tools::csgUnion(ga, *copy);
            else if (op == SparseOp::Intersection)
                openvdb::tools::csgIntersection(ga, *copy);
            else
                openvdb::tools::csgDifference(ga, *copy);
        } catch (const openvdb::Exception& e) { fail("OpenVDB: ", e.what()); }
    });
}

bool levelSetOffset(void* g, double distance, std::string* error) {
    return guarded(error, [&] {
        try {
            openvdb::tools::LevelSetFilter<openvdb::FloatGrid> filter(lsGrid(g));
            filter.offset(float(-distance)); // OpenVDB's offset adds to the values: > 0 shrinks
        } catch (const openvdb::Exception& e) { fail("OpenVDB: ", e.what()); }
    });
}

bool levelSetWrite(const char* path, const void* g, std::string* error) {
    return guarded(error, [&] { writeFile(path, static_cast<const LevelSetHandle*>(g)->grid); });
}

// OpenVDB's polygons as plain arrays.
void copyPolygons(const std::vector<openvdb::Vec3s>& points, const std::vector<openvdb::Vec3I>& triangles,
                  const std::vector<openvdb::Vec4I>& quads, VdbPolygons* out) {
    out->points.resize(3 * points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        for (int a = 0; a < 3; ++a) out->points[3 * i + std::size_t(a)] = points[i][a];
    out->triangles.resize(3 * triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
        for (int a = 0; a < 3; ++a) out->triangles[3 * i + std::size_t(a)] = triangles[i][a];
    out->quads.resize(4 * quads.size());
    for (std::size_t i = 0; i < quads.size(); ++i)
        for (int a = 0; a < 4; ++a) out->quads[4 * i + std::size_t(a)] = quads[i][a];
}

void meshFloatGrid(const openvdb::FloatGrid& grid, double isovalue, double adaptivity, VdbPolygons* out) {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    try {
        openvdb::tools::volumeToMesh(grid, points, triangles, quads, isovalue, adaptivity);
    } catch (const openvdb::Exception& e) { fail("OpenVDB: ", e.what()); }
    copyPolygons(points, triangles, quads, out);
}

bool levelSetToMesh(const void* g, double isovalue, double adaptivity, VdbPolygons* out, std::string* error) {
    return guarded(error, [&] { meshFloatGrid(lsGrid(g), isovalue, adaptivity, out); });
}

// The dense field as a sparse level set for the mesher: a voxel is active where one of its 26
// neighbours lies on the other side of the iso value (beyond the box: the background, outside), so
// every corner of every cell the surface crosses is an active voxel of a real leaf, with its value;
// leaves without an active voxel hold one side only and become inactive tiles (inside:
// -background) or nothing (outside). volumeToMesh then works on the band, not the whole volume.
// "Some neighbour differs" is the 3 x 3 x 3 maximum of the inside flags differing from their
// minimum, taken one axis at a time (z, y, then x per leaf) over flags padded by one outside cell:
// bit 0 the maximum (some cell inside), bit 1 the minimum (every cell inside). Leaves are made in
// parallel, only where the band passes, and inserted in their order (a deterministic tree).
openvdb::FloatGrid::Ptr denseBand(const float* values, const int64_t dims[3], bool zFastest, float background,
                                  double isovalue, ParallelFor parallelFor) {
    const int64_t nx = dims[0], ny = dims[1], nz = dims[2];
    const int64_t py = ny + 2, pz = nz + 2;
    const auto at = [&](int64_t i, int64_t j, int64_t k) {
        return zFastest ? values[(i * ny + j) * nz + k] : values[i + nx * (j + ny * k)];
    };
    // Padded index of (i, j, k), z fastest; i, j, k from -1 to n.
    const auto pad = [&](int64_t i, int64_t j, int64_t k) {
        return std::size_t(((i + 1) * py + (j + 1)) * pz + k + 1);
    };
    const std::size_t padded = std::size_t((nx + 2) * py * pz);
    // inside: the flags, then (passY) their min/max over j and k; alongZ: over k. Zero (outside,
    // neither bit) in the padding.
    std::vector<uint8_t> inside(padded, 0), alongZ(padded, 0);
    std::vector<uint8_t>& span = inside;
    auto flags = [&](int64_t b, int64_t e) {
        // Locals, so that the byte stores (which may alias anything) do not reload them.
        const float* v = values;
        const double iso = isovalue;
        const int64_t strideK = zFastest ? 1 : nx * ny;
        for (int64_t i = b; i < e; ++i)
            for (int64_t j = 0; j < ny; ++j) {
                uint8_t* row = &inside[pad(i, j, 0)];
                const float* src = zFastest ? v + (i * ny + j) * nz : v + i + nx * j;
                for (int64_t k = 0; k < nz; ++k) row[k] = double(src[k * strideK]) < iso;
            }
    };
    forChunks(parallelFor, 0, nx, 4, flags);
    auto passZ = [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i)
            for (int64_t j = 0; j < ny; ++j) {
                const uint8_t* f = &inside[pad(i, j, 0)];
                uint8_t* out = &alongZ[pad(i, j, 0)];
                for (int64_t k = 0; k < nz; ++k)
                    out[k] = uint8_t((f[k - 1] | f[k] | f[k + 1]) | ((f[k - 1] & f[k] & f[k + 1]) << 1));
            }
    };
    forChunks(parallelFor, 0, nx, 4, passZ);
    auto passY = [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; ++i)
            for (int64_t j = 0; j < ny; ++j) {
                const uint8_t* lo = &alongZ[pad(i, j - 1, 0)];
                const uint8_t* mid = &alongZ[pad(i, j, 0)];
                const uint8_t* hi = &alongZ[pad(i, j + 1, 0)];
                uint8_t* out = &span[pad(i, j, 0)];
                for (int64_t k = 0; k < nz; ++k)
                    out[k] = uint8_t(((lo[k] | mid[k] | hi[k]) & 1) | (lo[k] & mid[k] & hi[k] & 2));
            }
    };
    forChunks(parallelFor, 0, nx, 4, passY);
    const int64_t lx = (nx + 7) / 8, ly = (ny + 7) / 8, lz = (nz + 7) / 8;
    std::vector<std::unique_ptr<FloatLeaf>> leaves(std::size_t(lx * ly * lz));
    std::vector<uint8_t> insideTile(leaves.size(), 0);
    auto body = [&](int64_t b, int64_t e) {
        const std::size_t d = std::size_t(py * pz);
        for (int64_t l = b; l < e; ++l) {
            // Leaves in z-fastest order, as the padded flags lie in memory.
            const int64_t i0 = 8 * (l / (ly * lz)), j0 = 8 * (l / lz % ly), k0 = 8 * (l % lz);
            const int64_t i1 = std::min(i0 + 8, nx), j1 = std::min(j0 + 8, ny), k1 = std::min(k0 + 8, nz);
            // The leaf's active mask (along x: the last pass). OpenVDB's voxel (di, dj, dk) is bit
            // (dj << 3) | dk of mask word di: one byte per row of 8 along z.
            uint64_t words[8] = {0, 0, 0, 0, 0, 0, 0, 0};
            for (int64_t i = i0; i < i1; ++i)
                for (int64_t j = j0; j < j1; ++j) {
                    const uint8_t* lo = &span[pad(i, j, k0)] - d;
                    const uint8_t* mid = lo + d;
                    const uint8_t* hi = mid + d;
                    uint64_t row = 0;
                    for (int64_t k = 0; k < k1 - k0; ++k) {
                        const unsigned some = (lo[k] | mid[k] | hi[k]) & 1u,
                                       all = (lo[k] & mid[k] & hi[k]) >> 1;
                        row |= uint64_t(some & ~all & 1u) << k;
                    }
                    words[i - i0] |= row << (8 * (j - j0));
                }
            if (!(words[0] | words[1] | words[2] | words[3] | words[4] | words[5] | words[6] | words[7])) {
                // One side only (see above): inside when its first voxel's whole neighbourhood is.
                insideTile[std::size_t(l)] = (span[pad(i0, j0, k0)] >> 1) & 1;
                continue;
            }
            FloatLeaf::NodeMaskType mask;
            for (int w = 0; w < 8; ++w) mask.template getWord<uint64_t>(openvdb::Index(w)) = words[w];
            auto leaf =
                std::make_unique<FloatLeaf>(openvdb::Coord(int(i0), int(j0), int(k0)), background, false);
            float* buffer = leaf->buffer().data();
            for (int64_t i = i0; i < i1; ++i)
                for (int64_t j = j0; j < j1; ++j)
                    for (int64_t k = k0; k < k1; ++k)
                        buffer[((i - i0) << 6) | ((j - j0) << 3) | (k - k0)] = at(i, j, k);
            leaf->setValueMask(mask);
            leaves[std::size_t(l)] = std::move(leaf);
        }
    };
    forChunks(parallelFor, 0, int64_t(leaves.size()), 16, body);
    auto grid = openvdb::FloatGrid::create(background);
    auto& tree = grid->tree();
    for (std::size_t l = 0; l < leaves.size(); ++l) {
        if (leaves[l]) {
            tree.addLeaf(leaves[l].release());
        } else if (insideTile[l]) {
            const auto L = int64_t(l);
            tree.addTile(1,
                         openvdb::Coord(int(8 * (L / (ly * lz))), int(8 * (L / lz % ly)), int(8 * (L % lz))),
                         -background, false);
        }
    }
    return grid;
}

bool denseToMesh(const float* values, const int64_t dims[3], bool zFastest, const VdbPlacement& placement,
                 float background, double isovalue, double adaptivity, ParallelFor parallelFor,
                 VdbPolygons* out, std::string* error) {
    return guarded(error, [&] {
        initializeOpenVdb();
        auto grid = denseBand(values, dims, zFastest, background, isovalue, parallelFor);
        auto xform = openvdb::math::Transform::createLinearTransform(1.0);
        xform->preScale(openvdb::Vec3d(placement.cell[0], placement.cell[1], placement.cell[2]));
        xform->postTranslate(
            openvdb::Vec3d(placement.centre0[0], placement.centre0[1], placement.centre0[2]));
        grid->setTransform(xform);
        // volumeToMesh reads a level set's inside as below the iso value (other float grids as fog
        // volumes: above it), which is this function's convention.
        grid->setGridClass(openvdb::GRID_LEVEL_SET);
        meshFloatGrid(*grid, isovalue, adaptivity, out);
    });
}

constexpr VdbModule kTable{
    kModuleAbi,      sizeof(VdbModule), writeBits,       writeFloats,      readBits,
    readFloats,      sparseCreate,      sparseDestroy,   sparseCopy,       sparseAddBrick,
    sparseFinish,    sparseFromBits,    sparseToBits,    sparseCount,      sparseBounds,
    sparseMemory,    sparseGet,         sparseCombine,   sparseMorphology, sparseFill,
    sparseClip,      sparseCoordinates, sparseWrite,     sparseRead,       writeLevelSet,
    writeDenseGrids, levelSetCreate,    levelSetDestroy, levelSetAdd,      levelSetStreamWrite,
    levelSetRead,    levelSetProbe,     levelSetBuild,   levelSetCopy,     levelSetInfo,
    levelSetValue,   levelSetValues,    levelSetActive,  levelSetCombine,  levelSetOffset,
    levelSetWrite,   levelSetToMesh,    denseToMesh};

} // namespace
} // namespace voxfx::detail

extern "C" const void* voxfx_module_vdb(uint32_t abi) {
    return abi == voxfx::detail::kModuleAbi ? &voxfx::detail::kTable : nullptr;
}
