#include "voxfx/voxel_grid.hpp"

#include <cmath>

#include "core/bitops.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace {
void requireOrthographic(const Frame& f, const char* what) {
    if (f.isPerspective()) fail(what, " needs an orthographic grid, this one is perspective");
    if (f.isOriented()) fail(what, " needs an axis-aligned orthographic grid, this one is oriented");
}

// Re-slices along the next axis in cyclic order (a -> a+1). With the source sliced along a,
// columns (x, y) run along (a+1, a+2); the target, sliced along a+1, has columns (x', y') along
// (a+2, a) and holds target(x' = y, y' = s, bit x) = source(x, y, bit s). For each source row y,
// the W x D bit matrix [x][s] is transposed in 64 x 64 blocks.
VoxelGrid resliceNext(const VoxelGrid& src) {
    const Frame& f = src.frame;
    const Axis next = Axis((int(f.axis()) + 1) % 3);
    const int64_t W = f.width(), H = f.height(), D = f.depth();
    VoxelGrid dst{Frame::orthographic(f.box(), next, H, D, W), BitGrid(H, D, W)};
    const int64_t srcWpc = src.bits.wordsPerColumn(), dstWpc = dst.bits.wordsPerColumn();
    const uint64_t* in = src.bits.words();
    uint64_t* out = dst.bits.words();
    // One owner per (y, block of 64 x): writes go to target word x/64 of columns (y, s), disjoint.
    const int64_t xBlocks = (W + 63) / 64;
    parallelFor(0, H * xBlocks, 16, [&](int64_t b, int64_t e) {
        uint64_t block[64];
        for (int64_t t = b; t < e; ++t) {
            const int64_t y = t / xBlocks, xb = t % xBlocks;
            const int64_t x0 = xb * 64, nx = std::min<int64_t>(64, W - x0);
            for (int64_t sw = 0; sw < srcWpc; ++sw) {
                for (int64_t i = 0; i < 64; ++i) block[i] = i < nx ? in[(y * W + x0 + i) * srcWpc + sw] : 0;
                detail::transpose64(block);
                const int64_t s0 = sw * 64, ns = std::min<int64_t>(64, D - s0);
                for (int64_t j = 0; j < ns; ++j) out[((s0 + j) * H + y) * dstWpc + xb] = block[j];
            }
        }
    });
    return dst;
}
} // namespace

Vec3i VoxelGrid::worldDims() const {
    Vec3i d;
    d[columnXAxis(frame.axis())] = frame.width();
    d[columnYAxis(frame.axis())] = frame.height();
    d[sliceAxis(frame.axis())] = frame.depth();
    return d;
}

bool VoxelGrid::atWorldIndex(int64_t i, int64_t j, int64_t k) const {
    const Vec3i w{i, j, k};
    const Axis a = frame.axis();
    return bits.get(w[columnXAxis(a)], w[columnYAxis(a)], w[sliceAxis(a)]);
}

VoxelGrid reslice(const VoxelGrid& grid, Axis axis) {
    requireOrthographic(grid.frame, "re-slicing");
    const VoxelGrid uniform = grid.frame.slicing() == Slicing::Local ? resampleToUniform(grid) : VoxelGrid{};
    const VoxelGrid& src = grid.frame.slicing() == Slicing::Local ? uniform : grid;
    const int steps = (int(axis) - int(src.frame.axis()) + 3) % 3;
    if (steps == 0) return src;
    VoxelGrid once = resliceNext(src);
    return steps == 1 ? once : resliceNext(once);
}

VoxelGrid resampleToUniform(const VoxelGrid& grid) {
    requireOrthographic(grid.frame, "resampling to uniform slicing");
    if (grid.frame.slicing() == Slicing::Uniform) return grid;
    Frame uniformFrame = grid.frame;
    uniformFrame.setUniformSlicing();
    VoxelGrid out{uniformFrame, BitGrid(grid.frame.width(), grid.frame.height(), grid.frame.depth())};
    const int64_t D = grid.frame.depth();
    parallelFor(0, grid.frame.columnCount(), 1024, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            const DepthToSlice m = grid.frame.depthToSlice(c);
            const uint64_t* in = grid.bits.column(c);
            uint64_t* o = out.bits.column(c);
            for (int64_t s = 0; s < D; ++s) {
                const double t = m(double(s) + 0.5);
                if (!(t >= 0 && t < double(D))) continue;
                const auto ls = static_cast<int64_t>(t);
                if ((in[ls >> 6] >> (ls & 63)) & 1u) o[s >> 6] |= uint64_t(1) << (s & 63);
            }
        }
    });
    return out;
}

} // namespace voxfx
