// voxfx_vdb — level sets (voxfx/level_set.hpp, io/sdf_io.cpp): built from a SignedDistanceField's
// leaves and inside runs, whole or streamed; read, copied, queried, combined (CSG), offset and
// written.
#include <algorithm>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tree/ValueAccessor.h>

#include "io/modules/vdb_internal.hpp"

namespace voxfx::detail::vdbmodule {

namespace {

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

} // namespace

bool writeLevelSet(const char* path, const VdbLevelSet& ls, const VdbPlacement& placement,
                   const char* gridName, ParallelFor parallelFor, std::string* error) {
    return guarded(error, [&] { writeFile(path, buildLevelSet(ls, placement, gridName, parallelFor)); });
}

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

namespace {

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

} // namespace

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

} // namespace voxfx::detail::vdbmodule
