// voxfx — STL reader, binary and ASCII.
//
// Binary: an 80-byte header, a little-endian uint32 triangle count n, then n records of 50 bytes
// (normal, three vertices as 3 x float32, a 16-bit attribute): the file must hold 84 + 50 n bytes.
// ASCII: "solid name", then facets "facet normal nx ny nz / outer loop / vertex x y z (x3) /
// endloop / endfacet", then "endsolid name"; several solids may follow each other.
//
// Some binary writers start their header with "solid" too, so the choice is made on the size
// (84 + 50 n) and on whether the first bytes look like text. STL has no shared vertices: each
// triangle gets its own three, in file order (analyzeTopology merges identical positions).
#include <algorithm>

#include "io/mesh_formats.hpp"

namespace voxfx::detail {

namespace {

constexpr std::size_t kHeaderBytes = 84;
constexpr std::size_t kRecordBytes = 50;

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return (x | 0x20) == (y | 0x20); // ASCII letters only, which is all STL keywords use
           });
}

// True when the first kilobyte is printable text (binary triangle records hold NULs and control
// bytes almost surely).
bool looksLikeText(std::string_view bytes) {
    const std::size_t n = std::min<std::size_t>(bytes.size(), 1024);
    for (std::size_t i = 0; i < n; ++i) {
        const auto c = static_cast<unsigned char>(bytes[i]);
        if (c < 0x20 && !TextReader::isSpace(char(c))) return false;
    }
    return true;
}

ParsedMesh parseBinaryStl(std::string_view bytes, const std::string& path) {
    if (bytes.size() < kHeaderBytes)
        fail(path, ": the file has ", bytes.size(),
             " bytes, too few for a binary STL (84-byte header) (truncated?)");
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
    const uint64_t count = loadValue<uint32_t>(data + 80, false);
    const uint64_t needed = kHeaderBytes + kRecordBytes * count;
    if (bytes.size() < needed) {
        const uint64_t complete = (bytes.size() - kHeaderBytes) / kRecordBytes;
        fail(path, ": byte ", kHeaderBytes + kRecordBytes * complete,
             ": truncated binary STL: the header declares ", count, " triangles (", needed,
             " bytes) but the file has ", bytes.size(), " bytes; triangle ", complete, " is incomplete");
    }
    if (3 * count > kMaxVertices)
        fail(path, ": binary STL with ", count, " triangles, more than 32-bit indices allow");

    ParsedMesh out;
    auto& positions = out.mesh.positions;
    auto& indices = out.mesh.indices;
    positions.resize(3 * count);
    indices.resize(3 * count);
    for (uint64_t t = 0; t < count; ++t) {
        const unsigned char* record = data + kHeaderBytes + kRecordBytes * t;
        for (int c = 0; c < 3; ++c) {
            const unsigned char* v = record + 12 + 12 * c;
            Vec3f p{loadValue<float>(v, false), loadValue<float>(v + 4, false),
                    loadValue<float>(v + 8, false)};
            const uint64_t i = 3 * t + uint64_t(c);
            if (!isFinite(p))
                fail(path, ": byte ", v - data, ": vertex ", c, " of triangle ", t,
                     " has a non-finite coordinate (", p.x, " ", p.y, " ", p.z, ")");
            positions[i] = p;
            indices[i] = uint32_t(i);
        }
    }
    return out;
}

ParsedMesh parseAsciiStl(std::string_view bytes, const std::string& path) {
    ParsedMesh out;
    auto& positions = out.mesh.positions;
    auto& indices = out.mesh.indices;
    // A facet takes about 250 bytes of text; a bound that avoids most regrowth.
    positions.reserve(3 * (bytes.size() / 200));
    indices.reserve(3 * (bytes.size() / 200));

    TextReader in(bytes, path, 0);
    auto expect = [&](std::string_view keyword) {
        in.skipSpace();
        const std::string_view w = in.word();
        if (!equalsIgnoreCase(w, keyword)) {
            if (w.empty()) in.error("expected '", keyword, "', found the end of the file (truncated?)");
            in.error("expected '", keyword, "', found '", w.substr(0, 40), "'",
                     in.eof() ? " at the end of the file (truncated?)" : "");
        }
    };
    in.skipSpace();
    expect("solid");
    in.nextLine(); // the solid's name
    for (uint64_t facet = 0;;) {
        in.skipSpace();
        const std::string_view key = in.word();
        if (equalsIgnoreCase(key, "endsolid")) {
            in.nextLine();
            in.skipSpace();
            if (in.eof()) break;
            expect("solid"); // another solid follows
            in.nextLine();
            continue;
        }
        if (key.empty()) in.error("the file ends without 'endsolid' (truncated?)");
        if (!equalsIgnoreCase(key, "facet"))
            in.error("expected 'facet' or 'endsolid', found '", key.substr(0, 40), "'",
                     in.eof() ? " at the end of the file (truncated?)" : "");
        in.nextLine(); // "normal nx ny nz": recomputed from the vertices by whoever needs it
        expect("outer");
        expect("loop");
        const std::size_t base = positions.size();
        for (;;) {
            in.skipSpace();
            const std::string_view w = in.word();
            if (equalsIgnoreCase(w, "endloop")) break;
            if (!equalsIgnoreCase(w, "vertex")) {
                if (w.empty()) in.error("the file ends inside facet ", facet, " (truncated?)");
                in.error("expected 'vertex' or 'endloop' in facet ", facet, ", found '", w.substr(0, 40), "'",
                         in.eof() ? " at the end of the file (truncated?)" : "");
            }
            const std::size_t k = positions.size() - base;
            Vec3f p;
            p.x = in.readFloat("x of vertex ", k, " of facet ", facet);
            p.y = in.readFloat("y of vertex ", k, " of facet ", facet);
            p.z = in.readFloat("z of vertex ", k, " of facet ", facet);
            if (!isFinite(p))
                in.error("vertex ", k, " of facet ", facet, " has a non-finite coordinate (", p.x, " ", p.y,
                         " ", p.z, ")");
            if (positions.size() >= kMaxVertices) in.error("more than 2^32 - 1 vertices");
            positions.push_back(p);
        }
        const std::size_t corners = positions.size() - base;
        if (corners < 3) in.error("facet ", facet, " has ", corners, " vertices, a triangle needs 3");
        for (std::size_t k = 2; k < corners; ++k)
            appendFanTriangle(indices, uint32_t(base), uint32_t(base + k - 1), uint32_t(base + k));
        expect("endfacet");
        ++facet;
    }
    return out;
}

} // namespace

ParsedMesh parseStl(std::string_view bytes, const std::string& path) {
    std::size_t start = 0;
    while (start < bytes.size() && TextReader::isSpace(bytes[start])) ++start;
    const bool solid = bytes.size() - start >= 5 && equalsIgnoreCase(bytes.substr(start, 5), "solid");
    bool binarySize = false;
    if (bytes.size() >= kHeaderBytes) {
        const uint64_t count =
            loadValue<uint32_t>(reinterpret_cast<const unsigned char*>(bytes.data()) + 80, false);
        binarySize = bytes.size() == kHeaderBytes + kRecordBytes * count;
    }
    if (solid && !binarySize && looksLikeText(bytes)) return parseAsciiStl(bytes, path);
    return parseBinaryStl(bytes, path);
}

} // namespace voxfx::detail
