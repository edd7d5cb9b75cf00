// voxfx — robust inside tests for meshes that are not closed (internal header).
#pragma once

#include "voxfx/bitgrid.hpp"
#include "voxfx/frame.hpp"

namespace voxfx::detail {

/// Cells not reachable from the grid border through empty cells (6-connected), i.e. the walls
/// plus everything they enclose. One pass settles each column outside its wall span (lowest to
/// highest wall); row sweeps over the columns still undecided then carry the outside sideways
/// and along the free runs (bit-parallel carries along depth), a column looked at only when a
/// neighbour grew since. Cost ~ one pass over the grid + (undecided columns) x (words of their
/// undecided range) x (times looked at).
BitGrid floodFillInside(const BitGrid& walls);

/// Bitwise majority of three grids of equal size.
BitGrid majority(const BitGrid& a, const BitGrid& b, const BitGrid& c);

/// The same orthographic box and cells, sliced along another axis.
Frame reframe(const Frame& frame, Axis axis);

} // namespace voxfx::detail
