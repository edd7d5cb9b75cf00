// voxfx — memory made ready ahead of a voxelization, so that the first voxelization in a process
// does not pay the kernel for zeroing its pages (see prepareVoxelizeMemory).
#pragma once

#include <cstdint>
#include <memory>

namespace voxfx {

/// Memory made ready ahead of the voxelizations of a process (prepareVoxelizeMemory). Move-only;
/// destroying it waits for the preparation and unmaps what no voxelization took.
class PreparedMemory {
public:
    PreparedMemory() noexcept;
    PreparedMemory(PreparedMemory&&) noexcept;
    PreparedMemory& operator=(PreparedMemory&&) noexcept;
    ~PreparedMemory();
    /// Waits until the preparation has finished (at once when it has).
    void wait();
    /// Waits, then unmaps what no voxelization has taken (later voxelizations map fresh memory).
    void release() noexcept;

private:
    friend PreparedMemory prepareVoxelizeMemory(uint64_t bytes);
    struct State;
    std::unique_ptr<State> state_;
};

/// The bytes a voxelization into a grid of at most w x h x d cells maps in large blocks, about: the
/// grid in whole 2 MiB pages and 24 MiB for the rasterizer's and the closed-mesh test's temporaries
/// (meshes of up to a few hundred thousand triangles; a larger one maps the rest fresh).
uint64_t voxelizeMemoryBound(int64_t w, int64_t h, int64_t d);

/// The first voxelization in a process pays the kernel for zeroing its grid's fresh pages on
/// their first touch (on a virtual machine a third of a cold 512^3 voxelize step). This maps
/// `bytes` and touches them on a background thread and returns at once; the voxelizations that
/// follow take their grids and temporaries from that memory while it lasts. A program that loads
/// its mesh first calls it before the load, so that the zeroing runs beside the load on another
/// core, and wait()s before voxelizing (`voxfx voxelize` does, sized by voxelizeMemoryBound for the
/// resolution asked). A preparation that cannot map its memory leaves nothing prepared (the
/// voxelization then maps its own and reports a shortage itself).
PreparedMemory prepareVoxelizeMemory(uint64_t bytes);

} // namespace voxfx
