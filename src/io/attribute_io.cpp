// voxfx — writing attribute grids (see voxfx/attribute_io.hpp): OpenVDB grids through the voxfx_vdb
// module, NRRD and NumPy dense arrays here.
#include "voxfx/attribute_io.hpp"

#include <cstring>
#include <sstream>

#include "core/atomic_file.hpp"
#include "io/grid_formats.hpp"
#include "io/module_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"

namespace voxfx {
namespace {
namespace attribute_file { // a name of its own: unity builds share one anonymous namespace

enum class Format { Vdb, Nrrd, Npy };

Format formatFromPath(const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext == ".vdb") return Format::Vdb;
    if (ext == ".nrrd") return Format::Nrrd;
    if (ext == ".npy") return Format::Npy;
    fail("'", path, "': unknown attribute grid extension '", ext, "' (allowed: .vdb .nrrd .npy)");
}

bool holds(const AttributeGrid& g, AttributeChannel c) {
    switch (c) {
    case AttributeChannel::Count:
        return !g.count.empty();
    case AttributeChannel::Absorption:
        return !g.absorption.empty();
    case AttributeChannel::Normal:
        return !g.normalSum.empty();
    case AttributeChannel::Material:
        return !g.material.empty();
    case AttributeChannel::Ior:
        return !g.ior.empty();
    case AttributeChannel::Attenuation:
        return !g.attenuation.empty();
    }
    return false;
}

int components(AttributeChannel c) {
    return c == AttributeChannel::Normal || c == AttributeChannel::Attenuation ? 3 : 1;
}

// The grid's voxels in world order (x fastest, then y, then z): world index (i, j, k) of an
// axis-aligned frame is column (w[cx], w[cy]), slice w[cs].
struct WorldOrder {
    Vec3i dims;
    std::vector<int64_t> index; // world order -> grid.index()
};

WorldOrder worldOrder(const AttributeGrid& g, const std::string& path) {
    const Frame& f = g.frame;
    if (f.isPerspective() || f.isOriented() || f.slicing() != Slicing::Uniform)
        fail("cannot write '", path,
             "': attribute files hold axis-aligned orthographic grids with uniform "
             "slicing");
    const int cx = columnXAxis(f.axis()), cy = columnYAxis(f.axis()), cs = sliceAxis(f.axis());
    WorldOrder w;
    w.dims[cx] = f.width();
    w.dims[cy] = f.height();
    w.dims[cs] = f.depth();
    w.index.reserve(std::size_t(g.voxelCount()));
    int64_t v[3];
    for (v[2] = 0; v[2] < w.dims.z; ++v[2])
        for (v[1] = 0; v[1] < w.dims.y; ++v[1])
            for (v[0] = 0; v[0] < w.dims.x; ++v[0]) w.index.push_back(g.index(v[cx], v[cy], v[cs]));
    return w;
}

// The channel's values in world order as floats (components innermost).
std::vector<float> channelFloats(const AttributeGrid& g, AttributeChannel c, const WorldOrder& w) {
    const int k = components(c);
    std::vector<float> out(w.index.size() * std::size_t(k));
    float* o = out.data();
    for (const int64_t i : w.index) {
        const auto s = std::size_t(i);
        switch (c) {
        case AttributeChannel::Count:
            *o++ = float(g.count[s]);
            break;
        case AttributeChannel::Absorption:
            *o++ = g.absorption[s];
            break;
        case AttributeChannel::Material:
            *o++ = g.material[s] == AttributeGrid::kNoMaterial ? -1.0f : float(g.material[s]);
            break;
        case AttributeChannel::Ior:
            *o++ = g.ior[s];
            break;
        case AttributeChannel::Normal:
        case AttributeChannel::Attenuation: {
            const Vec3f v = c == AttributeChannel::Normal ? g.normal(i) : g.attenuation[s];
            *o++ = v.x;
            *o++ = v.y;
            *o++ = v.z;
            break;
        }
        }
    }
    return out;
}

// Active voxels: those written at least once (the count, material or ior channel says so), else
// those whose value is not zero.
std::vector<uint8_t> activeMask(const AttributeGrid& g, const WorldOrder& w) {
    std::vector<uint8_t> active(w.index.size());
    const bool knowsWrites = !g.count.empty() || !g.material.empty() || !g.ior.empty();
    for (std::size_t n = 0; n < w.index.size(); ++n) {
        const int64_t i = w.index[n];
        if (knowsWrites) {
            active[n] = g.written(i);
            continue;
        }
        const auto s = std::size_t(i);
        const Vec3f nv = g.normalSum.empty() ? Vec3f{} : g.normalSum[s];
        const Vec3f av = g.attenuation.empty() ? Vec3f{} : g.attenuation[s];
        active[n] = (!g.absorption.empty() && g.absorption[s] != 0) || nv.x != 0 || nv.y != 0 || nv.z != 0 ||
                    av.x != 0 || av.y != 0 || av.z != 0;
    }
    return active;
}

void writeVdb(const AttributeGrid& g, const std::vector<AttributeChannel>& list, const WorldOrder& w,
              detail::AtomicFile& file) {
    const Vec3d cell = g.frame.cellSize();
    const Vec3d centre0 = g.frame.box().lo + cell * 0.5;
    const detail::VdbPlacement placement{{cell.x, cell.y, cell.z}, {centre0.x, centre0.y, centre0.z}};
    std::vector<std::vector<float>> values;
    std::vector<detail::VdbDenseGrid> grids;
    for (const AttributeChannel c : list) values.push_back(channelFloats(g, c, w));
    for (std::size_t k = 0; k < list.size(); ++k)
        grids.push_back({toString(list[k]), components(list[k]), values[k].data(),
                         list[k] == AttributeChannel::Material ? -1.0f : 0.0f});
    const std::vector<uint8_t> active = activeMask(g, w);
    const int64_t dims[3] = {w.dims.x, w.dims.y, w.dims.z};
    std::string error;
    if (!detail::vdbModule().writeDenseGrids(file.tempPath().c_str(), dims, active.data(), grids.data(),
                                             grids.size(), placement, &error))
        fail("cannot write '", file.targetPath().string(), "': ", error);
}

void writeDense(const AttributeGrid& g, AttributeChannel c, const WorldOrder& w, Format format,
                std::ostream& out) {
    // The channel's bytes in world order, and its element type.
    std::vector<char> bytes;
    const char* nrrdType = "float";
    const char* npyType = "<f4";
    if (c == AttributeChannel::Count || c == AttributeChannel::Material) {
        const bool count = c == AttributeChannel::Count;
        nrrdType = count ? "ushort" : "uint";
        npyType = count ? "<u2" : "<u4";
        const std::size_t size = count ? 2 : 4;
        bytes.resize(w.index.size() * size);
        char* o = bytes.data();
        for (const int64_t i : w.index) {
            if (count)
                std::memcpy(o, &g.count[std::size_t(i)], 2);
            else
                std::memcpy(o, &g.material[std::size_t(i)], 4);
            o += size;
        }
    } else {
        const std::vector<float> v = channelFloats(g, c, w);
        bytes.resize(v.size() * sizeof(float));
        std::memcpy(bytes.data(), v.data(), bytes.size());
    }
    const bool vector = components(c) == 3;
    if (format == Format::Nrrd) {
        const Vec3d cell = g.frame.cellSize();
        const Vec3d origin = g.frame.box().lo + cell * 0.5;
        out << "NRRD0004\n"
            << "# Complete NRRD file format specification at:\n"
            << "# http://teem.sourceforge.net/nrrd/format.html\n"
            << "# voxfx attribute grid, channel " << toString(c) << "\n"
            << "type: " << nrrdType << "\n"
            << "dimension: " << (vector ? 4 : 3) << "\n"
            << "space: right-anterior-superior\n"
            << "sizes: " << (vector ? "3 " : "") << w.dims.x << ' ' << w.dims.y << ' ' << w.dims.z << '\n'
            << "space directions: " << (vector ? "none " : "") << "(" << detail::formatDouble(cell.x)
            << ",0,0) (0," << detail::formatDouble(cell.y) << ",0) (0,0," << detail::formatDouble(cell.z)
            << ")\n"
            << "kinds: " << (vector ? "3-vector " : "") << "domain domain domain\n"
            << "endian: little\n"
            << "encoding: raw\n"
            << "space origin: (" << detail::formatDouble(origin.x) << ',' << detail::formatDouble(origin.y)
            << ',' << detail::formatDouble(origin.z) << ")\n\n";
    } else {
        std::ostringstream shape;
        shape << "(" << (vector ? "3, " : "") << w.dims.x << ", " << w.dims.y << ", " << w.dims.z << ")";
        detail::writeNpyHeader(out, npyType, shape.str());
    }
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

} // namespace attribute_file
} // namespace

const char* toString(AttributeChannel c) { return enumName(c, kAttributeChannelNames); }

AttributeChannels parseAttributeChannels(const std::string& list) {
    AttributeChannels c{false, false, false, false, false, false};
    std::size_t start = 0, named = 0;
    while (start <= list.size()) {
        const std::size_t end = std::min(list.find(',', start), list.size());
        const std::string name = list.substr(start, end - start);
        start = end + 1;
        if (name.empty()) continue;
        ++named;
        switch (parseEnum<AttributeChannel>(name, "attribute channel", kAttributeChannelNames)) {
        case AttributeChannel::Count:
            c.count = true;
            break;
        case AttributeChannel::Absorption:
            c.absorption = true;
            break;
        case AttributeChannel::Normal:
            c.normals = true;
            break;
        case AttributeChannel::Material:
            c.material = true;
            break;
        case AttributeChannel::Ior:
            c.ior = true;
            break;
        case AttributeChannel::Attenuation:
            c.attenuation = true;
            break;
        }
    }
    if (!named)
        fail("no attribute channel named (allowed: ", enumNameList<AttributeChannel>(kAttributeChannelNames),
             ")");
    return c;
}

std::vector<AttributeChannel> channelList(const AttributeChannels& c) {
    std::vector<AttributeChannel> out;
    if (c.count) out.push_back(AttributeChannel::Count);
    if (c.absorption) out.push_back(AttributeChannel::Absorption);
    if (c.normals) out.push_back(AttributeChannel::Normal);
    if (c.material) out.push_back(AttributeChannel::Material);
    if (c.ior) out.push_back(AttributeChannel::Ior);
    if (c.attenuation) out.push_back(AttributeChannel::Attenuation);
    return out;
}

void writeAttributeGrid(const AttributeGrid& grid, const std::string& path,
                        std::optional<AttributeChannel> only) {
    using namespace attribute_file;
    const Format format = formatFromPath(path);
    std::vector<AttributeChannel> list = channelList(grid.channels());
    if (only) {
        if (!holds(grid, *only))
            fail("cannot write '", path, "': the attribute grid has no ", toString(*only), " channel");
        list = {*only};
    }
    if (list.empty()) fail("cannot write '", path, "': the attribute grid holds no channel");
    if (format != Format::Vdb && list.size() > 1) {
        std::string names;
        for (const AttributeChannel c : list) names += std::string(names.empty() ? "" : ", ") + toString(c);
        fail("cannot write '", path, "': a ", format == Format::Nrrd ? ".nrrd" : ".npy",
             " file holds one channel and the grid has ", list.size(), " (", names,
             "): name one, or write .vdb for all");
    }
    const WorldOrder w = worldOrder(grid, path);
    detail::AtomicFile file(path);
    if (format == Format::Vdb)
        writeVdb(grid, list, w, file);
    else
        writeDense(grid, list.front(), w, format, file.stream());
    file.commit();
}

} // namespace voxfx
