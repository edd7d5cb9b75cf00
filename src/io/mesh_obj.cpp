// voxfx — Wavefront OBJ reader: geometry only.
//
//   v x y z [w | r g b]     a vertex (extra columns ignored)
//   f a b c ...             a polygon; each corner is v, v/vt, v//vn or v/vt/vn; 1-based indices,
//                           negative ones relative to the vertices read so far; fan-triangulated
//
// Everything else (vt, vn, l, p, g, o, s, usemtl, mtllib, free-form curves) is skipped: OBJ has no
// transforms, and groups only name parts of the one mesh. '#' starts a comment.
#include <algorithm>

#include "io/mesh_formats.hpp"

namespace voxfx::detail {

ParsedMesh parseObj(std::string_view bytes, const std::string& path) {
    ParsedMesh out;
    out.firstVertexNumber = 1;
    auto& positions = out.mesh.positions;
    auto& indices = out.mesh.indices;
    // A vertex line is at least "v 0 0 0\n": a cheap bound that avoids most regrowth.
    positions.reserve(bytes.size() / 64);
    indices.reserve(bytes.size() / 16);

    // Positive indices may refer to vertices defined later in the file (many writers do so), so
    // they are checked at the end; the largest one and its line are kept for the message.
    uint64_t largestIndex = 0, largestIndexLine = 0;

    TextReader in(bytes, path, '#');
    while (!in.eof()) {
        in.skipBlanks();
        const char c = in.peek();
        if (c == 'v') {
            in.advance();
            if (in.peek() == ' ' || in.peek() == '\t') {
                if (positions.size() >= kMaxVertices) in.error("more than 2^32 - 1 vertices");
                const std::size_t v = positions.size();
                Vec3f p;
                p.x = in.readFloat("x of vertex ", v + 1);
                p.y = in.readFloat("y of vertex ", v + 1);
                p.z = in.readFloat("z of vertex ", v + 1);
                if (!isFinite(p)) out.nonFiniteVertices.emplace_back(uint32_t(v), in.location());
                positions.push_back(p);
            }
        } else if (c == 'f') {
            in.advance();
            if (in.peek() == ' ' || in.peek() == '\t') {
                uint32_t first = 0, previous = 0;
                for (int k = 0; !in.atLineEnd(); ++k) {
                    const int64_t i = in.readSigned(true, "a vertex index");
                    // Skip the texture and normal indices of this corner.
                    while (in.peek() == '/' || (in.peek() >= '0' && in.peek() <= '9') || in.peek() == '-')
                        in.advance();
                    int64_t v = 0;
                    if (i > 0) {
                        v = i - 1;
                        if (uint64_t(i) > largestIndex) {
                            largestIndex = uint64_t(i);
                            largestIndexLine = in.line();
                        }
                    } else if (i < 0) {
                        v = int64_t(positions.size()) + i;
                        if (v < 0)
                            in.error("relative vertex index ", i, " reaches before the first vertex (",
                                     positions.size(), " vertices so far)");
                    } else {
                        in.error("vertex index 0 is invalid (OBJ indices start at 1)");
                    }
                    if (v >= int64_t(kMaxVertices)) in.error("vertex index ", i, " is out of range");
                    if (k == 0)
                        first = uint32_t(v);
                    else if (k >= 2)
                        appendFanTriangle(indices, first, previous, uint32_t(v));
                    previous = uint32_t(v);
                }
            }
        }
        in.nextLine();
    }
    if (largestIndex > positions.size())
        fail(path, ":", largestIndexLine, ": vertex index ", largestIndex, " is out of range (the file has ",
             positions.size(), " vertices)");
    return out;
}

} // namespace voxfx::detail
