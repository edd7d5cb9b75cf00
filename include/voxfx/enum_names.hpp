// voxfx — the names of enum values: one table per enum, from which toString() and parsing come.
//
// Each enum that users name (modes, fills, operations, formats, light types, ...) states its
// names once, in a `k<Enum>Names` table of {name, value} entries next to the enum in its header.
// The first entry of a value is its name (toString); later entries of the same value are aliases,
// accepted when parsing but not listed in error messages. Matching ignores ASCII case.
// tests/test_enum_names.cpp enumerates every enumerator the compiler knows and fails on a value
// without a name, a name given twice, or a name that does not parse back to its value.
// Thread-safety: constant tables and pure functions; use from any thread.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

#include "voxfx/error.hpp"

namespace voxfx {

/// One name of an enum value; `alias` names are accepted but not listed.
template <class T> struct EnumName {
    const char* name;
    T value;
    bool alias = false;
};

namespace detail {
constexpr bool equalsIgnoringCase(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
        if (lower(a[i]) != lower(b[i])) return false;
    }
    return true;
}
} // namespace detail

/// The name of `value` (its first entry in `names`), or "?" for a value the table lacks.
template <class T>
constexpr const char* enumName(T value, std::type_identity_t<std::span<const EnumName<T>>> names) {
    for (const EnumName<T>& n : names)
        if (n.value == value) return n.name;
    return "?";
}

/// The value called `name` (any case, aliases included), or nothing.
template <class T>
constexpr std::optional<T> findEnum(std::string_view name, std::span<const EnumName<T>> names) {
    for (const EnumName<T>& n : names)
        if (detail::equalsIgnoringCase(name, n.name)) return n.value;
    return std::nullopt;
}

/// "a, b, c" (or with another separator): the names that are not aliases, for messages and help.
template <class T>
std::string enumNameList(std::span<const EnumName<T>> names, std::string_view separator = ", ") {
    std::string list;
    for (const EnumName<T>& n : names)
        if (!n.alias) {
            if (!list.empty()) list += separator;
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

} // namespace voxfx
