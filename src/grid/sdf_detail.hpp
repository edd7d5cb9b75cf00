// voxfx — signed distance fields, internal: where the sign's solid bits come from (voxfx/sdf.hpp).
//
// signedDistanceField takes the solid bits brick by brick from a tiled voxelization
// (voxfx/tiled.hpp) wherever the fill allows tiling (wholeGridReason() is empty: parity, winding,
// gwn), so that no grid of the whole volume is made; flood and vote need the whole grid and take
// them from one dense voxelization. Both give the same bits, hence the same field: the tests
// compare the two paths through this entry point.
#pragma once

#include <cstdint>

#include "voxfx/sdf.hpp"

namespace voxfx::detail {

enum class SdfSign {
    Auto,  ///< tiled where the fill allows it, else dense (what signedDistanceField does)
    Dense, ///< one dense solid voxelization of the grid (W * H * D / 8 bytes)
};

/// What the sign's voxelization held besides the field.
struct SdfSignReport {
    bool tiled = false;
    /// Tiled: the tiling's working bytes (TileOptions::workingBytes: bins, projected vertices, a
    /// few bricks per thread). Dense: the solid grid's bytes.
    uint64_t workingBytes = 0;
};

/// signedDistanceField with the sign's source chosen; `report` (optional) says what was used.
SignedDistanceField signedDistanceField(const MeshView& mesh, const Frame& frame, const SdfOptions& options,
                                        SdfSign sign, SdfSignReport* report = nullptr);

} // namespace voxfx::detail
