// voxfx_vdb — reading: a .vdb file's bytes, checked by the walker (vdb_validate.hpp) and read by
// OpenVDB from memory, to the bits of an occupancy grid or the dense floats of a volume.
#include <algorithm>
#include <bit>
#include <cmath>
#include <istream>
#include <limits>
#include <span>
#include <streambuf>
#include <string_view>
#include <type_traits>
#include <vector>

#include <openvdb/io/Stream.h>

#include "core/bitops.hpp"
#include "io/modules/vdb_internal.hpp"
#include "io/modules/vdb_validate.hpp"

namespace voxfx::detail::vdbmodule {

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

namespace {

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

} // namespace

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

// What the sparse grids use besides this file's readers.
template void readTree<openvdb::BoolGrid>(const openvdb::BoolGrid&, const openvdb::Coord&, const Target&);

namespace {

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

} // namespace

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

namespace {

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

} // namespace

bool readBits(const uint8_t* data, std::size_t size, void* ctx,
              uint64_t* (*allocate)(void* ctx, const VdbReadBox& box, int64_t* wordsPerColumn),
              std::string* error) {
    return guarded(error, [&] { readBitsImpl(data, size, ctx, allocate); });
}

bool readFloats(const uint8_t* data, std::size_t size, const char* gridName, void* ctx,
                float* (*allocate)(void* ctx, const VdbFloatBox& box), std::string* error) {
    return guarded(error, [&] { readFloatsImpl(data, size, gridName, ctx, allocate); });
}

} // namespace voxfx::detail::vdbmodule
