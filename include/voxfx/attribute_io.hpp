// voxfx — writing attribute grids (voxfx/attribute_grid.hpp), so that CHANG's voxelization (which
// voxels a triangle wrote, their normals, materials and refraction indices) can be looked at in
// ParaView, Houdini or Blender.
//
//   .vdb   one OpenVDB grid per channel the grid holds, named as AttributeChannel: "count",
//          "absorption", "material", "ior" (FloatGrid) and "normal", "attenuation" (Vec3SGrid; the
//          normal is the unit average of the voxel's writes). The written voxels are active, the
//          others inactive at the background (material -1, the others 0). Index (i, j, k) is voxel
//          (i, j, k) along world x, y, z, and the transform maps it to the voxel's centre, as for
//          voxfx's occupancy and level-set .vdb files; the dimensions as Vec3i "voxfx_dims".
//   .nrrd  one channel (the grid must hold exactly one, or name it): count as uint16, material
//          as uint32 (4294967295 where nothing was written), the others as float32; normal and
//          attenuation as a 3-vector axis first. "space origin" is the centre of voxel (0, 0, 0).
//   .npy   one channel as .nrrd, shape (nx, ny, nz) or (3, nx, ny, nz), Fortran order (x fastest
//          after the components).
// The frame must be an axis-aligned orthographic grid with uniform slicing (any slicing axis).
// Writes are atomic (a temporary file beside the target, renamed when complete).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "voxfx/attribute_grid.hpp"
#include "voxfx/enum_names.hpp"

namespace voxfx {

/// One channel of an attribute grid, as files and the command line name it.
enum class AttributeChannel : uint8_t { Count, Absorption, Normal, Material, Ior, Attenuation };
inline constexpr EnumName<AttributeChannel> kAttributeChannelNames[] = {
    {"count", AttributeChannel::Count},
    {"absorption", AttributeChannel::Absorption},
    {"normal", AttributeChannel::Normal},
    {"material", AttributeChannel::Material},
    {"ior", AttributeChannel::Ior},
    {"attenuation", AttributeChannel::Attenuation},
    {"normals", AttributeChannel::Normal, true}};
const char* toString(AttributeChannel c);

/// "count,normal,ior" as the channels to store; voxfx::Error naming an unknown one (with the list)
/// or an empty list.
AttributeChannels parseAttributeChannels(const std::string& list);
/// The channels of `c` in kAttributeChannelNames order.
std::vector<AttributeChannel> channelList(const AttributeChannels& c);

/// Writes `grid` (format from the extension, see the file comment). `only`: the channel a .nrrd or
/// .npy holds (default: the grid's one channel); a .vdb holds only it when given. Throws
/// voxfx::Error naming the path for an unknown extension, a dense format with several channels
/// and none named, a channel the grid lacks, a frame that is not an axis-aligned uniform grid, or
/// a file that cannot be written.
void writeAttributeGrid(const AttributeGrid& grid, const std::string& path,
                        std::optional<AttributeChannel> only = std::nullopt);

} // namespace voxfx
