// voxfx — OpenVDB (.vdb) reading and writing through the voxfx_vdb module (io/modules/vdb_module.cpp
// holds the format's conventions); the library itself does not link OpenVDB.
#include <cstring>

#include "io/grid_formats.hpp"
#include "io/module_api.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

namespace {
void hostParallelFor(int64_t begin, int64_t end, int64_t grain, void* body,
                     void (*call)(void* body, int64_t b, int64_t e)) {
    parallelFor(begin, end, grain, [&](int64_t b, int64_t e) { call(body, b, e); });
}

VdbPlacement placementOf(const Frame& frame) {
    const Vec3d cell = frame.cellSize();
    const Vec3d centre0 = frame.box().lo + cell * 0.5;
    return {{cell.x, cell.y, cell.z}, {centre0.x, centre0.y, centre0.z}};
}
} // namespace

void writeVdb(const VoxelGrid& grid, AtomicFile& file, const GridWriteOptions& options) {
    const VdbModule& vdb = vdbModule();
    // Columns (x, y), bits along z: a grid sliced so already is read in place (no copy).
    const Frame& f = grid.frame;
    const bool zSliced =
        f.axis() == Axis::Z && f.slicing() == Slicing::Uniform && !f.isPerspective() && !f.isOriented();
    VoxelGrid resliced;
    if (!zSliced) resliced = reslice(grid, Axis::Z);
    const BitGrid& g = zSliced ? grid.bits : resliced.bits;
    const VdbBits bits{g.width(), g.height(), g.depth(), g.wordsPerColumn(), g.column(0)};
    std::string error;
    if (!vdb.writeBits(file.tempPath().c_str(), bits, placementOf(grid.frame), options.gridName.c_str(),
                       options.vdbFloat, hostParallelFor, &error))
        fail("cannot write '", file.targetPath().string(), "': ", error);
}

void writeSparseVdb(const SparseGrid& grid, AtomicFile& file, const GridWriteOptions& options) {
    const Vec3i d = grid.dims();
    const int64_t dims[3] = {d.x, d.y, d.z};
    const int64_t origin[3] = {grid.treeOrigin().x, grid.treeOrigin().y, grid.treeOrigin().z};
    std::string error;
    if (!grid.handle()) fail("cannot write '", file.targetPath().string(), "': the sparse grid has no frame");
    if (!vdbModule().sparseWrite(file.tempPath().c_str(), grid.handle(), origin, placementOf(grid.frame()),
                                 dims, options.gridName.c_str(), options.vdbFloat, &error))
        fail("cannot write '", file.targetPath().string(), "': ", error);
}

SparseGrid readSparseVdb(std::span<const uint8_t> bytes) {
    VdbReadBox box;
    int64_t origin[3] = {0, 0, 0};
    std::string error;
    void* tree = vdbModule().sparseRead(bytes.data(), bytes.size(), &box, origin, &error);
    if (!tree) fail(error);
    const Box3d world{{box.lo[0], box.lo[1], box.lo[2]}, {box.hi[0], box.hi[1], box.hi[2]}};
    try {
        return SparseGrid::adopt(Frame::orthographic(world, Axis::Z, box.dims[0], box.dims[1], box.dims[2]),
                                 tree, {origin[0], origin[1], origin[2]});
    } catch (...) {
        vdbModule().sparseDestroy(tree);
        throw;
    }
}

VoxelGrid readVdb(std::span<const uint8_t> bytes, std::vector<uint8_t>* release) {
    const VdbModule& vdb = vdbModule();
    struct Target {
        VoxelGrid grid;
        std::vector<uint8_t>* release;
    } target{{}, release};
    auto allocate = [](void* ctx, const VdbReadBox& box, int64_t* wordsPerColumn) -> uint64_t* {
        Target& t = *static_cast<Target*>(ctx);
        // The module no longer reads the bytes (module_api.hpp): let them go before the grid comes.
        if (t.release) std::vector<uint8_t>().swap(*t.release);
        VoxelGrid& out = t.grid;
        const Box3d world{{box.lo[0], box.lo[1], box.lo[2]}, {box.hi[0], box.hi[1], box.hi[2]}};
        out = VoxelGrid{Frame::orthographic(world, Axis::Z, box.dims[0], box.dims[1], box.dims[2]),
                        BitGrid(box.dims[0], box.dims[1], box.dims[2])};
        *wordsPerColumn = out.bits.wordsPerColumn();
        return out.bits.column(0);
    };
    std::string error;
    if (!vdb.readBits(bytes.data(), bytes.size(), &target, allocate, &error)) fail(error);
    return std::move(target.grid);
}

} // namespace voxfx::detail
