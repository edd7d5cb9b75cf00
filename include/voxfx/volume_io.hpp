// voxfx — reading scalar volumes and transfer functions.
//
// Readers (loadVolume) pick the format by extension, then by magic bytes:
//   .inr, .inr.gz   INRIMAGE-4 (CGAL's images); TX/TY/TZ is the centre of voxel (0, 0, 0), as in
//                   CGAL's ImageIO, and 0 when absent, so meshes CGAL makes from the image line up
//   .nrrd, .nhdr    NRRD scalar volumes (raw or gzip encoding, either endian, attached or one
//                   detached data file); "space origin" is the centre of voxel (0, 0, 0); without
//                   it the box starts at 0, as voxfx's NRRD grid reader does
//   .json           raw samples described by a JSON header:
//                   {"file": "ct.raw", "dims": [nx, ny, nz], "type": "uint16",
//                    "endian": "little", "spacing": [sx, sy, sz], "origin": [x, y, z],
//                    "offset": 0, "encoding": "raw"}
//                   "origin" is the centre of voxel (0, 0, 0) (box from 0 without it), "file"
//                   is relative to the JSON file, "offset" skips a header of that many bytes,
//                   "encoding": "gzip" inflates the file first
//   .vdb            OpenVDB: the first float or double grid, or the one named by
//                   VolumeLoadOptions::vdbGrid; the dense box is the grid's stored dimensions
//                   (voxfx's "voxfx_dims" metadata) or else the bounding box of its active voxels,
//                   and every voxel there gets the grid's value (active or not: the background
//                   where nothing is stored). The transform must be linear with orthogonal index
//                   axes (scale per axis, rotation, mirror, translation): index (i, j, k) is the
//                   centre of voxel (i, j, k) of that box, and a rotated grid gives a turned volume
//                   (Volume::setAxes); sheared and non-linear transforms are refused. Read through
//                   the voxfx_vdb module, which checks the file's structure before OpenVDB reads it.
// Every header is checked against the bytes the file holds before anything is allocated, and a
// NaN or infinite sample is an error: voxfx::Error names the file and what is wrong.
#pragma once

#include <cstdint>
#include <string>

#include "voxfx/enum_names.hpp"
#include "voxfx/transfer_function.hpp"
#include "voxfx/volume.hpp"

namespace voxfx {

/// File format of a volume.
enum class VolumeFormat : uint8_t { Inr, Nrrd, RawJson, Vdb };
inline constexpr EnumName<VolumeFormat> kVolumeFormatNames[] = {{"inr", VolumeFormat::Inr},
                                                                {"nrrd", VolumeFormat::Nrrd},
                                                                {"raw+json", VolumeFormat::RawJson},
                                                                {"vdb", VolumeFormat::Vdb}};
const char* toString(VolumeFormat f);

/// What loadVolume found besides the volume.
struct VolumeLoadReport {
    VolumeFormat format = VolumeFormat::Inr;
    bool gzip = false;      ///< the samples were gzip-compressed
    uint64_t fileBytes = 0; ///< size of the file named (the header for a detached NRRD or JSON)
    std::string gridName;   ///< .vdb: the grid read
    std::string gridClass;  ///< .vdb: its class ("fog volume", "level set", ...)
};

/// How loadVolume reads a file.
struct VolumeLoadOptions {
    /// .vdb: the name of the grid to read; empty reads the first float or double grid.
    std::string vdbGrid;
};

/// Reads a scalar volume (see the file comment for the formats). Throws voxfx::Error naming the
/// file and the problem.
Volume loadVolume(const std::string& path, VolumeLoadReport* report = nullptr);
Volume loadVolume(const std::string& path, const VolumeLoadOptions& options,
                  VolumeLoadReport* report = nullptr);

/// Reads a transfer function's JSON file (format: voxfx/transfer_function.hpp).
TransferFunction loadTransferFunction(const std::string& path);

} // namespace voxfx
