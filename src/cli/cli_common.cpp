#include "cli_common.hpp"

#include <cstdio>

#include <unistd.h>

#include "cli_registry.hpp"

namespace voxfx::cli {

double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string withCommas(int64_t v) {
    // The magnitude as unsigned: -v overflows for INT64_MIN.
    std::string s = std::to_string(v < 0 ? uint64_t(0) - uint64_t(v) : uint64_t(v));
    for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(size_t(i), 1, ',');
    if (v < 0) s.insert(0, 1, '-'); // not "-" + s: GCC 12 warns falsely (-Wrestrict) once inlined
    return s;
}

std::string fmt(double v, int precision) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    return buf;
}

std::string fmtMs(double ms) {
    char buf[64];
    if (ms < 1000)
        std::snprintf(buf, sizeof buf, "%.1f ms", ms);
    else
        std::snprintf(buf, sizeof buf, "%.2f s", ms / 1000);
    return buf;
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
