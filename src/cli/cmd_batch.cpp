// voxfx batch MANIFEST -o OUTDIR — many meshes to grids in one process (voxfx/batch.hpp).
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <unistd.h>

#include "cli_common.hpp"
#include "grid_input.hpp"
#include "voxfx/batch.hpp"

namespace voxfx::cli {
namespace {

struct BatchArgs {
    std::string manifest, outDir, format = "binvox", report;
    FitArgs fit;
    VoxelizeChoiceArgs choice;
    int threads = 0;
    bool nested = false, force = false, quiet = false;
};

// done/total, failures, rate and ETA on stderr: in place on a terminal (at most 10 times a
// second), otherwise one line every 10 s; nothing for batches shorter than that. Failed meshes are
// reported on a line of their own at once.
class BatchProgressLine : public BatchProgress {
public:
    explicit BatchProgressLine(bool enabled) : enabled_(enabled), tty_(isatty(fileno(stderr)) != 0) {}

    void jobDone(const BatchResult& r, int64_t done, int64_t total) override {
        if (!enabled_) return;
        if (r.status == BatchStatus::Skipped) ++skipped_;
        if (r.status == BatchStatus::Ok) ++ok_;
        if (r.status == BatchStatus::Error) {
            ++failed_;
            clear();
            // Loader messages name the file already.
            std::cerr << "voxfx: error: " << (r.error.find(r.mesh) == std::string::npos ? r.mesh + ": " : "")
                      << r.error << "\n";
        }
        // The summary follows the last job; the line is for the wait before it.
        const double ms = msSince(start_);
        if (done == total || ms - lastMs_ < (tty_ ? 100 : 10000)) return;
        lastMs_ = ms;
        // The rate counts the meshes written: failed ones (often fast to fail) and skipped ones
        // (next to free) would inflate it. The ETA counts every mesh worked on.
        const double rate = ms > 0 ? double(ok_) * 1000 / ms : 0;
        const double worked = ms > 0 ? double(done - skipped_) * 1000 / ms : 0;
        std::string line = "batch: " + withCommas(done) + "/" + withCommas(total) + " meshes, " +
                           withCommas(failed_) + " failed, " + fmt(rate, 3) + " meshes/s";
        if (done < total && worked > 0) line += ", ETA " + fmtMs(double(total - done) / worked * 1000);
        if (tty_) {
            std::cerr << "\r" << line << "\033[K" << std::flush;
            shown_ = true;
        } else {
            std::cerr << line << "\n";
        }
    }

    void clear() {
        if (shown_) std::cerr << "\r\033[K" << std::flush;
        shown_ = false;
    }

private:
    bool enabled_, tty_, shown_ = false;
    int64_t skipped_ = 0, ok_ = 0, failed_ = 0;
    double lastMs_ = 0;
    Clock::time_point start_ = Clock::now();
};

int runBatchCommand(const BatchArgs& a) {
    const GridFormat format = gridFormatFromPath("x." + a.format);
    BatchOptions bo;
    bo.voxelize = toVoxelizeOptions(a.choice);
    bo.fit = toFitOptions(a.fit, voxelizeFitChoices());
    bo.fit.axis = parseAxis(a.choice.axis);
    bo.voxelize.emptyBorder = a.fit.padding; // --padding: the ring stays empty in every mode
    bo.write.vdbFloat = a.choice.vdbFloat;
    bo.threads = a.threads;
    bo.nested = a.nested;
    bo.skipExisting = !a.force;
    // Duplicate stems and an unreadable manifest fail here, before any work.
    const std::vector<BatchJob> jobs = readBatchManifest(a.manifest, a.outDir, format);
    const std::string reportPath =
        a.report.empty() ? (std::filesystem::path(a.outDir) / "report.json").string() : a.report;

    std::error_code ec;
    std::filesystem::create_directories(a.outDir, ec);
    if (ec) fail("cannot create output folder '", a.outDir, "': ", ec.message());

    BatchProgressLine progress(!a.quiet);
    bo.progress = &progress;
    const BatchSummary s = runBatch(jobs, bo);
    progress.clear();
    writeBatchReport(s, reportPath);

    // The rate is over the meshes written (BatchSummary::okPerSecond); failures are counted apart.
    std::cout << "batch: " << withCommas(int64_t(jobs.size())) << " meshes: " << withCommas(s.ok) << " ok, "
              << withCommas(s.skipped) << " skipped (already done), " << withCommas(s.errors) << " failed in "
              << fmtMs(s.seconds * 1000) << " (" << fmt(s.okPerSecond(), 3) << " meshes/s written) -> "
              << a.outDir << ", report " << reportPath << "\n";
    return s.errors > 0 ? 2 : 0;
}

const char* kBatchHelp = R"(
Each line of MANIFEST is a mesh file, relative to the manifest's folder; lines starting
with '#' and blank lines are ignored. Mesh M is written to OUTDIR/<stem of M>.<format>, byte
for byte what 'voxfx voxelize M -o OUTDIR/<stem>.<format>' with the same options writes
(.vdb: but for the UUID OpenVDB puts in every file; see 'voxfx voxelize --help' for grid
placement, modes and fills). Two meshes with the same stem are refused before any work.

Meshes run in parallel on every core (-j), each voxelized by one thread (--nested: by all).
Outputs are written atomically and an existing output is skipped, so an interrupted batch is
restarted by running the same command again (--force redoes everything). A mesh that fails
(unreadable, malformed, NaN coordinates, bad indices, grid too large) is reported on stderr
and in the report, and the others go on.

The report (default OUTDIR/report.json) lists every mesh: {mesh, output, status (ok, skipped,
error), error, triangles, ms}, with the counts, the total time and ok_per_second. The rate
(there, in the progress line and in the summary) counts the meshes written: failed and skipped
meshes are counted separately and left out of it.

Exit status: 0 when every mesh is ok or skipped, 2 when at least one mesh failed (the report
says which), 1 when the batch could not start (bad manifest, duplicate stems, bad options).)";

const Command kBatch{
    "batch", "Voxelize every mesh of a manifest into OUTDIR, in parallel, restartable", [](CLI::App& app) {
        app.footer(kBatchHelp);
        auto a = std::make_shared<BatchArgs>();
        app.add_option("MANIFEST", a->manifest, "Text file: one mesh path per line")->required();
        app.add_option("-o,--output", a->outDir, "Output folder (created if missing)")->required();
        app.add_option("--format", a->format, enumNameList<GridFormat>(kGridFormatNames, " | "))
            ->default_val("binvox")
            ->check(CLI::IsMember([] {
                std::vector<std::string> names;
                for (const EnumName<GridFormat>& n : kGridFormatNames) names.push_back(n.name);
                return names;
            }()));
        addFitOptions(app, a->fit, voxelizeFitChoices());
        addVoxelizeChoiceOptions(app, a->choice);
        app.add_option("-j,--threads", a->threads, "Worker threads, 0 = all (outputs are identical)")
            ->default_val(0)
            ->check(CLI::NonNegativeNumber);
        app.add_flag("--nested", a->nested,
                     "Spread each voxelization over the threads too (large grids, few meshes)");
        app.add_flag("--force", a->force, "Redo meshes whose output exists");
        app.add_option("--report", a->report, "JSON report (default OUTDIR/report.json)");
        app.add_flag("-q,--quiet", a->quiet, "No progress (the summary line stays)");
        return std::function<int()>([a] { return runBatchCommand(*a); });
    }};

} // namespace
} // namespace voxfx::cli
