// voxfx — the renderer's anti-aliasing and output transform (internal): which cells of the
// G-buffer adaptive anti-aliasing shades at every sample, the FXAA-style post-process, and the
// filmic tone map (see render.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include "render/frame_state.hpp"

namespace voxfx::detail {

/// frame.refined values: every sample of the cell is shaded (an edge), or `adaptive` samples, one
/// per row and column (N-rooks: glass inside, where the light through it varies but no edge does).
/// 0: the representative (adaptive / 2, adaptive / 2) only.
inline constexpr uint8_t kEveryRefinedSample = 2, kRookSamples = 1;

/// Fills frame.refined from the G-buffer: every sample of a cell (adaptive x adaptive samples)
/// where its samples show different meshes or materials, background and geometry, faces whose
/// normals differ by more than 30 degrees or depths more than 2 % apart; N-rooks samples where it
/// shows glass (when a glass method is chosen) and no such edge.
void markRefinedCells(FrameState& frame);

/// Whether the passes shade sample (x, y) (every sample when adaptive is 1).
bool shadedSample(const FrameState& frame, int64_t x, int64_t y);

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
/// `luma` is scratch memory (reused between frames).
void postAntiAlias(const Image& image, const std::vector<uint8_t>& skip, Image& out,
                   std::vector<float>& luma);

} // namespace voxfx::detail
