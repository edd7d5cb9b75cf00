// voxfx_vdb — writing: bit grids (bool, or float fog volumes with 1 in filled voxels), float
// volumes and dense attribute grids to .vdb files (see vdb_module.cpp for the grids' placement).
//
// The writer fills leaf nodes straight from the bit columns: with the grid sliced along z, the
// 8 x 8 x 8 leaf at (x0, y0, z0) has value-mask word x & 7 = eight bytes, byte y & 7 being bits
// z0 .. z0+7 of column (x, y) (offset = (x & 7) << 6 | (y & 7) << 3 | (z & 7)), and the internal
// nodes above them in parallel (fillLeaves).
#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <type_traits>
#include <vector>

#include "io/modules/vdb_internal.hpp"

namespace voxfx::detail::vdbmodule {

namespace {

// The 8 x 8 x 8 value masks of the leaf column (leafX, leafY) of a z-sliced grid: masks[bz * 8 + i]
// is word i of leaf bz's value mask. Column (x, y) word w holds bits z = 64w .. 64w+63: byte k
// goes to leaf bz = 8w + k.
void leafColumnMasks(const VdbBits& g, int64_t leafX, int64_t leafY, int64_t lz,
                     std::vector<uint64_t>& masks) {
    std::fill(masks.begin(), masks.end(), 0);
    for (int64_t ix = 0; ix < 8 && leafX * 8 + ix < g.nx; ++ix)
        for (int64_t jy = 0; jy < 8 && leafY * 8 + jy < g.ny; ++jy) {
            const uint64_t* col = g.words + ((leafY * 8 + jy) * g.nx + leafX * 8 + ix) * g.wordsPerColumn;
            for (int64_t w = 0; w < g.wordsPerColumn; ++w) {
                const uint64_t word = col[w];
                if (!word) continue;
                for (int64_t k = 0; k < 8 && w * 8 + k < lz; ++k)
                    masks[size_t((w * 8 + k) * 8 + ix)] |= ((word >> (8 * k)) & 0xFF) << (8 * jy);
            }
        }
}

} // namespace

// Builds the tree of a z-sliced grid bottom up, in parallel: each task makes the lower internal
// nodes (128^3) of one column of them, with a leaf for each mixed 8^3 block and an active tile
// for each full one (nothing for an empty one); a lower node whose blocks are all full becomes a
// tile of its upper node instead. The upper nodes (4096^3) are then assembled and handed to the
// root in a fixed order. This is the tree that adding the leaves and leaf tiles one by one and
// pruning gave (leaves that are neither empty nor full are never constant; full blocks merge
// upwards exactly as prune merges them), without the serial walk from the root per leaf and the
// pass of prune over every node.
template <class GridT> void fillLeaves(const VdbBits& g, ParallelFor parallelFor, GridT& grid) {
    using TreeT = typename GridT::TreeType;
    using UpperT = typename TreeT::RootNodeType::ChildNodeType;
    using LowerT = typename UpperT::ChildNodeType;
    using LeafT = typename TreeT::LeafNodeType;
    using ValueT = typename LeafT::ValueType;
    constexpr int64_t kLeavesPerLower = LowerT::DIM / LeafT::DIM;
    const int64_t lx = (g.nx + 7) / 8, ly = (g.ny + 7) / 8, lz = (g.nz + 7) / 8;
    const int64_t bx = (lx + kLeavesPerLower - 1) / kLeavesPerLower,
                  by = (ly + kLeavesPerLower - 1) / kLeavesPerLower,
                  bz = (lz + kLeavesPerLower - 1) / kLeavesPerLower;
    std::vector<std::vector<std::unique_ptr<LowerT>>> lowers(size_t(bx * by));
    std::vector<std::vector<openvdb::Coord>> fullLowers(size_t(bx * by));
    auto body = [&](int64_t b, int64_t e) {
        std::vector<uint64_t> masks(size_t(lz * 8));
        std::vector<std::unique_ptr<LowerT>> column(static_cast<size_t>(bz));
        std::vector<openvdb::Index> full(static_cast<size_t>(bz));
        for (int64_t t = b; t < e; ++t) {
            const int64_t cx = t % bx, cy = t / bx;
            std::fill(full.begin(), full.end(), 0);
            for (int64_t iy = 0; iy < kLeavesPerLower && cy * kLeavesPerLower + iy < ly; ++iy)
                for (int64_t ix = 0; ix < kLeavesPerLower && cx * kLeavesPerLower + ix < lx; ++ix) {
                    const int64_t leafX = cx * kLeavesPerLower + ix, leafY = cy * kLeavesPerLower + iy;
                    leafColumnMasks(g, leafX, leafY, lz, masks);
                    for (int64_t z = 0; z < lz; ++z) {
                        const uint64_t* m = &masks[size_t(z * 8)];
                        if (!(m[0] | m[1] | m[2] | m[3] | m[4] | m[5] | m[6] | m[7])) continue;
                        const openvdb::Coord origin(int(leafX * 8), int(leafY * 8), int(z * 8));
                        std::unique_ptr<LowerT>& lower = column[size_t(z / kLeavesPerLower)];
                        if (!lower) lower = std::make_unique<LowerT>(origin, ValueT(0), false);
                        if (!~(m[0] & m[1] & m[2] & m[3] & m[4] & m[5] & m[6] & m[7])) {
                            lower->addTile(LowerT::coordToOffset(origin), ValueT(1), true);
                            ++full[size_t(z / kLeavesPerLower)];
                            continue;
                        }
                        auto leaf = std::make_unique<LeafT>(origin, ValueT(0), false);
                        typename LeafT::NodeMaskType mask;
                        for (int i = 0; i < 8; ++i) mask.template getWord<uint64_t>(openvdb::Index(i)) = m[i];
                        leaf->setValueMask(mask);
                        if constexpr (std::is_same_v<ValueT, bool>) {
                            std::copy(m, m + 8, leaf->buffer().data()); // value true exactly where active
                        } else {
                            auto* values = leaf->buffer().data();
                            for (int i = 0; i < 512; ++i) values[i] = float((m[i >> 6] >> (i & 63)) & 1u);
                        }
                        lower->addChild(leaf.release());
                    }
                }
            for (int64_t z = 0; z < bz; ++z) {
                std::unique_ptr<LowerT>& lower = column[size_t(z)];
                if (!lower) continue;
                if (full[size_t(z)] == LowerT::NUM_VALUES)
                    fullLowers[size_t(t)].push_back(lower->origin());
                else
                    lowers[size_t(t)].push_back(std::move(lower));
                lower.reset();
            }
        }
    };
    forChunks(parallelFor, 0, bx * by, 1, body);
    // The upper nodes, in the order of their origins (a deterministic tree).
    std::map<std::array<int, 3>, std::pair<std::unique_ptr<UpperT>, openvdb::Index>> uppers;
    auto upperOf = [&](const openvdb::Coord& c) -> auto& {
        const int mask = ~int(UpperT::DIM - 1);
        const std::array<int, 3> key{c.x() & mask, c.y() & mask, c.z() & mask};
        auto& slot = uppers[key];
        if (!slot.first)
            slot.first = std::make_unique<UpperT>(openvdb::Coord(key[0], key[1], key[2]), ValueT(0), false);
        return slot;
    };
    for (size_t t = 0; t < lowers.size(); ++t) {
        for (auto& lower : lowers[t]) upperOf(lower->origin()).first->addChild(lower.release());
        for (const openvdb::Coord& origin : fullLowers[t]) {
            auto& slot = upperOf(origin);
            slot.first->addTile(UpperT::coordToOffset(origin), ValueT(1), true);
            ++slot.second;
        }
    }
    auto& root = grid.tree().root();
    for (auto& [key, slot] : uppers) {
        if (slot.second == UpperT::NUM_VALUES) // all full: a tile of the root, as prune makes it
            root.addTile(slot.first->origin(), ValueT(1), true);
        else
            root.addChild(slot.first.release());
    }
}

// What the sparse grids use besides this file's writers.
template void fillLeaves<openvdb::BoolGrid>(const VdbBits&, ParallelFor, openvdb::BoolGrid&);

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

namespace {

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

} // namespace

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

} // namespace voxfx::detail::vdbmodule
