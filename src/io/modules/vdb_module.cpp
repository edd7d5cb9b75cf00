// voxfx_vdb — the OpenVDB module: .vdb reading and writing (see io/module_api.hpp, io/vdb.cpp,
// io/volume_vdb.cpp).
//
// Written grids: a BoolGrid (or a FloatGrid fog volume with 1 in filled voxels) whose index
// (i, j, k) is voxel (i, j, k) of the grid and whose transform maps it to the voxel centre:
// scale by the cell size, then translate by lo + cell / 2 (OpenVDB's cell-centred convention).
// The grid's dimensions travel as Vec3i metadata "voxfx_dims", so empty borders survive a round
// trip; grids without it get the bounding box of their active voxels.
//
// One file per concern (vdb_internal.hpp lists them); this one holds the table, the entry and
// what every writer shares.
#include <mutex>

#include "io/modules/vdb_internal.hpp"

namespace voxfx::detail::vdbmodule {

void initializeOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
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

namespace {

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
} // namespace voxfx::detail::vdbmodule

extern "C" const void* voxfx_module_vdb(uint32_t abi) {
    return abi == voxfx::detail::kModuleAbi ? &voxfx::detail::vdbmodule::kTable : nullptr;
}
