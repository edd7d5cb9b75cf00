// voxfx — internal to io/: the volume readers behind loadVolume and what they share (gzip,
// sample decoding, file reading).
//
// Each reader gets the whole file in memory and the path for its messages. Sizes from headers
// are checked against the bytes the file holds (or, compressed, can hold) before the volume is
// allocated.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "voxfx/volume_io.hpp"

namespace voxfx::detail {

/// The whole file as bytes; throws voxfx::Error naming the path when it cannot be read.
std::vector<uint8_t> readVolumeFile(const std::string& path);

/// True when the bytes start with the gzip magic (1f 8b).
bool isGzip(std::span<const uint8_t> bytes);

/// Largest ratio of output to input that deflate can reach (about 1032:1), plus room for the
/// gzip header: a header that claims more output than this is lying before anything is inflated.
uint64_t maxInflatedBytes(uint64_t compressedBytes);

/// A gzip (or zlib) stream inflated piece by piece. Errors (corrupt or truncated data) throw
/// voxfx::Error naming `path`.
class GzipStream {
public:
    GzipStream(std::span<const uint8_t> compressed, std::string path);
    ~GzipStream();
    GzipStream(const GzipStream&) = delete;
    GzipStream& operator=(const GzipStream&) = delete;

    /// Inflates up to n bytes into dst and returns how many it wrote: fewer than n only at the end
    /// of the data (the end of the last gzip member).
    std::size_t read(uint8_t* dst, std::size_t n);

private:
    struct State;
    std::unique_ptr<State> state_;
    std::string path_;
};

/// Inflates up to `expected` bytes after the `prefix` already inflated, growing the buffer with
/// what the stream really holds: a header that claims more than the data costs no more memory
/// than the data. Returns fewer bytes only when the stream ends first.
std::vector<uint8_t> inflateUpTo(GzipStream& in, uint64_t expected, std::vector<uint8_t> prefix = {});

/// Inflates exactly `expected` bytes of samples; throws when the stream holds fewer or more.
std::vector<uint8_t> inflateExactly(std::span<const uint8_t> compressed, uint64_t expected,
                                    const std::string& path);

/// The number of bytes a volume of `dims` samples of `type` needs; throws (naming the path) for
/// dimensions < 1 or above kMaxVolumeVoxels voxels.
uint64_t checkedSampleBytes(const Vec3i& dims, ScalarType type, const std::string& path);

/// Throws (naming the path) when a volume of `dims` (4 bytes a voxel) plus `bufferBytes` of
/// buffers alive beside it needs more memory than the machine has available.
void checkVolumeMemory(const Vec3i& dims, uint64_t bufferBytes, const std::string& path);

/// Converts the samples (x fastest) to the volume's floats, swapping bytes when the file's
/// endianness is not the host's. Throws (naming the path and the voxel) for a NaN or infinite
/// sample, or a double beyond float's range.
void decodeSamples(const uint8_t* data, ScalarType type, bool bigEndian, Volume& volume,
                   const std::string& path);

/// Reverses the voxel order along `axis` (for files whose axis runs towards negative world
/// coordinates).
void flipAxis(Volume& volume, int axis);

Volume readInr(std::span<const uint8_t> bytes, const std::string& path, VolumeLoadReport& report);
Volume readScalarNrrd(std::span<const uint8_t> bytes, const std::string& path, VolumeLoadReport& report);
Volume readRawJson(std::span<const uint8_t> bytes, const std::string& path, VolumeLoadReport& report);
/// The float or double grid `gridName` (the first one when empty) of a .vdb file's bytes, through
/// the voxfx_vdb module (which checks them before OpenVDB reads them from memory).
/// `release` as for readVdb: the buffer holding `bytes`, emptied once they are parsed.
Volume readVdbVolume(std::span<const uint8_t> bytes, const std::string& path, const std::string& gridName,
                     VolumeLoadReport& report, std::vector<uint8_t>* release = nullptr);

} // namespace voxfx::detail
