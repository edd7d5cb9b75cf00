// voxfx — batch voxelization: many mesh files to grid files in one process (dataset preparation).
//
// A batch is a list of jobs (mesh path -> output path). Each job does exactly what
// `voxfx voxelize MESH -o OUTPUT` does with the same options: load the mesh, pick the fill
// (auto: parity for closed meshes, flood otherwise), fit the frame to the mesh bounds (or
// `fit.bounds`), voxelize, write the grid atomically. Outputs are therefore byte-identical to
// the single-file command (.vdb files differ in the UUID OpenVDB writes into every file's
// header, run to run, and nowhere else). Jobs run in parallel over the meshes; a failing job (unreadable or
// malformed mesh, grid too large, write error) is recorded with its message and the others go
// on. An output that already exists is skipped (restart after an interruption: writers are
// atomic, so an existing output is complete and a partial temporary file never counts).
//
// Thread-safety: runBatch may be called concurrently for disjoint output paths; `progress` is
// called from worker threads, one call at a time (serialized by runBatch).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "voxfx/enum_names.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {

struct BatchJob {
    std::string mesh;   ///< mesh file
    std::string output; ///< grid file (format from its extension)
};

/// The file extension (with the dot) of a grid format: ".binvox", ".vdb", ".nrrd", ".ply", ".obj",
/// ".npy", ".npz".
const char* gridFormatExtension(GridFormat format);

/// Reads a manifest: one mesh path per line, relative to the manifest's folder (absolute paths
/// stay); '#' starts a comment line, blank lines and surrounding whitespace are ignored. Each job
/// writes `outDir`/<mesh file stem><extension of `format`>. Throws voxfx::Error naming the
/// manifest for an unreadable file, a folder, a mesh file (.off .obj .ply .stl .gltf .glb) given
/// as the manifest, a NUL byte in a path or a line (a binary file), and, before any work, for two
/// meshes with the same stem (their outputs would collide), naming both lines.
std::vector<BatchJob> readBatchManifest(const std::string& manifestPath, const std::string& outDir,
                                        GridFormat format);

/// The jobs for a list of mesh paths (used as given), with the same output naming and the same
/// duplicate-stem and NUL-byte checks as readBatchManifest.
std::vector<BatchJob> batchJobs(const std::vector<std::string>& meshPaths, const std::string& outDir,
                                GridFormat format);

enum class BatchStatus : uint8_t { Ok, Skipped, Error };
inline constexpr EnumName<BatchStatus> kBatchStatusNames[] = {
    {"ok", BatchStatus::Ok}, {"skipped", BatchStatus::Skipped}, {"error", BatchStatus::Error}};
const char* toString(BatchStatus s);

struct BatchResult {
    std::string mesh, output;
    BatchStatus status = BatchStatus::Ok;
    std::string error;      ///< the error message (status Error), else empty
    int64_t triangles = -1; ///< triangles after loading; -1 when not loaded (skipped, load error)
    double ms = 0;          ///< wall time of the job (load, voxelize, write)
};

/// Called once per finished job, in completion order, one call at a time.
class BatchProgress {
public:
    virtual ~BatchProgress() = default;
    /// `done` jobs of `total` are finished, `result` the one that just finished.
    virtual void jobDone(const BatchResult& result, int64_t done, int64_t total) = 0;
};

struct BatchOptions {
    FitOptions fit;                    ///< as for voxfx voxelize (default: resolution 256)
    VoxelizeOptions voxelize;          ///< mode, fill (default Auto), slicing; `threads`, `progress` ignored
    GridWriteOptions write;            ///< vdbFloat, grid name
    int threads = 0;                   ///< worker threads for the whole batch, 0 = all
    bool nested = false;               ///< also spread each voxelization over the workers (else 1 each)
    bool skipExisting = true;          ///< an existing output is not redone (status Skipped)
    BatchProgress* progress = nullptr; ///< not owned
    /// Cancellation (not owned): polled before each mesh and between the tiles of each
    /// voxelization, from worker threads and possibly from several at once (update() must be
    /// thread-safe), with the share of jobs finished. Once it returns false no mesh starts, the
    /// voxelizations under way stop, and runBatch throws voxfx::Error when the workers are done;
    /// outputs already written stay (a rerun skips them), the report is not made.
    Progress* cancel = nullptr;
    BatchOptions() {
        fit.resolution = 256;
        voxelize.fill = Fill::Auto;
    }
};

struct BatchSummary {
    std::vector<BatchResult> results; ///< in job order
    int64_t ok = 0, skipped = 0, errors = 0;
    double seconds = 0; ///< wall time of the whole batch
    /// The rate: meshes voxelized and written per second of the batch's wall time. Failed meshes
    /// are not in it (they are counted in `errors`; a corpus of unreadable files fails fast and
    /// would otherwise show as a high rate), nor are skipped ones.
    double okPerSecond() const { return seconds > 0 ? double(ok) / seconds : 0; }
};

/// Runs the jobs (see the top of this header). Never throws for a failing job; throws
/// voxfx::Error only for unusable options (e.g. no resolution, voxel size or dims). The summary
/// lists the jobs in the order given, whatever the order they finished in.
BatchSummary runBatch(const std::vector<BatchJob>& jobs, const BatchOptions& options);

/// The batch report as JSON text, the one definition of its shape: {"ok", "skipped", "errors",
/// "seconds", "ok_per_second" (okPerSecond()), "jobs": [batchResultJson of each result, in order]}.
/// `indent` as nlohmann-json's dump: spaces per level, -1 for one line. Text that is not UTF-8
/// (paths, messages quoting file contents) has its invalid bytes replaced by U+FFFD.
std::string batchReportJson(const BatchSummary& summary, int indent = 2);

/// One job's record in the report: {"mesh", "output", "status" (toString), "error", "triangles",
/// "ms"}, with "error" and "triangles" null where they do not apply; one line.
std::string batchResultJson(const BatchResult& result);

/// Writes batchReportJson(summary) and a newline, atomically. Throws voxfx::Error on a failed write.
void writeBatchReport(const BatchSummary& summary, const std::string& path);

} // namespace voxfx
