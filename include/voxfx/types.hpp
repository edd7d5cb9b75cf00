// voxfx — the small shared types: the enums that options structs of several layers hold (slicing,
// coverage, voxelization modes and fills, the device, deep shadow map storage and filtering) with
// their names, and the defaults shared between headers. A header that only needs one of these (an
// options struct, voxfx/shadow_options.hpp, voxfx/glass_options.hpp, voxfx/render.hpp) includes
// this one instead of the header of the code that uses it; what each value does is documented
// there: Slicing in voxfx/frame.hpp, Coverage in voxfx/raster.hpp, VoxelizeMode and Fill in
// voxfx/voxelize.hpp, Device in voxfx/device.hpp, DsmStorage and DsmFilter in voxfx/dsm.hpp. Their
// toString and parse functions are declared beside that code.
//
// Thread-safety: constants.
#pragma once

#include <cstdint>

#include "voxfx/enum_names.hpp"

namespace voxfx {

/// How a frame's slices are placed along a column (voxfx/frame.hpp): one depth range for every
/// column, or each column its own (ED06's local slicing).
enum class Slicing : uint8_t { Uniform, Local };
inline constexpr EnumName<Slicing> kSlicingNames[] = {{"uniform", Slicing::Uniform},
                                                      {"local", Slicing::Local}};

/// Which pixels (columns) a triangle covers in the rasterizer (voxfx/raster.hpp).
enum class Coverage : uint8_t { Center, Conservative };
inline constexpr EnumName<Coverage> kCoverageNames[] = {{"center", Coverage::Center},
                                                        {"conservative", Coverage::Conservative}};

/// Voxelization modes (voxfx/voxelize.hpp).
enum class VoxelizeMode : uint8_t { Surface, Conservative, Solid, SolidConservative, Interior };
inline constexpr EnumName<VoxelizeMode> kVoxelizeModeNames[] = {
    {"surface", VoxelizeMode::Surface},
    {"conservative", VoxelizeMode::Conservative},
    {"solid", VoxelizeMode::Solid},
    {"solid-conservative", VoxelizeMode::SolidConservative},
    {"interior", VoxelizeMode::Interior}};
/// How the inside is decided (see voxfx/voxelize.hpp's file comment); Auto: Parity for a closed mesh, Flood
/// for any other (VoxelizeReport says which and why).
enum class Fill : uint8_t { Parity, Flood, Vote, Winding, Gwn, Auto };
inline constexpr EnumName<Fill> kFillNames[] = {{"auto", Fill::Auto},       {"parity", Fill::Parity},
                                                {"flood", Fill::Flood},     {"vote", Fill::Vote},
                                                {"winding", Fill::Winding}, {"gwn", Fill::Gwn}};

/// Cpu: always the CPU. Cuda: the GPU, else the CPU with a note saying why. Auto: the GPU when
/// one can take the job, else the CPU without a note.
enum class Device : uint8_t { Cpu, Cuda, Auto };
inline constexpr EnumName<Device> kDeviceNames[] = {
    {"cpu", Device::Cpu}, {"cuda", Device::Cuda}, {"auto", Device::Auto}};

/// Deep shadow map storage (voxfx/dsm.hpp): a fixed number of nodes per texel, or chunks of 64.
enum class DsmStorage : uint8_t { Fixed, Chunked };
inline constexpr EnumName<DsmStorage> kDsmStorageNames[] = {{"fixed", DsmStorage::Fixed},
                                                            {"chunked", DsmStorage::Chunked}};

/// How a lookup between texels filters (`--dsm-filter`): Bilinear weighs the visibility functions of
/// the four texels around the point (the paper's §3.2 filtering, a 2x2 PCF); None takes the one
/// texel the point falls in (the unfiltered lookup of the paper's table 1).
enum class DsmFilter : uint8_t { Bilinear, None };
inline constexpr EnumName<DsmFilter> kDsmFilterNames[] = {{"bilinear", DsmFilter::Bilinear},
                                                          {"none", DsmFilter::None}};

/// The crease angle flattenScene splits normals at by default, degrees (RenderOptions::creaseAngle).
inline constexpr double kDefaultCreaseAngle = 45;

} // namespace voxfx
