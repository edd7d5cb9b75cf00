// voxfx — the names of enum values, for parsing options and files (internal header).
//
// Each enum that users name (modes, fills, operations, light types, ...) has one table of
// {name, value} entries; aliases are accepted but not listed in errors. Matching ignores ASCII
// case. toString() stays a switch next to the enum so that the compiler checks it is complete;
// tests/test_enum_names.cpp checks that every toString() name parses back to its value.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "voxfx/error.hpp"

namespace voxfx::detail {

template <class T> struct EnumName {
    std::string_view name;
    T value;
    bool alias = false;
};

inline bool equalsIgnoringCase(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
        if (lower(a[i]) != lower(b[i])) return false;
    }
    return true;
}

template <class T> std::optional<T> findEnum(std::string_view name, std::span<const EnumName<T>> names) {
    for (const EnumName<T>& n : names)
        if (equalsIgnoringCase(name, n.name)) return n.value;
    return std::nullopt;
}

/// "a, b, c": the names that are not aliases, for error messages.
template <class T> std::string enumNameList(std::span<const EnumName<T>> names) {
    std::string list;
    for (const EnumName<T>& n : names)
        if (!n.alias) {
            if (!list.empty()) list += ", ";
            list += n.name;
        }
    return list;
}

/// The value called `name`, or voxfx::Error "[where: ]unknown WHAT 'NAME' (allowed: a, b, c)".
template <class T>
T parseEnum(std::string_view name, const char* what, std::span<const EnumName<T>> names,
            std::string_view where = {}) {
    if (const std::optional<T> v = findEnum(name, names)) return *v;
    if (!where.empty()) fail(where, ": unknown ", what, " '", name, "' (allowed: ", enumNameList(names), ")");
    fail("unknown ", what, " '", name, "' (allowed: ", enumNameList(names), ")");
}

} // namespace voxfx::detail
