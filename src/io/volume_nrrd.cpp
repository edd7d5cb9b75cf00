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
#include <string_view>

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

} // namespace

Volume readScalarNrrd(std::span<const uint8_t> bytes, const std::string& path, VolumeLoadReport& report) {
    const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    if (!all.starts_with("NRRD000") || all.size() < 9 || all[7] < '1' || all[7] > '5' ||
        (all[8] != '\n' && all[8] != '\r'))
        fail(path, ": not a NRRD file (it does not start with NRRD0001..NRRD0005)");
    std::size_t pos = all.find('\n') + 1;

    bool haveType = false, haveSizes = false, haveDirections = false, haveSpacings = false,
         haveEndian = false;
    bool bigEndian = false, gzip = false;
    ScalarType type = ScalarType::UInt8;
    Vec3i dims{0, 0, 0};
    Vec3d dirs[3], spacings{1, 1, 1}, origin{0, 0, 0};
    bool haveOrigin = false;
    std::string dataFile;
    int64_t byteSkip = 0, lineSkip = 0;
    int line = 1;
    bool headerDone = false;
    while (!headerDone && pos < all.size()) { // a detached header may end without a blank line
        if (pos > kMaxHeaderBytes) fail(path, ": NRRD header is longer than ", kMaxHeaderBytes, " bytes");
        std::size_t eol = all.find('\n', pos);
        if (eol == std::string_view::npos) eol = all.size();
        const std::string_view l = trim(all.substr(pos, eol - pos));
        pos = std::min(all.size(), eol + 1);
        ++line;
        if (l.empty()) {
            headerDone = true;
            continue;
        }
        if (l.front() == '#') continue;
        if (l.find(":=") != std::string_view::npos) continue; // key/value pairs carry no geometry
        const std::size_t colon = l.find(": ");
        if (colon == std::string_view::npos)
            fail(path, ":", line, ": NRRD header line without 'field: value': '", l.substr(0, 80), "'");
        const std::string_view field = l.substr(0, colon);
        const std::string_view raw = trim(l.substr(colon + 2));
        std::string_view value = raw;
        const auto bad = [&](const char* expected) {
            fail(path, ":", line, ": NRRD ", field, " must be ", expected, ", got '", raw.substr(0, 80), "'");
        };
        if (field == "type") {
            if (!typeFromNrrd(value, type))
                fail(path, ":", line, ": NRRD type '", value,
                     "' is not supported (signed char, uchar, short, ushort, int, uint, float, double)");
            haveType = true;
        } else if (field == "dimension") {
            int d = 0;
            if (!parseNumber(value, d) || d != 3) bad("3 (a 3D volume)");
        } else if (field == "sizes") {
            for (int a = 0; a < 3; ++a)
                if (!parseNumber(value, dims[a])) bad("three integers");
            if (!trim(value).empty()) bad("three integers (this is a 3D volume)");
            haveSizes = true;
        } else if (field == "endian") {
            if (value == "little")
                bigEndian = false;
            else if (value == "big")
                bigEndian = true;
            else
                bad("'little' or 'big'");
            haveEndian = true;
        } else if (field == "encoding") {
            if (value == "gzip" || value == "gz")
                gzip = true;
            else if (value != "raw")
                fail(path, ":", line, ": NRRD encoding '", value, "' is not supported (raw or gzip)");
        } else if (field == "space dimension") {
            int d = 0;
            if (!parseNumber(value, d) || d != 3) bad("3");
        } else if (field == "space directions") {
            for (Vec3d& d : dirs)
                if (!parseVector(value, d)) bad("three vectors (a,b,c)");
            haveDirections = true;
        } else if (field == "spacings") {
            for (int a = 0; a < 3; ++a)
                if (!parseNumber(value, spacings[a])) bad("three numbers");
            haveSpacings = true;
        } else if (field == "space origin") {
            if (!parseVector(value, origin)) bad("a vector (x,y,z)");
            haveOrigin = true;
        } else if (field == "data file" || field == "datafile") {
            if (value.starts_with("LIST") || value.find(' ') != std::string_view::npos)
                fail(path, ":", line,
                     ": NRRD data file lists and patterns are not supported, only one file name");
            dataFile = std::string(value);
        } else if (field == "byte skip" || field == "byteskip") {
            if (!parseNumber(value, byteSkip) || byteSkip < -1) bad("an integer >= -1");
        } else if (field == "line skip" || field == "lineskip") {
            if (!parseNumber(value, lineSkip) || lineSkip < 0) bad("an integer >= 0");
        }
    }
    if (!haveType) fail(path, ": NRRD header has no 'type' field");
    if (!haveSizes) fail(path, ": NRRD header has no 'sizes' field");
    const uint64_t expected = checkedSampleBytes(dims, type, path);
    if (scalarBytes(type) > 1 && !haveEndian)
        fail(path, ": NRRD header has no 'endian' field, needed for ", toString(type), " samples");

    // Voxel size and orientation: diagonal directions (negative ones mirror the axis), oblique
    // ones (the volume is turned: voxel axis a runs along dirs[a]), or spacings.
    Vec3d cell = spacings;
    bool mirror[3] = {false, false, false};
    bool oblique = false;
    Vec3d axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (haveDirections) {
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) oblique = oblique || (a != b && dirs[a][b] != 0);
        for (int a = 0; a < 3; ++a) {
            if (oblique) {
                const Vec3d d{dirs[a][0], dirs[a][1], dirs[a][2]};
                cell[a] = length(d);
                if (std::isfinite(cell[a]) && cell[a] > 0) axes[a] = d / cell[a];
            } else {
                cell[a] = std::fabs(dirs[a][a]);
                mirror[a] = dirs[a][a] < 0;
            }
        }
    } else if (!haveSpacings) {
        cell = {1, 1, 1};
    }
    for (int a = 0; a < 3; ++a)
        if (!(std::isfinite(cell[a]) && cell[a] > 0))
            fail(path, ": NRRD voxel size along axis ", a, " must be positive and finite, got ", cell[a]);
    if (!isFinite(origin)) fail(path, ": NRRD space origin is not finite");

    // The data: after the header, or in the detached file.
    std::vector<uint8_t> detached;
    std::span<const uint8_t> data = bytes.subspan(std::min(pos, bytes.size()));
    std::string dataPath = path;
    if (!dataFile.empty()) {
        std::filesystem::path p(dataFile);
        if (p.is_relative()) p = std::filesystem::path(path).parent_path() / p;
        dataPath = p.string();
        try {
            detached = readVolumeFile(dataPath);
        } catch (const Error& e) { fail(path, ": NRRD data file: ", e.what()); }
        data = detached;
    } else if (pos >= all.size()) {
        fail(path, ": NRRD file has no data after its header (and no 'data file' field)");
    }
    for (int64_t l = 0; l < lineSkip; ++l) {
        const void* nl = std::memchr(data.data(), '\n', data.size());
        if (!nl) fail(dataPath, ": NRRD line skip ", lineSkip, " passes the end of the data");
        data = data.subspan(std::size_t(static_cast<const uint8_t*>(nl) - data.data()) + 1);
    }

    std::vector<uint8_t> inflated;
    if (gzip) {
        if (byteSkip != 0) fail(path, ": NRRD byte skip with gzip encoding is not supported");
        inflated = inflateExactly(data, expected, dataPath);
        data = inflated;
        report.gzip = true;
    } else if (byteSkip == -1) {
        if (data.size() < expected)
            fail(dataPath, ": NRRD data is truncated: ", data.size(), " of ", expected, " bytes");
        data = data.subspan(data.size() - expected);
    } else {
        if (uint64_t(byteSkip) > data.size())
            fail(dataPath, ": NRRD byte skip ", byteSkip, " passes the end of the data (", data.size(),
                 " bytes)");
        data = data.subspan(std::size_t(byteSkip));
        if (data.size() < expected)
            fail(dataPath, ": NRRD data is truncated: the file holds ", data.size(), " of the ", expected,
                 " bytes of samples the header declares (", dims.x, " x ", dims.y, " x ", dims.z, " ",
                 toString(type), ")");
        if (data.size() > expected)
            fail(dataPath, ": NRRD data has ", data.size() - expected, " bytes more than the ", expected,
                 " the header declares (wrong sizes or type?)");
    }

    // Centre of voxel 0 after mirroring: the far end of a mirrored axis.
    Vec3d centre0 = haveOrigin ? origin : cell * 0.5;
    for (int a = 0; a < 3; ++a)
        if (mirror[a]) centre0[a] -= double(dims[a] - 1) * cell[a];
    // The data is all there: now the memory the volume takes (beside the inflated samples).
    checkVolumeMemory(dims, inflated.size(), dataPath);
    const Vec3d corner0 =
        centre0 - axes[0] * (0.5 * cell.x) - axes[1] * (0.5 * cell.y) - axes[2] * (0.5 * cell.z);
    Volume v(dims, corner0, cell, type);
    if (oblique) try {
            v.setAxes(axes[0], axes[1], axes[2]);
        } catch (const Error& e) { fail(path, ": NRRD space directions: ", e.what()); }
    decodeSamples(data.data(), type, bigEndian, v, dataPath);
    for (int a = 0; a < 3; ++a)
        if (mirror[a]) flipAxis(v, a);
    return v;
}

} // namespace voxfx::detail
