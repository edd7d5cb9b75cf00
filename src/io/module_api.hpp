// voxfx — the interfaces of the loadable I/O modules (internal to io/).
//
// OpenVDB, Assimp and OpenEXR are heavy to load and initialize (tens of milliseconds per process),
// so the library does not link them: each sits behind a small module (voxfx_vdb.so,
// voxfx_assimp.so, voxfx_exr.so) that core/module_loader dlopen()s the first time a format needs
// it. A module exports one extern "C" function, voxfx_module_<name>(abi), returning a table of
// plain function pointers (or null for another ABI). The tables pass views (pointers and sizes)
// and standard containers; a module uses no voxfx symbol (it is linked with --no-undefined), so it
// works the same under a static library, a shared one, or a consumer's executable.
//
// Functions return false and set *error to the message's cause (without the file name, which the
// caller adds as before) instead of throwing across the module boundary.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace voxfx::detail {

/// Bump when a table below changes.
inline constexpr uint32_t kModuleAbi = 11;

/// The library's parallel-for handed to a module (so that modules follow withThreads and name no
/// thread library): calls call(body, b, e) over chunks of `grain` items covering [begin, end).
using ParallelFor = void (*)(int64_t begin, int64_t end, int64_t grain, void* body,
                             void (*call)(void* body, int64_t b, int64_t e));

// ---- voxfx_vdb: OpenVDB (.vdb) ----------------------------------------------------------------

/// A z-sliced bit grid: column (x, y) is words[(y * nx + x) * wordsPerColumn ...], bit z of it.
struct VdbBits {
    int64_t nx = 0, ny = 0, nz = 0, wordsPerColumn = 0;
    const uint64_t* words = nullptr;
};

/// Index (i, j, k) sits at centre0 + (i, j, k) * cell.
struct VdbPlacement {
    double cell[3] = {1, 1, 1};
    double centre0[3] = {0, 0, 0};
};

/// What the reader found, for the caller to allocate the grid: the index box's size and world box.
struct VdbReadBox {
    int64_t dims[3] = {0, 0, 0};
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
};

/// What readFloats found, for the caller to allocate the volume: the index box's size, the world
/// corner of its voxel (0, 0, 0), the voxel size, the world directions of the index axes (unit,
/// orthogonal: a turned grid), and the grid read.
struct VdbFloatBox {
    int64_t dims[3] = {0, 0, 0};
    double lo[3] = {0, 0, 0}, spacing[3] = {1, 1, 1};
    double axes[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    std::string name, gridClass;
    bool isDouble = false;
};

/// One brick of a tiled voxelization for a sparse grid (voxfx/sparse_grid.hpp): cells
/// [origin, origin + size) of the world-axis index space (i, j, k), in the slicemap layout of a
/// frame sliced along world axis `axis` (columns along axis + 1 and axis + 2, slices along axis):
/// `width` x `height` columns of `depth` bits, wordsPerColumn words each. Null words: every cell
/// holds `value`. The origin is a multiple of 8 along every axis.
struct SparseBrick {
    int64_t origin[3] = {0, 0, 0};
    int64_t width = 0, height = 0, depth = 0, wordsPerColumn = 0;
    const uint64_t* words = nullptr;
    bool value = false;
    int axis = 2;
};

/// Topology operations of sparse grids (sparseCombine).
enum class SparseOp : int { Union = 0, Intersection = 1, Difference = 2 };

/// An 8 x 8 x 8 leaf of a level set: index origin (multiples of 8), the active mask and the 512
/// values in OpenVDB's leaf order (offset (i << 6) | (j << 3) | k). Laid out as voxfx::SdfLeaf.
struct VdbLevelSetLeaf {
    int64_t origin[3];
    uint64_t active[8];
    float values[512];
};

/// A run of leaf-sized blocks along x inside the surface: blocks x0 .. x1 - 1 at (y, z), block units.
struct VdbInsideRun {
    int32_t x0, x1, y, z;
};

/// A narrow-band level set as the library computed it (see voxfx/sdf.hpp). Its voxel (i, j, k) is
/// index indexOffset + (i, j, k) of the tree: indexOffset (multiples of 8, so that the leaves stay
/// OpenVDB's leaves) is added to every leaf origin and, in blocks, to every inside run.
struct VdbLevelSet {
    int64_t dims[3] = {0, 0, 0};
    int64_t indexOffset[3] = {0, 0, 0};
    float background = 0;
    const VdbLevelSetLeaf* leaves = nullptr;
    std::size_t leafCount = 0;
    const VdbInsideRun* insideRuns = nullptr;
    std::size_t insideRunCount = 0;
};

/// One grid of writeDenseGrids: `components` (1: FloatGrid, 3: Vec3SGrid) floats per voxel, x
/// fastest, then y, then z (components innermost); voxels outside the call's active mask hold
/// `background`.
struct VdbDenseGrid {
    const char* name = "";
    int components = 1;
    const float* values = nullptr;
    float background = 0;
};

/// What levelSetInfo reports about a level set (an openvdb::FloatGrid of class level set).
struct VdbLevelSetInfo {
    float background = 0;
    double voxelSize[3] = {1, 1, 1};
    double centre0[3] = {0, 0, 0}; ///< world position of index (0, 0, 0)
    /// The transform is a positive scale and a translation: centre0 + ijk * voxelSize.
    bool axisAligned = false;
    int64_t activeCount = 0;
    bool anyActive = false;
    int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1}; ///< the active voxels' index box (inclusive)
    std::string name;
};

/// A polygon mesh as OpenVDB's volumeToMesh makes it: world positions (three floats each),
/// triangles (three indices) and quads (four), corners in OpenVDB's order.
struct VdbPolygons {
    std::vector<float> points;
    std::vector<uint32_t> triangles, quads;
};

struct VdbModule {
    uint32_t abi;
    uint32_t size; ///< sizeof(VdbModule) as the module was built
    /// A BoolGrid (or, with asFloat, a FloatGrid fog volume with 1 in filled voxels).
    bool (*writeBits)(const char* path, const VdbBits& bits, const VdbPlacement& placement,
                      const char* gridName, bool asFloat, ParallelFor parallelFor, std::string* error);
    /// A FloatGrid fog volume from dense values, x fastest, then y, then z; zeros stay inactive.
    bool (*writeFloats)(const char* path, const int64_t dims[3], const float* values,
                        const VdbPlacement& placement, const char* gridName, std::string* error);
    /// Reads the first bool, float or double grid of a .vdb file's bytes (in memory: checked,
    /// then handed to OpenVDB as a stream): `allocate` receives its box and returns the z-sliced
    /// words to set (zeroed, wordsPerColumn per column). The bytes are parsed in full before
    /// `allocate` is called and not read after: the caller may free them there.
    bool (*readBits)(const uint8_t* data, std::size_t size, void* ctx,
                     uint64_t* (*allocate)(void* ctx, const VdbReadBox& box, int64_t* wordsPerColumn),
                     std::string* error);
    /// Reads the grid named `gridName` (empty: the first float or double grid) of a .vdb file's
    /// bytes (checked, then read from memory, as readBits) as dense floats
    /// over its index box (the stored dimensions, else the active voxels' box), x fastest:
    /// `allocate` receives the box and returns dims[0] * dims[1] * dims[2] floats, or null to
    /// stop (it must not throw); the bytes are not read once it is called (as readBits). Rotated and
    /// mirrored transforms give turned axes; sheared and non-linear transforms and values that are
    /// not finite floats are errors.
    bool (*readFloats)(const uint8_t* data, std::size_t size, const char* gridName, void* ctx,
                       float* (*allocate)(void* ctx, const VdbFloatBox& box), std::string* error);

    // ---- Sparse bool grids (voxfx/sparse_grid.hpp): an openvdb::BoolGrid the module owns, whose
    // active voxels (value true) are the filled cells, indexed (i, j, k) along world x, y, z. A
    // handle is used by one thread at a time, except sparseAddBrick (see there).

    /// A new empty grid; null (and *error) on failure.
    void* (*sparseCreate)(std::string* error);
    void (*sparseDestroy)(void* grid);
    void* (*sparseCopy)(const void* grid, std::string* error);
    /// Adds one brick's filled cells (bricks are disjoint). May be called from several threads at
    /// once on one grid: the leaves are built on the calling thread and inserted under the
    /// handle's lock. *bytes receives an estimate of the memory the tree grew by.
    bool (*sparseAddBrick)(void* grid, const SparseBrick& brick, uint64_t* bytes, std::string* error);
    /// After the last brick: merges uniform nodes into tiles (prune).
    bool (*sparseFinish)(void* grid, std::string* error);
    /// Adds the filled cells of a z-sliced dense grid whose cell (0, 0, 0) is index (0, 0, 0).
    bool (*sparseFromBits)(void* grid, const VdbBits& bits, ParallelFor parallelFor, std::string* error);
    /// Sets the bits of the index box [origin, origin + (nx, ny, nz)) into a zeroed z-sliced grid.
    bool (*sparseToBits)(const void* grid, const int64_t origin[3], int64_t nx, int64_t ny, int64_t nz,
                         int64_t wordsPerColumn, uint64_t* words, std::string* error);
    int64_t (*sparseCount)(const void* grid);
    /// The index box of the filled cells (inclusive); false when there is none.
    bool (*sparseBounds)(const void* grid, int64_t lo[3], int64_t hi[3]);
    uint64_t (*sparseMemory)(const void* grid);
    bool (*sparseGet)(const void* grid, const int64_t ijk[3]);
    /// a = a op b (OpenVDB's topology union, intersection, difference).
    bool (*sparseCombine)(void* a, const void* b, SparseOp op, std::string* error);
    /// OpenVDB's dilateActiveValues / erodeActiveValues: `iterations` steps over `neighbours`
    /// (6 face, 18 face and edge, 26 face, edge and vertex neighbours).
    bool (*sparseMorphology)(void* grid, bool erode, int iterations, int neighbours, std::string* error);
    /// Tree indices [lo, hi] (inclusive; every index fits int32): sparseFill fills them (OpenVDB's
    /// fill: tiles where a node is covered), sparseClip empties everything outside them (clip).
    bool (*sparseFill)(void* grid, const int64_t lo[3], const int64_t hi[3], std::string* error);
    bool (*sparseClip)(void* grid, const int64_t lo[3], const int64_t hi[3], std::string* error);
    /// The filled cells' indices minus `origin`, three int32 per cell in the tree's order
    /// (leaves, then tiles), into `out` (room for `count` cells: sparseCount).
    bool (*sparseCoordinates)(const void* grid, const int64_t origin[3], int32_t* out, int64_t count,
                              std::string* error);
    /// Writes the grid as a BoolGrid (or FloatGrid fog volume) with writeBits' conventions; index
    /// `origin` is the placement's voxel (0, 0, 0) and `dims` go in "voxfx_dims".
    bool (*sparseWrite)(const char* path, const void* grid, const int64_t origin[3],
                        const VdbPlacement& placement, const int64_t dims[3], const char* gridName,
                        bool asFloat, std::string* error);
    /// Reads the first bool, float or double grid of a .vdb file's bytes (checked as readBits) as a
    /// sparse grid of its filled voxels (active; for scalars also > 0); `box` receives its index
    /// box (dims and world box, as readBits) and `origin` the index of the box's first cell.
    void* (*sparseRead)(const uint8_t* data, std::size_t size, VdbReadBox* box, int64_t origin[3],
                        std::string* error);

    /// A FloatGrid of class level set, background `ls.background` (+ outside, - inside): the
    /// leaves as given, leaf-sized inactive tiles at -background for the inside runs (merged into
    /// larger tiles where they fill a node), the placement's transform, the dimensions as
    /// "voxfx_dims".
    bool (*writeLevelSet)(const char* path, const VdbLevelSet& ls, const VdbPlacement& placement,
                          const char* gridName, ParallelFor parallelFor, std::string* error);
    /// Several dense grids of the same voxels in one file (class unknown), each with the
    /// placement's transform and the dimensions as "voxfx_dims"; a voxel is active where
    /// active[x + nx * (y + ny * z)] is non-zero.
    bool (*writeDenseGrids)(const char* path, const int64_t dims[3], const uint8_t* active,
                            const VdbDenseGrid* grids, std::size_t gridCount, const VdbPlacement& placement,
                            std::string* error);

    // ---- A level set streamed into its tree (voxfx/sdf_io.hpp's writeSdf of a mesh): the blocks
    // of writeLevelSet added brick by brick as they are made, then written. The tree is the one
    // writeLevelSet makes of the same blocks.

    /// A new empty FloatGrid with background `background`; null (and *error) on failure.
    void* (*levelSetCreate)(float background, std::string* error);
    /// Frees a grid made by levelSetCreate, levelSetRead, levelSetBuild or levelSetCopy.
    void (*levelSetDestroy)(void* grid);
    /// Adds leaves and inside runs (disjoint from those added before). May be called from several
    /// threads at once on one grid: the leaves are built on the calling thread and inserted under
    /// the handle's lock; the caller may free its arrays when it returns.
    bool (*levelSetAdd)(void* grid, const VdbLevelSetLeaf* leaves, std::size_t leafCount,
                        const VdbInsideRun* runs, std::size_t runCount, std::string* error);
    /// After the last add: writeLevelSet's pruning, transform, class, name and "voxfx_dims", and
    /// the file.
    bool (*levelSetStreamWrite)(const char* path, void* grid, const VdbPlacement& placement,
                                const int64_t dims[3], const char* gridName, std::string* error);

    // ---- Level sets (voxfx/level_set.hpp): an openvdb::FloatGrid of class level set the module
    // owns, with its own transform. A handle is used by one thread at a time.

    /// The first bool, float or double grid of a .vdb file's bytes (checked as readBits), when it
    /// is a FloatGrid of class level set; null and *error saying what the grid is otherwise.
    void* (*levelSetRead)(const uint8_t* data, std::size_t size, std::string* error);
    /// 1 when the file's first bool, float or double grid is a float level set, 0 when it is
    /// another grid (*what says which), -1 on an error (*error).
    int (*levelSetProbe)(const uint8_t* data, std::size_t size, std::string* what, std::string* error);
    /// The grid writeLevelSet writes, kept in memory. With `transformOf` (a level-set handle) the
    /// grid takes that grid's transform (a copy sharing its map: the same numbers, equal under
    /// OpenVDB's Transform ==, so that levelSetCombine does not resample) instead of the
    /// placement's, and no "voxfx_dims".
    void* (*levelSetBuild)(const VdbLevelSet& ls, const VdbPlacement& placement, const void* transformOf,
                           const char* gridName, ParallelFor parallelFor, std::string* error);
    void* (*levelSetCopy)(const void* grid, std::string* error);
    bool (*levelSetInfo)(const void* grid, VdbLevelSetInfo* info, std::string* error);
    float (*levelSetValue)(const void* grid, const int64_t ijk[3]);
    /// The values at `count` indices (three int32 each) into out[count], through value accessors
    /// over chunks of the indices in parallel.
    bool (*levelSetValues)(const void* grid, const int32_t* ijk, std::size_t count, float* out,
                           ParallelFor parallelFor, std::string* error);
    /// The active voxels: three int32 indices and one value each, in the tree's order.
    bool (*levelSetActive)(const void* grid, std::vector<int32_t>* ijk, std::vector<float>* values,
                           std::string* error);
    /// a = a op b by OpenVDB's csgUnion, csgIntersection, csgDifference on a copy of b; when the
    /// transforms differ, the copy is b resampled onto a's transform (resampleToMatch: a level-set
    /// rebuild with a's band) and *resampled is set.
    bool (*levelSetCombine)(void* a, const void* b, SparseOp op, bool* resampled, std::string* error);
    /// OpenVDB's LevelSetFilter::offset by -distance: the surface moves `distance` world units
    /// outwards (inwards when negative), the band rebuilt by the tracker.
    bool (*levelSetOffset)(void* grid, double distance, std::string* error);
    bool (*levelSetWrite)(const char* path, const void* grid, std::string* error);

    // ---- Marching cubes (voxfx/volume_to_mesh.hpp): OpenVDB's tools::volumeToMesh, the inside
    // being where values are below `isovalue`.

    /// The level set handle's surface at `isovalue` (OpenVDB's adaptivity in [0, 1]).
    bool (*levelSetToMesh)(const void* grid, double isovalue, double adaptivity, VdbPolygons* out,
                           std::string* error);
    /// The surface of dense values (x fastest, then y, then z; zFastest: z fastest, then y, then x)
    /// whose index (i, j, k) sits at placement.centre0 + (i, j, k) * placement.cell, in a FloatGrid
    /// of class level set (inside below the iso value, as OpenVDB reads level sets) whose voxels
    /// beyond the box hold `background` (above `isovalue`: outside, so surfaces close at the box),
    /// active only near the iso value.
    bool (*denseToMesh)(const float* values, const int64_t dims[3], bool zFastest,
                        const VdbPlacement& placement, float background, double isovalue, double adaptivity,
                        ParallelFor parallelFor, VdbPolygons* out, std::string* error);
};

// ---- voxfx_assimp: Assimp (glTF 2.0 and the long tail) ----------------------------------------

/// One mesh instance of the node tree, in world coordinates. A node whose transform mirrors
/// (negative determinant) gets its triangles' corner order reversed, so closed meshes stay
/// outward-oriented, and its normals negated after the inverse-transpose.
struct AssimpPart {
    std::string name;              ///< node name (or the mesh's), "#k" when the node has several meshes
    std::string nodeName;          ///< the node's own name
    unsigned material = 0;         ///< Assimp's material index
    std::vector<float> positions;  ///< x, y, z per vertex
    std::vector<float> normals;    ///< unit x, y, z per vertex, or empty
    std::vector<uint32_t> indices; ///< three per triangle, into this part's vertices
};

struct AssimpMaterial {
    std::string name;
    float baseColor[4] = {1, 1, 1, 1};
};

struct AssimpScene {
    std::vector<AssimpPart> parts; ///< depth-first node order, meshes in node order
    std::vector<AssimpMaterial> materials;
    std::size_t skippedFaces = 0; ///< points and lines (not surfaces)
};

struct AssimpModule {
    uint32_t abi;
    uint32_t size;
    bool (*load)(const char* path, AssimpScene* out, std::string* error);
    /// Extension in lower case, without the dot.
    bool (*readsExtension)(const char* extension);
    /// Assimp's extensions as ".a .b .c".
    void (*extensions)(std::string* out);
};

// ---- voxfx_exr: OpenEXR -----------------------------------------------------------------------

struct ExrModule {
    uint32_t abi;
    uint32_t size;
    /// Half-float R, G, B from `rgb` (3 floats per pixel, row 0 on top), ZIP compression.
    bool (*writeRgb)(const char* path, int width, int height, const float* rgb, std::string* error);
    /// R, G, B as floats (3 per pixel, row 0 on top) of the file's data window.
    bool (*readRgb)(const char* path, int* width, int* height, std::vector<float>* rgb, std::string* error);
};

/// The loaded modules (loaded on first call; voxfx::Error naming where they were searched when
/// missing). Thread-safe.
const VdbModule& vdbModule();
const AssimpModule& assimpModule();
const ExrModule& exrModule();
/// Starts loading voxfx_vdb.so in the background (core/module_loader.hpp: prefetchModule).
void prefetchVdbModule();

} // namespace voxfx::detail
