// voxfx command line — the render options as flags (internal to cli/): --shadows, --glass and one
// flag per name of the library's option catalog (voxfx/render.hpp: renderOptionCatalog), in
// kebab-case; on/off options also as --no-NAME. The library states the names, types, ranges and
// defaults; this file only spells them for CLI11 and hands the values back by name.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "cli_common.hpp"

namespace voxfx::cli {

/// What a command renders with where the library's defaults do not suit it (the demo's image size
/// and shadow kinds): applied before the flags given and shown as the defaults in --help, so the
/// help and the render read one value.
struct RenderDefaults {
    std::string shadows; ///< --shadows when not given; empty: the library's (renderOptionsFor)
    std::vector<std::pair<std::string, OptionValue>> options; ///< by lowerCamelCase name
};

class RenderFlags {
public:
    RenderFlags() = default;
    explicit RenderFlags(RenderDefaults defaults) : defaults_(std::move(defaults)) {}
    /// Adds --shadows, --glass and every named option to `app`, in groups (Image, Shadows, Glass).
    void add(CLI::App& app);
    /// The footer of a command that takes them: the shadow kinds and glass methods with a line each.
    static std::string footer();

    std::string shadows, glass; ///< as given (empty: not given)
    /// --shadows as given, else the command's default (empty: the library's).
    const std::string& shadowsOrDefault() const { return shadows.empty() ? defaults_.shadows : shadows; }
    /// The command's default of option `name` (lowerCamelCase), or null: the library's.
    const OptionValue* defaultOf(const std::string& name) const;
    /// Applies the command's defaults, then the named options given (in the catalog's order), to
    /// `options`, whose shadow kind and glass method are already chosen. An option that neither the options
    /// nor the chosen technique and method have does nothing; with `warn`, a line on stderr says so and names
    /// who has it.
    void apply(RenderOptions& options, bool warn) const;
    /// The value given for `name` (lowerCamelCase), or null.
    const OptionValue* find(const std::string& name) const;

private:
    RenderDefaults defaults_;
    std::vector<std::pair<std::string, OptionValue>> given_;
};

} // namespace voxfx::cli
