// voxfx — a part of a long operation's progress (internal): a step of a longer operation (the
// distance functions' voxelization, distances and inside test; a frame's shadow per light) reports
// its [0, 1] as its share of the whole line.
#pragma once

#include "voxfx/parallel.hpp"

namespace voxfx::detail {

/// Reports a step's progress [0, 1] as [lo, hi] of the whole operation's; passes cancellation on.
class ProgressRange final : public Progress {
public:
    ProgressRange(Progress* whole, double lo, double hi) : whole_(whole), lo_(lo), hi_(hi) {}
    bool update(double f) override { return whole_ ? whole_->update(lo_ + (hi_ - lo_) * f) : true; }
    /// This, or null when there is nothing to report to (so a step skips its polling).
    Progress* get() { return whole_ ? this : nullptr; }

private:
    Progress* whole_;
    double lo_, hi_;
};

} // namespace voxfx::detail
