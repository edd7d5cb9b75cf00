// voxfx — the command line: a thin client of the public headers in include/voxfx/.
// Subcommands live in cmd_*.cpp and register themselves; this file parses, dispatches, and is
// the one place that catches errors, prints them on one line and exits non-zero.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>
#include <string_view>

#include "cli_registry.hpp"

#ifndef VOXFX_VERSION_STRING
#define VOXFX_VERSION_STRING "unknown"
#endif

int main(int argc, char** argv) {
    using namespace voxfx::cli;
    // Answered before the command tree is built: scripts call it to probe for voxfx.
    if (argc == 2 && std::string_view(argv[1]) == "--version") {
        std::puts("voxfx " VOXFX_VERSION_STRING);
        return 0;
    }
    CLI::App app{"voxfx: fast, exact voxelization of triangle meshes into bit grids (slicemaps),\n"
                 "and the grid tools and renderers built on them. 'voxfx COMMAND --help' for details."};
    app.require_subcommand(1);
    app.set_version_flag("--version", "voxfx " VOXFX_VERSION_STRING);
    auto commands = commandRegistry();
    std::sort(commands.begin(), commands.end(),
              [](const CommandEntry& a, const CommandEntry& b) { return std::string(a.name) < b.name; });
    std::vector<std::pair<CLI::App*, std::function<int()>>> runners;
    for (const CommandEntry& c : commands) {
        CLI::App* sub = app.add_subcommand(c.name, c.description);
        runners.emplace_back(sub, c.setup(*sub));
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) { return app.exit(e); } catch (const voxfx::Error& e) {
        // A flag's value checked while parsing (render flags: "--angle-threshold abc"); it aborted
        // the program uncaught before.
        std::cerr << "voxfx: error: " << e.what() << "\n";
        return 1;
    }
    try {
        for (auto& [sub, run] : runners)
            if (sub->parsed()) return run();
    } catch (const voxfx::Error& e) {
        std::cerr << "voxfx: error: " << e.what() << "\n";
        return 1;
    } catch (const std::bad_alloc&) {
        std::cerr << "voxfx: error: out of memory\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "voxfx: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
