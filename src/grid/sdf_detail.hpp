// voxfx — signed distance fields, internal: where the sign's solid bits come from (voxfx/sdf.hpp).
//
// signedDistanceField takes the solid bits brick by brick from a tiled voxelization
// (voxfx/tiled.hpp) wherever the fill allows tiling (wholeGridReason() is empty: parity, winding,
// gwn), so that no grid of the whole volume is made; flood and vote need the whole grid and take
// them from one dense voxelization. Both give the same bits, hence the same field: the tests
// compare the two paths through this entry point.
#pragma once

#include <cstdint>
#include <vector>

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

/// Receives the field brick by brick as it is made, instead of the field holding it (so that a
/// writer can move each brick into its own structure and free it: one copy of the band at a time).
/// begin() once, with the field's description (no leaves or runs yet), before any brick; then
/// add() with each brick's leaves and inside runs, on the worker thread that made them: several
/// at once (add must be thread-safe) and in no fixed order. The bricks' blocks are disjoint and
/// together are the field's leaves and inside runs (runs that meet at a brick's side not joined).
/// add() may move from the vectors; they are freed after it returns.
class SdfSink {
public:
    virtual ~SdfSink() = default;
    virtual void begin(const SignedDistanceField& description) = 0;
    virtual void add(std::vector<SdfLeaf>& leaves, std::vector<SdfInsideRun>& runs) = 0;
};

/// signedDistanceField with the sign's source chosen; `report` (optional) says what was used. With
/// a `sink`, the bricks go to it and the result holds no leaves and no inside runs.
SignedDistanceField signedDistanceField(const MeshView& mesh, const Frame& frame, const SdfOptions& options,
                                        SdfSign sign, SdfSignReport* report = nullptr,
                                        SdfSink* sink = nullptr);

} // namespace voxfx::detail
