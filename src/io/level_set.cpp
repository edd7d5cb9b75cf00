// voxfx — level-set CSG and offsets (voxfx/level_set.hpp): OpenVDB's tools behind the voxfx_vdb
// module, and the exact offset of a mesh's signed distance field. In io/ because the module is
// io's (module_api.hpp).
#include "voxfx/level_set.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "core/atomic_file.hpp"
#include "io/grid_formats.hpp"
#include "io/module_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace level_set_detail {

const detail::VdbModule& module() { return detail::vdbModule(); }

void check(bool ok, const std::string& error, const char* what) {
    if (!ok) fail(what, ": ", error);
}

void levelSetParallelFor(int64_t begin, int64_t end, int64_t grain, void* body,
                         void (*call)(void* body, int64_t b, int64_t e)) {
    parallelFor(begin, end, grain, [&](int64_t b, int64_t e) { call(body, b, e); });
}

detail::VdbLevelSetInfo info(const void* grid) {
    if (!grid) fail("the level set is empty (no grid)");
    detail::VdbLevelSetInfo i;
    std::string error;
    check(module().levelSetInfo(grid, &i, &error), error, "level set");
    return i;
}

detail::SparseOp sparseOp(CsgOp op) {
    switch (op) {
    case CsgOp::Union:
        return detail::SparseOp::Union;
    case CsgOp::Intersection:
        return detail::SparseOp::Intersection;
    default:
        return detail::SparseOp::Difference;
    }
}

// a = a op b in place (op not Xor).
void combine(LevelSet& a, const LevelSet& b, CsgOp op, bool* resampled) {
    if (!a.valid() || !b.valid()) fail("level-set CSG: an operand is empty (no grid)");
    bool r = false;
    std::string error;
    check(module().levelSetCombine(a.handle(), b.handle(), sparseOp(op), &r, &error), error, "level-set CSG");
    if (resampled) *resampled = *resampled || r;
}

} // namespace level_set_detail

namespace lsd = level_set_detail;

LevelSet::LevelSet() = default;

LevelSet::~LevelSet() {
    if (grid_) lsd::module().levelSetDestroy(grid_);
}

LevelSet::LevelSet(const LevelSet& o) {
    if (!o.grid_) return;
    std::string error;
    grid_ = lsd::module().levelSetCopy(o.grid_, &error);
    lsd::check(grid_ != nullptr, error, "cannot copy a level set");
}

LevelSet& LevelSet::operator=(const LevelSet& o) {
    if (this != &o) *this = LevelSet(o);
    return *this;
}

LevelSet::LevelSet(LevelSet&& o) noexcept : grid_(std::exchange(o.grid_, nullptr)) {}

LevelSet& LevelSet::operator=(LevelSet&& o) noexcept {
    if (this != &o) {
        if (grid_) lsd::module().levelSetDestroy(grid_);
        grid_ = std::exchange(o.grid_, nullptr);
    }
    return *this;
}

LevelSet LevelSet::adopt(void* grid) {
    LevelSet ls;
    ls.grid_ = grid;
    return ls;
}

LevelSet LevelSet::fromField(const SignedDistanceField& f, const std::string& name) {
    if (f.full) fail("a level set needs a narrow band: the field was computed in full (SdfOptions::full)");
    const Vec3i d = f.dims();
    if (d.x <= 0 || d.y <= 0 || d.z <= 0) fail("the distance field is empty");
    const Vec3d cell = f.frame.cellSize();
    const Vec3d centre0 = f.frame.box().lo + cell * 0.5;
    const detail::VdbPlacement placement{{cell.x, cell.y, cell.z}, {centre0.x, centre0.y, centre0.z}};
    detail::VdbLevelSet ls;
    ls.dims[0] = d.x;
    ls.dims[1] = d.y;
    ls.dims[2] = d.z;
    ls.background = float(f.background);
    // Same layout (checked in sdf_io.cpp).
    ls.leaves = reinterpret_cast<const detail::VdbLevelSetLeaf*>(f.leaves.data());
    ls.leafCount = f.leaves.size();
    ls.insideRuns = reinterpret_cast<const detail::VdbInsideRun*>(f.insideRuns.data());
    ls.insideRunCount = f.insideRuns.size();
    std::string error;
    void* g =
        lsd::module().levelSetBuild(ls, placement, nullptr, name.c_str(), lsd::levelSetParallelFor, &error);
    lsd::check(g != nullptr, error, "cannot make a level set");
    return adopt(g);
}

float LevelSet::background() const { return lsd::info(grid_).background; }

Vec3d LevelSet::voxelSize() const {
    const auto i = lsd::info(grid_);
    return {i.voxelSize[0], i.voxelSize[1], i.voxelSize[2]};
}

double LevelSet::bandVoxels() const {
    const auto i = lsd::info(grid_);
    return double(i.background) / i.voxelSize[0];
}

bool LevelSet::axisAligned() const { return lsd::info(grid_).axisAligned; }

Vec3d LevelSet::indexOrigin() const {
    const auto i = lsd::info(grid_);
    return {i.centre0[0], i.centre0[1], i.centre0[2]};
}

int64_t LevelSet::activeCount() const { return lsd::info(grid_).activeCount; }

void LevelSet::activeBounds(Vec3i& lo, Vec3i& hi) const {
    const auto i = lsd::info(grid_);
    lo = {i.lo[0], i.lo[1], i.lo[2]};
    hi = {i.hi[0], i.hi[1], i.hi[2]};
}

float LevelSet::value(int64_t i, int64_t j, int64_t k) const {
    if (!grid_) fail("the level set is empty (no grid)");
    const int64_t ijk[3] = {i, j, k};
    return lsd::module().levelSetValue(grid_, ijk);
}

void LevelSet::values(std::span<const std::array<int32_t, 3>> indices, std::span<float> out) const {
    if (!grid_) fail("the level set is empty (no grid)");
    if (out.size() != indices.size())
        fail("level-set values: ", indices.size(), " indices but room for ", out.size(), " values");
    if (indices.empty()) return;
    std::string error;
    lsd::check(lsd::module().levelSetValues(grid_, indices.data()->data(), indices.size(), out.data(),
                                            lsd::levelSetParallelFor, &error),
               error, "level set");
}

void LevelSet::activeVoxels(std::vector<std::array<int32_t, 3>>& indices, std::vector<float>& values) const {
    if (!grid_) fail("the level set is empty (no grid)");
    std::vector<int32_t> flat;
    std::string error;
    lsd::check(lsd::module().levelSetActive(grid_, &flat, &values, &error), error, "level set");
    indices.resize(values.size());
    for (size_t n = 0; n < indices.size(); ++n) indices[n] = {flat[3 * n], flat[3 * n + 1], flat[3 * n + 2]};
}

std::string LevelSet::name() const { return lsd::info(grid_).name; }

LevelSet readLevelSet(const std::string& path) {
    const std::vector<uint8_t> bytes = detail::readFileBytes(path);
    std::string error;
    void* g = lsd::module().levelSetRead(bytes.data(), bytes.size(), &error);
    if (!g) fail("cannot read '", path, "' as a level set: ", error);
    return LevelSet::adopt(g);
}

bool isLevelSetFile(const std::string& path, std::string* what) {
    const std::vector<uint8_t> bytes = detail::readFileBytes(path);
    std::string w, error;
    const int r = lsd::module().levelSetProbe(bytes.data(), bytes.size(), &w, &error);
    if (r < 0) fail("cannot read '", path, "': ", error);
    if (what) *what = w;
    return r == 1;
}

void writeLevelSet(const LevelSet& levelSet, const std::string& path) {
    if (!levelSet.valid()) fail("cannot write '", path, "': the level set is empty (no grid)");
    detail::AtomicFile file(path);
    std::string error;
    if (!lsd::module().levelSetWrite(file.tempPath().c_str(), levelSet.handle(), &error))
        fail("cannot write '", path, "': ", error);
    file.commit();
}

LevelSet levelSetCsg(const LevelSet& a, const LevelSet& b, CsgOp op, bool* resampled) {
    if (resampled) *resampled = false;
    LevelSet out = a;
    if (op != CsgOp::Xor) {
        lsd::combine(out, b, op, resampled);
        return out;
    }
    LevelSet both = a;
    lsd::combine(both, b, CsgOp::Intersection, resampled);
    lsd::combine(out, b, CsgOp::Union, resampled);
    lsd::combine(out, both, CsgOp::Difference, nullptr); // same transform as out: no resampling
    return out;
}

LevelSet levelSetOfMesh(const MeshView& mesh, const LevelSet& lattice, const SdfOptions& options,
                        const Vec3d& meshOrigin) {
    if (!lattice.valid()) fail("level set of a mesh: the lattice level set is empty (no grid)");
    if (options.full)
        fail("level set of a mesh: a level set is a narrow band, not a full field (SdfOptions::full)");
    const detail::VdbLevelSetInfo info = lsd::info(lattice.handle());
    if (!info.axisAligned)
        fail(
            "level set of a mesh: level set '", info.name,
            "' has a transform that is not a positive scale and a translation (rotated, sheared, mirrored or "
            "non-linear); a mesh's distance field needs axis-aligned voxels");
    const double h = info.voxelSize[0];
    if (!(info.voxelSize[1] == h && info.voxelSize[2] == h))
        fail("level set of a mesh: level set '", info.name, "' has voxels of ", info.voxelSize[0], " x ",
             info.voxelSize[1], " x ", info.voxelSize[2], "; a mesh's level set needs cubic voxels");
    if (!isFinite(meshOrigin)) fail("level set of a mesh: the mesh's origin is not finite");
    validateMesh(mesh, "level set of a mesh");
    const float background = info.background;
    const std::string name = info.name;

    detail::VdbLevelSet ls;
    ls.background = background;
    const Box3d bounds = computeBounds(mesh);
    SignedDistanceField f;
    if (!bounds.empty()) {
        // The lattice in the mesh's coordinates: index (i, j, k) at c0 + (i, j, k) * h.
        const Vec3d c0 = Vec3d{info.centre0[0], info.centre0[1], info.centre0[2]} - meshOrigin;
        // Computed a little wider than the lattice's band (at least signedDistanceField's 1 voxel),
        // then cut to it below: active exactly where |value| < background, whatever the rounding
        // of the frame's cell size.
        SdfOptions o = options;
        o.bandVoxels = std::max(1.0, double(background) / h) * (1 + 1e-6);
        // The voxels within the band of the mesh's bounds (plus a voxel for rounding), from a
        // multiple of 8 so that the field's leaves are the tree's.
        const double margin = std::ceil(o.bandVoxels) + 1;
        const double limit = double(std::numeric_limits<int32_t>::max()) - 64;
        Vec3i first, count;
        for (int a = 0; a < 3; ++a) {
            const double lo = std::floor((bounds.lo[a] - c0[a]) / h) - margin;
            const double hi = std::ceil((bounds.hi[a] - c0[a]) / h) + margin;
            if (!(lo > -limit && hi < limit))
                fail("level set of a mesh: the mesh's bounds lie at indices [", lo, ", ", hi, "] along ",
                     "xyz"[a], " of level set '", name, "', beyond OpenVDB's 32-bit indices");
            first[a] = int64_t(std::floor(lo / 8)) * 8;
            count[a] = int64_t(hi) - first[a] + 1;
        }
        // Voxel (i, j, k) of the frame is lattice index first + (i, j, k): its centre is
        // lo + (i + 0.5) * cell = c0 + (first + i) * h, up to rounding.
        Box3d box;
        for (int a = 0; a < 3; ++a) {
            box.lo[a] = c0[a] + (double(first[a]) - 0.5) * h;
            box.hi[a] = c0[a] + (double(first[a] + count[a]) - 0.5) * h;
        }
        f = signedDistanceField(mesh, Frame::orthographic(box, Axis::Z, count.x, count.y, count.z), o);
        // Cut to the lattice's band: inactive values are +-background, with their sign.
        std::vector<SdfLeaf> kept;
        kept.reserve(f.leaves.size());
        for (SdfLeaf& leaf : f.leaves) {
            bool anyActive = false, allOutside = true;
            for (int n = 0; n < 512; ++n) {
                float& v = leaf.values[std::size_t(n)];
                uint64_t& word = leaf.active[std::size_t(n >> 6)];
                const uint64_t bit = uint64_t(1) << (n & 63);
                const bool inside = std::signbit(v);
                if ((word & bit) && std::abs(v) < background) {
                    anyActive = true;
                    allOutside = false;
                    continue;
                }
                word &= ~bit;
                v = inside ? -background : background;
                allOutside = allOutside && !inside;
            }
            // A block wholly outside the band and the solid is the background: no leaf.
            if (anyActive || !allOutside) kept.push_back(leaf);
        }
        f.leaves = std::move(kept);
        for (int a = 0; a < 3; ++a) {
            ls.dims[a] = count[a];
            ls.indexOffset[a] = first[a];
        }
    }
    ls.leaves = reinterpret_cast<const detail::VdbLevelSetLeaf*>(f.leaves.data());
    ls.leafCount = f.leaves.size();
    ls.insideRuns = reinterpret_cast<const detail::VdbInsideRun*>(f.insideRuns.data());
    ls.insideRunCount = f.insideRuns.size();
    std::string error;
    void* g = lsd::module().levelSetBuild(ls, detail::VdbPlacement{}, lattice.handle(), name.c_str(),
                                          lsd::levelSetParallelFor, &error);
    lsd::check(g != nullptr, error, "cannot make the level set of a mesh");
    return LevelSet::adopt(g);
}

LevelSet evaluateLevelSetCsg(const CsgNode& node, const std::function<LevelSet(const std::string&)>& leaf,
                             int* resampledLeaves) {
    if (node.isMesh) return leaf(node.mesh);
    if (node.args.empty()) fail("CSG: operation '", toString(node.op), "' without arguments");
    LevelSet acc = evaluateLevelSetCsg(node.args[0], leaf, resampledLeaves);
    for (size_t i = 1; i < node.args.size(); ++i) {
        const LevelSet b = evaluateLevelSetCsg(node.args[i], leaf, resampledLeaves);
        bool resampled = false;
        acc = levelSetCsg(acc, b, node.op, &resampled);
        if (resampled && resampledLeaves) ++*resampledLeaves;
    }
    return acc;
}

LevelSet offsetLevelSet(const LevelSet& levelSet, double distance) {
    if (!std::isfinite(distance)) fail("level-set offset: the distance is not finite");
    const Vec3d vs = levelSet.voxelSize();
    if (!(vs.x == vs.y && vs.y == vs.z))
        fail("level-set offset: OpenVDB's level-set filter needs cubic voxels, the grid's are ", vs.x, " x ",
             vs.y, " x ", vs.z);
    LevelSet out = levelSet;
    if (distance == 0) return out;
    std::string error;
    lsd::check(lsd::module().levelSetOffset(out.handle(), distance, &error), error, "level-set offset");
    return out;
}

SignedDistanceField offsetSignedDistanceField(const MeshView& mesh, const Frame& frame, double distance,
                                              const SdfOptions& options) {
    if (!std::isfinite(distance)) fail("SDF offset: the distance is not finite");
    if (options.full) {
        SignedDistanceField f = signedDistanceField(mesh, frame, options);
        if (distance == 0) return f;
        for (SdfLeaf& leaf : f.leaves)
            for (float& v : leaf.values) v = float(double(v) - distance);
        f.background += std::abs(distance);
        return f;
    }
    if (!(options.bandVoxels >= 1) || !std::isfinite(options.bandVoxels))
        fail("SDF: the band must be at least 1 voxel, got ", options.bandVoxels);
    const Vec3d cell = frame.cellSize();
    const double edge = std::max({cell.x, cell.y, cell.z});
    // Every voxel within the band of the new surface is within band + |distance| of the old one.
    SdfOptions wide = options;
    wide.bandVoxels = options.bandVoxels + std::abs(distance) / edge;
    SignedDistanceField f = signedDistanceField(mesh, frame, wide);
    const double w = options.bandVoxels * edge;
    const float wf = float(w);
    std::vector<SdfLeaf> kept;
    kept.reserve(f.leaves.size());
    for (SdfLeaf& leaf : f.leaves) {
        bool anyActive = false, allOutside = true;
        for (int n = 0; n < 512; ++n) {
            const double v = double(leaf.values[n]) - distance;
            uint64_t& word = leaf.active[n >> 6];
            const uint64_t bit = uint64_t(1) << (n & 63);
            // Inactive voxels (beyond the wide band) keep their side: |v| >= w there.
            if ((word & bit) && std::abs(v) < w) {
                leaf.values[n] = float(v);
                anyActive = true;
                allOutside = false;
            } else {
                word &= ~bit;
                leaf.values[n] = v < 0 ? -wf : wf;
                allOutside = allOutside && v >= 0;
            }
        }
        // A block wholly outside the new band is the background: no leaf.
        if (anyActive || !allOutside) kept.push_back(leaf);
    }
    f.leaves = std::move(kept);
    f.background = w;
    f.bandVoxels = options.bandVoxels;
    return f;
}

} // namespace voxfx
