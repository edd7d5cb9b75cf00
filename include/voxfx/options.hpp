// voxfx — named options: the fields of an options struct described once (name, help, type, range)
// so that every front end sets them alike and none repeats a default or a range.
//
// A field's name is lowerCamelCase, as scene files spell their keys ("gridDepth"); the command line
// spells it in kebab-case (--grid-depth) and Python in snake_case (grid_depth). Values are one of
// OptionValue's alternatives; setOption converts what is exact (a whole double to an Integer
// field, an integer to a Real one), checks the range or the name, and stores it. The defaults are
// the struct's own member initializers: a front end that shows a default reads it from a
// default-constructed struct (OptionField::get).
//
// Options structs that front ends reach (a shadow technique's, a glass method's, the renderer's)
// give their table as `static std::span<const OptionField<O>> fields()`.
//
// Thread-safety: tables are immutable after static initialization; every function is pure.
#pragma once

#include <concepts>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

#include "voxfx/enum_names.hpp"
#include "voxfx/error.hpp"
#include "voxfx/math.hpp"

namespace voxfx {

/// A value given to an option: on/off, a whole number, a real number, a name, or three numbers.
using OptionValue = std::variant<bool, int64_t, double, std::string, Vec3d>;

enum class OptionType : uint8_t { Flag, Integer, Real, Name, Triple };
inline constexpr EnumName<OptionType> kOptionTypeNames[] = {{"on/off", OptionType::Flag},
                                                            {"whole number", OptionType::Integer},
                                                            {"number", OptionType::Real},
                                                            {"name", OptionType::Name},
                                                            {"three numbers", OptionType::Triple}};
const char* toString(OptionType t);

/// "grid-depth" from "gridDepth" (the command line's spelling).
std::string kebabCase(std::string_view camel);
/// "grid_depth" from "gridDepth" (Python's spelling).
std::string snakeCase(std::string_view camel);
/// "gridDepth" from "grid-depth", "grid_depth" or "gridDepth".
std::string camelCase(std::string_view name);
/// Text of a value for help and messages: "256", "0.05", "on", "uniform", "(1, 2, 3)".
std::string formatOption(const OptionValue& v);

/// One field of an options struct O.
template <class O> struct OptionField {
    std::string_view name; ///< lowerCamelCase
    std::string_view help; ///< what it is, with units
    OptionType type = OptionType::Real;
    double lo = 0, hi = 0;    ///< Integer, Real, Triple (each component): the closed range allowed
    std::string_view choices; ///< Name: the names allowed, "a | b | c"
    std::string_view alias;   ///< an older name that means this field too (lowerCamelCase), or empty
    void (*store)(O&, const OptionValue&) = nullptr; ///< stores a value checkOption returned
    OptionValue (*get)(const O&) = nullptr;

    bool named(std::string_view n) const { return n == name || (!alias.empty() && n == alias); }
};

namespace detail {

/// The value converted to the alternative `type` stores (bool, int64_t, double, string, Vec3d) and
/// checked against [lo, hi]; voxfx::Error "WHERE: NAME: ..." otherwise.
OptionValue checkOptionValue(OptionType type, double lo, double hi, std::string_view name,
                             const OptionValue& v, std::string_view where);
/// voxfx::Error "WHERE: NAME: MESSAGE".
[[noreturn]] void failOption(std::string_view name, std::string_view where, std::string_view message);

/// The member reached from o through the member pointers Path (one, or several for a nested member).
template <auto... Path, class O> decltype(auto) optionMember(O& o) { return (o.*....*Path); }
template <class O, auto... Path>
using OptionMemberType = std::remove_cvref_t<decltype(optionMember<Path...>(std::declval<O&>()))>;

} // namespace detail

/// Sets field `f` of `o` to `v` after converting and checking it; voxfx::Error "WHERE: NAME: ..."
/// (NAME as `spelled`, else the field's name) for a value of the wrong type, out of range, or an
/// unknown name.
template <class O>
void setOption(O& o, const OptionField<O>& f, const OptionValue& v, std::string_view where = {},
               std::string_view spelled = {}) {
    const std::string_view name = spelled.empty() ? f.name : spelled;
    const OptionValue checked = detail::checkOptionValue(f.type, f.lo, f.hi, name, v, where);
    if (f.type != OptionType::Name) return f.store(o, checked);
    try { // the parser's message lists the names allowed; say whose they are
        f.store(o, checked);
    } catch (const Error& e) { detail::failOption(name, where, e.what()); }
}

/// The options of a technique front ends choose by name: its name, a line about it, its fields.
template <class O>
concept NamedOptions = requires {
    { O::kName } -> std::convertible_to<std::string_view>;
    { O::kSummary } -> std::convertible_to<std::string_view>;
    { O::fields() } -> std::convertible_to<std::span<const OptionField<O>>>;
};

/// "name value, name value, ..." of every field of `o` (for summaries), the names as `spell` spells
/// them (kebabCase, snakeCase; null: lowerCamelCase).
template <class O> std::string optionsText(const O& o, std::string (*spell)(std::string_view) = nullptr) {
    std::string out;
    for (const OptionField<O>& f : O::fields()) {
        if (!out.empty()) out += ", ";
        out += (spell ? spell(f.name) : std::string(f.name)) + " " + formatOption(f.get(o));
    }
    return out;
}

/// The field of `fields` called `name` (or with that alias), or null.
template <class O>
const OptionField<O>* findOption(std::span<const OptionField<O>> fields, std::string_view name) {
    for (const OptionField<O>& f : fields)
        if (f.named(name)) return &f;
    return nullptr;
}

/// A field without its accessors (the builders below add them).
template <class O>
OptionField<O> optionField(std::string_view name, std::string_view help, OptionType type, double lo = 0,
                           double hi = 0, std::string_view alias = {}) {
    OptionField<O> f;
    f.name = name;
    f.help = help;
    f.type = type;
    f.lo = lo;
    f.hi = hi;
    f.alias = alias;
    return f;
}

/// A number member (integral: Integer; floating: Real) at Path, allowed in [lo, hi].
template <class O, auto... Path>
OptionField<O> numberOption(std::string_view name, std::string_view help, double lo, double hi,
                            std::string_view alias = {}) {
    using T = detail::OptionMemberType<O, Path...>;
    static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "numberOption: a number member");
    OptionField<O> f = optionField<O>(
        name, help, std::is_integral_v<T> ? OptionType::Integer : OptionType::Real, lo, hi, alias);
    if constexpr (std::is_integral_v<T>) {
        f.store =
            +[](O& o, const OptionValue& v) { detail::optionMember<Path...>(o) = T(std::get<int64_t>(v)); };
        f.get = +[](const O& o) { return OptionValue(int64_t(detail::optionMember<Path...>(o))); };
    } else {
        f.store =
            +[](O& o, const OptionValue& v) { detail::optionMember<Path...>(o) = T(std::get<double>(v)); };
        f.get = +[](const O& o) { return OptionValue(double(detail::optionMember<Path...>(o))); };
    }
    return f;
}

/// An on/off member at Path.
template <class O, auto... Path>
OptionField<O> flagOption(std::string_view name, std::string_view help, std::string_view alias = {}) {
    static_assert(std::is_same_v<detail::OptionMemberType<O, Path...>, bool>, "flagOption: a bool member");
    OptionField<O> f = optionField<O>(name, help, OptionType::Flag, 0, 0, alias);
    f.store = +[](O& o, const OptionValue& v) { detail::optionMember<Path...>(o) = std::get<bool>(v); };
    f.get = +[](const O& o) { return OptionValue(bool(detail::optionMember<Path...>(o))); };
    return f;
}

/// toString(e) of an enum (found by argument-dependent lookup) as one function nameOption can take.
template <class E> const char* optionName(E e) { return toString(e); }

/// An enum member at Path, named by `Parse` (a name -> value function that throws voxfx::Error
/// listing the names) and `Format` (value -> name, e.g. optionName<E>); `choices` lists the names
/// for help.
template <class O, auto Parse, auto Format, auto... Path>
OptionField<O> nameOption(std::string_view name, std::string_view help, std::string_view choices,
                          std::string_view alias = {}) {
    OptionField<O> f = optionField<O>(name, help, OptionType::Name, 0, 0, alias);
    f.choices = choices;
    f.store = +[](O& o, const OptionValue& v) {
        detail::optionMember<Path...>(o) = Parse(std::get<std::string>(v));
    };
    f.get = +[](const O& o) { return OptionValue(std::string(Format(detail::optionMember<Path...>(o)))); };
    return f;
}

/// A Vec3f or Vec3d member at Path, each component in [lo, hi].
template <class O, auto... Path>
OptionField<O> tripleOption(std::string_view name, std::string_view help, double lo, double hi,
                            std::string_view alias = {}) {
    using T = detail::OptionMemberType<O, Path...>;
    OptionField<O> f = optionField<O>(name, help, OptionType::Triple, lo, hi, alias);
    f.store = +[](O& o, const OptionValue& v) { detail::optionMember<Path...>(o) = T(std::get<Vec3d>(v)); };
    f.get = +[](const O& o) { return OptionValue(Vec3d(detail::optionMember<Path...>(o))); };
    return f;
}

} // namespace voxfx
