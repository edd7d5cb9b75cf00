// voxfx command line — the render options as flags (render_flags.hpp).
#include "render_flags.hpp"

#include <cerrno>
#include <cstdlib>
#include <iostream>
#include <iterator>
#include <memory>

namespace voxfx::cli {

namespace {

// The text of a flag as the value of an option of `type`.
OptionValue parseFlagValue(const RenderOptionInfo& info, const std::string& text) {
    const std::string flag = "--" + kebabCase(info.name);
    char* end = nullptr;
    errno = 0;
    switch (info.type) {
    case OptionType::Integer: {
        const long long v = std::strtoll(text.c_str(), &end, 10);
        if (text.empty() || *end || errno) fail(flag, ": expected a whole number, got '", text, "'");
        return int64_t(v);
    }
    case OptionType::Real: {
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end || errno) fail(flag, ": expected a number, got '", text, "'");
        return v;
    }
    case OptionType::Triple: {
        Vec3d v;
        const char* p = text.c_str();
        for (int k = 0; k < 3; ++k) {
            v[k] = std::strtod(p, &end);
            if (end == p || (k < 2 && *end != ',') || (k == 2 && *end))
                fail(flag, ": expected x,y,z, got '", text, "'");
            p = end + 1;
        }
        return v;
    }
    default:
        return text;
    }
}

// "(transmittance, absorption; default 256)" or "(default 1280)" from the catalog's users.
std::string usersText(const RenderOptionInfo& info) {
    std::vector<std::string> who, defaults;
    for (const std::string& u : info.users) {
        const std::size_t open = u.rfind(" (");
        std::string name = u.substr(0, open);
        for (const char* prefix : {"shadows ", "glass "})
            if (name.rfind(prefix, 0) == 0) name = name.substr(std::string(prefix).size());
        who.push_back(name);
        defaults.push_back(u.substr(open + 2, u.size() - open - 3));
    }
    bool same = true;
    for (const std::string& d : defaults) same = same && d == defaults[0];
    std::string out;
    for (std::size_t i = 0; i < who.size(); ++i) {
        if (who[i] == "render") continue;
        out += (out.empty() ? "" : ", ") + who[i] + (same ? "" : " " + defaults[i]);
    }
    if (same) out += (out.empty() ? "" : "; ") + std::string("default ") + defaults[0];
    return "(" + out + ")";
}

// How --help shows the value an option takes, by OptionType (a flag takes none).
constexpr const char* kTypeNames[] = {"", "INT", "NUM", "NAME", "X,Y,Z"};
static_assert(std::size(kTypeNames) == std::size(kOptionTypeNames));

const char* groupOf(const RenderOptionInfo& info) {
    for (const std::string& u : info.users)
        if (u.rfind("render ", 0) == 0) return "Image";
    return info.users.front().rfind("glass ", 0) == 0 ? "Glass" : "Shadows";
}

} // namespace

void RenderFlags::add(CLI::App& app) {
    const std::string shadowDefault =
        defaults_.shadows.empty() ? std::string(shadowName(RenderOptions{}.shadow)) : defaults_.shadows;
    app.add_option("--shadows", shadows, "Shadow kind (default " + shadowDefault + "; see below)")
        ->group("Shadows");
    app.add_option("--glass", glass, "Glass method (default: exact if the scene has glass, else none)")
        ->group("Glass");
    for (const RenderOptionInfo& info : renderOptionCatalog()) {
        std::string names = "--" + kebabCase(info.name);
        if (!info.alias.empty()) names += ",--" + kebabCase(info.alias);
        const OptionValue* own = defaultOf(info.name);
        const std::string help = info.help + " " +
                                 (own ? "(default " + formatOption(*own) + ")" : usersText(info)) +
                                 (info.choices.empty() ? std::string() : ": " + info.choices);
        const std::string name = info.name;
        if (info.type == OptionType::Flag) {
            // --no-NAME is an option of its own, out of the help (one name with "!" would print
            // as "--no-NAME{false}"); the help line names it.
            const std::string negated = "--no-" + kebabCase(info.name);
            app.add_flag_function(
                   names, [this, name](int64_t) { given_.emplace_back(name, OptionValue(true)); },
                   help + " (off: " + negated + ")")
                ->group(groupOf(info));
            app.add_flag_function(
                   negated, [this, name](int64_t) { given_.emplace_back(name, OptionValue(false)); }, help)
                ->group("");
        } else {
            app.add_option_function<std::string>(
                   names,
                   [this, info](const std::string& text) {
                       // A value that does not parse fails the parse (CLI11 prints it, exit non-zero)
                       // instead of leaving the callback as an uncaught voxfx::Error (abort).
                       try {
                           given_.emplace_back(info.name, parseFlagValue(info, text));
                       } catch (const Error& e) { throw CLI::ValidationError(e.what()); }
                   },
                   help)
                ->type_name(kTypeNames[int(info.type)])
                ->group(groupOf(info));
        }
    }
}

std::string RenderFlags::footer() {
    std::string out = "\nShadow kinds (--shadows):\n";
    for (const std::string_view n : shadowNames())
        out += "  " + std::string(n) + std::string(n.size() < 14 ? 14 - n.size() : 1, ' ') +
               std::string(shadowSummary(n)) + "\n";
    out += "\nGlass methods (--glass; materials with transmission > 0 and opacity 1):\n";
    for (const std::string_view n : glassNames())
        out += "  " + std::string(n) + std::string(n.size() < 14 ? 14 - n.size() : 1, ' ') +
               std::string(glassSummary(n)) + "\n";
    return out;
}

const OptionValue* RenderFlags::defaultOf(const std::string& name) const {
    for (const auto& [n, v] : defaults_.options)
        if (n == name) return &v;
    return nullptr;
}

void RenderFlags::apply(RenderOptions& options, bool warn) const {
    for (const auto& [name, value] : defaults_.options) setRenderOption(options, name, value);
    for (const auto& [name, value] : given_) {
        const std::string flag = "--" + kebabCase(name);
        if (setRenderOption(options, flag, value) || !warn) continue;
        std::string users;
        for (const RenderOptionInfo& info : renderOptionCatalog())
            if (info.name == name)
                for (const std::string& u : info.users)
                    users += (users.empty() ? "" : ", ") + u.substr(0, u.rfind(" ("));
        std::cerr << "voxfx: " << flag << " does nothing with --shadows " << shadowName(options.shadow)
                  << " and --glass " << glassName(options.glass) << " (it is an option of " << users << ")\n";
    }
}

const OptionValue* RenderFlags::find(const std::string& name) const {
    for (const auto& [n, v] : given_)
        if (n == name) return &v;
    return nullptr;
}

} // namespace voxfx::cli
