// voxfx — PLY reader (Turk's Stanford polygon format): ASCII, binary little- and big-endian.
//
//   ply
//   format ascii|binary_little_endian|binary_big_endian 1.0
//   element vertex N          with scalar properties x, y, z (any numeric type) among others,
//                             and optionally red, green, blue (per-vertex colours)
//   element face M            with a list property vertex_indices (or vertex_index)
//   end_header
//   body: the elements in header order, instance by instance, property by property
//
// Colours are kept when the vertex element has all three of red, green and blue as scalars: integer
// types scaled by their largest value (uchar / 255, ushort / 65535), floating-point ones as they are.
// Other elements and properties are read past and ignored; polygons are fan-triangulated. The
// header's counts are checked against the bytes that remain before anything is reserved.
#include <algorithm>
#include <array>
#include <optional>

#include "io/mesh_formats.hpp"

namespace voxfx::detail {

namespace {

enum class PlyType : uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

constexpr std::size_t sizeOf(PlyType t) {
    constexpr std::array<std::size_t, 8> sizes{1, 1, 2, 2, 4, 4, 4, 8};
    return sizes[std::size_t(t)];
}
constexpr bool isInteger(PlyType t) { return t != PlyType::kFloat32 && t != PlyType::kFloat64; }

std::optional<PlyType> parseType(std::string_view name) {
    static constexpr std::pair<std::string_view, PlyType> kNames[] = {
        {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
        {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
        {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
        {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
        {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
        {"float64", PlyType::kFloat64}};
    for (const auto& [n, t] : kNames)
        if (n == name) return t;
    return std::nullopt;
}

// Reads one binary value of type t as a double (exact for every PLY type).
double loadAsDouble(PlyType t, const unsigned char* p, bool bigEndian) {
    switch (t) {
    case PlyType::kInt8:
        return double(int8_t(p[0]));
    case PlyType::kUint8:
        return double(p[0]);
    case PlyType::kInt16:
        return double(loadValue<int16_t>(p, bigEndian));
    case PlyType::kUint16:
        return double(loadValue<uint16_t>(p, bigEndian));
    case PlyType::kInt32:
        return double(loadValue<int32_t>(p, bigEndian));
    case PlyType::kUint32:
        return double(loadValue<uint32_t>(p, bigEndian));
    case PlyType::kFloat32:
        return double(loadValue<float>(p, bigEndian));
    case PlyType::kFloat64:
        return loadValue<double>(p, bigEndian);
    }
    return 0;
}

// Reads one binary integer of type t (the header guarantees an integer type).
int64_t loadAsInteger(PlyType t, const unsigned char* p, bool bigEndian) {
    switch (t) {
    case PlyType::kInt8:
        return int8_t(p[0]);
    case PlyType::kUint8:
        return p[0];
    case PlyType::kInt16:
        return loadValue<int16_t>(p, bigEndian);
    case PlyType::kUint16:
        return loadValue<uint16_t>(p, bigEndian);
    case PlyType::kInt32:
        return loadValue<int32_t>(p, bigEndian);
    case PlyType::kUint32:
        return loadValue<uint32_t>(p, bigEndian);
    default:
        return 0;
    }
}

struct PlyProperty {
    std::string name;
    bool list = false;
    PlyType countType = PlyType::kUint8; // lists only
    PlyType type = PlyType::kFloat32;    // the value, or the list items
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    uint64_t line = 0; // of its header line, for messages
    std::vector<PlyProperty> properties;
};

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyHeader {
    PlyFormat format = PlyFormat::kAscii;
    std::vector<PlyElement> elements;
    std::size_t bodyOffset = 0; // first byte after "end_header\n"
    uint64_t bodyLine = 0;      // its line, for ASCII messages
};

PlyHeader parseHeader(std::string_view bytes, const std::string& path) {
    PlyHeader header;
    TextReader in(bytes, path, 0);
    if (in.word() != "ply") fail(path, ": not a PLY file (it does not start with 'ply')");
    in.nextLine();
    bool haveFormat = false;
    for (;;) {
        if (in.onLastLine()) in.error("the PLY header ends without 'end_header' (truncated?)");
        const std::string_view key = in.word();
        if (key == "end_header") {
            in.nextLine();
            header.bodyOffset = std::size_t(in.position() - bytes.data());
            header.bodyLine = in.line();
            break;
        } else if (key == "format") {
            const std::string_view format = in.word();
            if (format == "ascii")
                header.format = PlyFormat::kAscii;
            else if (format == "binary_little_endian")
                header.format = PlyFormat::kBinaryLittleEndian;
            else if (format == "binary_big_endian")
                header.format = PlyFormat::kBinaryBigEndian;
            else
                in.error("unknown PLY format '", format,
                         "' (expected ascii, binary_little_endian or binary_big_endian)");
            haveFormat = true;
        } else if (key == "element") {
            PlyElement element;
            element.name = std::string(in.word());
            element.line = in.line();
            element.count = in.readUnsigned("the count of element '", element.name, "'");
            header.elements.push_back(std::move(element));
        } else if (key == "property") {
            if (header.elements.empty()) in.error("'property' before any 'element'");
            PlyProperty property;
            std::string_view typeName = in.word();
            if (typeName == "list") {
                property.list = true;
                const std::string_view countName = in.word();
                const auto countType = parseType(countName);
                if (!countType || !isInteger(*countType))
                    in.error("list length type '", countName, "' is not an integer type");
                property.countType = *countType;
                typeName = in.word();
            }
            const auto type = parseType(typeName);
            if (!type)
                in.error("unknown property type '", typeName,
                         "' (expected char, uchar, short, ushort, int, uint, float, double or their "
                         "int8...float64 names)");
            property.type = *type;
            property.name = std::string(in.word());
            if (property.name.empty()) in.error("property without a name");
            header.elements.back().properties.push_back(std::move(property));
        } else if (!(key.empty() || key == "comment" || key == "obj_info")) {
            in.error("unknown PLY header line '", key.substr(0, 40), "'");
        }
        in.nextLine();
    }
    if (!haveFormat) fail(path, ": the PLY header has no 'format' line");
    return header;
}

// The roles of an element's properties for the mesh.
struct ElementRoles {
    bool isVertex = false;
    bool isFace = false;
    std::vector<int> axis;          // per property: 0, 1, 2 for x, y, z of a vertex; -1 otherwise
    std::vector<int> channel;       // per property: 0, 1, 2 for red, green, blue of a vertex; -1 otherwise
    std::vector<double> colorScale; // per property: what a colour value is multiplied by
    bool hasColor = false;          // all three of red, green, blue
    int indexList = -1;             // the face's vertex_indices property
    std::size_t minBytes = 0;       // smallest binary size of one instance (lists empty)
    bool fixedSize = true;          // no list properties
};

ElementRoles rolesOf(const PlyElement& element, const std::string& path) {
    ElementRoles roles;
    roles.isVertex = element.name == "vertex";
    roles.isFace = element.name == "face";
    roles.axis.assign(element.properties.size(), -1);
    roles.channel.assign(element.properties.size(), -1);
    roles.colorScale.assign(element.properties.size(), 1.0);
    std::array<bool, 3> found{}, foundColor{};
    for (std::size_t j = 0; j < element.properties.size(); ++j) {
        const PlyProperty& p = element.properties[j];
        roles.minBytes += p.list ? sizeOf(p.countType) : sizeOf(p.type);
        roles.fixedSize = roles.fixedSize && !p.list;
        if (roles.isVertex && !p.list && p.name.size() == 1 && p.name[0] >= 'x' && p.name[0] <= 'z') {
            roles.axis[j] = p.name[0] - 'x';
            found[std::size_t(roles.axis[j])] = true;
        }
        if (roles.isVertex && !p.list && (p.name == "red" || p.name == "green" || p.name == "blue")) {
            const int c = p.name == "red" ? 0 : p.name == "green" ? 1 : 2;
            roles.channel[j] = c;
            foundColor[std::size_t(c)] = true;
            roles.colorScale[j] = p.type == PlyType::kUint8    ? 1.0 / 255
                                  : p.type == PlyType::kUint16 ? 1.0 / 65535
                                  : p.type == PlyType::kInt8   ? 1.0 / 127
                                  : p.type == PlyType::kInt16  ? 1.0 / 32767
                                  : p.type == PlyType::kUint32 ? 1.0 / 4294967295.0
                                  : p.type == PlyType::kInt32  ? 1.0 / 2147483647.0
                                                               : 1.0;
        }
        if (roles.isFace && p.list && roles.indexList < 0 &&
            (p.name == "vertex_indices" || p.name == "vertex_index")) {
            if (!isInteger(p.type))
                fail(path, ":", element.line, ": face property '", p.name, "' holds non-integer indices");
            roles.indexList = int(j);
        }
    }
    roles.hasColor = foundColor[0] && foundColor[1] && foundColor[2];
    if (!roles.hasColor) roles.channel.assign(element.properties.size(), -1);
    if (roles.isVertex && !(found[0] && found[1] && found[2]))
        fail(path, ":", element.line, ": the PLY vertex element lacks scalar x, y and z properties");
    if (roles.isFace && roles.indexList < 0)
        fail(path, ":", element.line, ": the PLY face element has no 'vertex_indices' list");
    return roles;
}

// Builds the mesh from the body, given the header; one body reader per encoding.
class PlyBuilder {
public:
    PlyBuilder(ParsedMesh& out, uint64_t vertexCount) : out_(out), vertexCount_(vertexCount) {}

    // Adds corner k of face f; `where` is only evaluated on error.
    template <class Where> void corner(uint64_t f, uint64_t k, int64_t v, const Where& where) {
        if (v < 0 || uint64_t(v) >= vertexCount_)
            where("face ", f, ": vertex index ", v, " is out of range (the file has ", vertexCount_,
                  " vertices)");
        if (k == 0)
            first_ = uint32_t(v);
        else if (k >= 2)
            appendFanTriangle(out_.mesh.indices, first_, previous_, uint32_t(v));
        previous_ = uint32_t(v);
    }
    void vertex(const Vec3f& p, FileLocation where) {
        if (!isFinite(p)) out_.nonFiniteVertices.emplace_back(uint32_t(out_.mesh.positions.size()), where);
        out_.mesh.positions.push_back(p);
    }
    void color(const Vec3f& c) { out_.colors.push_back(c); }

private:
    ParsedMesh& out_;
    uint64_t vertexCount_;
    uint32_t first_ = 0, previous_ = 0;
};

void readAsciiBody(std::string_view bytes, const std::string& path, const PlyHeader& header,
                   const std::vector<ElementRoles>& roles, PlyBuilder& build) {
    TextReader in(bytes.substr(header.bodyOffset), path, 0, header.bodyLine);
    for (std::size_t e = 0; e < header.elements.size(); ++e) {
        const PlyElement& element = header.elements[e];
        const ElementRoles& role = roles[e];
        if (element.properties.empty()) continue; // nothing to read, whatever the count
        for (uint64_t i = 0; i < element.count; ++i) {
            Vec3f p, color;
            for (std::size_t j = 0; j < element.properties.size(); ++j) {
                const PlyProperty& property = element.properties[j];
                in.skipSpace();
                if (in.eof())
                    in.error("unexpected end of file in element '", element.name, "' ", i, " of ",
                             element.count, " (truncated?)");
                if (!property.list) {
                    if (role.axis[j] >= 0)
                        p[role.axis[j]] = in.readFloat(property.name, " of vertex ", i);
                    else if (role.channel[j] >= 0)
                        color[role.channel[j]] =
                            float(in.readFloat(property.name, " of vertex ", i) * role.colorScale[j]);
                    else
                        in.word();
                    continue;
                }
                const uint64_t n =
                    in.readUnsigned("the length of list '", property.name, "' of ", element.name, " ", i);
                const bool indices = int(j) == role.indexList;
                for (uint64_t k = 0; k < n; ++k) {
                    in.skipSpace();
                    if (in.eof())
                        in.error("unexpected end of file in list '", property.name, "' of ", element.name,
                                 " ", i, " (truncated?)");
                    if (!indices) {
                        in.word();
                        continue;
                    }
                    const int64_t v = in.readSigned(false, "vertex ", k, " of face ", i);
                    build.corner(i, k, v, [&](const auto&... args) { in.error(args...); });
                }
            }
            if (role.isVertex) build.vertex(p, in.location());
            if (role.isVertex && role.hasColor) build.color(color);
        }
    }
}

void readBinaryBody(std::string_view bytes, const std::string& path, const PlyHeader& header,
                    const std::vector<ElementRoles>& roles, PlyBuilder& build) {
    const bool bigEndian = header.format == PlyFormat::kBinaryBigEndian;
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
    const std::size_t size = bytes.size();
    std::size_t offset = header.bodyOffset;
    for (std::size_t e = 0; e < header.elements.size(); ++e) {
        const PlyElement& element = header.elements[e];
        const ElementRoles& role = roles[e];
        if (element.properties.empty()) continue; // nothing to read, whatever the count
        // Every instance needs at least minBytes: a count the file cannot hold is reported here,
        // before the loop, with what it would need.
        if (role.minBytes > 0 && element.count > (size - offset) / role.minBytes)
            fail(path, ": byte ", offset, ": element '", element.name, "' declares ", element.count,
                 " instances of ", role.fixedSize ? "" : "at least ", role.minBytes, " bytes, but only ",
                 size - offset, " bytes remain (truncated?)");
        auto truncated = [&](uint64_t i) {
            fail(path, ": byte ", offset, ": unexpected end of file in element '", element.name, "' ", i,
                 " of ", element.count, " (truncated?)");
        };
        for (uint64_t i = 0; i < element.count; ++i) {
            Vec3f p, color;
            const std::size_t start = offset;
            for (std::size_t j = 0; j < element.properties.size(); ++j) {
                const PlyProperty& property = element.properties[j];
                if (!property.list) {
                    const std::size_t s = sizeOf(property.type);
                    if (size - offset < s) truncated(i);
                    if (role.axis[j] >= 0)
                        p[role.axis[j]] = toFloat(loadAsDouble(property.type, data + offset, bigEndian));
                    else if (role.channel[j] >= 0)
                        color[role.channel[j]] = toFloat(
                            loadAsDouble(property.type, data + offset, bigEndian) * role.colorScale[j]);
                    offset += s;
                    continue;
                }
                const std::size_t countBytes = sizeOf(property.countType);
                if (size - offset < countBytes) truncated(i);
                const int64_t n = loadAsInteger(property.countType, data + offset, bigEndian);
                if (n < 0)
                    fail(path, ": byte ", offset, ": negative list length ", n, " in ", element.name, " ", i);
                offset += countBytes;
                const std::size_t itemBytes = sizeOf(property.type);
                if (uint64_t(n) > (size - offset) / itemBytes) truncated(i);
                if (int(j) == role.indexList) {
                    for (int64_t k = 0; k < n; ++k) {
                        const int64_t v = loadAsInteger(
                            property.type, data + offset + std::size_t(k) * itemBytes, bigEndian);
                        const std::size_t at = offset + std::size_t(k) * itemBytes;
                        build.corner(i, uint64_t(k), v,
                                     [&](const auto&... args) { fail(path, ": byte ", at, ": ", args...); });
                    }
                }
                offset += std::size_t(n) * itemBytes;
            }
            if (role.isVertex) build.vertex(p, {FileLocation::Kind::kByte, start});
            if (role.isVertex && role.hasColor) build.color(color);
        }
    }
}

} // namespace

ParsedMesh parsePly(std::string_view bytes, const std::string& path) {
    const PlyHeader header = parseHeader(bytes, path);
    std::vector<ElementRoles> roles;
    uint64_t vertexCount = 0, faceCount = 0;
    for (const PlyElement& element : header.elements) {
        roles.push_back(rolesOf(element, path));
        if (roles.back().isVertex) vertexCount += element.count;
        if (roles.back().isFace) faceCount += element.count;
    }
    if (vertexCount > kMaxVertices)
        fail(path, ": the PLY header declares ", vertexCount, " vertices, more than 2^32 - 1");

    // Reserve no more than the body could hold (one byte per value at least).
    ParsedMesh out;
    const uint64_t bodyBytes = bytes.size() - header.bodyOffset;
    out.mesh.positions.reserve(std::min(vertexCount, bodyBytes / 3));
    out.mesh.indices.reserve(3 * std::min(faceCount, bodyBytes / 4));
    PlyBuilder build(out, vertexCount);
    if (header.format == PlyFormat::kAscii)
        readAsciiBody(bytes, path, header, roles, build);
    else
        readBinaryBody(bytes, path, header, roles, build);
    // Several vertex elements of which some lack colours: no colour is given for any vertex.
    if (out.colors.size() != out.mesh.positions.size()) out.colors.clear();
    return out;
}

} // namespace voxfx::detail
