// Many meshes in one process: batch (as `voxfx batch` does) and batch_jobs.
#include <exception>
#include <filesystem>

#include "common.hpp"

namespace voxfx::python {
namespace {

/// JSON text of the library's batch report (batchReportJson, batchResultJson) as Python objects:
/// the dicts voxfx.batch returns and hands to progress have the report file's shape by construction.
py::object batchJsonObject(const std::string& text) {
    return py::module_::import("json").attr("loads")(text);
}

/// The batch's grid format from an extension, with or without its dot.
GridFormat batchGridFormat(const std::string& format) {
    return asArgument(
        [&] { return gridFormatFromPath("x" + (format.starts_with(".") ? format : "." + format)); });
}

/// The jobs of a batch argument: a manifest path (str, bytes or os.PathLike) or an iterable of mesh
/// paths. What is not a manifest (a folder, a mesh file, a binary file) is an ArgumentError.
std::vector<BatchJob> batchJobsArgument(const py::object& manifestOrList, const std::string& outDir,
                                        GridFormat format) {
    if (py::isinstance<py::str>(manifestOrList) || py::isinstance<py::bytes>(manifestOrList) ||
        py::hasattr(manifestOrList, "__fspath__")) {
        const std::string manifest = pathString(manifestOrList);
        return asArgument([&] {
            py::gil_scoped_release release;
            return readBatchManifest(manifest, outDir, format);
        });
    }
    if (!py::hasattr(manifestOrList, "__iter__"))
        throw py::type_error("meshes must be a manifest path or an iterable of mesh paths");
    std::vector<std::string> meshes;
    for (const py::handle p : manifestOrList) meshes.push_back(pathString(p));
    return asArgument([&] { return batchJobs(meshes, outDir, format); });
}

/// Calls a Python callable per finished job, from the worker thread that finished it (runBatch
/// serializes the calls), holding the GIL for the call only. The first exception it raises
/// cancels the batch (no further mesh starts) and is raised when the workers are done.
class PyBatchProgress : public BatchProgress {
public:
    explicit PyBatchProgress(py::object fn) : fn_(std::move(fn)) {}
    void jobDone(const BatchResult& r, int64_t done, int64_t total) override {
        if (error_) return;
        py::gil_scoped_acquire gil;
        try {
            fn_(batchJsonObject(batchResultJson(r)), done, total);
        } catch (...) {
            error_ = std::current_exception();
            if (cancel_) cancel_->request();
        }
    }
    void setCancel(Cancel* cancel) { cancel_ = cancel; }
    bool failed() const { return bool(error_); }
    void raiseIfFailed() const {
        if (error_) std::rethrow_exception(error_);
    }

private:
    py::object fn_;
    Cancel* cancel_ = nullptr;
    std::exception_ptr error_;
};

} // namespace

void bindBatch(py::module_& m) {
    // ---- batch
    m.def(
        "batch",
        [](const py::object& manifestOrList, const py::object& outDirObj, const std::string& format,
           std::optional<Int> resolution, std::optional<double> voxelSize,
           std::optional<std::vector<int64_t>> dims, const py::object& bounds, int64_t margin, bool cube,
           Int padding, const std::string& mode, const std::string& fill, const std::string& axis,
           const std::string& slicing, bool vdbFloat, int threads, bool nested, bool skipExisting,
           const py::object& report, const py::object& progress) {
            const std::string outDir = pathString(outDirObj);
            const GridFormat gridFormat = batchGridFormat(format);
            BatchOptions bo;
            bo.fit = fitOptions(resolution, voxelSize, dims, bounds, margin, axis, cube);
            // padding p: p empty cells kept inside the resolution, as voxelize() keeps them.
            if (padding < 0) throw ArgumentError("padding must be >= 0");
            if (padding > 0) {
                if (bo.fit.resolution == 0)
                    throw ArgumentError("padding needs a resolution (not voxel_size or dims)");
                if (bo.fit.resolution <= 2 * padding)
                    throw ArgumentError(
                        "padding needs a resolution above 2 * padding (the cells left for the mesh)");
                bo.fit.resolution -= 2 * padding;
                bo.fit.marginCells += padding;
                bo.voxelize.emptyBorder = padding; // empty in every mode
            }
            asArgument([&] {
                bo.voxelize.mode = parseVoxelizeMode(mode);
                bo.voxelize.slicing = parseSlicing(slicing);
                bo.voxelize.fill = parseFill(fill);
            });
            bo.write.vdbFloat = vdbFloat;
            if (threads < 0) throw ArgumentError("threads must be >= 0");
            bo.threads = threads;
            bo.nested = nested;
            bo.skipExisting = skipExisting;
            std::string reportPath;
            if (report.is_none()) {
                reportPath = (std::filesystem::path(outDir) / "report.json").string();
            } else if (!(py::isinstance<py::bool_>(report) && !report.cast<bool>())) {
                reportPath = pathString(report);
            }
            const std::vector<BatchJob> jobs = batchJobsArgument(manifestOrList, outDir, gridFormat);
            std::optional<PyBatchProgress> pyProgress;
            if (!progress.is_none()) {
                if (!PyCallable_Check(progress.ptr()))
                    throw py::type_error("progress must be callable as progress(job, done, total), or None");
                bo.progress = &pyProgress.emplace(progress);
            }
            // Ctrl-C, or an exception from progress, stops the batch between meshes (and the
            // voxelizations under way between tiles); that exception is raised.
            BatchSummary summary;
            try {
                interruptible([&](Cancel& cancel) {
                    bo.cancel = &cancel;
                    if (pyProgress) pyProgress->setCancel(&cancel);
                    std::error_code ec;
                    std::filesystem::create_directories(outDir, ec);
                    if (ec) fail("cannot create output folder '", outDir, "': ", ec.message());
                    summary = runBatch(jobs, bo);
                    if (!reportPath.empty()) writeBatchReport(summary, reportPath);
                });
            } catch (const Error&) {
                if (pyProgress && pyProgress->failed()) pyProgress->raiseIfFailed();
                throw;
            }
            if (pyProgress) pyProgress->raiseIfFailed();
            return batchJsonObject(batchReportJson(summary, -1));
        },
        py::arg("meshes"), py::arg("out_dir"), py::kw_only(), py::arg("format") = ".binvox",
        py::arg("resolution") = py::none(), py::arg("voxel_size") = py::none(), py::arg("dims") = py::none(),
        py::arg("bounds") = py::none(), py::arg("margin") = 0, py::arg("cube") = false,
        py::arg("padding") = 0, py::arg("mode") = "solid", py::arg("fill") = "auto", py::arg("axis") = "z",
        py::arg("slicing") = "uniform", py::arg("vdb_float") = false, py::arg("threads") = 0,
        py::arg("nested") = false, py::arg("skip_existing") = true, py::arg("report") = py::none(),
        py::arg("progress") = py::none(),
        "Voxelizes many meshes in this process, as `voxfx batch` does (the same outputs, byte for byte): "
        "meshes is a manifest file (one path per line, relative to its folder, '#' comments) or a list of "
        "paths; mesh M is written to out_dir/<stem of M><format> (.binvox .vdb .nrrd .ply .obj .npy .npz). "
        "Options as voxelize (cube, padding included); threads: workers for "
        "the whole batch (0 = all), each mesh on one of them (nested=True: on all). A mesh that fails is "
        "recorded with its error and the rest go on; existing outputs are skipped (skip_existing=False "
        "redoes them). report: the JSON report's path (None: out_dir/report.json, False: none). progress: "
        "progress(job, done, total) after each mesh, from a worker thread. Returns the report as a dict: "
        "ok, skipped, errors, seconds, ok_per_second (meshes written per second; failed ones are not in "
        "it) and jobs, a list of {mesh, output, status ('ok', 'skipped', 'error'), error, triangles, ms} "
        "in the order given. The GIL is released while meshes are processed; Ctrl-C, or an exception from "
        "progress, stops the batch between meshes (outputs written stay) and is raised.");

    m.def(
        "batch_jobs",
        [](const py::object& manifestOrList, const py::object& outDirObj, const std::string& format) {
            py::list out;
            for (const BatchJob& j :
                 batchJobsArgument(manifestOrList, pathString(outDirObj), batchGridFormat(format)))
                out.append(py::make_tuple(utf8Text(j.mesh), utf8Text(j.output)));
            return out;
        },
        py::arg("meshes"), py::arg("out_dir"), py::kw_only(), py::arg("format") = ".binvox",
        "The (mesh, output) pairs voxfx.batch(meshes, out_dir, format=...) would process, in order, "
        "without running them: the manifest read and the outputs named as `voxfx batch` does, with "
        "its error for two meshes of the same stem.");
}

} // namespace voxfx::python
