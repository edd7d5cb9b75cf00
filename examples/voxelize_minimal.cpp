// The smallest useful voxfx program: load a mesh, voxelize it solid at 128 cells along its longest
// side, ask a few questions of the grid, write it (here as an OpenVDB file) and read it back.
//
//   build/voxelize_minimal data/meshes/bunny00.off bunny.vdb
#include <cstdio>

#include "voxfx/voxfx.hpp"

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s MESH OUT.{vdb,binvox,nrrd,ply}\n", argv[0]);
        return 2;
    }
    try {
        // Loaders validate (NaN coordinates, bad indices, truncated files) and throw voxfx::Error.
        const voxfx::Mesh mesh = voxfx::loadMesh(argv[1]);

        // A frame places the grid in the world: here an orthographic box fitted to the mesh, with
        // cubic cells, 128 along the longest side, sliced along z (columns are (x, y)).
        voxfx::FitOptions fit;
        fit.resolution = 128;
        const voxfx::Frame frame = voxfx::fitFrame(voxfx::computeBounds(mesh.view()), fit);

        // Solid voxelization: a cell is filled when its centre is inside the (closed) mesh.
        voxfx::VoxelizeOptions options;
        options.mode = voxfx::VoxelizeMode::Solid;
        const voxfx::VoxelGrid grid = voxfx::voxelize(mesh.view(), frame, options);

        // The bits are a slicemap: one 64-bit word holds 64 slices of a column.
        const voxfx::Vec3i dims = grid.worldDims();
        const voxfx::Vec3d cell = frame.cellSize();
        std::printf("%lld x %lld x %lld cells, %lld filled, volume %.6g\n", (long long)dims.x,
                    (long long)dims.y, (long long)dims.z, (long long)grid.bits.count(),
                    double(grid.bits.count()) * cell.x * cell.y * cell.z);
        std::printf("centre voxel filled: %s\n",
                    grid.atWorldIndex(dims.x / 2, dims.y / 2, dims.z / 2) ? "yes" : "no");

        // Written atomically: a temporary file beside the target, renamed when complete.
        voxfx::writeGrid(grid, argv[2]);

        // Read back (binvox, vdb and nrrd are readable): the same cells.
        const voxfx::GridFormat format = voxfx::gridFormatFromPath(argv[2]);
        if (format != voxfx::GridFormat::Ply && format != voxfx::GridFormat::Obj) {
            const voxfx::VoxelGrid back = voxfx::readGrid(argv[2]);
            std::printf("read back %s: %lld filled\n", argv[2], (long long)back.bits.count());
            if (back.bits.count() != grid.bits.count()) return 1;
        }
    } catch (const voxfx::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
