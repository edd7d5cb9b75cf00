// voxfx — grids as NumPy files (see voxfx/grid_io.hpp): .npy, the occupancy as a bool array indexed
// [x, y, z] in C order (np.load gives grid.to_numpy()), and .npz, a zip archive as
// np.savez_compressed writes it (deflate) holding that array as "occupancy" with the grid's
// placement: "origin" (the world corner of voxel (0, 0, 0)) and "cell_size", float64 (3,) each.
// The zip is written by hand (local headers, central directory, end record; zlib's raw deflate and
// CRC-32): NumPy reads any standard zip, and no zip library is a dependency.
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <zlib.h>

#include "io/grid_formats.hpp"
#include "voxfx/error.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

namespace {

/// The occupancy as bytes 0/1 in [x, y, z] C order (z fastest: one slicemap column at a time, the
/// grid sliced along z first when it is not; writeGrid made its slicing uniform).
std::vector<uint8_t> occupancyBytes(const VoxelGrid& grid) {
    const VoxelGrid resliced = grid.frame.axis() == Axis::Z ? VoxelGrid{} : reslice(grid, Axis::Z);
    const VoxelGrid& g = grid.frame.axis() == Axis::Z ? grid : resliced;
    const Vec3i d = g.worldDims();
    std::vector<uint8_t> out(std::size_t(d.x * d.y * d.z));
    parallelFor(0, d.x * d.y, 256, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            const int64_t x = c / d.y, y = c % d.y;
            const uint64_t* col = g.bits.column(x, y);
            uint8_t* dst = out.data() + c * d.z;
            for (int64_t s = 0; s < d.z; ++s) dst[s] = uint8_t((col[s >> 6] >> (s & 63)) & 1u);
        }
    });
    return out;
}

std::string npyShape(const Vec3i& d) {
    return "(" + std::to_string(d.x) + ", " + std::to_string(d.y) + ", " + std::to_string(d.z) + ")";
}

/// A whole .npy file in memory: header and data.
std::string npyBytes(const std::string& descr, const std::string& shape, const void* data,
                     std::size_t bytes) {
    std::ostringstream s;
    writeNpyHeader(s, descr, shape, false);
    s.write(static_cast<const char*>(data), std::streamsize(bytes));
    return std::move(s).str();
}

void put16(std::string& out, uint32_t v) {
    out += char(v & 0xFF);
    out += char((v >> 8) & 0xFF);
}
void put32(std::string& out, uint32_t v) {
    put16(out, v & 0xFFFF);
    put16(out, v >> 16);
}

/// Raw deflate (no zlib header: zip's method 8) of `in`.
std::string deflateRaw(const std::string& in) {
    z_stream z{};
    if (deflateInit2(&z, 6, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        fail("zlib: deflateInit2 failed");
    std::string out(deflateBound(&z, uLong(in.size())), '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
    z.avail_in = uInt(in.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    const int r = deflate(&z, Z_FINISH);
    const uLong written = z.total_out;
    deflateEnd(&z);
    if (r != Z_STREAM_END) fail("zlib: deflate failed (", r, ")");
    out.resize(written);
    return out;
}

struct ZipEntry {
    std::string name, data; // data uncompressed
};

/// A zip archive of deflated entries (no zip64: each entry and the archive below 4 GiB).
void writeZip(const std::vector<ZipEntry>& entries, std::ostream& out) {
    std::string central;
    uint64_t offset = 0;
    for (const ZipEntry& e : entries) {
        if (e.data.size() >= std::numeric_limits<uint32_t>::max())
            fail("a .npz entry of ", e.data.size(), " bytes needs zip64, which is not written: use .npy");
        const std::string packed = deflateRaw(e.data);
        const auto crc =
            uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(e.data.data()), uInt(e.data.size())));
        // Shared by the local header and the central directory: version needed 2.0, no flags,
        // deflate, time 00:00 and date 1980-01-01 (fixed, so the bytes depend on the grid alone).
        std::string common;
        put16(common, 20);
        put16(common, 0);
        put16(common, 8);
        put16(common, 0);
        put16(common, 0x21);
        put32(common, crc);
        put32(common, uint32_t(packed.size()));
        put32(common, uint32_t(e.data.size()));
        put16(common, uint32_t(e.name.size()));
        put16(common, 0); // extra field length
        std::string local;
        put32(local, 0x04034b50);
        local += common;
        local += e.name;
        out.write(local.data(), std::streamsize(local.size()));
        out.write(packed.data(), std::streamsize(packed.size()));
        put32(central, 0x02014b50);
        put16(central, 20); // version made by
        central += common;
        put16(central, 0); // comment length
        put16(central, 0); // disk number
        put16(central, 0); // internal attributes
        put32(central, 0); // external attributes
        put32(central, uint32_t(offset));
        central += e.name;
        offset += local.size() + packed.size();
        if (offset >= std::numeric_limits<uint32_t>::max())
            fail("the .npz archive exceeds 4 GiB, which needs zip64: use .npy");
    }
    std::string end;
    put32(end, 0x06054b50);
    put16(end, 0);
    put16(end, 0);
    put16(end, uint32_t(entries.size()));
    put16(end, uint32_t(entries.size()));
    put32(end, uint32_t(central.size()));
    put32(end, uint32_t(offset));
    put16(end, 0);
    out.write(central.data(), std::streamsize(central.size()));
    out.write(end.data(), std::streamsize(end.size()));
}

} // namespace

void writeGridNpy(const VoxelGrid& grid, std::ostream& out) {
    const std::vector<uint8_t> bytes = occupancyBytes(grid);
    writeNpyHeader(out, "|b1", npyShape(grid.worldDims()), false);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

void writeGridNpz(const VoxelGrid& grid, std::ostream& out) {
    const std::vector<uint8_t> bytes = occupancyBytes(grid);
    const Vec3d lo = grid.frame.box().lo, cell = grid.frame.cellSize();
    const double origin[3] = {lo.x, lo.y, lo.z}, size[3] = {cell.x, cell.y, cell.z};
    std::vector<ZipEntry> entries;
    entries.push_back(
        {"occupancy.npy", npyBytes("|b1", npyShape(grid.worldDims()), bytes.data(), bytes.size())});
    entries.push_back({"origin.npy", npyBytes("<f8", "(3,)", origin, sizeof(origin))});
    entries.push_back({"cell_size.npy", npyBytes("<f8", "(3,)", size, sizeof(size))});
    writeZip(entries, out);
}

} // namespace voxfx::detail
