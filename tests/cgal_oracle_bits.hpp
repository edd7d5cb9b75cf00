// voxfx tests — a lean exact solid oracle for timing (bench_oracle), beside cgal_oracle.hpp's
// oracleSolid; implemented in cgal_oracle.cpp with the other CGAL work. A header of its own so
// that the tests including cgal_oracle.hpp do not depend on it.
#pragma once

#include <cstdint>
#include <vector>

#include "cgal_oracle.hpp"

namespace voxfx::test {

/// oracleSolid's classification along z, as a lean exact oracle for timing (bench_oracle): one
/// thread, bits instead of byte grids, no sort, and the crossing's centre found from its
/// floating-point depth and confirmed by orientation_3 at the centres on either side (the binary
/// search of oracleSolid only where that check fails). The Surface_mesh and
/// Side_of_triangle_mesh are built only when a column needs them (an edge or vertex hit, a centre
/// on a triangle's plane). Bit k % 64 of words[(j * nx + i) * wordsPerColumn + k / 64] is
/// centre (i, j, k); `leftOut` (same layout, empty when nothing is left out) marks the centres
/// oracleSolid leaves out. Equal to oracleSolid(mesh, g, 2) cell for cell (a test checks it).
struct SolidOracleBits {
    Vec3i dims{0, 0, 0};
    int64_t wordsPerColumn = 0;
    std::vector<uint64_t> words;
    std::vector<uint64_t> leftOut;
    int64_t crossings = 0;
    int64_t degenerateColumns = 0; ///< columns decided centre by centre, or left out (open mesh)
    bool inside(int64_t i, int64_t j, int64_t k) const {
        return (words[size_t((j * dims.x + i) * wordsPerColumn + (k >> 6))] >> (k & 63)) & 1u;
    }
    bool left(int64_t i, int64_t j, int64_t k) const {
        return !leftOut.empty() &&
               ((leftOut[size_t((j * dims.x + i) * wordsPerColumn + (k >> 6))] >> (k & 63)) & 1u);
    }
};
SolidOracleBits oracleSolidBits(const MeshView& mesh, const CellGeometry& g);

} // namespace voxfx::test
