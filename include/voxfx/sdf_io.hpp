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
// Writes are atomic (a temporary file beside the target, renamed when complete). writeSdf of a mesh
// computes and writes in one call, streaming a .vdb brick by brick (peak memory: one copy of the
// band).
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

/// What writeSdf(mesh, ...) made: the field's description (frame, background, band, fill: every
/// member but its values, i.e. leaves and insideRuns are empty), its active voxel count, and the
/// seconds spent writing the file once the field was complete (the rest of the call computed it).
struct SdfWriteReport {
    SignedDistanceField field;
    int64_t activeCount = 0;
    double writeSeconds = 0;
};

/// Writes the field signedDistanceField(mesh, frame, options) to `path` (format from the
/// extension), the same file as writeSdf(signedDistanceField(mesh, frame, options), path) with the
/// same values, without keeping the whole field in memory where the format allows it: a .vdb is
/// streamed (each brick's blocks go into the file's OpenVDB tree as soon as they are made and are
/// freed, so the band is held once, in the tree, instead of as the field and then the tree); the
/// dense formats compute the field, then write it. The path and format are checked before the
/// work. Throws voxfx::Error as signedDistanceField and writeSdf do.
SdfWriteReport writeSdf(const MeshView& mesh, const Frame& frame, const SdfOptions& options,
                        const std::string& path, const SdfWriteOptions& writeOptions = {});

} // namespace voxfx
