// voxfx — the renderer's anti-aliasing and output transform (internal): which cells of the
// G-buffer adaptive anti-aliasing shades at every sample, the FXAA-style post-process, and the
// filmic tone map (see render.hpp).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "render/frame_state.hpp"

namespace voxfx::detail {

/// frame.refined values: every sample of the cell is shaded (an edge), or `adaptive` samples, one
/// per row and column (N-rooks: glass inside, where the light through it varies but no edge does).
/// 0: the representative (adaptive / 2, adaptive / 2) only.
inline constexpr uint8_t kEveryRefinedSample = 2, kRookSamples = 1;

/// How far (perceptual luma of the shown image, 0..1) the light through a glass or volume cell must
/// depart from its neighbours' for it to get more samples (curvesAcrossNeighbours): the smallest step the
/// post-process blends (FXAA's 1/32 of contrast), below which the eye sees no stair-steps.
inline constexpr float kRefineContrast = 1.0f / 32;

/// Fills frame.refined from the G-buffer: every sample of a cell (adaptive x adaptive samples)
/// where its samples show different meshes or materials, background and geometry, faces whose
/// normals differ by more than 30 degrees or depths more than 2 % apart; 0 elsewhere (glass cells:
/// see curvesAcrossNeighbours). Returns the number of samples showing geometry (it reads them all);
/// -1 without adaptive anti-aliasing (frame.adaptive 1: nothing to mark).
int64_t markRefinedCells(FrameState& frame);

/// renderGBuffer (voxfx/gbuffer.hpp) into frame.gbuffer with camera `camera`, then what
/// markRefinedCells does, each tile of the rasterizer's cells marked as soon as its rows are done
/// (its samples still in the cache): the same G-buffer, marks and count.
int64_t renderGBufferAndMark(FrameState& frame, const Frame& camera, Progress* progress);

/// renderGBuffer (voxfx/gbuffer.hpp) in tiles of a multiple of `rowAlign` rows, calling
/// rowsDone(y0, y1) on a tile's thread once its rows [y0, y1) hold their final values (every row of
/// the frame once, in some order; the whole frame once when nothing is drawn). The same G-buffer.
void renderGBufferTiles(const SceneGeometry& geometry, const Frame& camera, GBuffer& out, int64_t rowAlign,
                        Progress* progress, const std::function<void(int64_t, int64_t)>& rowsDone);

/// The index of cell (cx, cy)'s representative sample (adaptive / 2, adaptive / 2).
inline std::size_t representativeSample(const FrameState& frame, int64_t cx, int64_t cy) {
    const int a = frame.adaptive;
    return std::size_t((cy * a + a / 2) * frame.width + cx * a + a / 2);
}

inline constexpr std::size_t kNoSample = ~std::size_t(0);

/// The representative sample of a cell next to (cx, cy) (its four sides first, then its corners)
/// that shows `triangle` (GBuffer::kNone: the background), or kNoSample. The shading pass shades an
/// edge cell's sample of another triangle than its representative's only where no neighbour shows
/// it: elsewhere the neighbour's shading, a cell away, stands for it (shading varies little over a
/// cell; what anti-aliasing needs at an edge is which surface covers each sample).
inline std::size_t neighbourShowing(const FrameState& frame, int64_t cx, int64_t cy, uint32_t triangle) {
    const int a = frame.adaptive;
    const int64_t cw = frame.width / a, ch = frame.height / a;
    // The four sides first, then the corners.
    constexpr int kX[8] = {-1, 1, 0, 0, -1, 1, -1, 1}, kY[8] = {0, 0, -1, 1, -1, -1, 1, 1};
    for (int k = 0; k < 8; ++k) {
        const int64_t nx = cx + kX[k], ny = cy + kY[k];
        if (nx < 0 || ny < 0 || nx >= cw || ny >= ch) continue;
        const std::size_t r = representativeSample(frame, nx, ny);
        if (frame.gbuffer.triangle[r] == triangle) return r;
    }
    return kNoSample;
}

/// The perceptual luma (gamma 2, of values clamped to [0, 1]) of linear radiance `c` as the image
/// shows it, after the output transform `t`.
float shownLuma(const Vec3f& c, ToneMap t);

/// Whether the shown luma of cell (cx, cy)'s representative departs from the straight line through
/// its two neighbours' along x or along y by more than `contrast` (the second difference
/// |l(-1) + l(+1) - 2 l(0)|; a neighbour past the image's side counts as the cell): light that
/// varies linearly across a cell averages to its centre's value, so only a bend or a step (an edge
/// inside glass or a volume) needs more samples. The glass pass (glass shaded once, N-rooks samples)
/// (at RenderOptions::glassSampleContrast) and the volume pass (every sample, at kRefineContrast) refine
/// by it.
bool curvesAcrossNeighbours(const FrameState& frame, int64_t cx, int64_t cy,
                            float contrast = kRefineContrast);

/// The test of curvesAcrossNeighbours on lumas given per cell (luma(x, y) of a cell inside the
/// cw x ch cells): for a caller that has them already (the volume pass's AA round).
template <class Luma>
bool curvesAcross(const Luma& luma, int64_t cx, int64_t cy, int64_t cw, int64_t ch, float contrast) {
    const float own = luma(cx, cy);
    // A neighbour past the image's side counts as the cell itself (a one-sided difference).
    const auto at = [&](int64_t x, int64_t y) {
        return x < 0 || y < 0 || x >= cw || y >= ch ? own : luma(x, y);
    };
    return std::abs(at(cx - 1, cy) + at(cx + 1, cy) - 2 * own) > contrast ||
           std::abs(at(cx, cy - 1) + at(cx, cy + 1) - 2 * own) > contrast;
}

/// The cells a cell of an image-space refinement lattice at spacing h takes its value from (the glass
/// and volume passes' lattices, after Levoy 1990): the two along x where cy is a multiple of 2h
/// ((cx - h, cy), (cx + h, cy)), else the two along y where cx is ((cx, cy - h), (cx, cy + h)), else
/// the four corners ((cx -+ h, cy - h), then (cx -+ h, cy + h)). May lie outside the image.
struct LatticeNeighbours {
    int n = 0;
    int64_t x[4] = {}, y[4] = {};
    bool alongX = false, alongY = false;
};
inline LatticeNeighbours latticeNeighbours(int64_t cx, int64_t cy, int64_t h) {
    LatticeNeighbours l;
    l.alongX = (cy / h) % 2 == 0;
    l.alongY = !l.alongX && (cx / h) % 2 == 0;
    if (l.alongX) {
        l.x[0] = cx - h, l.x[1] = cx + h, l.y[0] = l.y[1] = cy, l.n = 2;
    } else if (l.alongY) {
        l.x[0] = l.x[1] = cx, l.y[0] = cy - h, l.y[1] = cy + h, l.n = 2;
    } else {
        l.x[0] = l.x[2] = cx - h, l.x[1] = l.x[3] = cx + h, l.y[0] = l.y[1] = cy - h,
        l.y[2] = l.y[3] = cy + h;
        l.n = 4;
    }
    return l;
}

/// Whether the passes shade sample (x, y) (every sample when adaptive is 1).
bool shadedSample(const FrameState& frame, int64_t x, int64_t y);

/// The samples of cell (cx, cy) the passes shade, as sample indices into `out`, its representative
/// first where it is one of them, the others in row order except that the one the representative
/// displaced takes its place: every one of an edge cell, the N-rooks samples of a glass cell, else
/// the representative. Returns their count.
int cellSamples(const FrameState& frame, int64_t cx, int64_t cy, std::array<std::size_t, 64>& out);

/// The column of the N-rooks sample in row dy of an s x s cell (a permutation of 0..s-1).
int rookColumn(int s, int dy);

/// Post-process anti-aliasing (after Lottes 2009, FXAA 3.11's quality path): per pixel where
/// skip[pixel] is 0 and the local luma contrast exceeds max(1/32, max luma / 8), the edge's
/// orientation from the luma second differences, its ends searched up to 12 pixels each way, and the
/// pixel blended towards its neighbour across the edge by the sub-pixel distance to the nearer end
/// (or the sub-pixel aliasing estimate, whichever is larger). Luma is of values clamped to [0, 1].
/// `skip` is empty or one byte per pixel (row-major). Deterministic; rows in parallel.
Image postAntiAlias(const Image& image, const std::vector<uint8_t>& skip);
/// The same into `out`, which holds `image`'s pixels on entry (those it does not blend stay);
/// `luma` is scratch memory (reused between frames), or with `lumaGiven` holds postLuma of every
/// pixel of `image` already (the resolve pass makes it as it writes them).
void postAntiAlias(const Image& image, const std::vector<uint8_t>& skip, Image& out, std::vector<float>& luma,
                   bool lumaGiven);
/// The same over `image` itself, `luma` holding postLuma of each of its pixels: the blended pixels
/// are kept in `blends` (scratch, reused between frames) until every pixel has been read, then
/// written (the same image as postAntiAlias into a copy).
void postAntiAliasInPlace(Image& image, const std::vector<uint8_t>& skip, const std::vector<float>& luma,
                          std::vector<std::vector<std::pair<std::size_t, Vec3f>>>& blends);

/// The post-process's first test on one row of lumas W wide (`row`, and `above` and `below`, the
/// rows next to it, each the row itself at the image's top or bottom): lists into `out` (W entries),
/// in increasing x, the pixels where max - min of the luma and its four neighbours' (a neighbour past
/// the row's end: the pixel at the end) is not below max(1/32, max / 8) and `skipRow` (null: none)
/// is 0. A pixel with a NaN among those lumas may be listed whatever the test says (postAntiAlias
/// tests each listed pixel's contrast again). Returns the count.
int64_t postCandidates(const float* row, const float* above, const float* below, const uint8_t* skipRow,
                       int64_t W, int64_t* out);

/// The post-process's luma of a pixel: perceptual (gamma 2), of values clamped to [0, 1].
inline float postLuma(const Vec3f& c) {
    const float r = std::clamp(c.x, 0.0f, 1.0f), g = std::clamp(c.y, 0.0f, 1.0f),
                b = std::clamp(c.z, 0.0f, 1.0f);
    return std::sqrt(0.299f * r + 0.587f * g + 0.114f * b); // perceptual (gamma 2) luma
}

} // namespace voxfx::detail
