// voxfx — per-voxel absorption shadows (CHANG §3, "Real-time Realistic Voxel-based Rendering").
//
// An attribute voxelization from the light stores, per voxel, the absorption of every write
// (material optical depth per crossing; dense foliage writes a voxel several times and so absorbs
// more). The occlusion at p is the sum of the absorption of the occupied voxels between the light
// and p (CHANG §3 step 4); the light is attenuated by exp(-sum), per channel (coloured materials
// in grids of their own), and through glass by Beer–Lambert over the chord between paired writes.
// Columns are reduced to prefix sums once, so a lookup is a short scan per grid.
#include "voxfx/absorption_shadow.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "render/glass_crossing_fresnel.hpp"
#include "render/light_grid_lookup.hpp"
#include "render/shadow_casters.hpp"
#include "voxfx/glass_optics.hpp"
#include "voxfx/text.hpp"

namespace voxfx {

namespace {

Vec3f absorptionExp(const Vec3f& depth) {
    // One exp for a grey depth (every opaque-only or grey scene).
    if (depth.x == depth.y && depth.y == depth.z) {
        const auto v = float(std::exp(-double(depth.x)));
        return {v, v, v};
    }
    return beerLambert(depth, 1.0);
}

} // namespace

AbsorptionShadowMap AbsorptionShadowMap::build(const LightView& view, const MeshView& casters,
                                               std::span<const float> triangleAbsorption, Coverage coverage,
                                               Slicing slicing, Progress* progress) {
    const Group grey{casters, triangleAbsorption};
    return build(view, std::span<const Group>(&grey, 1), coverage, slicing, progress);
}

AbsorptionShadowMap AbsorptionShadowMap::build(const LightView& view, std::span<const Group> groups,
                                               Coverage coverage, Slicing slicing, Progress* progress) {
    AbsorptionShadowMap map;
    map.view_ = view;
    AttributeOptions ao;
    ao.coverage = coverage;
    ao.channels = AttributeChannels::shadows();
    ao.slicing = slicing;
    ao.progress = progress;
    for (const Group& group : groups) {
        // The sparse form of the attribute voxelization: light grids through foliage are mostly empty.
        AttributeColumns columns =
            voxelizeAttributeColumns(group.mesh, view.frame, group.triangleAbsorption, ao);
        Grid& g = map.grids_.emplace_back();
        g.frame = columns.frame;
        g.depthPerUnit = group.depthPerUnit;
        g.attenuation = group.attenuation;
        for (const uint16_t n : columns.count) map.writes_ += n;
        g.offsets = std::move(columns.offsets);
        g.slice = std::move(columns.slice);
        // Inclusive prefix sums along each column, in place; double accumulation.
        g.prefix = std::move(columns.absorption);
        const bool glass = g.attenuation.x > 0 || g.attenuation.y > 0 || g.attenuation.z > 0;
        if (glass) {
            g.chord.resize(g.slice.size());
            g.open.resize(g.slice.size());
        }
        parallelFor(0, g.frame.columnCount(), 4096, [&](int64_t c0, int64_t c1) {
            for (int64_t c = c0; c < c1; ++c) {
                double sum = 0, chord = 0, open = -1;
                const int64_t b = g.offsets[size_t(c)], e = g.offsets[size_t(c) + 1];
                int64_t runStart = b;
                for (int64_t i = b; i < e; ++i) {
                    sum += double(g.prefix[size_t(i)]);
                    g.prefix[size_t(i)] = float(sum);
                    if (!glass) continue;
                    // Glass: an odd count of writes in a voxel enters or leaves (an even one, a
                    // passage within the voxel or none, leaves the state as it was). Conservative
                    // writes: a run of consecutive voxels is one crossing, at its centre.
                    bool crosses = columns.count[size_t(i)] % 2 == 1;
                    double at = double(g.slice[size_t(i)]) + 0.5;
                    if (coverage == Coverage::Conservative) {
                        if (i > b && g.slice[size_t(i)] != g.slice[size_t(i - 1)] + 1) runStart = i;
                        crosses = i + 1 == e || g.slice[size_t(i + 1)] != g.slice[size_t(i)] + 1;
                        at = 0.5 * double(g.slice[size_t(runStart)] + g.slice[size_t(i)] + 1);
                    }
                    if (crosses) {
                        if (open < 0) {
                            open = at;
                        } else {
                            chord += at - open;
                            open = -1;
                        }
                    }
                    g.chord[size_t(i)] = float(chord);
                    g.open[size_t(i)] = float(open);
                }
            }
        });
    }
    const int64_t columns = view.frame.columnCount();
    map.occupied_.assign(size_t((columns + 63) / 64), 0);
    for (const Grid& g : map.grids_)
        for (int64_t c = 0; c < columns; ++c)
            if (g.offsets[size_t(c)] != g.offsets[size_t(c) + 1])
                map.occupied_[size_t(c >> 6)] |= uint64_t(1) << (c & 63);
    map.buildEntryLight();
    return map;
}

void AbsorptionShadowMap::buildEntryLight() {
    if (grids_.empty()) return;
    for (const Grid& g : grids_)
        if (!g.chord.empty() || !g.frame.sameGrid(grids_[0].frame)) return;
    const int64_t columns = grids_[0].frame.columnCount();
    const std::size_t G = grids_.size();
    // Column c's entries merged in slice order: at each distinct slice, every grid's entries up to
    // it taken, then emit(slice, grid i's last entry taken + 1 or its column's start: i == b, none).
    const auto merge = [&](int64_t c, std::vector<int64_t>& at, const auto& emit) {
        for (std::size_t k = 0; k < G; ++k) at[k] = grids_[k].offsets[size_t(c)];
        for (;;) {
            uint32_t s = UINT32_MAX;
            for (std::size_t k = 0; k < G; ++k)
                if (at[k] < grids_[k].offsets[size_t(c) + 1]) s = std::min(s, grids_[k].slice[size_t(at[k])]);
            if (s == UINT32_MAX) return;
            for (std::size_t k = 0; k < G; ++k)
                while (at[k] < grids_[k].offsets[size_t(c) + 1] && grids_[k].slice[size_t(at[k])] <= s)
                    ++at[k];
            emit(s);
        }
    };
    entryOffsets_.assign(size_t(columns) + 1, 0);
    parallelFor(0, columns, 4096, [&](int64_t c0, int64_t c1) {
        std::vector<int64_t> at(G);
        for (int64_t c = c0; c < c1; ++c) merge(c, at, [&](uint32_t) { ++entryOffsets_[size_t(c) + 1]; });
    });
    for (int64_t c = 0; c < columns; ++c) entryOffsets_[size_t(c) + 1] += entryOffsets_[size_t(c)];
    entrySlice_.resize(size_t(entryOffsets_.back()));
    entryLight_.resize(entrySlice_.size());
    parallelFor(0, columns, 4096, [&](int64_t c0, int64_t c1) {
        std::vector<int64_t> at(G);
        for (int64_t c = c0; c < c1; ++c) {
            auto i = size_t(entryOffsets_[size_t(c)]);
            merge(c, at, [&](uint32_t s) {
                // As columnDepth: the grids in order, each its prefix up to p (0 for none) times
                // its depth per unit (the chord term is +0 without glass).
                Vec3f depth{0, 0, 0};
                for (std::size_t k = 0; k < G; ++k) {
                    const Grid& g = grids_[k];
                    const float sum = at[k] == g.offsets[size_t(c)] ? 0.0f : g.prefix[size_t(at[k] - 1)];
                    depth += g.depthPerUnit * sum;
                }
                entrySlice_[i] = s;
                entryLight_[i++] = absorptionExp(depth);
            });
        }
    });
}

float AbsorptionShadowMap::columnSum(const Grid& g, int64_t column, double depth, int64_t skipCells,
                                     double& chord) const {
    chord = 0;
    const int64_t end = detail::slicesInFront(g.frame, column, depth, skipCells);
    // Written voxels of the column with slice < end (few per column: a linear scan).
    const int64_t b = g.offsets[size_t(column)], e = g.offsets[size_t(column) + 1];
    int64_t i = b;
    while (i < e && int64_t(g.slice[size_t(i)]) < end) ++i;
    if (i == b) return 0.0f;
    if (!g.chord.empty()) {
        const size_t last = size_t(i - 1);
        chord = double(g.chord[last]);
        // Inside an open passage: up to p, when the whole column pairs up (an odd one lost a
        // crossing to a glass thinner than a voxel: no chord then).
        if (g.open[last] >= 0 && g.open[size_t(e - 1)] < 0) {
            const double t = g.frame.depthToSlice(column)(depth);
            chord += std::clamp(t, double(g.open[last]), double(g.frame.depth())) - double(g.open[last]);
        }
        chord /= g.frame.depthToSlice(column).scale;
    }
    return g.prefix[size_t(i - 1)];
}

Vec3f AbsorptionShadowMap::columnDepth(int64_t column, double depth, int64_t skipCells,
                                       double lengthPerDepth) const {
    Vec3f out{0, 0, 0};
    for (const Grid& g : grids_) {
        double chord = 0;
        const float sum = columnSum(g, column, depth, skipCells, chord);
        out += g.depthPerUnit * sum + g.attenuation * float(chord * lengthPerDepth);
    }
    return out;
}

Vec3f AbsorptionShadowMap::columnLight(int64_t column, double depth, int64_t skipCells,
                                       double lengthPerDepth) const {
    if (entryLight_.empty()) return absorptionExp(columnDepth(column, depth, skipCells, lengthPerDepth));
    const int64_t end = detail::slicesInFront(grids_[0].frame, column, depth, skipCells);
    const int64_t b = entryOffsets_[size_t(column)], e = entryOffsets_[size_t(column) + 1];
    int64_t i = b;
    while (i < e && int64_t(entrySlice_[size_t(i)]) < end) ++i;
    return i == b ? Vec3f{1, 1, 1} : entryLight_[size_t(i - 1)];
}

Vec3f AbsorptionShadowMap::opticalDepth(const Vec3d& world, int64_t skipCells) const {
    if (grids_.empty() || !view_.covers(world)) return {0, 0, 0};
    const detail::ColumnAt c = detail::nearestColumn(view_, world);
    return columnDepth(c.column, c.depth, skipCells, detail::worldLengthPerDepth(view_, world));
}

Vec3f AbsorptionShadowMap::transmittance(const Vec3d& world, int64_t skipCells) const {
    return absorptionExp(opticalDepth(world, skipCells));
}

Vec3f AbsorptionShadowMap::transmittanceBilinear(const Vec3d& world, int64_t skipCells, const Vec3d& normal,
                                                 double sharpness) const {
    Vec3d grid;
    if (grids_.empty() || !view_.locate(world, grid)) return {1, 1, 1};
    if (!entryLight_.empty() && detail::orientedBilinearApplies(view_, grids_[0].frame, sharpness))
        return detail::orientedBilinearColumns(
            view_, grids_[0].frame, grid, normal, skipCells, occupied_.data(),
            [&](int64_t column, int64_t end) {
                // columnLight from the entries, at the slices in front given.
                const int64_t b = entryOffsets_[size_t(column)], e = entryOffsets_[size_t(column) + 1];
                int64_t i = b;
                while (i < e && int64_t(entrySlice_[size_t(i)]) < end) ++i;
                return i == b ? Vec3f{1, 1, 1} : entryLight_[size_t(i - 1)];
            });
    // Only glass needs the length per depth unit (grids without glass: none).
    const double lengthPerDepth = entryLight_.empty() ? detail::worldLengthPerDepth(view_, world) : 0.0;
    return detail::bilinearColumnsAt<Vec3f, float>(
        view_, grid, normal,
        [&](int64_t column, const auto& depth) {
            // A column no grid writes: exp(-0), without the receiver plane's depth.
            if (((occupied_[size_t(column >> 6)] >> (column & 63)) & 1u) == 0) return Vec3f{1, 1, 1};
            return columnLight(column, depth(), skipCells, lengthPerDepth);
        },
        sharpness);
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

Vec3f absorptionPerCrossing(const Material& m, float opaqueAbsorption) {
    if (m.isOpaque()) return {opaqueAbsorption, opaqueAbsorption, opaqueAbsorption};
    // Glass: half the tint per crossing; its Fresnel depends on the crossing's angle
    // (render/glass_crossing_fresnel.hpp, per column of the light grid).
    Vec3f t = m.shadowCrossingTransmittance();
    if (m.isGlass())
        for (int c = 0; c < 3; ++c) t[c] = float(std::sqrt(double(m.crossingTransmittance()[c])));
    Vec3f out;
    for (int c = 0; c < 3; ++c) out[c] = std::min(opaqueAbsorption, -std::log(std::max(t[c], 1e-30f)));
    return out;
}

AbsorptionShadowStats& AbsorptionShadowStats::operator+=(const AbsorptionShadowStats& o) {
    grids += o.grids;
    writes += o.writes;
    return *this;
}

std::string AbsorptionShadowStats::summary() const {
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
    // Grey materials (no glass attenuation) in one grid with their scalar depth per write; each
    // other (depth, attenuation) its own grid with a write count.
    using Key = std::array<float, 6>;
    std::map<Key, uint32_t> groupOf;
    std::vector<uint32_t> materialGroup(scene.materials.size());
    std::vector<float> materialScalar(scene.materials.size());
    std::vector<Key> keys{Key{1, 1, 1, 0, 0, 0}};
    for (std::size_t i = 0; i < scene.materials.size(); ++i) {
        const Vec3f d = absorptionPerCrossing(scene.materials[i], options.opaqueAbsorption);
        const Vec3f a = scene.materials[i].shadowAttenuationCoefficient();
        const bool grey = d.x == d.y && d.y == d.z && a == Vec3f{0, 0, 0};
        materialScalar[i] = grey ? d.x : 1.0f;
        if (grey) continue;
        const Key k{d.x, d.y, d.z, a.x, a.y, a.z};
        const auto [it, added] = groupOf.emplace(k, uint32_t(keys.size()));
        if (added) keys.push_back(k);
        materialGroup[i] = it->second;
    }
    // The casters of each group, with their per-write scalars (all of them when every material is
    // grey: no copy).
    const bool oneGroup = keys.size() == 1;
    std::vector<Mesh> meshes(oneGroup ? 0 : keys.size());
    std::vector<std::vector<float>> scalars(keys.size());
    const Mesh& all = casters.all;
    for (std::size_t t = 0; t < casters.allMaterialIndex.size(); ++t) {
        const uint32_t m = casters.allMaterialIndex[t], g = materialGroup[m];
        scalars[g].push_back(materialScalar[m]);
        if (!oneGroup) {
            Mesh& mesh = meshes[g];
            for (int k = 0; k < 3; ++k) {
                mesh.indices.push_back(uint32_t(mesh.positions.size()));
                mesh.positions.push_back(all.positions[all.indices[3 * t + size_t(k)]]);
            }
        }
    }
    std::vector<AbsorptionShadowMap::Group> groups;
    for (std::size_t g = 0; g < keys.size(); ++g)
        if (!scalars[g].empty())
            groups.push_back({oneGroup ? all.view() : meshes[g].view(), scalars[g],
                              Vec3f{keys[g][0], keys[g][1], keys[g][2]},
                              Vec3f{keys[g][3], keys[g][4], keys[g][5]}});
    out.views_ =
        makeLightViews(light, computeBounds(casters.all.view()), options.grid.resolution, options.grid.depth);
    for (const LightView& v : out.views_)
        out.maps_.push_back(
            AbsorptionShadowMap::build(v, groups, options.coverage, options.grid.slicing, progress));
    // Each glass crossing's whole Fresnel, at its angle, per column.
    out.fresnel_ = detail::buildGlassFresnelViews(scene, out.views_, false);
    return out;
}

Vec3f AbsorptionShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    Vec3d q;
    const int i = detail::lookupView(views_, p, n, options_.grid.normalOffset, q);
    if (i < 0) return {1, 1, 1};
    const AbsorptionShadowMap& m = maps_[size_t(i)];
    const int64_t skip = options_.grid.skipCells;
    const Vec3f v = options_.grid.bilinear ? m.transmittanceBilinear(q, skip, n, options_.grid.sharpness)
                                           : m.transmittance(q, skip);
    return v * float(detail::glassFresnelPass(fresnel_, views_, i, q, n, options_.grid));
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
