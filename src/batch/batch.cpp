// voxfx — batch voxelization: manifest, parallel jobs over meshes, restart, JSON report.
#include "voxfx/batch.hpp"

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <new>
#include <set>

#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"
#include "voxfx/mesh_io.hpp"
#include "voxfx/parallel.hpp"

namespace voxfx {

namespace fs = std::filesystem;

namespace {

using BatchClock = std::chrono::steady_clock;

double batchMsSince(BatchClock::time_point t0) {
    return std::chrono::duration<double, std::milli>(BatchClock::now() - t0).count();
}

std::string trimmed(const std::string& s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string::npos) return {};
    const auto e = s.find_last_not_of(" \t\r\n");
    return s.substr(b, e - b + 1);
}

// The jobs for `meshes`, each with where it came from (for the duplicate message).
std::vector<BatchJob> jobsFor(const std::vector<std::string>& meshes, const std::vector<std::string>& origins,
                              const std::string& outDir, GridFormat format) {
    if (outDir.find('\0') != std::string::npos) fail("batch: the output folder's name holds a NUL byte");
    std::vector<BatchJob> jobs;
    jobs.reserve(meshes.size());
    std::map<std::string, size_t> byStem;
    for (size_t i = 0; i < meshes.size(); ++i) {
        // The C library would open the path up to the NUL: another file than the one named.
        if (meshes[i].find('\0') != std::string::npos) fail(origins[i], ": the mesh path holds a NUL byte");
        const std::string stem = fs::path(meshes[i]).stem().string();
        if (stem.empty()) fail(origins[i], ": '", meshes[i], "' has no file name");
        const auto [it, fresh] = byStem.emplace(stem, i);
        if (!fresh)
            fail(origins[i], ": '", meshes[i], "' and ", origins[it->second], ": '", meshes[it->second],
                 "' would both write '", stem, gridFormatExtension(format),
                 "' (outputs are named by the mesh file's stem; rename or link one of them)");
        jobs.push_back({meshes[i], (fs::path(outDir) / (stem + gridFormatExtension(format))).string()});
    }
    return jobs;
}

// BatchOptions::cancel as every poll sees it: once it said stop, stop for good. Each
// voxelization polls it with the batch's fraction rather than its own.
class BatchCancel final : public Progress {
public:
    BatchCancel(Progress* user, int64_t total) : user_(user), total_(std::max<int64_t>(total, 1)) {}
    bool update(double) override {
        if (stop_.load(std::memory_order_relaxed)) return false;
        if (user_ && !user_->update(double(done_.load(std::memory_order_relaxed)) / double(total_)))
            stop_ = true;
        return !stop_;
    }
    bool stopped() const { return stop_; }
    void jobFinished() { ++done_; }

private:
    Progress* user_;
    int64_t total_;
    std::atomic<int64_t> done_{0};
    std::atomic<bool> stop_{false};
};

// A manifest that is none: a folder, or a mesh file given where the list of them belongs.
void checkManifestPath(const std::string& manifestPath) {
    if (manifestPath.find('\0') != std::string::npos) fail("batch: the manifest's path holds a NUL byte");
    std::error_code ec;
    if (fs::is_directory(manifestPath, ec))
        fail("batch: '", manifestPath,
             "' is a folder; a manifest is a text file with one mesh path per line (relative to its "
             "folder), or give the list of meshes");
    const std::string ext = fileExtension(manifestPath);
    for (const char* mesh : {".off", ".obj", ".ply", ".stl", ".gltf", ".glb"})
        if (ext == mesh)
            fail("batch: '", manifestPath, "' is a mesh file (", ext,
                 "), not a manifest; for one mesh give a list of it, or a text file with one mesh path "
                 "per line");
}

// One job, as `voxfx voxelize MESH -o OUTPUT` does it.
void runBatchJob(const BatchJob& job, const BatchOptions& o, BatchCancel& cancel, BatchResult& r) {
    const Mesh mesh = loadMesh(job.mesh);
    r.triangles = int64_t(mesh.triangleCount());
    VoxelizeOptions vo = o.voxelize;
    vo.progress = o.cancel ? &cancel : nullptr;
    vo.threads = o.nested ? 0 : 1;
    const Frame frame = fitFrame(computeBounds(mesh.view()), o.fit);
    const VoxelGrid grid = voxelize(mesh.view(), frame, vo);
    writeGrid(grid, job.output, o.write);
}

} // namespace

const char* gridFormatExtension(GridFormat format) {
    switch (format) {
    case GridFormat::Binvox:
        return ".binvox";
    case GridFormat::Vdb:
        return ".vdb";
    case GridFormat::Nrrd:
        return ".nrrd";
    case GridFormat::Ply:
        return ".ply";
    case GridFormat::Obj:
        return ".obj";
    case GridFormat::Npy:
        return ".npy";
    case GridFormat::Npz:
        return ".npz";
    }
    return "";
}

const char* toString(BatchStatus s) { return enumName(s, kBatchStatusNames); }

std::vector<BatchJob> readBatchManifest(const std::string& manifestPath, const std::string& outDir,
                                        GridFormat format) {
    checkManifestPath(manifestPath);
    std::ifstream in(manifestPath);
    if (!in) fail("cannot read manifest '", manifestPath, "': ", std::strerror(errno));
    const fs::path base = fs::path(manifestPath).parent_path();
    std::vector<std::string> meshes, origins;
    std::string line;
    for (int64_t number = 1; std::getline(in, line); ++number) {
        if (line.find('\0') != std::string::npos)
            fail("manifest '", manifestPath, "' line ", number,
                 " holds a NUL byte: not a text file of mesh paths (a binary mesh?)");
        const std::string entry = trimmed(line);
        if (entry.empty() || entry[0] == '#') continue;
        const fs::path p(entry);
        meshes.push_back(p.is_absolute() ? p.string() : (base / p).string());
        origins.push_back(detail::concat(manifestPath, " line ", number));
    }
    if (in.bad()) fail("error reading manifest '", manifestPath, "': ", std::strerror(errno));
    return jobsFor(meshes, origins, outDir, format);
}

std::vector<BatchJob> batchJobs(const std::vector<std::string>& meshPaths, const std::string& outDir,
                                GridFormat format) {
    std::vector<std::string> origins;
    for (size_t i = 0; i < meshPaths.size(); ++i) origins.push_back(detail::concat("mesh ", i + 1));
    return jobsFor(meshPaths, origins, outDir, format);
}

BatchSummary runBatch(const std::vector<BatchJob>& jobs, const BatchOptions& options) {
    const auto t0 = BatchClock::now();
    // Unusable options fail once, before any job (rather than once per job).
    if (options.fit.resolution <= 0 && options.fit.voxelSize <= 0 &&
        (options.fit.dims.x <= 0 || options.fit.dims.y <= 0 || options.fit.dims.z <= 0))
        fail("batch: give a resolution, a voxel size or dims");
    std::set<std::string> dirs;
    for (const BatchJob& j : jobs) dirs.insert(fs::path(j.output).parent_path().string());
    for (const std::string& d : dirs) {
        std::error_code ec;
        if (!d.empty()) fs::create_directories(d, ec);
        if (ec) fail("cannot create output folder '", d, "': ", ec.message());
    }

    BatchSummary summary;
    summary.results.resize(jobs.size());
    std::mutex progressMutex;
    int64_t done = 0;
    const int64_t total = int64_t(jobs.size());
    BatchCancel cancel(options.cancel, total);
    withThreads(options.threads, [&] {
        // One job per task: meshes differ wildly in cost, so the scheduler balances them.
        parallelFor(0, total, 1, [&](int64_t b, int64_t e) {
            for (int64_t i = b; i < e; ++i) {
                const BatchJob& job = jobs[size_t(i)];
                BatchResult& r = summary.results[size_t(i)];
                r.mesh = job.mesh;
                r.output = job.output;
                if (options.cancel && !cancel.update(0)) continue;
                const auto tj = BatchClock::now();
                std::error_code ec;
                if (options.skipExisting && fs::exists(job.output, ec)) {
                    r.status = BatchStatus::Skipped;
                } else {
                    try {
                        runBatchJob(job, options, cancel, r);
                        r.status = BatchStatus::Ok;
                    } catch (const std::bad_alloc&) {
                        r.status = BatchStatus::Error;
                        r.error = "out of memory";
                    } catch (const std::exception& ex) {
                        r.status = BatchStatus::Error;
                        r.error = ex.what();
                    }
                }
                r.ms = batchMsSince(tj);
                cancel.jobFinished();
                // A job that cancelling cut short is not reported: the batch throws instead.
                if (cancel.stopped() && r.status == BatchStatus::Error) continue;
                const std::lock_guard lock(progressMutex);
                ++done;
                if (options.progress) options.progress->jobDone(r, done, total);
            }
        });
    });
    if (cancel.stopped())
        fail("batch cancelled after ", done, " of ", total,
             " meshes (the outputs written stay, and a rerun skips them)");
    for (const BatchResult& r : summary.results) {
        summary.ok += r.status == BatchStatus::Ok;
        summary.skipped += r.status == BatchStatus::Skipped;
        summary.errors += r.status == BatchStatus::Error;
    }
    summary.seconds = batchMsSince(t0) / 1000;
    return summary;
}

namespace {

nlohmann::ordered_json batchResultObject(const BatchResult& r) {
    nlohmann::ordered_json e;
    e["mesh"] = r.mesh;
    e["output"] = r.output;
    e["status"] = toString(r.status);
    e["error"] = r.status == BatchStatus::Error ? nlohmann::ordered_json(r.error) : nlohmann::ordered_json();
    e["triangles"] = r.triangles >= 0 ? nlohmann::ordered_json(r.triangles) : nlohmann::ordered_json();
    e["ms"] = r.ms;
    return e;
}

// Invalid UTF-8 in a path or message is replaced rather than failing the report.
std::string batchJsonText(const nlohmann::ordered_json& j, int indent) {
    return j.dump(indent, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

} // namespace

std::string batchResultJson(const BatchResult& result) {
    return batchJsonText(batchResultObject(result), -1);
}

std::string batchReportJson(const BatchSummary& summary, int indent) {
    nlohmann::ordered_json j;
    j["ok"] = summary.ok;
    j["skipped"] = summary.skipped;
    j["errors"] = summary.errors;
    j["seconds"] = summary.seconds;
    j["ok_per_second"] = summary.okPerSecond();
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const BatchResult& r : summary.results) list.push_back(batchResultObject(r));
    j["jobs"] = std::move(list);
    return batchJsonText(j, indent);
}

void writeBatchReport(const BatchSummary& summary, const std::string& path) {
    const std::string text = batchReportJson(summary);
    detail::AtomicFile file(path);
    file.stream() << text << "\n";
    file.commit();
}

} // namespace voxfx
