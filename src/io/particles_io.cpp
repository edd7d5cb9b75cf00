// voxfx — writing particle sets (.ply binary little endian, .csv); the simulation lives in
// sim/particles.cpp.
#include "voxfx/particles_io.hpp"

#include <cstdio>

#include "core/atomic_file.hpp"
#include "io/ply_header.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/particles.hpp"

namespace voxfx {

void writeParticles(const Particles& ps, const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext != ".ply" && ext != ".csv") fail("'", path, "': particles are written as .ply or .csv");
    detail::AtomicFile file(path);
    std::ostream& out = file.stream();
    if (ext == ".ply") {
        detail::writePlyHeader(out, "voxfx particles",
                               {{"vertex",
                                 int64_t(ps.size()),
                                 {"float x", "float y", "float z", "float vx", "float vy", "float vz"}}});
        // Little-endian hosts only (x86-64, aarch64).
        for (std::size_t i = 0; i < ps.size(); ++i) {
            const float rec[6] = {ps.px[i], ps.py[i], ps.pz[i], ps.vx[i], ps.vy[i], ps.vz[i]};
            out.write(reinterpret_cast<const char*>(rec), sizeof(rec));
        }
    } else {
        out << "x,y,z,vx,vy,vz\n";
        char line[192];
        for (std::size_t i = 0; i < ps.size(); ++i) {
            const int len = std::snprintf(line, sizeof(line), "%.9g,%.9g,%.9g,%.7g,%.7g,%.7g\n", ps.px[i],
                                          ps.py[i], ps.pz[i], ps.vx[i], ps.vy[i], ps.vz[i]);
            out.write(line, len);
        }
    }
    file.commit();
}

} // namespace voxfx
