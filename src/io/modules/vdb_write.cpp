// voxfx_vdb — writing: bit grids (bool, or float fog volumes with 1 in filled voxels), float
// volumes and dense attribute grids to .vdb files (see vdb_module.cpp for the grids' placement).
//
// The writer fills leaf nodes straight from the bit columns: with the grid sliced along z, the
// 8 x 8 x 8 leaf at (x0, y0, z0) has value-mask word x & 7 = eight bytes, byte y & 7 being bits
// z0 .. z0+7 of column (x, y) (offset = (x & 7) << 6 | (y & 7) << 3 | (z & 7)).
#include <algorithm>
#include <memory>
#include <type_traits>
#include <vector>

#include "io/modules/vdb_internal.hpp"

namespace voxfx::detail::vdbmodule {

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
