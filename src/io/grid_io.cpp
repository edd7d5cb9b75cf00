#include "voxfx/grid_io.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "core/atomic_file.hpp"
#include "io/grid_formats.hpp"
#include "io/module_api.hpp"
#include "voxfx/file_name.hpp"

namespace voxfx {

namespace {
constexpr const char* kAllowedExtensions = ".binvox, .vdb, .nrrd, .ply, .obj, .npy, .npz";

} // namespace

namespace detail {
std::vector<uint8_t> readFileBytes(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) fail("cannot read '", path, "': it is a directory");
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) fail("cannot read '", path, "': ", errno ? std::strerror(errno) : "cannot open the file");
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    if (size < 0) fail("cannot read '", path, "': cannot determine the file size");
    in.seekg(0, std::ios::beg);
    std::vector<uint8_t> bytes(static_cast<size_t>(size));
    in.read(reinterpret_cast<char*>(bytes.data()), size);
    if (in.gcount() != size) fail("cannot read '", path, "': ", errno ? std::strerror(errno) : "short read");
    return bytes;
}

std::string formatDouble(double v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    return std::string(buf, r.ptr);
}

void writeNpyHeader(std::ostream& out, const std::string& descr, const std::string& shape,
                    bool fortranOrder) {
    std::string dict = "{'descr': '" + descr + "', 'fortran_order': " + (fortranOrder ? "True" : "False") +
                       ", 'shape': " + shape + ", }";
    const std::size_t unpadded = 10 + dict.size() + 1;
    dict.append((64 - unpadded % 64) % 64, ' ');
    dict += '\n';
    const auto len = uint16_t(dict.size());
    out.write("\x93NUMPY\x01\x00", 8);
    const char lenBytes[2] = {char(len & 0xFF), char(len >> 8)};
    out.write(lenBytes, 2);
    out << dict;
}
} // namespace detail

GridFormat gridFormatFromPath(const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext == ".binvox") return GridFormat::Binvox;
    if (ext == ".vdb") return GridFormat::Vdb;
    if (ext == ".nrrd") return GridFormat::Nrrd;
    if (ext == ".ply") return GridFormat::Ply;
    if (ext == ".obj") return GridFormat::Obj;
    if (ext == ".npy") return GridFormat::Npy;
    if (ext == ".npz") return GridFormat::Npz;
    fail("'", path, "': unknown voxel grid extension '", ext, "' (allowed: ", kAllowedExtensions, ")");
}

const char* toString(GridFormat f) { return enumName(f, kGridFormatNames); }

void prepareGridFormat(const std::string& path, bool background) {
    if (fileExtension(path) != ".vdb") return;
    if (background)
        detail::prefetchVdbModule();
    else
        detail::vdbModule();
}

void writeGrid(const VoxelGrid& grid, const std::string& path, const GridWriteOptions& options) {
    const GridFormat format = gridFormatFromPath(path);
    const Frame& f = grid.frame;
    if (f.isPerspective())
        fail("cannot write '", path, "': ", toString(format),
             " needs an orthographic grid, this one is perspective (re-voxelize with an orthographic frame)");
    if (f.isOriented())
        fail("cannot write '", path, "': ", toString(format),
             " holds axis-aligned grids, this one is oriented (e.g. a turned volume's lattice)");
    if (f.columnCount() == 0 || grid.bits.width() != f.width() || grid.bits.height() != f.height() ||
        grid.bits.depth() != f.depth())
        fail("cannot write '", path, "': the grid's bits (", grid.bits.width(), " x ", grid.bits.height(),
             " x ", grid.bits.depth(), ") do not match its frame (", f.width(), " x ", f.height(), " x ",
             f.depth(), ")");
    const VoxelGrid resampled = f.slicing() == Slicing::Local ? resampleToUniform(grid) : VoxelGrid{};
    const VoxelGrid& uniform = f.slicing() == Slicing::Local ? resampled : grid;

    detail::AtomicFile file(path);
    switch (format) {
    case GridFormat::Binvox:
        detail::writeBinvox(uniform, file.stream());
        break;
    case GridFormat::Vdb:
        detail::writeVdb(uniform, file, options);
        break;
    case GridFormat::Nrrd:
        detail::writeNrrd(uniform, file.stream());
        break;
    case GridFormat::Ply:
    case GridFormat::Obj:
        detail::writeVoxelMesh(uniform, file.stream(), format);
        break;
    case GridFormat::Npy:
        detail::writeGridNpy(uniform, file.stream());
        break;
    case GridFormat::Npz:
        detail::writeGridNpz(uniform, file.stream());
        break;
    }
    file.commit();
}

VoxelGrid readGrid(const std::string& path) {
    const GridFormat format = gridFormatFromPath(path);
    if (format == GridFormat::Ply || format == GridFormat::Obj)
        fail("cannot read '", path, "': ", toString(format),
             " voxel meshes are write-only (readable: .binvox, .vdb, .nrrd)");
    if (format == GridFormat::Npy || format == GridFormat::Npz)
        fail("cannot read '", path, "': ", toString(format),
             " grids are written for NumPy (np.load) and not read back (readable: .binvox, .vdb, .nrrd)");
    try {
        switch (format) {
        case GridFormat::Binvox:
            return detail::readBinvox(detail::readFileBytes(path));
        case GridFormat::Nrrd:
            return detail::readNrrd(detail::readFileBytes(path));
        default: {
            // The module checks the bytes, then hands them to OpenVDB as a stream; they are freed
            // once parsed, before the grid is allocated.
            std::vector<uint8_t> bytes = detail::readFileBytes(path);
            return detail::readVdb(bytes, &bytes);
        }
        }
    } catch (const Error& e) {
        const std::string what = e.what();
        if (what.find(path) != std::string::npos) throw;
        fail("cannot read '", path, "': ", what);
    } catch (const std::bad_alloc&) { fail("cannot read '", path, "': out of memory"); }
}

void writeGrid(const SparseGrid& grid, const std::string& path, const GridWriteOptions& options) {
    const GridFormat format = gridFormatFromPath(path);
    if (format == GridFormat::Ply || format == GridFormat::Obj || format == GridFormat::Npy ||
        format == GridFormat::Npz) {
        writeGrid(grid.toDense(), path, options);
        return;
    }
    detail::AtomicFile file(path);
    if (format == GridFormat::Vdb) {
        detail::writeSparseVdb(grid, file, options);
    } else {
        // Slabs along the format's slowest axis, each read densely from the tree.
        const Vec3i n = grid.dims();
        if (n.x == 0) fail("cannot write '", path, "': the sparse grid has no frame");
        // binvox: slabs of x, z-sliced (one column of nz bits per (x, y)); nrrd: slabs of z, whose
        // z-sliced columns take a word per 64 slices. Twice: the slab and its reslicing.
        const int a = format == GridFormat::Binvox ? 0 : 2;
        const int64_t unit = a == 0 ? 1 : 64;
        const uint64_t unitBytes = BitGrid::requiredBytes(a == 0 ? 1 : n.x, n.y, a == 0 ? n.z : 64);
        const uint64_t budget = options.slabBytes ? options.slabBytes : availableMemoryBytes() / 8;
        const int64_t slab =
            std::min<int64_t>(n[a], std::max<int64_t>(1, int64_t(budget / (2 * unitBytes))) * unit);
        auto cells = [&](int64_t lo, int64_t hi) {
            IndexBox box{{0, 0, 0}, n - Vec3i{1, 1, 1}};
            box.lo[a] = lo;
            box.hi[a] = hi - 1;
            return grid.toDense(box);
        };
        if (format == GridFormat::Binvox)
            detail::writeBinvoxSlabs(grid.frame(), n, slab, cells, file.stream());
        else
            detail::writeNrrdSlabs(grid.frame(), n, slab, cells, file.stream());
    }
    file.commit();
}

SparseGrid readSparseGrid(const std::string& path) {
    if (gridFormatFromPath(path) != GridFormat::Vdb) return SparseGrid::fromDense(readGrid(path));
    try {
        return detail::readSparseVdb(detail::readFileBytes(path));
    } catch (const Error& e) {
        const std::string what = e.what();
        if (what.find(path) != std::string::npos) throw;
        fail("cannot read '", path, "': ", what);
    } catch (const std::bad_alloc&) { fail("cannot read '", path, "': out of memory"); }
}

} // namespace voxfx
