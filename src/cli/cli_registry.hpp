// voxfx command line — the registry filled by the static Command objects (internal to cli/).
#pragma once

#include <vector>

#include "cli_common.hpp"

namespace voxfx::cli {

struct CommandEntry {
    const char* name;
    const char* description;
    Command::Setup setup;
};
std::vector<CommandEntry>& commandRegistry();

} // namespace voxfx::cli
