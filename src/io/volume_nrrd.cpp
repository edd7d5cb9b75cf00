// voxfx — NRRD reader for scalar volumes (Teem's format, http://teem.sourceforge.net/nrrd/format.html).
//
// voxfx's 0/1 grid reader (nrrd.cpp) stays as it is; this one reads what CT and simulation tools
// write: NRRD0001..NRRD0005, dimension 3, any of uchar, signed char, short, ushort, int, uint,
// float, double under their many spellings, raw or gzip encoding, either endian, an attached
// (.nrrd) or detached (.nhdr + "data file: NAME") data file, "byte skip" and "line skip".
// Placement: "space origin" is the centre of voxel (0, 0, 0); diagonal "space directions" (an axis
// with a negative direction is mirrored so the volume runs towards +world), oblique ones that are
// orthogonal (the volume is turned: Volume::setAxes; skewed ones are refused), or "spacings" give
// the voxel size. Without an origin the box starts at 0, as in voxfx's grid reader.
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "io/nrrd_header.hpp"
#include "io/volume_formats.hpp"

namespace voxfx::detail {

namespace {

constexpr std::size_t kMaxHeaderBytes = std::size_t(1) << 16;

using nrrd::parseNumber;
using nrrd::parseVector;
using nrrd::trim;

bool typeFromNrrd(std::string_view t, ScalarType& out) {
    static const struct {
        const char* name;
        ScalarType type;
    } kTypes[] = {
        {"signed char", ScalarType::Int8},
        {"int8", ScalarType::Int8},
        {"int8_t", ScalarType::Int8},
        {"uchar", ScalarType::UInt8},
        {"unsigned char", ScalarType::UInt8},
        {"uint8", ScalarType::UInt8},
        {"uint8_t", ScalarType::UInt8},
        {"short", ScalarType::Int16},
        {"short int", ScalarType::Int16},
        {"signed short", ScalarType::Int16},
        {"signed short int", ScalarType::Int16},
        {"int16", ScalarType::Int16},
        {"int16_t", ScalarType::Int16},
        {"ushort", ScalarType::UInt16},
        {"unsigned short", ScalarType::UInt16},
        {"unsigned short int", ScalarType::UInt16},
        {"uint16", ScalarType::UInt16},
        {"uint16_t", ScalarType::UInt16},
        {"int", ScalarType::Int32},
        {"signed int", ScalarType::Int32},
        {"int32", ScalarType::Int32},
        {"int32_t", ScalarType::Int32},
        {"uint", ScalarType::UInt32},
        {"unsigned int", ScalarType::UInt32},
        {"uint32", ScalarType::UInt32},
        {"uint32_t", ScalarType::UInt32},
        {"float", ScalarType::Float32},
        {"double", ScalarType::Float64},
    };
    for (const auto& e : kTypes)
        if (t == e.name) {
            out = e.type;
            return true;
        }
    return false;
}

// What the header says (the fields voxfx reads; others are skipped).
struct NrrdHeader {
    bool haveType = false, haveSizes = false, haveDirections = false, haveSpacings = false,
         haveEndian = false;
    bool haveOrigin = false, bigEndian = false, gzip = false;
    ScalarType type = ScalarType::UInt8;
    Vec3i dims{0, 0, 0};
    Vec3d dirs[3], spacings{1, 1, 1}, origin{0, 0, 0};
    std::string dataFile;
    int64_t byteSkip = 0, lineSkip = 0;
    std::size_t dataStart = 0; ///< where the samples start when they follow the header
};

// One "field: value" line of the header into `h`; `where` is "path:line" for messages.
void readNrrdField(NrrdHeader& h, std::string_view field, std::string_view raw, const std::string& where) {
    std::string_view value = raw;
    const auto bad = [&](const char* expected) {
        fail(where, ": NRRD ", field, " must be ", expected, ", got '", raw.substr(0, 80), "'");
    };
    if (field == "type") {
        if (!typeFromNrrd(value, h.type))
            fail(where, ": NRRD type '", value,
                 "' is not supported (signed char, uchar, short, ushort, int, uint, float, double)");
        h.haveType = true;
    } else if (field == "dimension" || field == "space dimension") {
        int d = 0;
        if (!parseNumber(value, d) || d != 3) bad(field == "dimension" ? "3 (a 3D volume)" : "3");
    } else if (field == "sizes") {
        for (int a = 0; a < 3; ++a)
            if (!parseNumber(value, h.dims[a])) bad("three integers");
        if (!trim(value).empty()) bad("three integers (this is a 3D volume)");
        h.haveSizes = true;
    } else if (field == "endian") {
        if (value == "little")
            h.bigEndian = false;
        else if (value == "big")
            h.bigEndian = true;
        else
            bad("'little' or 'big'");
        h.haveEndian = true;
    } else if (field == "encoding") {
        if (value == "gzip" || value == "gz")
            h.gzip = true;
        else if (value != "raw")
            fail(where, ": NRRD encoding '", value, "' is not supported (raw or gzip)");
    } else if (field == "space directions") {
        for (Vec3d& d : h.dirs)
            if (!parseVector(value, d)) bad("three vectors (a,b,c)");
        h.haveDirections = true;
    } else if (field == "spacings") {
        for (int a = 0; a < 3; ++a)
            if (!parseNumber(value, h.spacings[a])) bad("three numbers");
        h.haveSpacings = true;
    } else if (field == "space origin") {
        if (!parseVector(value, h.origin)) bad("a vector (x,y,z)");
        h.haveOrigin = true;
    } else if (field == "data file" || field == "datafile") {
        if (value.starts_with("LIST") || value.find(' ') != std::string_view::npos)
            fail(where, ": NRRD data file lists and patterns are not supported, only one file name");
        h.dataFile = std::string(value);
    } else if (field == "byte skip" || field == "byteskip") {
        if (!parseNumber(value, h.byteSkip) || h.byteSkip < -1) bad("an integer >= -1");
    } else if (field == "line skip" || field == "lineskip") {
        if (!parseNumber(value, h.lineSkip) || h.lineSkip < 0) bad("an integer >= 0");
    }
}

// The magic line and the header up to its blank line (or the end: a detached header may end
// without one).
NrrdHeader readNrrdHeader(std::string_view all, const std::string& path) {
    if (!all.starts_with("NRRD000") || all.size() < 9 || all[7] < '1' || all[7] > '5' ||
        (all[8] != '\n' && all[8] != '\r'))
        fail(path, ": not a NRRD file (it does not start with NRRD0001..NRRD0005)");
    NrrdHeader h;
    std::size_t pos = all.find('\n') + 1;
    int line = 1;
    while (pos < all.size()) {
        if (pos > kMaxHeaderBytes) fail(path, ": NRRD header is longer than ", kMaxHeaderBytes, " bytes");
        std::size_t eol = all.find('\n', pos);
        if (eol == std::string_view::npos) eol = all.size();
        const std::string_view l = trim(all.substr(pos, eol - pos));
        pos = std::min(all.size(), eol + 1);
        ++line;
        if (l.empty()) break;
        if (l.front() == '#') continue;
        if (l.find(":=") != std::string_view::npos) continue; // key/value pairs carry no geometry
        const std::size_t colon = l.find(": ");
        if (colon == std::string_view::npos)
            fail(path, ":", line, ": NRRD header line without 'field: value': '", l.substr(0, 80), "'");
        readNrrdField(h, l.substr(0, colon), trim(l.substr(colon + 2)), concat(path, ":", line));
    }
    h.dataStart = pos;
    if (!h.haveType) fail(path, ": NRRD header has no 'type' field");
    if (!h.haveSizes) fail(path, ": NRRD header has no 'sizes' field");
    return h;
}

// Voxel size and orientation: diagonal directions (negative ones mirror the axis), oblique ones
// (the volume is turned: voxel axis a runs along dirs[a]), or spacings.
struct NrrdPlacement {
    Vec3d cell;
    bool mirror[3] = {false, false, false};
    bool oblique = false;
    Vec3d axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
};

NrrdPlacement placementOf(const NrrdHeader& h, const std::string& path) {
    NrrdPlacement p;
    p.cell = h.spacings;
    if (h.haveDirections) {
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) p.oblique = p.oblique || (a != b && h.dirs[a][b] != 0);
        for (int a = 0; a < 3; ++a) {
            if (p.oblique) {
                const Vec3d d{h.dirs[a][0], h.dirs[a][1], h.dirs[a][2]};
                p.cell[a] = length(d);
                if (std::isfinite(p.cell[a]) && p.cell[a] > 0) p.axes[a] = d / p.cell[a];
            } else {
                p.cell[a] = std::fabs(h.dirs[a][a]);
                p.mirror[a] = h.dirs[a][a] < 0;
            }
        }
    } else if (!h.haveSpacings) {
        p.cell = {1, 1, 1};
    }
    for (int a = 0; a < 3; ++a)
        if (!(std::isfinite(p.cell[a]) && p.cell[a] > 0))
            fail(path, ": NRRD voxel size along axis ", a, " must be positive and finite, got ", p.cell[a]);
    if (!isFinite(h.origin)) fail(path, ": NRRD space origin is not finite");
    return p;
}

// The samples: after the header or in the detached file (read into `detached`), past the line
// and byte skips, inflated into `inflated` when gzipped; exactly `expected` bytes.
std::span<const uint8_t> nrrdSamples(std::span<const uint8_t> bytes, const NrrdHeader& h, uint64_t expected,
                                     const std::string& path, std::string& dataPath,
                                     std::vector<uint8_t>& detached, std::vector<uint8_t>& inflated) {
    std::span<const uint8_t> data = bytes.subspan(std::min(h.dataStart, bytes.size()));
    dataPath = path;
    if (!h.dataFile.empty()) {
        std::filesystem::path p(h.dataFile);
        if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
        dataPath = p.string();
        try {
            detached = readVolumeFile(dataPath);
        } catch (const Error& e) { fail(path, ": NRRD data file: ", e.what()); }
        data = detached;
    } else if (h.dataStart >= bytes.size()) {
        fail(path, ": NRRD file has no data after its header (and no 'data file' field)");
    }
    for (int64_t l = 0; l < h.lineSkip; ++l) {
        const void* nl = std::memchr(data.data(), '\n', data.size());
        if (!nl) fail(dataPath, ": NRRD line skip ", h.lineSkip, " passes the end of the data");
        data = data.subspan(std::size_t(static_cast<const uint8_t*>(nl) - data.data()) + 1);
    }
    if (h.gzip) {
        if (h.byteSkip != 0) fail(path, ": NRRD byte skip with gzip encoding is not supported");
        inflated = inflateExactly(data, expected, dataPath);
        return inflated;
    }
    if (h.byteSkip == -1) {
        if (data.size() < expected)
            fail(dataPath, ": NRRD data is truncated: ", data.size(), " of ", expected, " bytes");
        return data.subspan(data.size() - expected);
    }
    if (uint64_t(h.byteSkip) > data.size())
        fail(dataPath, ": NRRD byte skip ", h.byteSkip, " passes the end of the data (", data.size(),
             " bytes)");
    data = data.subspan(std::size_t(h.byteSkip));
    if (data.size() < expected)
        fail(dataPath, ": NRRD data is truncated: the file holds ", data.size(), " of the ", expected,
             " bytes of samples the header declares (", h.dims.x, " x ", h.dims.y, " x ", h.dims.z, " ",
             toString(h.type), ")");
    if (data.size() > expected)
        fail(dataPath, ": NRRD data has ", data.size() - expected, " bytes more than the ", expected,
             " the header declares (wrong sizes or type?)");
    return data;
}

} // namespace

Volume readScalarNrrd(std::span<const uint8_t> bytes, const std::string& path, VolumeLoadReport& report) {
    const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    const NrrdHeader h = readNrrdHeader(all, path);
    const uint64_t expected = checkedSampleBytes(h.dims, h.type, path);
    if (scalarBytes(h.type) > 1 && !h.haveEndian)
        fail(path, ": NRRD header has no 'endian' field, needed for ", toString(h.type), " samples");
    const NrrdPlacement p = placementOf(h, path);

    std::string dataPath;
    std::vector<uint8_t> detached, inflated;
    const std::span<const uint8_t> data = nrrdSamples(bytes, h, expected, path, dataPath, detached, inflated);
    report.gzip = report.gzip || h.gzip;

    // Centre of voxel 0 after mirroring: the far end of a mirrored axis.
    Vec3d centre0 = h.haveOrigin ? h.origin : p.cell * 0.5;
    for (int a = 0; a < 3; ++a)
        if (p.mirror[a]) centre0[a] -= double(h.dims[a] - 1) * p.cell[a];
    // The data is all there: now the memory the volume takes (beside the inflated samples).
    checkVolumeMemory(h.dims, inflated.size(), dataPath);
    const Vec3d corner0 =
        centre0 - p.axes[0] * (0.5 * p.cell.x) - p.axes[1] * (0.5 * p.cell.y) - p.axes[2] * (0.5 * p.cell.z);
    Volume v(h.dims, corner0, p.cell, h.type);
    if (p.oblique) try {
            v.setAxes(p.axes[0], p.axes[1], p.axes[2]);
        } catch (const Error& e) { fail(path, ": NRRD space directions: ", e.what()); }
    decodeSamples(data.data(), h.type, h.bigEndian, v, dataPath);
    for (int a = 0; a < 3; ++a)
        if (p.mirror[a]) flipAxis(v, a);
    return v;
}

} // namespace voxfx::detail
