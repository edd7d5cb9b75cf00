// voxfx — tiled voxelization (voxfx/tiled.hpp): the grid brick by brick, each column's parity or
// winding number carried from one brick of a stack to the next (GI08 §4's parity, ED06 §2's
// slicemap as the layout of one brick).
//
// One stack (the bricks over B x B columns) at a time per thread: the triangles binned to the
// stack are rasterized once over its window of columns by the rasterizer's own kernels, into
// *marks* (a slice range of a column: what the dense consumers would write), which are bucketed
// by brick; each brick then gets its marks and the state carried in from the brick in front.
#include "voxfx/tiled.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstring>
#include <exception>
#include <iomanip>
#include <memory>
#include <mutex>
#include <sstream>
#include <vector>

#include "core/bitops.hpp"
#include "voxelize/consumers.hpp"
#include "voxelize/memory_text.hpp"
#include "voxelize/winding_tree.hpp"
#include "voxfx/raster.hpp"

namespace voxfx {

namespace detail::tiles {

constexpr int64_t kDefaultBrick = 128;

// What a brick is made of, from the mode and fill.
struct Plan {
    bool spans = false;     // conservative spans set cells (the conservative surface)
    bool samples = false;   // centre fragments set the cell of their depth (ED06 surface)
    bool parity = false;    // centre fragments flip the first slice behind them
    bool crossings = false; // centre fragments count +1 / -1 at the first slice behind them
    bool gwn = false;       // the gwn fill's block rule (spans give its surface, crossings its counts)
    bool unite = false;     // inside | surface (solid-conservative)
    bool subtract = false;  // inside & ~surface (interior)
    bool inside() const { return parity || crossings || gwn; }
};

Plan planOf(const VoxelizeOptions& o) {
    Plan p;
    const bool inside = o.mode == VoxelizeMode::Solid || o.mode == VoxelizeMode::SolidConservative ||
                        o.mode == VoxelizeMode::Interior;
    p.samples = o.mode == VoxelizeMode::Surface;
    p.spans = o.mode == VoxelizeMode::Conservative || (inside && o.mode != VoxelizeMode::Solid) ||
              (inside && o.fill == Fill::Gwn);
    p.parity = inside && o.fill == Fill::Parity;
    p.crossings = inside && (o.fill == Fill::Winding || o.fill == Fill::Gwn);
    p.gwn = inside && o.fill == Fill::Gwn;
    p.unite = o.mode == VoxelizeMode::SolidConservative;
    p.subtract = o.mode == VoxelizeMode::Interior;
    return p;
}

// A slice range [s0, s1] of one column of a stack's window; `sign` is the crossing's +1 / -1.
// 16 bytes: slices fit int32 (fitFrame allows at most 1e9 cells along an axis).
struct Mark {
    int32_t s0, s1;
    uint32_t column;
    int32_t sign;
};

// The window of columns a stack rasterizes: its own, grown by `halo` on every side (clipped to
// the grid). Local column index = (y - y0) * width + (x - x0).
struct Window {
    int64_t x0, y0, width, height;
    uint32_t local(int64_t x, int64_t y) const { return uint32_t((y - y0) * width + (x - x0)); }
};

// Collects a stack's marks from the rasterizer: the slice mapping of the dense consumers
// (consumers.hpp), applied to the frame's global column.
struct MarkSink {
    const FrameView* frame;
    Window window;
    bool samples; // centre fragments: their cell (surface) rather than the first slice behind
    std::vector<Mark>* out;
    std::vector<int32_t>* totals = nullptr; // per column: the signs of every crossing (gwn)

    void fragment(int64_t x, int64_t y, double depth, uint32_t, bool front) {
        const int64_t c = y * frame->width + x;
        if (samples) {
            const int64_t s = fragmentSlice(*frame, c, depth);
            if (s >= 0) out->push_back({int32_t(s), int32_t(s), window.local(x, y), 0});
            return;
        }
        const int64_t s = firstSliceBehind(frame->depthToSlice(c)(depth), frame->depth);
        if (s < frame->depth) out->push_back({int32_t(s), int32_t(s), window.local(x, y), front ? 1 : -1});
        if (totals) (*totals)[window.local(x, y)] += front ? 1 : -1; // D too: behind every centre
    }
    void span(int64_t x, int64_t y, double depthMin, double depthMax, uint32_t) {
        int64_t s0, s1;
        if (spanSlices(*frame, y * frame->width + x, depthMin, depthMax, s0, s1))
            out->push_back({int32_t(s0), int32_t(s1), window.local(x, y), 0});
    }
    void finish() {}
};

// Marks bucketed by brick along the stack (a span over several bricks is in each of them).
struct Buckets {
    std::vector<int64_t> start; // bricks + 1
    std::vector<Mark> marks;
    std::vector<int64_t> cursor;

    void fill(const std::vector<Mark>& raw, int64_t bricks, int64_t B) {
        // Brick of a slice: a shift for the usual power-of-two sizes (a division per mark and pass
        // was a fifth of the time at 4096^3).
        const bool pow2 = (B & (B - 1)) == 0;
        const int shift = std::countr_zero(uint64_t(B));
        const auto brickOf = [&](int64_t s) { return pow2 ? s >> shift : s / B; };
        start.assign(size_t(bricks + 1), 0);
        for (const Mark& m : raw)
            for (int64_t b = brickOf(m.s0), e = brickOf(m.s1); b <= e; ++b) ++start[size_t(b + 1)];
        for (int64_t b = 0; b < bricks; ++b) start[size_t(b + 1)] += start[size_t(b)];
        marks.resize(size_t(start[size_t(bricks)]));
        cursor.assign(start.begin(), start.end() - 1);
        for (const Mark& m : raw)
            for (int64_t b = brickOf(m.s0), e = brickOf(m.s1); b <= e; ++b)
                marks[size_t(cursor[size_t(b)]++)] = m;
    }
    const Mark* begin(int64_t b) const { return marks.data() + start[size_t(b)]; }
    const Mark* end(int64_t b) const { return marks.data() + start[size_t(b + 1)]; }
    bool empty(int64_t b) const { return start[size_t(b)] == start[size_t(b + 1)]; }
};

// What a stack shares with all its bricks: the frame, the plan, the stack's columns and scratch.
struct Stack {
    const FrameView* frame = nullptr;
    const Plan* plan = nullptr;
    int64_t B = 0;
    Window own{};   // the stack's columns
    Window outer{}; // the columns its marks cover (own, plus the gwn fill's halo)
    std::vector<Mark> spans, centres;
    Buckets spanBuckets, centreBuckets;
    // Carried state per column of `own`: parity (0 / 1) or winding number; how many are nonzero.
    std::vector<int32_t> carry;
    int64_t carryNonzero = 0;
    std::vector<uint8_t> touched; // columns of the brick with a crossing
    std::vector<uint64_t> bitsWords, surfaceWords, haloWords;
    // The gwn fill: the winding number tree and boundary edges (shared), the stack's curtains and
    // each column's count over the whole column.
    const WindingTree* tree = nullptr;
    const std::vector<std::array<Vec3d, 2>>* edges = nullptr;
    const Frame* fullFrame = nullptr;
    const MeshView* mesh = nullptr;
    GwnCurtains curtains;
    std::vector<int32_t> totals;
    std::vector<Mark> sorted; // a brick's marks by column (winding, gwn)
    std::vector<int64_t> first;

    /// The bytes its vectors hold (what keeping it for the next task costs).
    size_t keptBytes() const {
        const auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
        return bytes(spans) + bytes(centres) + bytes(spanBuckets.start) + bytes(spanBuckets.marks) +
               bytes(spanBuckets.cursor) + bytes(centreBuckets.start) + bytes(centreBuckets.marks) +
               bytes(centreBuckets.cursor) + bytes(carry) + bytes(touched) + bytes(bitsWords) +
               bytes(surfaceWords) + bytes(haloWords) + bytes(totals) + bytes(sorted) + bytes(first);
    }
};

// Stacks' scratch kept between the chunks of a call and between calls: a Dask task is one call
// over a few stacks, and every fresh vector of a stack (its marks, buckets, bricks: a few MiB)
// costs a page fault per 4 KiB on first touch, or on every use where the allocator gives memory
// back eagerly (Dask workers set MALLOC_TRIM_THRESHOLD_=65536: a task ran 1.5-2x slower there).
// Kept: as many stacks as ran at once, each up to kMaxKeptBytes.
class StackPool {
public:
    static constexpr size_t kMaxKeptBytes = size_t(256) << 20;
    static std::unique_ptr<Stack> take() {
        std::lock_guard<std::mutex> lock(mutex());
        auto& kept = stacks();
        if (kept.empty()) return std::make_unique<Stack>();
        std::unique_ptr<Stack> st = std::move(kept.back());
        kept.pop_back();
        return st;
    }
    static void give(std::unique_ptr<Stack> st) {
        if (st->keptBytes() > kMaxKeptBytes) return;
        std::lock_guard<std::mutex> lock(mutex());
        if (stacks().size() < size_t(2 * hardwareThreads())) stacks().push_back(std::move(st));
    }

private:
    static std::mutex& mutex() {
        static std::mutex m;
        return m;
    }
    static std::vector<std::unique_ptr<Stack>>& stacks() {
        static std::vector<std::unique_ptr<Stack>> s;
        return s;
    }
};

BitGridView viewOf(std::vector<uint64_t>& words, int64_t w, int64_t h, int64_t d) {
    const int64_t wpc = (d + 63) / 64;
    const auto n = size_t(w * h * wpc);
    if (words.size() < n) words.resize(n);
    std::memset(words.data(), 0, n * sizeof(uint64_t));
    return {words.data(), w, h, d, wpc};
}

// Sets the cells of the spans (or samples) of brick `b` into `out` (brick slices from s0).
void applySpans(const Stack& st, int64_t b, int64_t s0, const BitGridView& out) {
    const int64_t d = out.depth;
    for (const Mark* m = st.spanBuckets.begin(b); m != st.spanBuckets.end(b); ++m) {
        const int64_t lx = int64_t(m->column % uint32_t(st.outer.width)) + st.outer.x0 - st.own.x0;
        const int64_t ly = int64_t(m->column / uint32_t(st.outer.width)) + st.outer.y0 - st.own.y0;
        if (lx < 0 || ly < 0 || lx >= out.width || ly >= out.height) continue; // halo: gwn's own
        const int64_t a = std::max<int64_t>(m->s0, s0) - s0, z = std::min<int64_t>(m->s1, s0 + d - 1) - s0;
        if (a <= z) setSliceRange(out.column(lx, ly), a, z);
    }
}

// Parity: flips at the first slice behind each crossing, the carried parity XORed into slice 0,
// then a prefix XOR down each column; the parity at the brick's last slice carries on.
void parityBrick(Stack& st, int64_t b, int64_t s0, const BitGridView& out) {
    st.touched.assign(size_t(out.columnCount()), 0);
    for (const Mark* m = st.centreBuckets.begin(b); m != st.centreBuckets.end(b); ++m) {
        out.column(m->column)[(m->s0 - s0) >> 6] ^= uint64_t(1) << ((m->s0 - s0) & 63);
        st.touched[m->column] = 1;
    }
    const int64_t wpc = out.wordsPerColumn, last = (out.depth - 1) & 63;
    const uint64_t mask = out.lastWordMask();
    st.carryNonzero = 0;
    for (int64_t c = 0; c < out.columnCount(); ++c) {
        uint64_t* col = out.column(c);
        if (!st.touched[size_t(c)]) { // no crossing: the carried parity all along
            if (st.carry[size_t(c)]) {
                std::fill(col, col + wpc, ~uint64_t(0));
                col[wpc - 1] &= mask;
                ++st.carryNonzero;
            }
            continue;
        }
        col[0] ^= uint64_t(st.carry[size_t(c)]); // bit 0: the parity in front of the brick
        prefixXorWords(col, wpc, 0);
        col[wpc - 1] &= mask;
        const int32_t p = int32_t((col[wpc - 1] >> last) & 1u);
        st.carry[size_t(c)] = p;
        st.carryNonzero += p;
    }
}

// Winding: per column, the crossings in slice order; cells where the running sum (from the
// carried winding number) is nonzero are set, as WindingConsumer does for the whole column.
void windingBrick(Stack& st, int64_t b, int64_t s0, const BitGridView& out) {
    std::vector<Mark>& sorted = st.sorted;
    sorted.assign(st.centreBuckets.begin(b), st.centreBuckets.end(b));
    std::sort(sorted.begin(), sorted.end(), [](const Mark& a, const Mark& z) {
        return a.column != z.column ? a.column < z.column : a.s0 < z.s0;
    });
    const int64_t d = out.depth;
    std::size_t i = 0;
    st.carryNonzero = 0;
    for (int64_t c = 0; c < out.columnCount(); ++c) {
        int32_t winding = st.carry[size_t(c)];
        int64_t from = 0; // first slice whose state is `winding`
        while (i < sorted.size() && sorted[i].column == uint32_t(c)) {
            const int64_t s = sorted[i].s0 - s0;
            if (winding != 0 && s > from) setSliceRange(out.column(c), from, s - 1);
            while (i < sorted.size() && sorted[i].column == uint32_t(c) && sorted[i].s0 - s0 == s)
                winding += sorted[i++].sign;
            from = s;
        }
        if (winding != 0) setSliceRange(out.column(c), from, d - 1);
        st.carry[size_t(c)] = winding;
        st.carryNonzero += winding != 0;
    }
}

// A brick no mark reaches: every column keeps its carried state.
void carriedBrick(const Stack& st, const BitGridView& out) {
    for (int64_t c = 0; c < out.columnCount(); ++c)
        if (st.carry[size_t(c)] != 0) setSliceRange(out.column(c), 0, out.depth - 1);
}

// The marks of brick b sorted by column (then slice), with each column's first mark.
void sortByColumn(const Buckets& buckets, int64_t b, int64_t columns, std::vector<Mark>& sorted,
                  std::vector<int64_t>& first) {
    sorted.assign(buckets.begin(b), buckets.end(b));
    std::sort(sorted.begin(), sorted.end(), [](const Mark& a, const Mark& z) {
        return a.column != z.column ? a.column < z.column : a.s0 < z.s0;
    });
    first.assign(size_t(columns + 1), 0);
    for (const Mark& m : sorted) ++first[size_t(m.column) + 1];
    for (int64_t c = 0; c < columns; ++c) first[size_t(c + 1)] += first[size_t(c)];
}

// Gwn: the dense fill's block rule on the brick (gwnFillRegion), with the conservative surface of
// the brick grown by a cell (from the span marks of this brick and the two around it) and the
// counts of crossings from the carried count in front; the count then carries on.
void gwnBrick(Stack& st, int64_t b, const GridTile& tile, const BitGridView& out) {
    const FrameView& f = *st.frame;
    const int64_t sx0 = std::max<int64_t>(0, tile.x0 - 1), sy0 = std::max<int64_t>(0, tile.y0 - 1),
                  sz0 = std::max<int64_t>(0, tile.s0 - 1);
    const int64_t sx1 = std::min(f.width, tile.x0 + tile.width + 1),
                  sy1 = std::min(f.height, tile.y0 + tile.height + 1),
                  sz1 = std::min(f.depth, tile.s0 + tile.depth + 1);
    const BitGridView halo = viewOf(st.haloWords, sx1 - sx0, sy1 - sy0, sz1 - sz0);
    const int64_t bricks = int64_t(st.spanBuckets.start.size()) - 1;
    for (int64_t k = std::max<int64_t>(0, b - 1); k <= std::min(bricks - 1, b + 1); ++k)
        for (const Mark* m = st.spanBuckets.begin(k); m != st.spanBuckets.end(k); ++m) {
            const int64_t x = int64_t(m->column % uint32_t(st.outer.width)) + st.outer.x0;
            const int64_t y = int64_t(m->column / uint32_t(st.outer.width)) + st.outer.y0;
            const int64_t a = std::max<int64_t>(m->s0, sz0), z = std::min<int64_t>(m->s1, sz1 - 1);
            if (x >= sx0 && x < sx1 && y >= sy0 && y < sy1 && a <= z)
                setSliceRange(halo.column(x - sx0, y - sy0), a - sz0, z - sz0);
        }
    std::vector<Mark>& sorted = st.sorted;
    std::vector<int64_t>& first = st.first;
    sortByColumn(st.centreBuckets, b, out.columnCount(), sorted, first);
    GwnRegion region;
    region.x0 = tile.x0;
    region.y0 = tile.y0;
    region.z0 = tile.s0;
    region.out = out;
    region.surface = halo;
    region.sx0 = sx0;
    region.sy0 = sy0;
    region.sz0 = sz0;
    region.curtains = &st.curtains;
    region.counts = [&](int64_t x, int64_t y, int32_t* n) {
        const int64_t c = (y - tile.y0) * tile.width + (x - tile.x0);
        std::fill(n, n + tile.depth, 0);
        for (int64_t i = first[size_t(c)]; i < first[size_t(c + 1)]; ++i)
            n[sorted[size_t(i)].s0 - tile.s0] += sorted[size_t(i)].sign;
        n[0] += st.carry[size_t(c)];
        for (int64_t z = 1; z < tile.depth; ++z) n[z] += n[z - 1];
        return st.totals[size_t(c)];
    };
    gwnFillRegion(*st.fullFrame, *st.tree, region);
    for (const Mark& m : sorted) st.carry[m.column] += m.sign;
}

// Combines the inside with the conservative surface (solid-conservative, interior).
void combineSurface(const Plan& plan, const BitGridView& inside, const BitGridView& surface) {
    const int64_t n = inside.columnCount() * inside.wordsPerColumn;
    for (int64_t k = 0; k < n; ++k)
        inside.words[k] =
            plan.unite ? (inside.words[k] | surface.words[k]) : (inside.words[k] & ~surface.words[k]);
}

// Builds brick `b` of the stack into `tile` (bits, or uniform); false when it is uniform.
bool buildBrick(Stack& st, int64_t b, GridTile& tile) {
    const Plan& plan = *st.plan;
    const int64_t s0 = tile.s0, d = tile.depth, w = tile.width, h = tile.height;
    const bool noSpans = !(plan.spans || plan.samples) || st.spanBuckets.empty(b);
    const bool noCentres = !plan.inside() || st.centreBuckets.empty(b);
    const int64_t columns = w * h;
    const bool carryUniform = st.carryNonzero == 0 || st.carryNonzero == columns;
    if (noSpans && noCentres && !plan.gwn && (!plan.inside() || carryUniform)) {
        tile.uniform = true;
        tile.value = plan.inside() && st.carryNonzero == columns; // interior: no surface here
        return false;
    }
    const BitGridView bits = viewOf(st.bitsWords, w, h, d);
    if (!plan.inside()) {
        applySpans(st, b, s0, bits);
    } else {
        if (plan.gwn)
            gwnBrick(st, b, tile, bits);
        else if (noCentres)
            carriedBrick(st, bits);
        else if (plan.parity)
            parityBrick(st, b, s0, bits);
        else
            windingBrick(st, b, s0, bits);
        if ((plan.unite || plan.subtract) && !noSpans) {
            const BitGridView surface = viewOf(st.surfaceWords, w, h, d);
            applySpans(st, b, s0, surface);
            combineSurface(plan, bits, surface);
        }
    }
    tile.uniform = false;
    tile.bits = bits;
    return true;
}

// Rasterizes the stack's triangles over its window into marks, bucketed by brick.
void rasterizeStack(Stack& st, const RasterSetup& setup, const TileBins& bins, int64_t stack,
                    int64_t bricks) {
    const Plan& plan = *st.plan;
    const FrameView& view = *st.frame;
    st.spans.clear();
    st.centres.clear();
    MarkSink spanSink{&view, st.outer, plan.samples, &st.spans};
    MarkSink centreSink{&view, st.own, false, &st.centres};
    if (plan.gwn) {
        st.totals.assign(size_t(st.own.width * st.own.height), 0);
        centreSink.totals = &st.totals;
        st.curtains = gwnCurtains(*st.fullFrame, *st.mesh, *st.edges, st.own.x0, st.own.y0, st.own.width,
                                  st.own.height);
    }
    const int64_t ox1 = st.outer.x0 + st.outer.width, oy1 = st.outer.y0 + st.outer.height;
    for (int64_t i = bins.offsets[size_t(stack)]; i < bins.offsets[size_t(stack) + 1]; ++i)
        setup.triangle(bins.entries[size_t(i)], [&](const RasterTriangle& rt) {
            if (plan.samples)
                rasterizePiece(rt, Coverage::Center, view, st.outer.y0, oy1, spanSink, st.outer.x0, ox1);
            if (plan.spans)
                rasterizePiece(rt, Coverage::Conservative, view, st.outer.y0, oy1, spanSink, st.outer.x0,
                               ox1);
            // Crossings only in the stack's own columns (the halo is for the surface).
            if (plan.inside())
                rasterizePiece(rt, Coverage::Center, view, st.own.y0, st.own.y0 + st.own.height, centreSink,
                               st.own.x0, st.own.x0 + st.own.width);
        });
    st.spanBuckets.fill(st.spans, bricks, st.B);
    st.centreBuckets.fill(st.centres, bricks, st.B);
}

// What the tiling holds besides the caller's results: the bins and their counts, the projected
// vertices and the triangles' tile spans, and per thread three bricks (the inside, the surface,
// the gwn halo) with a stack's marks (about a brick's worth).
uint64_t workingBytes(const MeshView& mesh, int64_t entries, int64_t stacks, int64_t B) {
    const uint64_t brick = uint64_t(B * B * ((B + 63) / 64) * 8);
    return uint64_t(entries) * 4 + uint64_t(stacks) * 8 + uint64_t(mesh.triangleCount) * 16 +
           uint64_t(mesh.vertexCount) * 24 + uint64_t(hardwareThreads()) * 4 * brick;
}

} // namespace detail::tiles

std::string detail::memoryText(uint64_t bytes) {
    std::ostringstream s;
    if (bytes >= uint64_t(1) << 30)
        s << std::fixed << std::setprecision(2) << double(bytes) / double(uint64_t(1) << 30) << " GiB";
    else
        s << std::fixed << std::setprecision(1) << double(bytes) / double(uint64_t(1) << 20) << " MiB";
    return s.str();
}

std::string wholeGridReason(const Frame& frame, const VoxelizeOptions& o) {
    if (frame.isPerspective() || frame.isOriented()) return "tiles need an axis-aligned orthographic frame";
    if (frame.slicing() != Slicing::Uniform || o.slicing != Slicing::Uniform)
        return "tiles need uniform slicing (local slicing is decided over whole columns)";
    const bool inside = o.mode == VoxelizeMode::Solid || o.mode == VoxelizeMode::SolidConservative ||
                        o.mode == VoxelizeMode::Interior;
    if (inside && (o.fill == Fill::Flood || o.fill == Fill::Vote))
        return detail::concat("fill '", toString(o.fill), "' needs the whole grid (",
                              o.fill == Fill::Flood ? "the flood from the border crosses any number of tiles"
                                                    : "it slices the grid along all three axes",
                              ")");
    return {};
}

void voxelizeTiles(const MeshView& mesh, const Frame& frame, const VoxelizeOptions& given,
                   const TileOptions& tiles, const std::function<void(const GridTile&)>& visit) {
    using namespace detail::tiles;
    validateMesh(mesh, "mesh");
    VoxelizeOptions options = given;
    options.fill = resolveFill(mesh, frame, given);
    if (const std::string why = wholeGridReason(frame, options); !why.empty()) fail(why);
    const int64_t B = tiles.brickSize == 0 ? kDefaultBrick : tiles.brickSize;
    if (B <= 0 || B % 8 != 0) fail("the brick size must be a positive multiple of 8, got ", tiles.brickSize);
    const Plan plan = planOf(options);
    if (plan.gwn && B % 16 != 0)
        fail("fill 'gwn' needs a brick size that is a multiple of 16 (its blocks), got ", tiles.brickSize);
    withThreads(options.threads, [&] {
        const int64_t W = frame.width(), H = frame.height(), D = frame.depth();
        const detail::RasterSetup setup = detail::prepareVertices(frame, mesh);
        const Coverage coverage = plan.spans ? Coverage::Conservative : Coverage::Center;
        const int64_t halo = plan.gwn ? 1 : 0;
        // The bins first counted, against the budget with the vertices and a brick per thread.
        const uint64_t budget = tiles.memoryBytes ? tiles.memoryBytes : availableMemoryBytes();
        const int64_t stacksX = (W + B - 1) / B, stacksY = (H + B - 1) / B, bricks = (D + B - 1) / B;
        // Every brick costs a step, uniform or not: a bound on the time (2^31 bricks of 128^3 cells
        // is a grid about 165,000 cells along every axis).
        if (double(stacksX) * double(stacksY) * double(bricks) > 0x1p31)
            fail("a ", W, " x ", H, " x ", D, " grid needs ", stacksX * stacksY * bricks, " tiles of ", B,
                 "^3 cells; tiled voxelization takes at most 2^31 of them");
        // The bins counted, then checked against the budget with the vertices and the bricks
        // before they are filled.
        const detail::TileBins bins = detail::binTriangles(setup, coverage, B, B, halo, [&](int64_t entries) {
            const uint64_t need = workingBytes(mesh, entries, stacksX * stacksY, B);
            if (need > budget)
                failMemory("tiled voxelization needs ", detail::memoryText(need), " for its triangle lists (",
                           entries, " entries over ", stacksX * stacksY, " stacks of ", B, " x ", B,
                           " columns) and bricks, but the memory budget is ", detail::memoryText(budget));
            if (tiles.workingBytes) *tiles.workingBytes = need;
        });
        const FrameView view = setup.frame;
        // The gwn fill's winding number tree and boundary edges, as the dense fill builds them.
        detail::WindingTree tree;
        std::vector<std::array<Vec3d, 2>> edges;
        if (plan.gwn) {
            tree.build(mesh, 2.0);
            edges = detail::gwnEdges(mesh);
        }
        std::atomic<bool> stop{false}; // an error: the first one is rethrown
        std::mutex errorMutex;
        std::exception_ptr error;
        // The stacks asked for (TileOptions' range, clipped to the grid's), numbered k = 0.. in
        // row-major order within the range.
        const int64_t ax0 = std::clamp<int64_t>(tiles.stackX0, 0, stacksX),
                      ay0 = std::clamp<int64_t>(tiles.stackY0, 0, stacksY);
        const int64_t ax1 = tiles.stackX1 < 0 ? stacksX : std::clamp<int64_t>(tiles.stackX1, ax0, stacksX),
                      ay1 = tiles.stackY1 < 0 ? stacksY : std::clamp<int64_t>(tiles.stackY1, ay0, stacksY);
        const int64_t rangeX = ax1 - ax0, stacks = rangeX * (ay1 - ay0);
        ProgressSteps steps(options.progress, stacks);
        parallelFor(0, stacks, 1, [&](int64_t sb, int64_t se) {
            std::unique_ptr<Stack> kept = StackPool::take();
            Stack& st = *kept;
            st.frame = &view;
            st.plan = &plan;
            st.B = B;
            st.tree = &tree;
            st.edges = &edges;
            st.fullFrame = &frame;
            st.mesh = &mesh;
            for (int64_t i = sb; i < se && !stop.load(std::memory_order_relaxed) && !steps.cancelled(); ++i) {
                try {
                    const int64_t bx = ax0 + i % rangeX, by = ay0 + i / rangeX, k = by * stacksX + bx;
                    const int64_t x0 = bx * B, y0 = by * B;
                    st.own = {x0, y0, std::min(B, W - x0), std::min(B, H - y0)};
                    const int64_t gx0 = std::max<int64_t>(0, x0 - halo),
                                  gy0 = std::max<int64_t>(0, y0 - halo);
                    st.outer = {gx0, gy0, std::min(W, x0 + st.own.width + halo) - gx0,
                                std::min(H, y0 + st.own.height + halo) - gy0};
                    rasterizeStack(st, setup, bins, k, bricks);
                    st.carry.assign(size_t(st.own.width * st.own.height), 0);
                    st.carryNonzero = 0;
                    for (int64_t b = 0; b < bricks; ++b) {
                        GridTile tile;
                        tile.x0 = x0;
                        tile.y0 = y0;
                        tile.s0 = b * B;
                        tile.width = st.own.width;
                        tile.height = st.own.height;
                        tile.depth = std::min(B, D - b * B);
                        buildBrick(st, b, tile);
                        visit(tile);
                    }
                } catch (...) {
                    std::lock_guard<std::mutex> lock(errorMutex);
                    if (!error) error = std::current_exception();
                    stop = true;
                }
                if (!stop) steps.step();
            }
            StackPool::give(std::move(kept));
        });
        if (error) std::rethrow_exception(error);
        if (steps.cancelled()) fail("cancelled");
    });
}
} // namespace voxfx
