// voxfx — raw samples described by a JSON header (NAME.json next to the raw file):
//
//   {"file": "ct.raw", "dims": [nx, ny, nz], "type": "uint16", "endian": "little",
//    "spacing": [sx, sy, sz], "origin": [x, y, z], "offset": 0, "encoding": "raw"}
//
// file, dims and type are required; endian is required for samples wider than a byte; spacing
// defaults to 1; origin is the centre of voxel (0, 0, 0) (the box starts at 0 without it); offset
// skips that many bytes of a header in the raw file; encoding "gzip" inflates the file first.
// Unknown keys are an error, so that a misspelt "spacings" does not pass silently.
#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "io/volume_formats.hpp"

namespace voxfx::detail {

namespace {

using nlohmann::json;

Vec3d readVec3(const json& j, const char* key, const std::string& path) {
    const json& a = j.at(key);
    if (!a.is_array() || a.size() != 3) fail(path, ": \"", key, "\" must be an array of three numbers");
    Vec3d v;
    for (int i = 0; i < 3; ++i) {
        if (!a[std::size_t(i)].is_number()) fail(path, ": \"", key, "\" must be an array of three numbers");
        v[i] = a[std::size_t(i)].get<double>();
        if (!std::isfinite(v[i])) fail(path, ": \"", key, "\" must be finite");
    }
    return v;
}

} // namespace

Volume readRawJson(std::span<const uint8_t> bytes, const std::string& path, VolumeLoadReport& report) {
    json j;
    try {
        j = json::parse(bytes.begin(), bytes.end());
    } catch (const json::exception& e) { fail(path, ": not valid JSON: ", e.what()); }
    if (!j.is_object()) fail(path, ": the raw volume header must be a JSON object");
    static const char* const kKeys[] = {"file",    "dims",   "type",   "endian",
                                        "spacing", "origin", "offset", "encoding"};
    for (const auto& item : j.items()) {
        bool known = false;
        for (const char* k : kKeys) known = known || item.key() == k;
        if (!known)
            fail(path, ": unknown key \"", item.key(),
                 "\" (known: file, dims, type, endian, spacing, origin, offset, encoding)");
    }
    for (const char* k : {"file", "dims", "type"})
        if (!j.contains(k)) fail(path, ": the raw volume header has no \"", k, "\"");
    if (!j["file"].is_string() || j["file"].get<std::string>().empty())
        fail(path, ": \"file\" must be the name of the raw file");
    if (!j["type"].is_string()) fail(path, ": \"type\" must be a string such as \"uint16\"");

    ScalarType type;
    try {
        type = scalarTypeFromString(j["type"].get<std::string>());
    } catch (const Error& e) { fail(path, ": ", e.what()); }
    const json& d = j["dims"];
    if (!d.is_array() || d.size() != 3) fail(path, ": \"dims\" must be an array of three integers");
    Vec3i dims;
    for (int i = 0; i < 3; ++i) {
        const json& e = d[std::size_t(i)];
        if (!e.is_number_integer()) fail(path, ": \"dims\" must be an array of three integers");
        if (e.is_number_unsigned() && e.get<uint64_t>() > uint64_t(kMaxVolumeVoxels))
            fail(path, ": \"dims\" entry ", e.get<uint64_t>(), " is larger than the limit of 2^40 voxels");
        dims[i] = e.get<int64_t>();
    }
    const uint64_t expected = checkedSampleBytes(dims, type, path);

    bool bigEndian = false;
    if (j.contains("endian")) {
        const json& e = j["endian"];
        if (!e.is_string() || (e != "little" && e != "big"))
            fail(path, ": \"endian\" must be \"little\" or \"big\"");
        bigEndian = e == "big";
    } else if (scalarBytes(type) > 1) {
        fail(path, ": the raw volume header has no \"endian\" (\"little\" or \"big\"), needed for ",
             toString(type), " samples");
    }
    const Vec3d spacing = j.contains("spacing") ? readVec3(j, "spacing", path) : Vec3d{1, 1, 1};
    for (int a = 0; a < 3; ++a)
        if (!(spacing[a] > 0)) fail(path, ": \"spacing\" must be positive");
    const Vec3d centre0 = j.contains("origin") ? readVec3(j, "origin", path) : spacing * 0.5;
    uint64_t offset = 0;
    if (j.contains("offset")) {
        if (!j["offset"].is_number_unsigned()) fail(path, ": \"offset\" must be an integer >= 0");
        offset = j["offset"].get<uint64_t>();
    }
    bool gzip = false;
    if (j.contains("encoding")) {
        const json& e = j["encoding"];
        if (!e.is_string() || (e != "raw" && e != "gzip"))
            fail(path, ": \"encoding\" must be \"raw\" or \"gzip\"");
        gzip = e == "gzip";
    }

    std::filesystem::path rawPath(j["file"].get<std::string>());
    if (rawPath.is_relative()) rawPath = std::filesystem::path(path).parent_path() / rawPath;
    const std::string raw = rawPath.string();
    std::vector<uint8_t> file;
    try {
        file = readVolumeFile(raw);
    } catch (const Error& e) { fail(path, ": raw data file: ", e.what()); }
    std::span<const uint8_t> data(file);
    if (offset > data.size())
        fail(raw, ": offset ", offset, " from ", path, " passes the end of the file (", data.size(),
             " bytes)");
    data = data.subspan(std::size_t(offset));
    std::vector<uint8_t> inflated;
    if (gzip) {
        inflated = inflateExactly(data, expected, raw);
        data = inflated;
        report.gzip = true;
    } else if (data.size() < expected) {
        fail(raw, ": raw data is truncated: the file holds ", data.size(), " of the ", expected,
             " bytes of samples ", path, " declares (", dims.x, " x ", dims.y, " x ", dims.z, " ",
             toString(type), ")");
    } else if (data.size() > expected) {
        fail(raw, ": the file holds ", data.size() - expected, " bytes more than the ", expected,
             " bytes of samples ", path, " declares (wrong dims or type?)");
    }
    // The data is all there: now the memory the volume takes (beside the inflated samples).
    checkVolumeMemory(dims, inflated.size(), path);
    Volume v(dims, centre0 - spacing * 0.5, spacing, type);
    decodeSamples(data.data(), type, bigEndian, v, raw);
    return v;
}

} // namespace voxfx::detail
