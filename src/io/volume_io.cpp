// voxfx — loadVolume: picks the reader by extension (then by magic bytes), and what the readers
// share: reading the file, gzip, and decoding samples of any scalar type and endianness.
#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string_view>

#include <zlib.h>

#include "io/volume_formats.hpp"
#include "voxfx/bitgrid.hpp"

namespace voxfx {

namespace detail {

std::vector<uint8_t> readVolumeFile(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) fail(path, ": cannot read file: it is a directory");
    // A header names its data file (NRRD "data file", raw + JSON "file"): a device or a pipe
    // there would be read without end (/dev/zero) or block (a FIFO), so only regular files.
    const auto status = std::filesystem::status(path, ec);
    if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
        fail(path, ": cannot read file: not a regular file (a device, pipe or socket)");
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, ": cannot open file: ", errno ? std::strerror(errno) : "unknown error");
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    if (size < 0) fail(path, ": cannot read file: cannot determine its size");
    in.seekg(0, std::ios::beg);
    std::vector<uint8_t> bytes(static_cast<std::size_t>(size));
    in.read(reinterpret_cast<char*>(bytes.data()), size);
    if (in.gcount() != size)
        fail(path, ": cannot read file: ", errno ? std::strerror(errno) : "it got shorter while reading");
    return bytes;
}

bool isGzip(std::span<const uint8_t> bytes) {
    return bytes.size() >= 2 && bytes[0] == 0x1f && bytes[1] == 0x8b;
}

uint64_t maxInflatedBytes(uint64_t compressedBytes) {
    // zlib's documented worst case for deflate is a ratio of 1032:1 (258-byte matches coded in one
    // bit each); 1 KiB covers headers and a tiny stream.
    return compressedBytes * 1032 + 1024;
}

struct GzipStream::State {
    z_stream z{};
    std::size_t remaining = 0; ///< input not yet handed to zlib (avail_in is 32-bit)
    bool ended = false;        ///< the last member has ended and no input follows
};

GzipStream::GzipStream(std::span<const uint8_t> compressed, std::string path)
    : state_(std::make_unique<State>()), path_(std::move(path)) {
    z_stream& z = state_->z;
    z.next_in = const_cast<Bytef*>(compressed.data());
    z.avail_in = 0;
    // 15 + 32: a window of 32 KiB, gzip or zlib header detected automatically.
    if (inflateInit2(&z, 15 + 32) != Z_OK) fail(path_, ": cannot start gzip decompression (zlib)");
    // avail_in is 32-bit: feed large inputs in slices (see read()).
    z.avail_in = uInt(std::min<std::size_t>(compressed.size(), std::numeric_limits<uInt>::max()));
    state_->remaining = compressed.size() - z.avail_in;
}

GzipStream::~GzipStream() { inflateEnd(&state_->z); }

std::size_t GzipStream::read(uint8_t* dst, std::size_t n) {
    z_stream& z = state_->z;
    std::size_t produced = 0;
    while (produced < n && !state_->ended) {
        if (z.avail_in == 0 && state_->remaining > 0) {
            z.avail_in = uInt(std::min<std::size_t>(state_->remaining, std::numeric_limits<uInt>::max()));
            state_->remaining -= z.avail_in;
        }
        const std::size_t want = std::min<std::size_t>(n - produced, std::numeric_limits<uInt>::max());
        z.next_out = dst + produced;
        z.avail_out = uInt(want);
        const int rc = inflate(&z, Z_NO_FLUSH);
        produced += want - z.avail_out;
        if (rc == Z_STREAM_END) {
            // Concatenated members (gzip allows them) continue the data.
            if (z.avail_in == 0 && state_->remaining == 0) {
                state_->ended = true;
            } else if (inflateReset(&z) != Z_OK) {
                fail(path_, ": gzip data is corrupt (cannot restart after a member)");
            }
        } else if (rc == Z_DATA_ERROR || rc == Z_NEED_DICT) {
            fail(path_, ": gzip data is corrupt (zlib: ", z.msg ? z.msg : "invalid data", ")");
        } else if (rc == Z_MEM_ERROR) {
            fail(path_, ": out of memory while inflating gzip data");
        } else if (rc == Z_BUF_ERROR ||
                   (rc == Z_OK && z.avail_in == 0 && state_->remaining == 0 && z.avail_out > 0)) {
            // No progress possible: the input ran out before the stream's end.
            if (z.avail_in == 0 && state_->remaining == 0)
                fail(path_, ": gzip data is truncated (the stream ends before its end marker)");
        } else if (rc != Z_OK) {
            fail(path_, ": gzip data is corrupt (zlib error ", rc, ")");
        }
    }
    return produced;
}

std::vector<uint8_t> inflateUpTo(GzipStream& in, uint64_t expected, std::vector<uint8_t> prefix) {
    std::vector<uint8_t> out = std::move(prefix);
    std::size_t have = std::min<std::size_t>(out.size(), std::size_t(expected));
    out.resize(have);
    while (have < expected) {
        // Doubling from 1 MiB: amortized linear, and never more than twice what was inflated.
        const auto next =
            std::size_t(std::min<uint64_t>(expected, std::max<uint64_t>(uint64_t(1) << 20, 2 * have)));
        out.resize(next);
        have += in.read(out.data() + have, next - have);
        if (have < next) break;
    }
    out.resize(have);
    return out;
}

std::vector<uint8_t> inflateExactly(std::span<const uint8_t> compressed, uint64_t expected,
                                    const std::string& path) {
    if (expected > maxInflatedBytes(compressed.size()))
        fail(path, ": header declares ", expected, " bytes of samples, more than ", compressed.size(),
             " bytes of gzip data can hold (truncated or wrong sizes?)");
    GzipStream in(compressed, path);
    std::vector<uint8_t> out = inflateUpTo(in, expected);
    if (out.size() < expected)
        fail(path, ": gzip data is truncated: it inflates to ", out.size(), " of the ", expected,
             " bytes of samples the header declares");
    uint8_t extra[1];
    if (in.read(extra, 1) != 0)
        fail(path, ": gzip data inflates to more than the ", expected,
             " bytes of samples the header declares (wrong sizes or type?)");
    return out;
}

void checkVolumeMemory(const Vec3i& dims, uint64_t bufferBytes, const std::string& path) {
    const uint64_t voxels = uint64_t(dims.x) * uint64_t(dims.y) * uint64_t(dims.z); // <= 2^40, checked
    const std::string what = concat(path, ": a volume of ", dims.x, " x ", dims.y, " x ", dims.z, " voxels");
    checkMemory(voxels * sizeof(float) + bufferBytes, what.c_str());
}

uint64_t checkedSampleBytes(const Vec3i& dims, ScalarType type, const std::string& path) {
    if (dims.x < 1 || dims.y < 1 || dims.z < 1)
        fail(path, ": volume dimensions must be at least 1, got ", dims.x, " x ", dims.y, " x ", dims.z);
    if (dims.x > kMaxVolumeVoxels || dims.y > kMaxVolumeVoxels / dims.x ||
        dims.z > kMaxVolumeVoxels / (dims.x * dims.y))
        fail(path, ": volume of ", dims.x, " x ", dims.y, " x ", dims.z,
             " voxels is larger than the limit of 2^40 voxels");
    return uint64_t(dims.x * dims.y * dims.z) * uint64_t(scalarBytes(type));
}

namespace {

template <class T> T loadSample(const uint8_t* p, bool swap) {
    uint8_t b[sizeof(T)];
    std::memcpy(b, p, sizeof(T));
    if (swap) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
}

template <class T> void decodeAs(const uint8_t* data, bool swap, Volume& volume, const std::string& path) {
    std::vector<float>& out = volume.values();
    const std::size_t n = out.size();
    for (std::size_t idx = 0; idx < n; ++idx) {
        const T v = loadSample<T>(data + idx * sizeof(T), swap);
        if constexpr (std::is_floating_point_v<T>) {
            if (!std::isfinite(v) || std::fabs(double(v)) > double(std::numeric_limits<float>::max())) {
                const Vec3i d = volume.dims();
                const auto i = int64_t(idx) % d.x, j = int64_t(idx) / d.x % d.y,
                           k = int64_t(idx) / (d.x * d.y);
                fail(path, ": sample of voxel (", i, ", ", j, ", ", k, ") is ",
                     std::isnan(v) ? "NaN" : (std::isinf(v) ? "infinite" : "beyond the range of float"), " (",
                     toString(volume.sourceType()), " data must be finite)");
            }
        }
        out[idx] = float(v);
    }
}

} // namespace

void decodeSamples(const uint8_t* data, ScalarType type, bool bigEndian, Volume& volume,
                   const std::string& path) {
    const bool swap = bigEndian != (std::endian::native == std::endian::big);
    switch (type) {
    case ScalarType::UInt8:
        return decodeAs<uint8_t>(data, false, volume, path);
    case ScalarType::Int8:
        return decodeAs<int8_t>(data, false, volume, path);
    case ScalarType::UInt16:
        return decodeAs<uint16_t>(data, swap, volume, path);
    case ScalarType::Int16:
        return decodeAs<int16_t>(data, swap, volume, path);
    case ScalarType::UInt32:
        return decodeAs<uint32_t>(data, swap, volume, path);
    case ScalarType::Int32:
        return decodeAs<int32_t>(data, swap, volume, path);
    case ScalarType::Float32:
        return decodeAs<float>(data, swap, volume, path);
    case ScalarType::Float64:
        return decodeAs<double>(data, swap, volume, path);
    }
}

void flipAxis(Volume& volume, int axis) {
    const Vec3i d = volume.dims();
    for (int64_t k = 0; k < d.z; ++k)
        for (int64_t j = 0; j < d.y; ++j)
            for (int64_t i = 0; i < d.x; ++i) {
                const Vec3i a{i, j, k};
                Vec3i b = a;
                b[axis] = d[axis] - 1 - a[axis];
                if (b[axis] > a[axis]) std::swap(volume.at(a.x, a.y, a.z), volume.at(b.x, b.y, b.z));
            }
}

} // namespace detail

const char* toString(VolumeFormat f) { return enumName(f, kVolumeFormatNames); }

namespace {

std::string lowerName(const std::string& path) {
    std::string name = std::filesystem::path(path).filename().string();
    for (char& c : name) c = char(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    return name;
}

bool startsWith(std::span<const uint8_t> bytes, std::string_view magic) {
    return bytes.size() >= magic.size() && std::memcmp(bytes.data(), magic.data(), magic.size()) == 0;
}

} // namespace

Volume loadVolume(const std::string& path, VolumeLoadReport* report) { return loadVolume(path, {}, report); }

Volume loadVolume(const std::string& path, const VolumeLoadOptions& options, VolumeLoadReport* report) {
    VolumeLoadReport local;
    VolumeLoadReport& r = report ? *report : local;
    const std::string name = lowerName(path);
    if (name.ends_with(".vdb")) {
        r.format = VolumeFormat::Vdb;
        std::vector<uint8_t> bytes = detail::readVolumeFile(path);
        return detail::readVdbVolume(bytes, path, options.vdbGrid, r, &bytes);
    }
    if (!options.vdbGrid.empty()) fail(path, ": a grid name is only for .vdb files");
    const std::vector<uint8_t> bytes = detail::readVolumeFile(path);
    r.fileBytes = bytes.size();
    const std::span<const uint8_t> all(bytes);

    enum class Kind { kUnknown, kInr, kNrrd, kJson } kind = Kind::kUnknown;
    if (name.ends_with(".inr") || name.ends_with(".inr.gz"))
        kind = Kind::kInr;
    else if (name.ends_with(".nrrd") || name.ends_with(".nhdr"))
        kind = Kind::kNrrd;
    else if (name.ends_with(".json"))
        kind = Kind::kJson;
    else if (startsWith(all, "#INRIMAGE") || detail::isGzip(all))
        kind = Kind::kInr; // gzip without a known extension: CGAL's images are the gzipped volumes we meet
    else if (startsWith(all, "NRRD"))
        kind = Kind::kNrrd;
    if (kind == Kind::kUnknown)
        fail(path,
             ": unknown volume format (known: .inr, .inr.gz, .nrrd, .nhdr, .vdb, and raw samples described "
             "by a .json header)");
    switch (kind) {
    case Kind::kInr:
        r.format = VolumeFormat::Inr;
        return detail::readInr(all, path, r);
    case Kind::kNrrd:
        r.format = VolumeFormat::Nrrd;
        return detail::readScalarNrrd(all, path, r);
    default:
        r.format = VolumeFormat::RawJson;
        return detail::readRawJson(all, path, r);
    }
}

} // namespace voxfx
