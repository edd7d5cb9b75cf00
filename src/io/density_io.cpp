// voxfx — writing density maps (NRRD counts, OpenVDB fog volumes) and their normals (NRRD).
// Placement follows grid_io.hpp: index (i, j, k) along world x, y, z sits at the centre of the
// density cell, origin = lower box corner + half a density cell.
#include <algorithm>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <vector>

#include "core/atomic_file.hpp"
#include "io/module_api.hpp"
#include "voxfx/density.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace {

std::string num(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    return std::string(buf, r.ptr);
}

// World-index view of a density grid in the axes of its (density) frame.
struct WorldIndexer {
    Axis axis;
    Vec3i dims; // cells along world x, y, z
    void grid(int64_t i, int64_t j, int64_t k, int64_t& x, int64_t& y, int64_t& s) const {
        const Vec3i w{i, j, k};
        x = w[columnXAxis(axis)];
        y = w[columnYAxis(axis)];
        s = w[sliceAxis(axis)];
    }
};

WorldIndexer indexerFor(const DensityGrid& density, const Frame& coarse) {
    WorldIndexer ix{coarse.axis(), {}};
    ix.dims[columnXAxis(ix.axis)] = density.width();
    ix.dims[columnYAxis(ix.axis)] = density.height();
    ix.dims[sliceAxis(ix.axis)] = density.depth();
    return ix;
}

Frame checkedCoarseFrame(const DensityGrid& density, const Frame& fineFrame, const std::string& path) {
    if (density.empty()) fail("cannot write '", path, "': the density map is empty");
    if (fineFrame.isPerspective() || fineFrame.slicing() != Slicing::Uniform)
        fail("cannot write '", path, "': density files need an orthographic, uniformly sliced grid");
    const Frame coarse = densityFrame(fineFrame, density.level());
    if (coarse.width() != density.width() || coarse.height() != density.height() ||
        coarse.depth() != density.depth())
        fail("cannot write '", path, "': the density map (", density.width(), " x ", density.height(), " x ",
             density.depth(), ") was not computed from a grid of this frame");
    return coarse;
}

void writeNrrdHeader(std::ostream& out, const Frame& coarse, const Vec3i& n, const char* type, bool vector,
                     const char* comment) {
    const Vec3d cell = coarse.cellSize();
    const Vec3d origin = coarse.box().lo + cell * 0.5;
    out << "NRRD0004\n"
        << "# Complete NRRD file format specification at:\n"
        << "# http://teem.sourceforge.net/nrrd/format.html\n"
        << "# " << comment << "\n"
        << "type: " << type << "\n"
        << "dimension: " << (vector ? 4 : 3) << "\n"
        << "space: right-anterior-superior\n"
        << "sizes: " << (vector ? "3 " : "") << n.x << ' ' << n.y << ' ' << n.z << '\n'
        << "space directions: " << (vector ? "none " : "") << "(" << num(cell.x) << ",0,0) (0," << num(cell.y)
        << ",0) (0,0," << num(cell.z) << ")\n"
        << "kinds: " << (vector ? "3-vector " : "") << "domain domain domain\n"
        << "endian: little\n"
        << "encoding: raw\n"
        << "space origin: (" << num(origin.x) << ',' << num(origin.y) << ',' << num(origin.z) << ")\n\n";
}

// Streams the world-ordered samples slab by slab (z = k): `sample(x, y, s, dst)` writes one
// sample of `bytes` bytes.
template <class F>
void writeWorldOrdered(std::ostream& out, const WorldIndexer& ix, size_t bytes, const F& sample) {
    const Vec3i n = ix.dims;
    std::vector<char> slab(size_t(n.x * n.y) * bytes);
    for (int64_t k = 0; k < n.z; ++k) {
        parallelFor(0, n.y, 16, [&](int64_t b, int64_t e) {
            for (int64_t j = b; j < e; ++j)
                for (int64_t i = 0; i < n.x; ++i) {
                    int64_t x, y, s;
                    ix.grid(i, j, k, x, y, s);
                    sample(x, y, s, slab.data() + size_t(j * n.x + i) * bytes);
                }
        });
        out.write(slab.data(), std::streamsize(slab.size()));
    }
}

bool hasExtension(const std::string& path, const char* ext) { return fileExtension(path) == ext; }

} // namespace

void writeDensity(const DensityGrid& density, const Frame& fineFrame, const std::string& path) {
    const bool nrrd = hasExtension(path, ".nrrd"), vdb = hasExtension(path, ".vdb");
    if (!nrrd && !vdb) fail("'", path, "': density maps are written as .nrrd (counts) or .vdb (occupancy)");
    const Frame coarse = checkedCoarseFrame(density, fineFrame, path);
    const WorldIndexer ix = indexerFor(density, coarse);

    detail::AtomicFile file(path);
    if (nrrd) {
        const bool wide = density.maxCount() > 255;
        writeNrrdHeader(file.stream(), coarse, ix.dims, wide ? "ushort" : "uchar", false,
                        detail::concat("voxfx density map, level ", density.level(), ": filled cells per ",
                                       density.kernel(), "^3 block (0..", density.maxCount(), ")")
                            .c_str());
        if (wide)
            writeWorldOrdered(file.stream(), ix, 2, [&](int64_t x, int64_t y, int64_t s, char* dst) {
                const auto v = uint16_t(density.count(x, y, s));
                const unsigned char le[2] = {uint8_t(v & 0xFF), uint8_t(v >> 8)};
                std::memcpy(dst, le, 2);
            });
        else
            writeWorldOrdered(file.stream(), ix, 1, [&](int64_t x, int64_t y, int64_t s, char* dst) {
                *dst = char(uint8_t(density.count(x, y, s)));
            });
    } else {
        // Dense values in world index order (x fastest); the module keeps zeros inactive.
        const float scale = 1.0f / float(density.maxCount());
        std::vector<float> values(size_t(ix.dims.x * ix.dims.y * ix.dims.z), 0.0f);
        for (int64_t y = 0; y < density.height(); ++y)
            for (int64_t x = 0; x < density.width(); ++x)
                for (int64_t s = 0; s < density.depth(); ++s) {
                    const uint64_t c = density.count(x, y, s);
                    if (!c) continue;
                    Vec3i g;
                    g[columnXAxis(ix.axis)] = x;
                    g[columnYAxis(ix.axis)] = y;
                    g[sliceAxis(ix.axis)] = s;
                    values[size_t((g.z * ix.dims.y + g.y) * ix.dims.x + g.x)] = float(c) * scale;
                }
        const Vec3d cell = coarse.cellSize();
        const Vec3d centre0 = coarse.box().lo + cell * 0.5;
        const detail::VdbPlacement placement{{cell.x, cell.y, cell.z}, {centre0.x, centre0.y, centre0.z}};
        const int64_t dims[3] = {ix.dims.x, ix.dims.y, ix.dims.z};
        std::string error;
        if (!detail::vdbModule().writeFloats(file.tempPath().c_str(), dims, values.data(), placement,
                                             "density", &error))
            fail("cannot write '", path, "': ", error);
    }
    file.commit();
}

void writeDensityNormalsNrrd(const DensityGrid& density, const Frame& fineFrame, const std::string& path) {
    if (!hasExtension(path, ".nrrd")) fail("'", path, "': density normals are written as .nrrd");
    const Frame coarse = checkedCoarseFrame(density, fineFrame, path);
    const WorldIndexer ix = indexerFor(density, coarse);
    detail::AtomicFile file(path);
    writeNrrdHeader(
        file.stream(), coarse, ix.dims, "float", true,
        "voxfx density normals: outward unit vectors in world axes (0 where the gradient vanishes)");
    writeWorldOrdered(file.stream(), ix, 12, [&](int64_t x, int64_t y, int64_t s, char* dst) {
        const Vec3d n = worldFromGridNormal(coarse, Vec3d(densityNormal(density, x, y, s)));
        const float v[3] = {float(n.x), float(n.y), float(n.z)};
        std::memcpy(dst, v, sizeof(v)); // little-endian hosts only (x86-64, aarch64)
    });
    file.commit();
}

} // namespace voxfx
