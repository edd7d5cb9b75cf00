// voxfx — transmittance shadow maps (ED06 §3.1, "Fast Scene Voxelization and Applications").
//
// The partial occluders are voxelized from the light into slicemaps, one per channel (a group of
// equal crossing transmittance, e.g. leaves of one colour). At a point p the light has crossed
// n = popcount(column bits in front of p) filled cells, and is attenuated by t^n per channel;
// through glass also by Beer–Lambert over the chord between paired crossings (entering, leaving),
// and by each crossing's Fresnel at its angle (render/glass_crossing_fresnel.hpp).
// The lookup skips the cell holding p (its own surface; see light_grid.hpp's bias note). Opaque
// casters go to a standard shadow map (shadow_map.hpp). Where the channels share one frame and
// none is glass, the counts are read from one sparse index of every channel's column (the slices
// where a count steps, each with every channel's count): the same n, from one short run of entries
// (in sparse foliage a small fraction of the bit columns' size), and none at all for an empty column.
#include "voxfx/transmittance_shadow.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "render/glass_crossing_fresnel.hpp"
#include "render/light_grid_lookup.hpp"
#include "render/shadow_casters.hpp"
#include "voxfx/grid_query.hpp"
#include "voxfx/parallel.hpp"
#include "voxfx/text.hpp"

namespace voxfx {

TransmittanceShadowMap TransmittanceShadowMap::build(const LightView& view, std::span<const MeshView> groups,
                                                     std::span<const Vec3f> transmittances, VoxelizeMode mode,
                                                     Slicing slicing, Progress* progress, Device device,
                                                     std::span<const Vec3f> attenuations) {
    if (groups.size() != transmittances.size())
        fail("transmittance shadow map: ", groups.size(), " groups but ", transmittances.size(),
             " transmittances");
    if (!attenuations.empty() && attenuations.size() != groups.size())
        fail("transmittance shadow map: ", groups.size(), " groups but ", attenuations.size(),
             " attenuations");
    if (mode != VoxelizeMode::Surface && mode != VoxelizeMode::Conservative)
        fail("transmittance shadow map: voxelization mode must be surface or conservative, got ",
             toString(mode));
    TransmittanceShadowMap map;
    map.view_ = view;
    map.mode_ = mode;
    for (std::size_t k = 0; k < groups.size(); ++k) {
        VoxelizeOptions vo;
        vo.mode = mode;
        vo.slicing = slicing;
        vo.progress = progress;
        vo.device = device;
        map.channels_.push_back({voxelize(groups[k], view.frame, vo), transmittances[k],
                                 attenuations.empty() ? Vec3f{0, 0, 0} : attenuations[k]});
        // A column holds at most D filled cells.
        const Vec3f& t = transmittances[k];
        std::vector<Vec3f>& powers = map.powers_.emplace_back(size_t(view.frame.depth() + 1));
        for (std::size_t n = 0; n < powers.size(); ++n)
            for (int ch = 0; ch < 3; ++ch) powers[n][ch] = std::pow(t[ch], float(n));
    }
    map.buildEventIndex();
    return map;
}

namespace {

// Word w of a column's events: its filled cells, or (runs) the last cell of each run of filled
// cells (cell i when i + 1 is empty; the padding bits beyond the depth are 0).
uint64_t columnEventWord(const uint64_t* words, int64_t w, int64_t wordsPerColumn, bool runs) {
    if (!runs) return words[w];
    const uint64_t next = w + 1 < wordsPerColumn ? words[w + 1] & 1u : 0;
    return words[w] & ~((words[w] >> 1) | (next << 63));
}

// Runs of filled cells (maximal sequences of consecutive ones) whose last cell lies in [0, end):
// cell i ends a run when it is filled and i + 1 is not (the padding bits beyond the depth are 0).
// One popcount per word.
int64_t runsEndingBefore(const BitGrid& bits, int64_t column, int64_t end) {
    end = std::min(end, bits.depth());
    if (end <= 0) return 0;
    const uint64_t* words = bits.column(column);
    const int64_t last = (end - 1) >> 6, P = bits.wordsPerColumn();
    int64_t n = 0;
    for (int64_t w = 0; w <= last; ++w) {
        const uint64_t next = w + 1 < P ? words[w + 1] & 1u : 0;
        uint64_t ends = words[w] & ~((words[w] >> 1) | (next << 63));
        if (w == last) ends &= ~uint64_t(0) >> (63 - ((end - 1) & 63));
        n += std::popcount(ends);
    }
    return n;
}

// The crossings of a column in slices [0, end), in depth order, as slice coordinates: each filled
// cell's centre, or (runs) the centre of each run of filled cells that ends before `end`.
template <class Crossing>
void forEachCrossing(const BitGrid& bits, int64_t column, int64_t end, bool runs, const Crossing& crossing) {
    end = std::min(end, bits.depth());
    const uint64_t* words = bits.column(column);
    int64_t runStart = -1;
    for (int64_t w = 0; w * 64 < end; ++w) {
        uint64_t word = words[w];
        while (word) {
            const int64_t s = w * 64 + std::countr_zero(word);
            word &= word - 1;
            if (!runs) {
                if (s < end) crossing(double(s) + 0.5);
                continue;
            }
            if (runStart < 0) runStart = s;
            const bool next = s + 1 < bits.depth() && ((words[(s + 1) >> 6] >> ((s + 1) & 63)) & 1u);
            if (!next) {
                if (s < end) crossing(0.5 * double(runStart + s + 1));
                runStart = -1;
            }
        }
    }
}

} // namespace

void TransmittanceShadowMap::buildEventIndex() {
    eventOffsets_.clear();
    if (channels_.empty()) return;
    const Frame& frame = channels_[0].grid.frame;
    for (const Channel& c : channels_) {
        const Vec3f& a = c.attenuation;
        if (a.x > 0 || a.y > 0 || a.z > 0 || !c.grid.frame.sameGrid(frame)) return;
    }
    const int64_t columns = frame.columnCount(), P = channels_[0].grid.bits.wordsPerColumn();
    const std::size_t C = channels_.size();
    const bool runs = mode_ == VoxelizeMode::Conservative;
    // The union of the channels' events in word w of a column, each channel's in `own`.
    auto events = [&](int64_t column, int64_t w, uint64_t* own) {
        uint64_t any = 0;
        for (std::size_t k = 0; k < C; ++k)
            any |= own[k] = columnEventWord(channels_[k].grid.bits.column(column), w, P, runs);
        return any;
    };
    std::vector<uint64_t> perColumn(static_cast<std::size_t>(columns));
    parallelFor(0, columns, 4096, [&](int64_t c0, int64_t c1) {
        std::vector<uint64_t> own(C);
        for (int64_t c = c0; c < c1; ++c)
            for (int64_t w = 0; w < P; ++w)
                perColumn[size_t(c)] += uint64_t(std::popcount(events(c, w, own.data())));
    });
    uint64_t total = 0;
    for (const uint64_t n : perColumn) total += n;
    // Only where the index is no larger than the bit columns (sparse foliage, not a dense solid).
    const uint64_t indexBytes = 4 * uint64_t(columns + 1) + 2 * total * (1 + C);
    if (total > UINT32_MAX || frame.depth() > 65535 || indexBytes > 8 * C * uint64_t(columns * P)) return;
    eventOffsets_.resize(size_t(columns) + 1);
    eventColumns_.assign(size_t((columns + 63) / 64), 0);
    for (std::size_t c = 0; c < perColumn.size(); ++c) {
        eventOffsets_[c + 1] = eventOffsets_[c] + uint32_t(perColumn[c]);
        if (perColumn[c] != 0) eventColumns_[c >> 6] |= uint64_t(1) << (c & 63);
    }
    eventSlice_.assign(total, 0);
    eventLight_.assign(total, Vec3f{1, 1, 1});
    parallelFor(0, columns, 4096, [&](int64_t c0, int64_t c1) {
        std::vector<uint64_t> own(C);
        std::vector<uint16_t> count(C);
        for (int64_t c = c0; c < c1; ++c) {
            std::fill(count.begin(), count.end(), uint16_t(0));
            std::size_t i = eventOffsets_[size_t(c)];
            for (int64_t w = 0; w < P; ++w)
                for (uint64_t any = events(c, w, own.data()); any; any &= any - 1, ++i) {
                    const int bit = std::countr_zero(any);
                    for (std::size_t k = 0; k < C; ++k)
                        count[k] = uint16_t(count[k] + ((own[k] >> bit) & 1u));
                    eventSlice_[i] = uint16_t(w * 64 + bit);
                    // As columnTransmittance: the channels in order, those with no cell in front
                    // left out.
                    Vec3f light{1, 1, 1};
                    for (std::size_t k = 0; k < C; ++k)
                        if (count[k] != 0) light = light * powers_[k][count[k]];
                    eventLight_[i] = light;
                }
        }
    });
}

VOXFX_ALWAYS_INLINE inline Vec3f TransmittanceShadowMap::indexedTransmittance(int64_t column,
                                                                              int64_t end) const {
    const std::size_t b = eventOffsets_[size_t(column)], e = eventOffsets_[size_t(column) + 1];
    std::size_t i = b;
    while (i < e && int64_t(eventSlice_[i]) < end) ++i;
    return i == b ? Vec3f{1, 1, 1} : eventLight_[i - 1];
}

double TransmittanceShadowMap::columnChord(std::size_t k, int64_t column, double depth,
                                           int64_t skipCells) const {
    const VoxelGrid& g = channels_[k].grid;
    const int64_t end = detail::slicesInFront(g.frame, column, depth, skipCells);
    if (end <= 0) return 0;
    const bool runs = mode_ == VoxelizeMode::Conservative;
    // Pairs in depth order: the first crossing enters, the next leaves.
    bool inside = false;
    int64_t crossings = 0;
    double entered = 0, chord = 0;
    forEachCrossing(g.bits, column, end, runs, [&](double s) {
        ++crossings;
        if (!inside)
            entered = s;
        else
            chord += s - entered;
        inside = !inside;
    });
    // Still inside: p lies in the glass when the whole column pairs up (an odd column has lost a
    // crossing to a cell it shares with another, a glass thinner than a cell: no chord then).
    if (inside) {
        const int64_t all =
            runs ? runsEndingBefore(g.bits, column, g.frame.depth())
                 : countColumnRange(g.bits.column(column), g.frame.depth(), 0, g.frame.depth());
        if (all % 2 == 0) {
            const double t = g.frame.depthToSlice(column)(depth);
            chord += std::clamp(t, entered, double(g.frame.depth())) - entered;
        }
    }
    return chord / g.frame.depthToSlice(column).scale;
}

int64_t TransmittanceShadowMap::columnCells(std::size_t k, int64_t column, double depth,
                                            int64_t skipCells) const {
    const VoxelGrid& g = channels_[k].grid;
    const int64_t end = detail::slicesInFront(g.frame, column, depth, skipCells);
    // Surface: ED06's count of filled cells. Conservative: a leaf fills every cell its depth range
    // over the column touches (2-3 for a tilted one), so the occluders are the runs of cells, each
    // counted once when it ends in front of p's skipped cells.
    if (mode_ == VoxelizeMode::Conservative) return runsEndingBefore(g.bits, column, end);
    return countColumnRange(g.bits.column(column), g.frame.depth(), 0, end);
}

Vec3f TransmittanceShadowMap::columnTransmittance(int64_t column, double depth, int64_t skipCells,
                                                  double lengthPerDepth) const {
    if (!eventOffsets_.empty())
        return indexedTransmittance(column,
                                    detail::slicesInFront(channels_[0].grid.frame, column, depth, skipCells));
    Vec3f out{1, 1, 1};
    for (std::size_t k = 0; k < channels_.size(); ++k) {
        const int64_t n = columnCells(k, column, depth, skipCells);
        if (n == 0) continue;
        out = out * powers_[k][size_t(n)];
        const Vec3f& sigma = channels_[k].attenuation;
        if (sigma.x > 0 || sigma.y > 0 || sigma.z > 0)
            out = out * beerLambert(sigma, columnChord(k, column, depth, skipCells) * lengthPerDepth);
    }
    return out;
}

int64_t TransmittanceShadowMap::cellsBefore(std::size_t k, const Vec3d& world, int64_t skipCells) const {
    if (k >= channels_.size() || !view_.covers(world)) return 0;
    const detail::ColumnAt c = detail::nearestColumn(view_, world);
    return columnCells(k, c.column, c.depth, skipCells);
}

Vec3f TransmittanceShadowMap::transmittance(const Vec3d& world, int64_t skipCells) const {
    if (channels_.empty() || !view_.covers(world)) return {1, 1, 1};
    const detail::ColumnAt c = detail::nearestColumn(view_, world);
    return columnTransmittance(c.column, c.depth, skipCells, detail::worldLengthPerDepth(view_, world));
}

Vec3f TransmittanceShadowMap::transmittanceBilinear(const Vec3d& world, int64_t skipCells,
                                                    const Vec3d& normal, double sharpness) const {
    Vec3d grid;
    if (channels_.empty() || !view_.locate(world, grid)) return {1, 1, 1};
    if (!eventOffsets_.empty() && detail::orientedBilinearApplies(view_, channels_[0].grid.frame, sharpness))
        return detail::orientedBilinearColumns(
            view_, channels_[0].grid.frame, grid, normal, skipCells, eventColumns_.data(),
            [&](int64_t column, int64_t end) { return indexedTransmittance(column, end); });
    if (!eventOffsets_.empty())
        return detail::bilinearColumnsAt<Vec3f, float>(
            view_, grid, normal,
            [&](int64_t column, const auto& depth) {
                // An empty column: no need for the receiver plane's depth.
                if (((eventColumns_[size_t(column >> 6)] >> (column & 63)) & 1u) == 0) return Vec3f{1, 1, 1};
                return indexedTransmittance(
                    column, detail::slicesInFront(channels_[0].grid.frame, column, depth(), skipCells));
            },
            sharpness);
    const double lengthPerDepth = detail::worldLengthPerDepth(view_, world);
    return detail::bilinearColumns<Vec3f, float>(
        view_, world, normal,
        [&](const detail::ColumnAt& c) {
            return columnTransmittance(c.column, c.depth, skipCells, lengthPerDepth);
        },
        sharpness);
}

std::span<const OptionField<TransmittanceShadowOptions>> TransmittanceShadowOptions::fields() {
    using O = TransmittanceShadowOptions;
    static const std::vector<OptionField<O>> table = [] {
        std::vector<OptionField<O>> t;
        detail::appendLightGridFields(t);
        OptionField<O> offset = optionField<O>(
            "normalOffset", "lookup offset along the surface normal, in column footprints (grids and map)",
            OptionType::Real, 0, 1000);
        offset.store = +[](O& o, const OptionValue& v) {
            o.grid.normalOffset = o.opaque.normalOffset = std::get<double>(v);
        };
        offset.get = +[](const O& o) { return OptionValue(o.grid.normalOffset); };
        t.push_back(offset);
        t.push_back(nameOption<O, parseVoxelizeMode, optionName<VoxelizeMode>, &O::voxelMode>(
            "voxelMode", "voxelization of the partial occluders from the light", "surface | conservative"));
        t.push_back(nameOption<O, parseDevice, optionName<Device>, &O::device>(
            "device", "where the light grids are voxelized (the same grids; see voxfx devices)",
            "cpu | cuda | auto"));
        t.push_back(numberOption<O, &O::opaque, &ShadowMapOptions::resolution>(
            "mapResolution", "opaque casters' shadow map: texels along the longer side", 1, 32768,
            "shadowMapResolution"));
        t.push_back(numberOption<O, &O::opaque, &ShadowMapOptions::pcfRadius>(
            "pcf", "opaque casters' shadow map: PCF radius r, (2r+1)^2 taps", 0, 8));
        t.push_back(numberOption<O, &O::opaque, &ShadowMapOptions::depthBias>(
            "depthBias", "opaque casters' shadow map: depth bias, in texel footprints", 0, 1000));
        return t;
    }();
    return table;
}

TransmittanceShadowStats& TransmittanceShadowStats::operator+=(const TransmittanceShadowStats& o) {
    grids += o.grids;
    channels += o.channels;
    filledCells += o.filledCells;
    opaque += o.opaque;
    return *this;
}

std::string TransmittanceShadowStats::summary() const {
    return countText(grids) + (grids == 1 ? " light grid (" : " light grids (") + countText(channels) +
           (channels == 1 ? " channel), " : " channels), ") + countText(filledCells) +
           " filled cells; opaque casters: " + opaque.summary();
}

TransmittanceShadow TransmittanceShadow::build(const Scene& scene, const Light& light,
                                               const TransmittanceShadowOptions& options,
                                               Progress* progress) {
    detail::checkLightGrid(options.grid, "transmittance");
    TransmittanceShadow out;
    out.options_ = options;
    const detail::CasterSets casters = detail::collectCasters(scene);
    if (casters.all.indices.empty()) return out;
    out.opaque_ = MapShadow::build(light, casters.opaque.view(), options.opaque, progress);
    if (casters.partial.empty()) return out;
    Box3d bounds;
    std::vector<MeshView> groups;
    std::vector<Vec3f> transmittances, attenuations;
    for (const auto& [key, mesh] : casters.partial) {
        bounds.extend(computeBounds(mesh.view()));
        groups.push_back(mesh.view());
        transmittances.push_back({key[0], key[1], key[2]});
        attenuations.push_back({key[3], key[4], key[5]});
    }
    out.views_ = makeLightViews(light, bounds, options.grid.resolution, options.grid.depth);
    for (const LightView& v : out.views_)
        out.maps_.push_back(TransmittanceShadowMap::build(v, groups, transmittances, options.voxelMode,
                                                          options.grid.slicing, progress, options.device,
                                                          attenuations));
    // The grids pass 1 - F0 per glass crossing; the columns the rest of each crossing's Fresnel.
    out.fresnel_ = detail::buildGlassFresnelViews(scene, out.views_, true);
    return out;
}

Vec3f TransmittanceShadow::visibility(const Vec3d& p, const Vec3d& n) const {
    Vec3f v{1, 1, 1};
    v = v * opaque_.visibility(p, n);
    // In the opaque casters' shadow the grids cannot change the (zero) product.
    if (v.x == 0 && v.y == 0 && v.z == 0) return v;
    Vec3d q;
    const int i = detail::lookupView(views_, p, n, options_.grid.normalOffset, q);
    if (i < 0) return v;
    const TransmittanceShadowMap& m = maps_[size_t(i)];
    const int64_t skip = options_.grid.skipCells;
    v = v * (options_.grid.bilinear ? m.transmittanceBilinear(q, skip, n, options_.grid.sharpness)
                                    : m.transmittance(q, skip));
    return v * float(detail::glassFresnelPass(fresnel_, views_, i, q, n, options_.grid));
}

TransmittanceShadow::Stats TransmittanceShadow::stats() const {
    Stats s;
    s.opaque = opaque_.stats();
    for (const TransmittanceShadowMap& m : maps_)
        for (const TransmittanceShadowMap::Channel& c : m.channels()) {
            ++s.grids;
            s.filledCells += c.grid.bits.count();
        }
    if (!maps_.empty()) s.channels = int64_t(maps_[0].channels().size());
    return s;
}

} // namespace voxfx
