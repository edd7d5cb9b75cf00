#include "cli_common.hpp"

#include <cstdio>

#include <unistd.h>

#include "cli_registry.hpp"

namespace voxfx::cli {

double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string withCommas(int64_t v) { return countText(v); }

std::string fmt(double v, int precision) { return numberText(v, precision); }

std::string fmtMs(double ms) { return msText(ms); }

std::string passTimesText(const RenderTimings& timings) {
    std::string out;
    for (const PassTime& p : timings.passes)
        out += " " + std::string(p.name) + " " + fmtMs(p.ms) + (p.cached ? " (cached)," : ",");
    return out;
}

std::string boxString(const Box3d& b) {
    return "[" + fmt(b.lo.x, 6) + ", " + fmt(b.lo.y, 6) + ", " + fmt(b.lo.z, 6) + "] .. [" + fmt(b.hi.x, 6) +
           ", " + fmt(b.hi.y, 6) + ", " + fmt(b.hi.z, 6) + "]";
}

ProgressLine::ProgressLine(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled && isatty(2)) {}

bool ProgressLine::update(double fraction) {
    if (!enabled_ || msSince(start_) < 300) return true;
    const int pct = int(fraction * 100);
    if (pct != last_) {
        std::fprintf(stderr, "\r%s %3d%%", label_.c_str(), pct);
        std::fflush(stderr);
        last_ = pct;
        shown_ = true;
    }
    return true;
}

void ProgressLine::done() {
    if (shown_) std::fprintf(stderr, "\r%*s\r", int(label_.size()) + 6, "");
    shown_ = false;
}

std::vector<CommandEntry>& commandRegistry() {
    static std::vector<CommandEntry> commands;
    return commands;
}

Command::Command(const char* name, const char* description, Setup setup) {
    commandRegistry().push_back({name, description, std::move(setup)});
}

} // namespace voxfx::cli
