// voxfx command line — shared helpers of the subcommands: timing, number formatting, the
// progress line, and the registry through which each cmd_*.cpp adds its subcommand.
#pragma once

#include <chrono>
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "voxfx/voxfx.hpp"

namespace voxfx::cli {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0);
std::string withCommas(int64_t v);
/// %g with `precision` significant digits.
std::string fmt(double v, int precision = 3);
/// "12.3 ms" or "1.23 s".
std::string fmtMs(double ms);
/// A render's pass times as the time lines print them: " flatten 2.1 ms, G-buffer 9.8 ms (cached), ..."
/// (each pass, then its comma; "(cached)" where the pass reused an earlier frame's build).
std::string passTimesText(const RenderTimings& timings);
std::string boxString(const Box3d& b);

/// A one-line progress indicator on stderr, shown only on a terminal and only for long work.
class ProgressLine : public Progress {
public:
    ProgressLine(std::string label, bool enabled);
    ~ProgressLine() override { done(); }
    bool update(double fraction) override;
    /// Erases the line (call before printing results).
    void done();

private:
    std::string label_;
    bool enabled_;
    bool shown_ = false;
    int last_ = -1;
    Clock::time_point start_ = Clock::now();
};

/// A subcommand: `setup` adds options to its CLI11 app and returns the function that runs it
/// after parsing (exit code). Each cmd_*.cpp defines one static Command.
struct Command {
    using Setup = std::function<std::function<int()>(CLI::App& app)>;
    Command(const char* name, const char* description, Setup setup);
};

} // namespace voxfx::cli
