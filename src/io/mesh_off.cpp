// voxfx — OFF reader (Geomview's Object File Format; the ASCII variant with optional ST/C/N
// prefixes, as written by CGAL, MeshLab and most research code).
//
//   OFF                      header keyword (COFF, NOFF, STOFF... accepted; extra columns ignored)
//   nv nf ne                 counts (ne optional and ignored)
//   x y z [...]              nv vertex lines
//   n i0 i1 ... i(n-1) [...] nf face lines, 0-based indices, polygons fan-triangulated
//
// '#' starts a comment anywhere; blank lines are skipped. Vertices and faces are one per line.
//
// Vertex colours (a C in the keyword: COFF, CNOFF, STCOFF...): a vertex line is x y z, then the
// normal (N), then 3 or 4 colour components (r g b [a]), then the texture coordinates (ST), as
// Geomview orders them. Components written as integers (no '.', no exponent: "192 192 192 255",
// as CGAL and MeshLab write them) are on a 0..255 scale, others in 0..1 (Geomview's "0.9 0 0"),
// decided per vertex; alpha is dropped.
#include <algorithm>
#include <cmath>

#include "io/mesh_formats.hpp"

namespace voxfx::detail {

namespace {

// Shortest vertex and face lines ("0 0 0\n", "0\n"): header counts are checked against them
// before anything is reserved.
constexpr uint64_t kMinVertexBytes = 6;
constexpr uint64_t kMinFaceBytes = 2;

/// A COFF vertex's colour: what follows the coordinates (and the normal) on its line, less the
/// texture coordinates, must be 3 or 4 components (see the file comment for their scale).
Vec3f readOffColor(TextReader& in, uint64_t v, bool normal, bool texture) {
    if (normal)
        for (int k = 0; k < 3; ++k) in.readFloat("normal component ", k, " of vertex ", v);
    std::string_view words[7];
    int n = 0;
    while (!in.atLineEnd()) {
        if (n == 7) in.error("vertex ", v, ": more values than colour and texture coordinates");
        std::string_view w = in.word();
        // A comment right after a value ("0.9 0 0#red") ends the line's values.
        const std::size_t hash = w.find('#');
        if (hash != std::string_view::npos) w = w.substr(0, hash);
        if (!w.empty()) words[n++] = w;
        if (hash != std::string_view::npos) break;
    }
    const int components = n - (texture ? 2 : 0);
    if (components != 3 && components != 4)
        in.error("vertex ", v, ": expected 3 or 4 colour components (the header says C", texture ? "ST" : "",
                 "OFF), found ", std::max(components, 0));
    bool integers = true;
    float c[3];
    for (int k = 0; k < 3; ++k) {
        const std::string_view w = words[k];
        integers = integers && w.find_first_of(".eE") == std::string_view::npos;
        double value = 0;
        const char* first = w.data() + (!w.empty() && w[0] == '+' ? 1 : 0);
        const auto [ptr, ec] = std::from_chars(first, w.data() + w.size(), value);
        if (ec != std::errc() || ptr != w.data() + w.size() || !std::isfinite(value))
            in.error("vertex ", v, ": colour component ", k, " is not a number: '", w.substr(0, 40), "'");
        c[k] = float(value);
    }
    if (integers)
        for (float& x : c) x /= 255.0f;
    return {c[0], c[1], c[2]};
}

} // namespace

ParsedMesh parseOff(std::string_view bytes, const std::string& path) {
    ParsedMesh out;
    TextReader in(bytes, path, '#');
    in.skipSpace();
    if (in.eof()) in.error("empty file, expected the 'OFF' header");

    // Header keyword: [ST][C][N][4][n]OFF, then optionally BINARY.
    std::string_view key = in.word();
    const std::string_view full = key;
    bool texture = false, color = false, normal = false;
    for (std::string_view prefix : {"ST", "C", "N"})
        if (key.starts_with(prefix)) {
            key.remove_prefix(prefix.size());
            (prefix == "ST" ? texture : prefix == "C" ? color : normal) = true;
        }
    if (key.starts_with("4") || key.starts_with("n"))
        in.error("'", full, "' (4D or nD OFF) is not supported, only 3D vertices");
    if (key != "OFF")
        in.error("not an OFF file: expected the 'OFF' header, found '", full.substr(0, 40), "'");
    if (!in.atLineEnd() && in.peekWord() == "BINARY") in.error("binary OFF is not supported");

    // The counts may follow the keyword on its line ("OFF 8 12 0") or come on the next one.
    in.skipSpace();
    const uint64_t headerLine = in.line();
    const uint64_t vertexCount = in.readUnsigned("the vertex count");
    const uint64_t faceCount = in.readUnsigned("the face count");
    in.nextLine(); // the edge count, when present, is not used
    const uint64_t remaining = uint64_t(bytes.size());
    if (vertexCount > kMaxVertices)
        in.error("header declares ", vertexCount, " vertices, more than 2^32 - 1");
    if (vertexCount > remaining / kMinVertexBytes || faceCount > remaining / kMinFaceBytes ||
        vertexCount * kMinVertexBytes + faceCount * kMinFaceBytes > remaining)
        fail(path, ":", headerLine, ": header declares ", vertexCount, " vertices and ", faceCount,
             " faces, more than a file of ", bytes.size(), " bytes can hold (truncated?)");

    auto& positions = out.mesh.positions;
    positions.reserve(vertexCount);
    if (color) out.colors.reserve(vertexCount);
    for (uint64_t v = 0; v < vertexCount; ++v) {
        in.skipSpace();
        if (in.eof()) in.error("unexpected end of file at vertex ", v, " of ", vertexCount, " (truncated?)");
        Vec3f p;
        p.x = in.readFloat("x of vertex ", v);
        p.y = in.readFloat("y of vertex ", v);
        p.z = in.readFloat("z of vertex ", v);
        if (!isFinite(p)) out.nonFiniteVertices.emplace_back(uint32_t(v), in.location());
        positions.push_back(p);
        if (color) out.colors.push_back(readOffColor(in, v, normal, texture));
        in.nextLine();
    }

    auto& indices = out.mesh.indices;
    indices.reserve(3 * std::min<uint64_t>(faceCount, remaining / kMinFaceBytes));
    for (uint64_t f = 0; f < faceCount; ++f) {
        in.skipSpace();
        if (in.eof()) in.error("unexpected end of file at face ", f, " of ", faceCount, " (truncated?)");
        const uint64_t corners = in.readUnsigned("the vertex count of face ", f);
        uint32_t first = 0, previous = 0;
        for (uint64_t k = 0; k < corners; ++k) {
            const uint64_t v = in.readUnsigned("vertex ", k, " of face ", f, " (", corners, " vertices)");
            if (v >= vertexCount)
                in.error("face ", f, ": vertex index ", v, " is out of range (the file has ", vertexCount,
                         " vertices)");
            if (k == 0)
                first = uint32_t(v);
            else if (k >= 2)
                appendFanTriangle(indices, first, previous, uint32_t(v));
            previous = uint32_t(v);
        }
        in.nextLine(); // per-face colours, when present
    }
    return out;
}

} // namespace voxfx::detail
