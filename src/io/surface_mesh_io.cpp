// voxfx — writing marching-cubes surfaces (.ply binary little endian with normals, .obj); the
// extraction itself lives in grid/surface_mesh.cpp.
#include <cstdio>
#include <cstring>
#include <vector>

#include "core/atomic_file.hpp"
#include "io/ply_header.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/surface_mesh.hpp"

namespace voxfx {

void writeSurfaceMesh(const SurfaceMesh& mesh, const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext != ".ply" && ext != ".obj") fail("'", path, "': surface meshes are written as .ply or .obj");
    if (mesh.normals.size() != mesh.positions.size())
        fail("cannot write '", path, "': the mesh has ", mesh.positions.size(), " positions but ",
             mesh.normals.size(), " normals");
    detail::AtomicFile file(path);
    std::ostream& out = file.stream();
    if (ext == ".ply") {
        detail::writePlyHeader(out, "voxfx marching cubes",
                               {{"vertex",
                                 int64_t(mesh.positions.size()),
                                 {"float x", "float y", "float z", "float nx", "float ny", "float nz"}},
                                {"face", int64_t(mesh.triangleCount()), {"list uchar int vertex_indices"}}});
        std::vector<char> buf;
        buf.reserve(1 << 20);
        auto flush = [&] {
            out.write(buf.data(), std::streamsize(buf.size()));
            buf.clear();
        };
        auto put = [&](const void* p, size_t n) {
            const char* c = static_cast<const char*>(p);
            buf.insert(buf.end(), c, c + n);
            if (buf.size() >= (1 << 20)) flush();
        };
        // Little-endian hosts only (x86-64, aarch64): floats and ints are written as in memory.
        for (size_t i = 0; i < mesh.positions.size(); ++i) {
            const float v[6] = {mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z,
                                mesh.normals[i].x,   mesh.normals[i].y,   mesh.normals[i].z};
            put(v, sizeof(v));
        }
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            char rec[13];
            rec[0] = 3;
            const int32_t idx[3] = {int32_t(mesh.indices[3 * t]), int32_t(mesh.indices[3 * t + 1]),
                                    int32_t(mesh.indices[3 * t + 2])};
            std::memcpy(rec + 1, idx, sizeof(idx));
            put(rec, sizeof(rec));
        }
        flush();
    } else {
        out << "# voxfx marching cubes: " << mesh.positions.size() << " vertices, " << mesh.triangleCount()
            << " triangles\n";
        char line[160];
        for (const Vec3f& p : mesh.positions) {
            const int n = std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
            out.write(line, n);
        }
        for (const Vec3f& p : mesh.normals) {
            const int n = std::snprintf(line, sizeof(line), "vn %.6g %.6g %.6g\n", p.x, p.y, p.z);
            out.write(line, n);
        }
        for (size_t t = 0; t < mesh.triangleCount(); ++t) {
            const uint32_t a = mesh.indices[3 * t] + 1, b = mesh.indices[3 * t + 1] + 1,
                           c = mesh.indices[3 * t + 2] + 1;
            const int n = std::snprintf(line, sizeof(line), "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
            out.write(line, n);
        }
    }
    file.commit();
}

} // namespace voxfx
