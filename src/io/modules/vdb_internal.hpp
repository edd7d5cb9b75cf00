// voxfx_vdb — the OpenVDB module's internals shared by its files (not a header of the library):
// the helpers every concern uses, the pieces two concerns share, and the functions of the module's
// table (vdb_module.cpp), one file per concern:
//   vdb_write.cpp      bit grids, floats and dense grids to .vdb files
//   vdb_read.cpp       .vdb bytes, checked by the walker (vdb_validate.hpp), to bits and floats
//   vdb_sparse.cpp     SparseGrid: OpenVDB's bool tree fed brick by brick, its topology operations
//   vdb_level_set.cpp  level sets: built, streamed, read, combined, offset, queried, written
//   vdb_mesh.cpp       polygons from a level set or a dense field (volumeToMesh)
#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tree/LeafNode.h>

#include "io/module_api.hpp"
#include "voxfx/error.hpp"

namespace voxfx::detail::vdbmodule {

/// The metadata that carries a written grid's dimensions (empty borders survive a round trip).
inline constexpr const char* kDimsMeta = "voxfx_dims";

/// openvdb::initialize(), once per process.
void initializeOpenVdb();

/// body(b, e) over [begin, end) in chunks of `grain`, through the library's parallelFor.
template <class F>
void forChunks(ParallelFor parallelFor, int64_t begin, int64_t end, int64_t grain, F& body) {
    parallelFor(begin, end, grain, &body, [](void* f, int64_t b, int64_t e) { (*static_cast<F*>(f))(b, e); });
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

using BoolLeaf = openvdb::BoolGrid::TreeType::LeafNodeType;
static_assert(BoolLeaf::LOG2DIM == 3 && BoolLeaf::NodeMaskType::WORD_COUNT == 8);
using FloatLeaf = openvdb::FloatGrid::TreeType::LeafNodeType;
static_assert(FloatLeaf::SIZE == 512 && FloatLeaf::NodeMaskType::WORD_COUNT == 8);
using BoolTree = openvdb::BoolGrid::TreeType;

// ---- Shared by the writers (vdb_module.cpp) --------------------------------------------------

/// The transform of a placement: scale by the cell size, then translate to voxel (0,0,0)'s centre.
openvdb::math::Transform::Ptr transformFor(const VdbPlacement& p);
/// Writes one grid to a file; voxfx::Error with OpenVDB's message.
void writeFile(const char* path, const openvdb::GridBase::Ptr& grid);

// ---- Writing (vdb_write.cpp) -----------------------------------------------------------------

/// Builds the leaves of a z-sliced grid (defined for BoolGrid and FloatGrid; see vdb_write.cpp).
template <class GridT> void fillLeaves(const VdbBits& g, ParallelFor parallelFor, GridT& grid);

bool writeBits(const char* path, const VdbBits& bits, const VdbPlacement& placement, const char* gridName,
               bool asFloat, ParallelFor parallelFor, std::string* error);
bool writeFloats(const char* path, const int64_t dims[3], const float* values, const VdbPlacement& placement,
                 const char* gridName, std::string* error);
bool writeDenseGrids(const char* path, const int64_t dims[3], const uint8_t* active,
                     const VdbDenseGrid* grids, std::size_t gridCount, const VdbPlacement& placement,
                     std::string* error);

// ---- Reading (vdb_read.cpp) ------------------------------------------------------------------

// A z-sliced target: n = index box size, words wpc per column (x, y).
struct Target {
    int64_t nx, ny, nz, wpc;
    uint64_t* words;
    uint64_t* column(int64_t x, int64_t y) const { return words + (y * nx + x) * wpc; }
};

/// Sets the bits of a z-sliced grid whose index box starts at `o` from a tree's leaves and tiles
/// (defined for BoolGrid, FloatGrid and DoubleGrid; see vdb_read.cpp).
template <class GridT> void readTree(const GridT& grid, const openvdb::Coord& o, const Target& g);
/// Cell size and centre of voxel (0,0,0) of an axis-aligned scale + translate transform.
void boxTransform(const openvdb::GridBase& grid, double cell[3], double centre0[3]);
/// Every grid of a .vdb file's bytes, read by OpenVDB after the walker checked them.
openvdb::GridPtrVecPtr readValidatedGrids(const uint8_t* data, std::size_t size);
/// The index box of a grid: its stored dimensions when they cover every active voxel, else the
/// bounding box of its active voxels.
openvdb::CoordBBox indexBox(const openvdb::GridBase& grid);
/// The file's first bool, float or double grid (what readGrid reads as occupancy); level sets are
/// refused.
openvdb::GridBase::Ptr firstOccupancyGrid(const uint8_t* data, std::size_t size);

bool readBits(const uint8_t* data, std::size_t size, void* ctx,
              uint64_t* (*allocate)(void* ctx, const VdbReadBox& box, int64_t* wordsPerColumn),
              std::string* error);
bool readFloats(const uint8_t* data, std::size_t size, const char* gridName, void* ctx,
                float* (*allocate)(void* ctx, const VdbFloatBox& box), std::string* error);

// ---- Sparse grids (vdb_sparse.cpp) -----------------------------------------------------------

void* sparseCreate(std::string* error);
void sparseDestroy(void* g);
void* sparseCopy(const void* g, std::string* error);
bool sparseAddBrick(void* g, const SparseBrick& b, uint64_t* bytes, std::string* error);
bool sparseFinish(void* g, std::string* error);
bool sparseFromBits(void* g, const VdbBits& bits, ParallelFor parallelFor, std::string* error);
bool sparseToBits(const void* g, const int64_t origin[3], int64_t nx, int64_t ny, int64_t nz, int64_t wpc,
                  uint64_t* words, std::string* error);
int64_t sparseCount(const void* g);
bool sparseBounds(const void* g, int64_t lo[3], int64_t hi[3]);
uint64_t sparseMemory(const void* g);
bool sparseGet(const void* g, const int64_t ijk[3]);
bool sparseCombine(void* a, const void* b, SparseOp op, std::string* error);
bool sparseMorphology(void* g, bool erode, int iterations, int neighbours, std::string* error);
bool sparseFill(void* g, const int64_t lo[3], const int64_t hi[3], std::string* error);
bool sparseClip(void* g, const int64_t lo[3], const int64_t hi[3], std::string* error);
bool sparseCoordinates(const void* g, const int64_t origin[3], int32_t* out, int64_t count,
                       std::string* error);
bool sparseWrite(const char* path, const void* g, const int64_t origin[3], const VdbPlacement& placement,
                 const int64_t dims[3], const char* gridName, bool asFloat, std::string* error);
void* sparseRead(const uint8_t* data, std::size_t size, VdbReadBox* box, int64_t origin[3],
                 std::string* error);

// ---- Level sets (vdb_level_set.cpp) ----------------------------------------------------------

struct LevelSetHandle {
    openvdb::FloatGrid::Ptr grid;
    std::mutex mutex; // levelSetAdd's insertions
};
inline openvdb::FloatGrid& lsGrid(void* g) { return *static_cast<LevelSetHandle*>(g)->grid; }
inline const openvdb::FloatGrid& lsGrid(const void* g) {
    return *static_cast<const LevelSetHandle*>(g)->grid;
}

bool writeLevelSet(const char* path, const VdbLevelSet& ls, const VdbPlacement& placement,
                   const char* gridName, ParallelFor parallelFor, std::string* error);
void* levelSetCreate(float background, std::string* error);
void levelSetDestroy(void* g);
bool levelSetAdd(void* g, const VdbLevelSetLeaf* leaves, std::size_t leafCount, const VdbInsideRun* runs,
                 std::size_t runCount, std::string* error);
bool levelSetStreamWrite(const char* path, void* g, const VdbPlacement& placement, const int64_t dims[3],
                         const char* gridName, std::string* error);
void* levelSetRead(const uint8_t* data, std::size_t size, std::string* error);
int levelSetProbe(const uint8_t* data, std::size_t size, std::string* what, std::string* error);
void* levelSetBuild(const VdbLevelSet& ls, const VdbPlacement& placement, const void* transformOf,
                    const char* gridName, ParallelFor parallelFor, std::string* error);
void* levelSetCopy(const void* g, std::string* error);
bool levelSetInfo(const void* g, VdbLevelSetInfo* info, std::string* error);
float levelSetValue(const void* g, const int64_t ijk[3]);
bool levelSetValues(const void* g, const int32_t* ijk, std::size_t count, float* out, ParallelFor parallelFor,
                    std::string* error);
bool levelSetActive(const void* g, std::vector<int32_t>* ijk, std::vector<float>* values, std::string* error);
bool levelSetCombine(void* a, const void* b, SparseOp op, bool* resampled, std::string* error);
bool levelSetOffset(void* g, double distance, std::string* error);
bool levelSetWrite(const char* path, const void* g, std::string* error);

// ---- Meshes (vdb_mesh.cpp) -------------------------------------------------------------------

bool levelSetToMesh(const void* g, double isovalue, double adaptivity, VdbPolygons* out, std::string* error);
bool denseToMesh(const float* values, const int64_t dims[3], bool zFastest, const VdbPlacement& placement,
                 float background, double isovalue, double adaptivity, ParallelFor parallelFor,
                 VdbPolygons* out, std::string* error);

} // namespace voxfx::detail::vdbmodule
