// voxfx — writing signed distance fields (see voxfx/sdf_io.hpp): the OpenVDB level set through the
// voxfx_vdb module, NRRD and NumPy dense floats here.
#include "voxfx/sdf_io.hpp"

#include <atomic>
#include <bit>
#include <chrono>
#include <cstddef>
#include <cstring>

#include "core/atomic_file.hpp"
#include "grid/sdf_detail.hpp"
#include "io/grid_formats.hpp"
#include "io/module_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace detail {
namespace {

// The module reads the library's leaves and runs as its own plain structs: same layout.
static_assert(sizeof(SdfLeaf) == sizeof(VdbLevelSetLeaf) &&
              offsetof(SdfLeaf, origin) == offsetof(VdbLevelSetLeaf, origin) &&
              offsetof(SdfLeaf, active) == offsetof(VdbLevelSetLeaf, active) &&
              offsetof(SdfLeaf, values) == offsetof(VdbLevelSetLeaf, values));
static_assert(sizeof(SdfInsideRun) == sizeof(VdbInsideRun) &&
              offsetof(SdfInsideRun, x0) == offsetof(VdbInsideRun, x0) &&
              offsetof(SdfInsideRun, z) == offsetof(VdbInsideRun, z));

void sdfParallelFor(int64_t begin, int64_t end, int64_t grain, void* body,
                    void (*call)(void* body, int64_t b, int64_t e)) {
    parallelFor(begin, end, grain, [&](int64_t b, int64_t e) { call(body, b, e); });
}

VdbPlacement sdfPlacement(const SignedDistanceField& f) {
    const Vec3d cell = f.frame.cellSize();
    const Vec3d centre0 = f.frame.box().lo + cell * 0.5;
    return {{cell.x, cell.y, cell.z}, {centre0.x, centre0.y, centre0.z}};
}

void writeSdfVdb(const SignedDistanceField& f, AtomicFile& file, const SdfWriteOptions& options) {
    const VdbModule& vdb = vdbModule();
    const VdbPlacement placement = sdfPlacement(f);
    const Vec3i d = f.dims();
    VdbLevelSet ls;
    ls.dims[0] = d.x;
    ls.dims[1] = d.y;
    ls.dims[2] = d.z;
    ls.background = float(f.background);
    ls.leaves = reinterpret_cast<const VdbLevelSetLeaf*>(f.leaves.data());
    ls.leafCount = f.leaves.size();
    ls.insideRuns = reinterpret_cast<const VdbInsideRun*>(f.insideRuns.data());
    ls.insideRunCount = f.insideRuns.size();
    std::string error;
    if (!vdb.writeLevelSet(file.tempPath().c_str(), ls, placement, options.gridName.c_str(), sdfParallelFor,
                           &error))
        fail("cannot write '", file.targetPath().string(), "': ", error);
}

// The field's bricks straight into the module's level-set tree (SdfSink), each freed once added.
class SdfVdbSink final : public SdfSink {
public:
    explicit SdfVdbSink(const std::string& path) : vdb_(vdbModule()), path_(path) {}
    ~SdfVdbSink() override {
        if (grid_) vdb_.levelSetDestroy(grid_);
    }
    SdfVdbSink(const SdfVdbSink&) = delete;
    SdfVdbSink& operator=(const SdfVdbSink&) = delete;

    void begin(const SignedDistanceField& f) override {
        std::string error;
        grid_ = vdb_.levelSetCreate(float(f.background), &error);
        if (!grid_) fail("cannot write '", path_, "': ", error);
    }
    void add(std::vector<SdfLeaf>& leaves, std::vector<SdfInsideRun>& runs) override {
        int64_t n = 0;
        for (const SdfLeaf& l : leaves)
            for (const uint64_t w : l.active) n += std::popcount(w);
        active_ += n;
        std::string error;
        if (!vdb_.levelSetAdd(grid_, reinterpret_cast<const VdbLevelSetLeaf*>(leaves.data()), leaves.size(),
                              reinterpret_cast<const VdbInsideRun*>(runs.data()), runs.size(), &error))
            fail("cannot write '", path_, "': ", error);
    }
    void write(const SignedDistanceField& f, AtomicFile& file, const SdfWriteOptions& options) {
        const Vec3i d = f.dims();
        const int64_t dims[3] = {d.x, d.y, d.z};
        std::string error;
        if (!vdb_.levelSetStreamWrite(file.tempPath().c_str(), grid_, sdfPlacement(f), dims,
                                      options.gridName.c_str(), &error))
            fail("cannot write '", file.targetPath().string(), "': ", error);
    }
    int64_t activeCount() const { return active_; }

private:
    const VdbModule& vdb_;
    std::string path_;
    void* grid_ = nullptr;
    std::atomic<int64_t> active_{0};
};

void writeSdfNrrd(const SignedDistanceField& f, const std::vector<float>& values, std::ostream& out) {
    const Vec3i n = f.dims();
    const Vec3d cell = f.frame.cellSize();
    const Vec3d origin = f.frame.box().lo + cell * 0.5;
    out << "NRRD0004\n"
        << "# Complete NRRD file format specification at:\n"
        << "# http://teem.sourceforge.net/nrrd/format.html\n"
        << "# voxfx signed distance field: world units, negative inside, |value| <= "
        << formatDouble(f.background) << (f.full ? " (the grid's diagonal)\n" : " (the band width)\n")
        << "type: float\n"
        << "dimension: 3\n"
        << "space: right-anterior-superior\n"
        << "sizes: " << n.x << ' ' << n.y << ' ' << n.z << '\n'
        << "space directions: (" << formatDouble(cell.x) << ",0,0) (0," << formatDouble(cell.y) << ",0) (0,0,"
        << formatDouble(cell.z) << ")\n"
        << "kinds: domain domain domain\n"
        << "endian: little\n"
        << "encoding: raw\n"
        << "space origin: (" << formatDouble(origin.x) << ',' << formatDouble(origin.y) << ','
        << formatDouble(origin.z) << ")\n\n";
    out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * sizeof(float)));
}

// NumPy's .npy format, version 1.0: magic, header length, a Python dict literal padded with spaces
// to a multiple of 64 bytes and ended by a newline, then the data.
void writeSdfNpy(const SignedDistanceField& f, const std::vector<float>& values, std::ostream& out) {
    const Vec3i n = f.dims();
    writeNpyHeader(out, "<f4",
                   "(" + std::to_string(n.x) + ", " + std::to_string(n.y) + ", " + std::to_string(n.z) + ")");
    out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * sizeof(float)));
}

} // namespace
} // namespace detail

const char* toString(SdfFormat f) { return enumName(f, kSdfFormatNames); }

SdfFormat sdfFormatFromPath(const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext == ".vdb") return SdfFormat::Vdb;
    if (ext == ".nrrd") return SdfFormat::Nrrd;
    if (ext == ".npy") return SdfFormat::Npy;
    fail("'", path, "': unknown distance field extension '", ext, "' (allowed: .vdb .nrrd .npy)");
}

void writeSdf(const SignedDistanceField& field, const std::string& path, const SdfWriteOptions& options) {
    const SdfFormat format = sdfFormatFromPath(path);
    const Vec3i d = field.dims();
    if (d.x <= 0 || d.y <= 0 || d.z <= 0) fail("cannot write '", path, "': the distance field is empty");
    std::vector<float> dense;
    if (format != SdfFormat::Vdb) dense = field.dense(); // checks the memory first
    detail::AtomicFile file(path);
    if (format == SdfFormat::Vdb)
        detail::writeSdfVdb(field, file, options);
    else if (format == SdfFormat::Nrrd)
        detail::writeSdfNrrd(field, dense, file.stream());
    else
        detail::writeSdfNpy(field, dense, file.stream());
    file.commit();
}

SdfWriteReport writeSdf(const MeshView& mesh, const Frame& frame, const SdfOptions& options,
                        const std::string& path, const SdfWriteOptions& writeOptions) {
    const SdfFormat format = sdfFormatFromPath(path);
    SdfWriteReport report;
    if (format != SdfFormat::Vdb) {
        report.field = signedDistanceField(mesh, frame, options);
        report.activeCount = report.field.activeCount();
        const auto t = std::chrono::steady_clock::now();
        writeSdf(report.field, path, writeOptions);
        report.writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
        report.field.leaves = {};
        report.field.insideRuns = {};
        return report;
    }
    if (frame.width() <= 0 || frame.height() <= 0 || frame.depth() <= 0)
        fail("cannot write '", path, "': the distance field is empty");
    detail::AtomicFile file(path); // checks the path before the work
    detail::SdfVdbSink sink(path);
    report.field = detail::signedDistanceField(mesh, frame, options, detail::SdfSign::Auto, nullptr, &sink);
    report.activeCount = sink.activeCount();
    const auto t = std::chrono::steady_clock::now();
    sink.write(report.field, file, writeOptions);
    file.commit();
    report.writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    return report;
}

} // namespace voxfx
