// voxfx — "a grid or a mesh" input for the grid tools: read a grid file, or load, fit and
// voxelize a mesh (I/O, so it lives in io/ although voxelize.hpp declares it).
#include <string>

#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

bool isGridFile(const std::string& path) {
    const std::string ext = fileExtension(path);
    return ext == ".binvox" || ext == ".vdb" || ext == ".nrrd";
}

VoxelGrid loadOrVoxelize(const std::string& path, const FitOptions& fit, const VoxelizeOptions& options,
                         std::string* note) {
    if (note) note->clear();
    if (isGridFile(path)) return readGrid(path);
    const Mesh mesh = loadMesh(path);
    VoxelizeOptions vo = options;
    const bool needsInside = vo.mode == VoxelizeMode::Solid || vo.mode == VoxelizeMode::SolidConservative ||
                             vo.mode == VoxelizeMode::Interior;
    if (needsInside && vo.fill == Fill::Parity) {
        const MeshTopology topo = analyzeTopology(mesh.view());
        if (!topo.closed()) {
            vo.fill = Fill::Flood;
            if (note)
                *note = detail::concat(path, " is not closed (", topo.boundaryEdges, " boundary, ",
                                       topo.nonManifoldEdges, " non-manifold edges): filled by flood");
        }
    }
    return voxelize(mesh.view(), fitFrame(computeBounds(mesh.view()), fit), vo);
}

} // namespace voxfx
