// voxfx — walking the alternatives of a techniques' options variant (internal): by name, in order.
// Each alternative O has O::kName and O::kSummary (voxfx/shadow.hpp, voxfx/glass.hpp).
#pragma once

#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "voxfx/error.hpp"

namespace voxfx::detail {

/// Calls f(std::type_identity<O>{}) for every alternative O of Variant, in order.
template <class Variant, class F> void forEachAlternative(F&& f) {
    [&]<std::size_t... I>(std::index_sequence<I...>) {
        (f(std::type_identity<std::variant_alternative_t<I, Variant>>{}), ...);
    }
    (std::make_index_sequence<std::variant_size_v<Variant>>{});
}

template <class Variant> std::vector<std::string_view> alternativeNames() {
    std::vector<std::string_view> names;
    forEachAlternative<Variant>([&]<class O>(std::type_identity<O>) { names.push_back(O::kName); });
    return names;
}

/// The default-constructed alternative called `name`; voxfx::Error "unknown WHAT 'NAME' (allowed:
/// ...)" otherwise.
template <class Variant> Variant alternativeNamed(std::string_view name, const char* what) {
    Variant out;
    bool found = false;
    forEachAlternative<Variant>([&]<class O>(std::type_identity<O>) {
        if (!found && name == O::kName) {
            out = O{};
            found = true;
        }
    });
    if (found) return out;
    std::string list;
    for (const std::string_view n : alternativeNames<Variant>())
        list += (list.empty() ? "" : ", ") + std::string(n);
    fail("unknown ", what, " '", name, "' (allowed: ", list, ")");
}

template <class Variant> std::string_view alternativeSummary(std::string_view name, const char* what) {
    std::string_view summary;
    forEachAlternative<Variant>([&]<class O>(std::type_identity<O>) {
        if (name == O::kName) summary = O::kSummary;
    });
    if (summary.empty()) alternativeNamed<Variant>(name, what); // throws listing the names
    return summary;
}

/// The alternative G of a built-technique variant whose G::Options is O.
template <class O, class... G> struct FindBuilt;
template <class O> struct FindBuilt<O> {}; // no technique has these options
template <class O, class G, class... Rest>
struct FindBuilt<O, G, Rest...> : std::conditional_t<std::is_same_v<typename G::Options, O>,
                                                     std::type_identity<G>, FindBuilt<O, Rest...>> {};
template <class Built, class O> struct BuiltForT;
template <class... G, class O> struct BuiltForT<std::variant<G...>, O> : FindBuilt<O, G...> {};
template <class Built, class O> using BuiltFor = typename BuiltForT<Built, O>::type;

} // namespace voxfx::detail
