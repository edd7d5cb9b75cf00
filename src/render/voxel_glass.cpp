// voxfx — the voxel glass methods: the march through an attribute grid (CHANG §4.1.1 multiple
// refraction; Wyman's two-surface refraction as its baseline), voxfx/voxel_glass.hpp.
#include "voxfx/voxel_glass.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfx/error.hpp"
#include "voxfx/glass.hpp"

namespace voxfx {

namespace {

template <class O> std::vector<OptionField<O>> voxelGlassFields() {
    return {
        numberOption<O, &O::gridResolution>(
            "glassGrid",
            "glass voxels along the glass's longest side, 2..4096; 0: auto, about one voxel per 1.5 "
            "pixels of the largest glass object on screen (the summary line says which)",
            0, 4096),
        nameOption<O, parseCoverage, optionName<Coverage>, &O::coverage>(
            "glassCoverage",
            "glass voxels: every voxel a triangle touches (CHANG's widened slabs at their limit: no "
            "holes on steep faces), or one per column (thinner boundary, holes where faces are steep)",
            "conservative | center"),
        numberOption<O, &O::angleThreshold>(
            "angleThreshold",
            "glass (CHANG's angle threshold, radians): a boundary voxel of the last surface's material "
            "whose normal is this close to that surface's is the same surface, not a new event (0: "
            "only the media stack guards against refracting twice at one surface)",
            0, 3.2),
        numberOption<O, &O::slabOverlap>(
            "slabOverlap",
            "glass voxels: CHANG's widened slabs, each slab grown by this many slices on both sides "
            "(more voxels written, fewer holes where faces are steep under center coverage)",
            0, 4),
        numberOption<O, &O::maxEvents>("maxEvents",
                                       "glass: refractions and reflections followed per ray (then it leaves "
                                       "along its current direction)",
                                       1, 1024),
        numberOption<O, &O::absorptionConstant>(
            "absorptionConstant",
            "glass (CHANG's absorption constant): every glass material's attenuation per world unit "
            "(KHR_materials_volume) times this (0: no absorption inside glass)",
            0, 1e6),
        flagOption<O, &O::sceneBehind>(
            "sceneBehind", "glass: the light leaving it comes from the opaque scene, traced exactly "
                           "(off: the environment alone after the last exit, as CHANG)")};
}

} // namespace

std::span<const OptionField<MultiGlassOptions>> MultiGlassOptions::fields() {
    static const std::vector<OptionField<MultiGlassOptions>> table = voxelGlassFields<MultiGlassOptions>();
    return table;
}

std::span<const OptionField<TwoSurfaceGlassOptions>> TwoSurfaceGlassOptions::fields() {
    static const std::vector<OptionField<TwoSurfaceGlassOptions>> table =
        voxelGlassFields<TwoSurfaceGlassOptions>();
    return table;
}

template <class O, bool kTwoSurface>
VoxelGlassMethod<O, kTwoSurface> VoxelGlassMethod<O, kTwoSurface>::build(const GlassInput& input,
                                                                         const O& options) {
    return VoxelGlassMethod(
        VoxelGlass(input.mesh, input.triangleMedium, input.media, options, input.vertexNormals), options);
}

template class VoxelGlassMethod<MultiGlassOptions, false>;
template class VoxelGlassMethod<TwoSurfaceGlassOptions, true>;

VoxelGlass::VoxelGlass(const MeshView& mesh, std::vector<uint32_t> triangleMedium,
                       std::vector<GlassMedium> media, const VoxelGlassOptions& options,
                       std::span<const Vec3f> vertexNormals)
    : media_(std::move(media)) {
    validateMesh(mesh, "glass mesh");
    if (triangleMedium.size() != mesh.triangleCount) fail("voxel glass: one medium per triangle expected");
    for (const uint32_t m : triangleMedium)
        if (m >= media_.size()) fail("voxel glass: medium index ", m, " out of range");
    if ((options.gridResolution < 2 && options.gridResolution != kGlassGridAuto) ||
        options.gridResolution > 4096)
        fail("glass grid resolution must be between 2 and 4096 (or 0: auto), got ", options.gridResolution);
    const Box3d box = computeBounds(mesh);
    if (box.empty()) fail("voxel glass: no triangles");
    // Auto outside render() (no camera to size it from): the fixed default.
    const int64_t n =
        options.gridResolution == kGlassGridAuto ? kGlassGridResolution : options.gridResolution;
    const double longest = std::max({box.extent().x, box.extent().y, box.extent().z, 1e-12});
    // One voxel of margin on each side: n - 2 voxels span the longest side.
    voxel_ = longest / double(n - 2);
    int64_t dims[3];
    Box3d grid;
    for (int a = 0; a < 3; ++a) {
        dims[a] = std::min<int64_t>(n, int64_t(std::ceil(box.extent()[a] / voxel_)) + 2);
        const double centre = 0.5 * (box.lo[a] + box.hi[a]);
        grid.lo[a] = centre - 0.5 * double(dims[a]) * voxel_;
        grid.hi[a] = centre + 0.5 * double(dims[a]) * voxel_;
    }
    origin_ = grid.lo;
    AttributeOptions ao;
    ao.coverage = options.coverage;
    ao.slabOverlap = options.slabOverlap;
    // Normals and material id, and the write count, which tells a voxel holding both faces of a sheet
    // thinner than itself (its normals cancel) from one surface: 18 bytes per voxel.
    ao.channels = AttributeChannels::glass();
    ao.channels.count = true;
    ao.triangleMaterial = triangleMedium;
    ao.vertexNormals = vertexNormals;
    const Frame frame = Frame::orthographic(grid, Axis::Z, dims[0], dims[1], dims[2]);
    grid_ = voxelizeAttributes(mesh, frame, {}, ao);
    // Where two materials wrote a voxel: its material is that of the lowest-indexed triangle written
    // into it, so the same voxelization with the triangles in reverse order gives the highest one's.
    if (std::adjacent_find(triangleMedium.begin(), triangleMedium.end(), std::not_equal_to<>()) !=
        triangleMedium.end()) {
        std::vector<uint32_t> reversed(mesh.triangleCount * 3);
        std::vector<uint32_t> reversedMedium(mesh.triangleCount);
        for (std::size_t t = 0; t < mesh.triangleCount; ++t) {
            const std::size_t from = mesh.triangleCount - 1 - t;
            for (int c = 0; c < 3; ++c)
                reversed[3 * t + std::size_t(c)] = mesh.indices[3 * from + std::size_t(c)];
            reversedMedium[t] = triangleMedium[from];
        }
        MeshView back = mesh;
        back.indices = reversed.data();
        AttributeOptions last = ao;
        last.channels = {false, false, false, true, false, false}; // material id only
        last.triangleMaterial = reversedMedium;
        const AttributeGrid lastWriter = voxelizeAttributes(back, frame, {}, last);
        twoMaterials_.resize(grid_.material.size());
        for (std::size_t i = 0; i < twoMaterials_.size(); ++i)
            twoMaterials_[i] = grid_.material[i] != lastWriter.material[i];
        // The face between two touching media (CHANG §4.2): its voxels hold both media's faces, whose
        // normals cancel (where they do not, the voxel is no such face: an object inside another
        // touching its boundary, the edge where the face meets the outside). Which way the face
        // points is told by the triangles of one of the two media alone: for the lowest bit in which
        // the two ids differ, a normals-only voxelization of the triangles of the one whose id has
        // that bit set (one pass per bit that is needed: a few for any number of media).
        // side[k]: per medium, whether the pass for bit k voxelizes its triangles (only those of
        // media on a face whose lowest differing bit is k: the pass costs what those faces do).
        std::vector<std::vector<uint8_t>> side(32);
        for (std::size_t i = 0; i < twoMaterials_.size(); ++i) {
            if (!twoMaterials_[i]) continue;
            const uint32_t lo = grid_.material[i], hi = lastWriter.material[i];
            const bool between = length(Vec3d(grid_.normalSum[i])) < 0.5 * double(grid_.count[i]);
            interfaces_.push_back({int64_t(i), lo, hi, between, {0, 0, 0}});
            if (!between) continue;
            const int k = std::countr_zero(lo ^ hi);
            side[size_t(k)].resize(media_.size(), 0);
            side[size_t(k)][((lo >> k) & 1) ? lo : hi] = 1;
        }
        for (int k = 0; k < 32; ++k) {
            if (side[size_t(k)].empty()) continue;
            std::vector<uint32_t> part;
            for (std::size_t t = 0; t < mesh.triangleCount; ++t)
                if (side[size_t(k)][triangleMedium[t]])
                    for (int c = 0; c < 3; ++c) part.push_back(mesh.indices[3 * t + std::size_t(c)]);
            MeshView ofOne = mesh;
            ofOne.indices = part.data();
            ofOne.triangleCount = part.size() / 3;
            AttributeOptions normalsOnly = ao;
            normalsOnly.channels = {false, false, true, false, false, false};
            normalsOnly.triangleMaterial = {};
            const AttributeGrid sideGrid = voxelizeAttributes(ofOne, frame, {}, normalsOnly);
            for (Interface& f : interfaces_) {
                if (!f.between || std::countr_zero(f.lo ^ f.hi) != k) continue;
                const Vec3d nLo =
                    Vec3d(sideGrid.normalSum[size_t(f.voxel)]) * (((f.lo >> k) & 1) ? 1.0 : -1.0);
                const double len = length(nLo);
                if (len > 1e-6) f.normalLo = Vec3f(nLo / len);
            }
        }
    }
}

const VoxelGlass::Interface* VoxelGlass::interfaceAt(int64_t voxel) const {
    const auto it = std::lower_bound(interfaces_.begin(), interfaces_.end(), voxel,
                                     [](const Interface& f, int64_t v) { return f.voxel < v; });
    return it != interfaces_.end() && it->voxel == voxel ? &*it : nullptr;
}

} // namespace voxfx
