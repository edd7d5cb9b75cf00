// voxfx — NRRD reader and writer.
//
// Format: Teem's NRRD (http://teem.sourceforge.net/nrrd/format.html), version NRRD0004: an
// ASCII header of "field: value" lines ended by a blank line, then raw uint8 samples with the
// first axis fastest. Sample (i, j, k) of an orthogonal grid sits at
//     space origin + i * dir0 + j * dir1 + k * dir2
// so "space origin" is the centre of voxel (0, 0, 0) and the space directions are the cell
// sizes. We write "space: right-anterior-superior" and read any 3D space, taking its
// coordinates as our world coordinates (no LPS/RAS flip).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "io/grid_formats.hpp"
#include "io/nrrd_header.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx::detail {

namespace {
// kByteBits[v]: byte b of the entry is bit b of v, so 8 voxels expand with one 8-byte copy.
struct ByteExpandTable {
    uint64_t entry[256];
    constexpr ByteExpandTable() : entry{} {
        for (int v = 0; v < 256; ++v)
            for (int b = 0; b < 8; ++b)
                if ((v >> b) & 1) entry[v] |= uint64_t(1) << (8 * b);
    }
};
constexpr ByteExpandTable kByteBits;

// One bit per byte: bit b of the result is (byte b of x != 0).
inline uint64_t packNonzeroBytes(uint64_t x) {
    // OR each byte's bits into its bit 0 (spill into higher bits of a byte is masked away):
    //   byte: b7 .. b0  ->  bit 0 = b7 | ... | b0
    x |= x >> 4;
    x |= x >> 2;
    x |= x >> 1;
    x &= 0x0101010101010101ull;
    // Gather the eight bit-0s into the top byte (distinct partial products, no carries):
    //   byte k's bit 0 times 2^(7 * (7 - k) + 7) lands on bit 56 + k.
    return (x * 0x0102040810204080ull) >> 56;
}
} // namespace

namespace {

void writeNrrdHeader(const Frame& frame, const Vec3i& n, std::ostream& out) {
    const Vec3d cell = frame.cellSize();
    const Vec3d origin = frame.box().lo + cell * 0.5;
    auto fmt = [](double v) { return formatDouble(v); };
    out << "NRRD0004\n"
        << "# Complete NRRD file format specification at:\n"
        << "# http://teem.sourceforge.net/nrrd/format.html\n"
        << "# voxfx voxel grid: 1 = filled, 0 = empty\n"
        << "type: uchar\n"
        << "dimension: 3\n"
        << "space: right-anterior-superior\n"
        << "sizes: " << n.x << ' ' << n.y << ' ' << n.z << '\n'
        << "space directions: (" << fmt(cell.x) << ",0,0) (0," << fmt(cell.y) << ",0) (0,0," << fmt(cell.z)
        << ")\n"
        << "kinds: domain domain domain\n"
        << "endian: little\n"
        << "encoding: raw\n"
        << "space origin: (" << fmt(origin.x) << ',' << fmt(origin.y) << ',' << fmt(origin.z) << ")\n\n";
}

// Sliced along x, columns run along (y, z): column c = z * ny + y holds the bits of x, so
// the columns in memory order are NRRD's rows, each expanded to nx bytes.
void writeNrrdRows(const BitGrid& xSliced, std::ostream& out) {
    const int64_t nx = xSliced.depth(), columns = xSliced.columnCount();
    const int64_t batch = std::max<int64_t>(1, (int64_t(16) << 20) / nx);
    std::vector<uint8_t> buf(size_t(std::min(batch, columns) * nx));
    for (int64_t c0 = 0; c0 < columns; c0 += batch) {
        const int64_t c1 = std::min(columns, c0 + batch);
        parallelFor(c0, c1, 256, [&](int64_t b, int64_t e) {
            for (int64_t c = b; c < e; ++c) {
                const uint64_t* col = xSliced.column(c);
                uint8_t* dst = buf.data() + (c - c0) * nx;
                for (int64_t x = 0; x < nx; x += 8) {
                    const uint64_t bytes = kByteBits.entry[(col[x >> 6] >> (x & 63)) & 0xFF];
                    std::memcpy(dst + x, &bytes, size_t(std::min<int64_t>(8, nx - x)));
                }
            }
        });
        out.write(reinterpret_cast<const char*>(buf.data()), std::streamsize((c1 - c0) * nx));
    }
}

} // namespace

void writeNrrd(const VoxelGrid& grid, std::ostream& out) {
    writeNrrdHeader(grid.frame, grid.worldDims(), out);
    writeNrrdRows(reslice(grid, Axis::X).bits, out);
}

void writeNrrdSlabs(const Frame& frame, const Vec3i& n, int64_t slab,
                    const std::function<VoxelGrid(int64_t, int64_t)>& cells, std::ostream& out) {
    writeNrrdHeader(frame, n, out);
    for (int64_t z0 = 0; z0 < n.z; z0 += slab) {
        const VoxelGrid g = cells(z0, std::min(n.z, z0 + slab));
        writeNrrdRows(g.frame.axis() == Axis::X ? g.bits : reslice(g, Axis::X).bits, out);
    }
}

namespace {
constexpr size_t kMaxHeaderBytes = size_t(1) << 16;

using nrrd::parseNumber;
using nrrd::parseVector;
using nrrd::trim;
} // namespace

VoxelGrid readNrrd(std::span<const uint8_t> bytes) {
    const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    if (all.substr(0, 7) != "NRRD000" || all.size() < 9 || all[7] < '1' || all[7] > '5')
        fail("not a NRRD file (it does not start with NRRD0001..NRRD0005)");
    size_t pos = all.find('\n');
    if (pos == std::string_view::npos) fail("NRRD header is truncated");
    ++pos;

    int64_t sizes[3] = {0, 0, 0};
    bool haveSizes = false, haveDirections = false, haveSpacings = false, haveOrigin = false;
    Vec3d dirs[3], spacings{1, 1, 1}, origin{0, 0, 0};
    bool headerDone = false;
    while (!headerDone) {
        if (pos >= all.size()) fail("NRRD header is truncated (no blank line before the data)");
        if (pos > kMaxHeaderBytes) fail("NRRD header is longer than ", kMaxHeaderBytes, " bytes");
        size_t eol = all.find('\n', pos);
        if (eol == std::string_view::npos) fail("NRRD header is truncated (no blank line before the data)");
        const std::string_view line = trim(all.substr(pos, eol - pos));
        pos = eol + 1;
        if (line.empty()) {
            headerDone = true;
            continue;
        }
        if (line.front() == '#') continue;
        if (line.find(":=") != std::string_view::npos) continue; // key/value pairs carry no geometry
        const size_t colon = line.find(": ");
        if (colon == std::string_view::npos) fail("NRRD header line without 'field: value': '", line, "'");
        const std::string_view field = line.substr(0, colon);
        std::string_view value = trim(line.substr(colon + 2));
        if (field == "type") {
            if (value != "uchar" && value != "unsigned char" && value != "uint8" && value != "uint8_t" &&
                value != "signed char" && value != "int8" && value != "int8_t")
                fail("NRRD type '", value, "' is not supported (supported: uchar, signed char)");
        } else if (field == "dimension") {
            int d = 0;
            if (!parseNumber(value, d) || d != 3) fail("NRRD dimension must be 3, got '", value, "'");
        } else if (field == "sizes") {
            for (int64_t& s : sizes)
                if (!parseNumber(value, s) || s <= 0 || s > (int64_t(1) << 20))
                    fail("NRRD sizes must be three integers in [1, 2^20], got '", line.substr(colon + 2),
                         "'");
            haveSizes = true;
        } else if (field == "encoding") {
            if (value == "gzip" || value == "gz")
                fail("NRRD gzip encoding is not supported (save the volume with raw encoding)");
            if (value != "raw") fail("NRRD encoding '", value, "' is not supported (supported: raw)");
        } else if (field == "space dimension") {
            int d = 0;
            if (!parseNumber(value, d) || d != 3) fail("NRRD space dimension must be 3, got '", value, "'");
        } else if (field == "space directions") {
            for (Vec3d& d : dirs)
                if (!parseVector(value, d))
                    fail("NRRD space directions must be three vectors (a,b,c), got '", line.substr(colon + 2),
                         "'");
            haveDirections = true;
        } else if (field == "spacings") {
            for (int i = 0; i < 3; ++i) {
                double s;
                if (!parseNumber(value, s)) fail("NRRD spacings must be three numbers, got '", value, "'");
                spacings[i] = s;
            }
            haveSpacings = true;
        } else if (field == "space origin") {
            if (!parseVector(value, origin))
                fail("NRRD space origin must be a vector (x,y,z), got '", value, "'");
            haveOrigin = true;
        } else if (field == "data file" || field == "datafile") {
            fail("NRRD detached data files are not supported (save the volume as a single .nrrd)");
        } else if (field == "byte skip" || field == "byteskip" || field == "line skip" ||
                   field == "lineskip") {
            int skip = 0;
            if (!parseNumber(value, skip) || skip != 0) fail("NRRD ", field, " ", value, " is not supported");
        }
    }
    if (!haveSizes) fail("NRRD header has no 'sizes' field");

    // Cell sizes: diagonal space directions (or spacings); anything rotated cannot be a box.
    Vec3d cell = spacings;
    if (haveDirections) {
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                if (a != b && dirs[a][b] != 0)
                    fail("NRRD space directions must be axis-aligned (diagonal), axis ", a, " is not");
        cell = {dirs[0].x, dirs[1].y, dirs[2].z};
    } else if (!haveSpacings) {
        cell = {1, 1, 1};
    }
    if (!(isFinite(cell) && cell.x > 0 && cell.y > 0 && cell.z > 0))
        fail("NRRD cell sizes must be positive and finite");
    if (!haveOrigin) origin = cell * 0.5;
    if (!isFinite(origin)) fail("NRRD space origin is not finite");

    const int64_t nx = sizes[0], ny = sizes[1], nz = sizes[2];
    const uint64_t expected = uint64_t(nx) * uint64_t(ny) * uint64_t(nz);
    const uint64_t available = bytes.size() - pos;
    if (available < expected) fail("NRRD data is truncated: ", available, " of ", expected, " bytes");
    if (available > expected) fail("NRRD data has ", available - expected, " bytes more than sizes say");

    const Vec3d lo = origin - cell * 0.5;
    const Box3d box{lo, lo + Vec3d(double(nx), double(ny), double(nz)) * cell};
    // Sliced along x: column (y, z) = z * ny + y is one NRRD row of nx bytes.
    VoxelGrid g{Frame::orthographic(box, Axis::X, ny, nz, nx), BitGrid(ny, nz, nx)};
    const uint8_t* data = bytes.data() + pos;
    parallelFor(0, g.bits.columnCount(), 256, [&](int64_t b, int64_t e) {
        for (int64_t c = b; c < e; ++c) {
            const uint8_t* row = data + c * nx;
            uint64_t* col = g.bits.column(c);
            for (int64_t x = 0; x < nx; x += 8) {
                uint64_t chunk = 0;
                std::memcpy(&chunk, row + x, size_t(std::min<int64_t>(8, nx - x)));
                col[x >> 6] |= packNonzeroBytes(chunk) << (x & 63);
            }
        }
    });
    return reslice(g, Axis::Z);
}

} // namespace voxfx::detail
