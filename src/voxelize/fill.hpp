// voxfx — robust inside tests for meshes that are not closed (internal header).
#pragma once

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"

namespace voxfx::detail {

/// Cells not reachable from the grid border through empty cells (6-connected), i.e. the walls
/// plus everything they enclose. A column worklist fills whole runs per step (bit-parallel
/// carries along depth), so cost ~ (columns touched) x (words per column) x (passes).
BitGrid floodFillInside(const BitGrid& walls);

/// Bitwise majority of three grids of equal size.
BitGrid majority(const BitGrid& a, const BitGrid& b, const BitGrid& c);

/// The same orthographic box and cells, sliced along another axis.
Frame reframe(const Frame& frame, Axis axis);

} // namespace voxfx::detail
