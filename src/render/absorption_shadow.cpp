// voxfx — per-voxel absorption shadows (CHANG §3, "Real-time Realistic Voxel-based Rendering").
//
// An attribute voxelization from the light stores, per voxel, the absorption of every write
// (material optical depth per crossing; dense foliage writes a voxel several times and so absorbs
// more). The occlusion at p is the sum of the absorption of the occupied voxels between the light
// and p (CHANG §3 step 4); the light is attenuated by exp(-sum). Columns are reduced to exclusive
// prefix sums once, so a lookup is one read.
#include "voxfx/absorption_shadow.hpp"

#include <algorithm>
#include <cmath>

#include "render/light_grid_lookup.hpp"
#include "render/shadow_casters.hpp"
#include "voxfx/text.hpp"

namespace voxfx {

AbsorptionShadowMap AbsorptionShadowMap::build(const LightView& view, const MeshView& casters,
                                               std::span<const float> triangleAbsorption, Coverage coverage,
                                               Slicing slicing, Progress* progress) {
    AbsorptionShadowMap map;
    map.view_ = view;
    AttributeOptions ao;
    ao.coverage = coverage;
    ao.channels = AttributeChannels::shadows();
    ao.slicing = slicing;
    ao.progress = progress;
    // The sparse form of the attribute voxelization: light grids through foliage are mostly empty.
    AttributeColumns grid = voxelizeAttributeColumns(casters, view.frame, triangleAbsorption, ao);
    map.frame_ = grid.frame;
    for (const uint16_t n : grid.count) map.writes_ += n;
    map.offsets_ = std::move(grid.offsets);
    map.slice_ = std::move(grid.slice);
    // Inclusive prefix sums along each column, in place; double accumulation.
    map.prefix_ = std::move(grid.absorption);
    parallelFor(0, map.frame_.columnCount(), 4096, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            double sum = 0;
            for (int64_t i = map.offsets_[size_t(c)]; i < map.offsets_[size_t(c) + 1]; ++i) {
                sum += double(map.prefix_[size_t(i)]);
                map.prefix_[size_t(i)] = float(sum);
            }
        }
    });
    return map;
}

float AbsorptionShadowMap::columnDepth(int64_t column, double depth, int64_t skipCells) const {
    const int64_t end = detail::slicesInFront(frame_, column, depth, skipCells);
    // Written voxels of the column with slice < end (few per column: a linear scan).
    const int64_t b = offsets_[size_t(column)], e = offsets_[size_t(column) + 1];
    int64_t i = b;
    while (i < e && int64_t(slice_[size_t(i)]) < end) ++i;
    return i == b ? 0.0f : prefix_[size_t(i - 1)];
}

float AbsorptionShadowMap::opticalDepth(const Vec3d& world, int64_t skipCells) const {
    if (offsets_.empty() || !view_.covers(world)) return 0.0f;
    const detail::ColumnAt c = detail::nearestColumn(view_, world);
    return columnDepth(c.column, c.depth, skipCells);
}

float AbsorptionShadowMap::transmittance(const Vec3d& world, int64_t skipCells) const {
    return std::exp(-opticalDepth(world, skipCells));
}

float AbsorptionShadowMap::transmittanceBilinear(const Vec3d& world, int64_t skipCells) const {
    if (offsets_.empty() || !view_.covers(world)) return 1.0f;
    return float(detail::bilinearColumns<double, double>(view_, world, 1.0, [&](const detail::ColumnAt& c) {
        return std::exp(-double(columnDepth(c.column, c.depth, skipCells)));
    }));
}

std::span<const OptionField<AbsorptionShadowOptions>> AbsorptionShadowOptions::fields() {
    using O = AbsorptionShadowOptions;
    static const std::vector<OptionField<O>> table = [] {
        std::vector<OptionField<O>> t;
        detail::appendLightGridFields(t);
        t.push_back(numberOption<O, &O::grid, &LightGridOptions::normalOffset>(
            "normalOffset", "lookup offset along the surface normal, in column footprints", 0, 1000));
        t.push_back(nameOption<O, parseCoverage, optionName<Coverage>, &O::coverage>(
            "coverage", "CHANG's writes: one voxel per column (center) or every voxel a triangle touches",
            "center | conservative"));
        t.push_back(numberOption<O, &O::opaqueAbsorption>(
            "opaqueAbsorption", "optical depth of one crossing of an opaque material", 0, 1000));
        return t;
    }();
    return table;
}

float absorptionPerCrossing(const Material& m, float opaqueAbsorption) {
    if (m.isOpaque()) return opaqueAbsorption;
    const Vec3f t = m.shadowCrossingTransmittance();
    const float luminance = 0.2126f * t.x + 0.7152f * t.y + 0.0722f * t.z;
    return std::min(opaqueAbsorption, -std::log(std::max(luminance, 1e-30f)));
}

AbsorptionShadow::Stats& AbsorptionShadow::Stats::operator+=(const Stats& o) {
    grids += o.grids;
    writes += o.writes;
    return *this;
}

std::string AbsorptionShadow::Stats::summary() const {
    return countText(grids) + (grids == 1 ? " light grid, " : " light grids, ") + countText(writes) +
           " attribute writes";
}

AbsorptionShadow AbsorptionShadow::build(const Scene& scene, const Light& light,
                                         const AbsorptionShadowOptions& options, Progress* progress) {
    detail::checkLightGrid(options.grid, "absorption");
    AbsorptionShadow out;
    out.options_ = options;
    const detail::CasterSets casters = detail::collectCasters(scene);
    if (casters.all.indices.empty()) return out;
    std::vector<float> perTriangle(casters.allMaterialIndex.size());
    std::vector<float> perMaterial(scene.materials.size());
    for (std::size_t i = 0; i < scene.materials.size(); ++i)
        perMaterial[i] = absorptionPerCrossing(scene.materials[i], options.opaqueAbsorption);
    for (std::size_t i = 0; i < perTriangle.size(); ++i)
        perTriangle[i] = perMaterial[casters.allMaterialIndex[i]];
    out.views_ =
        makeLightViews(light, computeBounds(casters.all.view()), options.grid.resolution, options.grid.depth);
    for (const LightView& v : out.views_)
        out.maps_.push_back(AbsorptionShadowMap::build(v, casters.all.view(), perTriangle, options.coverage,
                                                       options.grid.slicing, progress));
    return out;
}

float AbsorptionShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    Vec3d q;
    const int i = detail::lookupView(views_, p, n, options_.grid.normalOffset, q);
    if (i < 0) return 1.0f;
    const AbsorptionShadowMap& m = maps_[size_t(i)];
    const int64_t skip = options_.grid.skipCells;
    return options_.grid.bilinear ? m.transmittanceBilinear(q, skip) : m.transmittance(q, skip);
}

AbsorptionShadow::Stats AbsorptionShadow::stats() const {
    Stats s;
    for (const AbsorptionShadowMap& m : maps_) {
        ++s.grids;
        s.writes += m.writeCount();
    }
    return s;
}

} // namespace voxfx
