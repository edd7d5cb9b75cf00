// voxfx — "a grid or a mesh" input for the grid tools: read a grid file, or load, fit and
// voxelize a mesh (declared in grid_io.hpp).
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
    VoxelizeReport report;
    VoxelizeOptions vo = options;
    if (!vo.report) vo.report = &report;
    VoxelGrid grid = voxelize(mesh.view(), fitFrame(computeBounds(mesh.view()), fit), vo);
    if (note && !vo.report->fillNote.empty()) *note = detail::concat(path, ": ", vo.report->fillNote);
    return grid;
}

} // namespace voxfx
