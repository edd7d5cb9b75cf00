// voxfx — robust inside tests for meshes that are not closed (internal header).
#pragma once

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"

namespace voxfx::detail {

/// Cells not reachable from the grid border through empty cells (6-connected), i.e. the walls
/// plus everything they enclose. One pass settles each column outside its wall span (lowest to
/// highest wall); a column worklist then fills whole runs of the spans per step (bit-parallel
/// carries along depth), so cost ~ one pass over the grid + (columns reached sideways) x (words
/// of their spans) x (passes).
BitGrid floodFillInside(const BitGrid& walls);

/// Bitwise majority of three grids of equal size.
BitGrid majority(const BitGrid& a, const BitGrid& b, const BitGrid& c);

/// The same orthographic box and cells, sliced along another axis.
Frame reframe(const Frame& frame, Axis axis);

} // namespace voxfx::detail
