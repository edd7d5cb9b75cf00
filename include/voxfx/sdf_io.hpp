// voxfx — writing signed distance fields (voxfx/sdf.hpp): an OpenVDB level set, or dense floats.
//
//   .vdb   an OpenVDB FloatGrid of class level set (GRID_LEVEL_SET) named "sdf" (SdfWriteOptions),
//          background = the band width in world units, the active voxels the band's, inactive
//          tiles at -background inside; index (i, j, k) is voxel (i, j, k) and the transform maps
//          it to the voxel's centre (scale by the cell size, then translate by lo + cell / 2), as
//          for voxfx's occupancy .vdb files; the dimensions as Vec3i metadata "voxfx_dims".
//          Sparse: the file grows with the band, not with the grid.
//   .nrrd  float32 NRRD of every voxel (x fastest), "space origin" = the centre of voxel (0, 0, 0),
//          "space directions" = the cell sizes (as voxfx's uint8 NRRD grids).
//   .npy   float32 NumPy array of shape (nx, ny, nz), indexed [i, j, k] (Fortran order: x fastest
//          in the file, no transpose on either side); the grid's placement is not in the file.
// The dense formats hold every voxel (4 bytes each): for grids that fit in memory (checked first).
// Writes are atomic (a temporary file beside the target, renamed when complete).
// Thread-safety: writes of different paths may run concurrently.
#pragma once

#include <cstdint>
#include <string>

#include "voxfx/enum_names.hpp"
#include "voxfx/sdf.hpp"

namespace voxfx {

enum class SdfFormat : uint8_t { Vdb, Nrrd, Npy };
inline constexpr EnumName<SdfFormat> kSdfFormatNames[] = {
    {"vdb", SdfFormat::Vdb}, {"nrrd", SdfFormat::Nrrd}, {"npy", SdfFormat::Npy}};
const char* toString(SdfFormat f);
/// Format from the extension (.vdb .nrrd .npy, any case); voxfx::Error listing them otherwise.
SdfFormat sdfFormatFromPath(const std::string& path);

struct SdfWriteOptions {
    std::string gridName = "sdf"; ///< .vdb: the grid's name
};

/// Writes `field` (format from the extension, see the file comment). Throws voxfx::Error naming
/// the path when it cannot be written, or when a dense format does not fit in memory.
void writeSdf(const SignedDistanceField& field, const std::string& path, const SdfWriteOptions& options = {});

} // namespace voxfx
