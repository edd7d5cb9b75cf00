// voxfx — what the light-grid shadows (transmittance, ED06 §3.1, and absorption, CHANG §3) share:
// the grids voxelized from the light and how a point is looked up in them.
//
// A grid has `resolution` columns along the longer side of each light view (voxfx/light_view.hpp)
// and `depth` slices, uniform or local (ED06's per-column range). Self-shadowing bias: the lookup
// point moves along the surface normal (turned towards the light) by `normalOffset` column
// footprints, and the lookup leaves out the `skipCells` cells ending at the point's own cell
// (default 1: the cell holding p, which holds p's own surface).
//
// Thread-safety: a value.
#pragma once

#include <cstdint>

#include "voxfx/types.hpp"

namespace voxfx {

struct LightGridOptions {
    int64_t resolution = 256; ///< columns along the longer side of each light view
    int64_t depth = 256;      ///< slices
    Slicing slicing = Slicing::Uniform;
    int64_t skipCells = 1;     ///< cells ending at p's own cell that a lookup ignores
    double normalOffset = 1.0; ///< lookup offset along the normal, in column footprints at p
    /// Interpolate bilinearly between the four columns around p, each read where the receiver's
    /// tangent plane crosses it (the default: edges without a column-wide staircase, as PCF filters
    /// a shadow map); false: p's own column only (ED06's lookup: a sharper, stair-stepped edge, and a
    /// slightly smaller mean error against exact transport at 128 columns and more).
    bool bilinear = true;
    /// Bilinear lookups: the blend of the four columns is stretched between the lowest and highest
    /// of them, per channel, by this slope about their middle (1, the default: plain bilinear, a
    /// column wide ramp at every edge; larger: the ramp narrows about bilinear's own contours, but a
    /// smooth gradient turns into terraces and a point can brighten where a leaf is added to a
    /// neighbouring column: BENCHMARKS.md, #37).
    double sharpness = 1.0;
};

} // namespace voxfx
