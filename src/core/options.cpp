// voxfx — named options (voxfx/options.hpp): spellings, formatting and the checked conversion of a
// value to the type of a field.
#include "voxfx/options.hpp"

#include <cmath>
#include <cstdio>

namespace voxfx {

const char* toString(OptionType t) { return enumName(t, kOptionTypeNames); }

namespace {

std::string separated(std::string_view camel, char separator) {
    std::string out;
    for (const char c : camel) {
        if (c >= 'A' && c <= 'Z') {
            out += separator;
            out += char(c - 'A' + 'a');
        } else {
            out += c;
        }
    }
    return out;
}

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

} // namespace

std::string kebabCase(std::string_view camel) { return separated(camel, '-'); }
std::string snakeCase(std::string_view camel) { return separated(camel, '_'); }

std::string camelCase(std::string_view name) {
    std::string out;
    bool upper = false;
    for (const char c : name) {
        if (c == '-' || c == '_') {
            upper = !out.empty(); // leading dashes ("--grid-depth") start no word
        } else {
            out += upper && c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c;
            upper = false;
        }
    }
    return out;
}

std::string formatOption(const OptionValue& v) {
    struct Format {
        std::string operator()(bool b) const { return b ? "on" : "off"; }
        std::string operator()(int64_t i) const { return std::to_string(i); }
        std::string operator()(double d) const { return number(d); }
        std::string operator()(const std::string& s) const { return s; }
        std::string operator()(const Vec3d& t) const {
            return "(" + number(t.x) + ", " + number(t.y) + ", " + number(t.z) + ")";
        }
    };
    return std::visit(Format{}, v);
}

namespace detail {

OptionValue checkOptionValue(OptionType type, double lo, double hi, std::string_view name,
                             const OptionValue& v, std::string_view where) {
    const std::string at = where.empty() ? std::string(name) : concat(where, ": ", name);
    const std::string range = "[" + number(lo) + ", " + number(hi) + "]";
    auto wrong = [&]() -> OptionValue {
        switch (type) {
        case OptionType::Integer:
            fail(at, ": expected a whole number in ", range, ", got ", formatOption(v));
        case OptionType::Real:
            fail(at, ": expected a number in ", range, ", got ", formatOption(v));
        case OptionType::Triple:
            fail(at, ": expected three numbers in ", range, ", got ", formatOption(v));
        default:
            fail(at, ": expected ", type == OptionType::Flag ? "on or off" : "a name", ", got ",
                 formatOption(v));
        }
    };
    const int64_t* i = std::get_if<int64_t>(&v);
    const double* d = std::get_if<double>(&v);
    const double x = i ? double(*i) : d ? *d : 0.0;
    switch (type) {
    case OptionType::Flag:
        if (const bool* b = std::get_if<bool>(&v)) return *b;
        return wrong();
    case OptionType::Integer:
        // The range lies within int64_t, so the conversion is defined once x is in it.
        if ((i || d) && x >= lo && x <= hi && x == std::floor(x)) return i ? *i : int64_t(x);
        return wrong();
    case OptionType::Real:
        if ((i || d) && x >= lo && x <= hi) return x;
        return wrong();
    case OptionType::Name:
        if (const std::string* s = std::get_if<std::string>(&v)) return *s;
        return wrong();
    case OptionType::Triple:
        if (const Vec3d* t = std::get_if<Vec3d>(&v))
            if (t->x >= lo && t->x <= hi && t->y >= lo && t->y <= hi && t->z >= lo && t->z <= hi) return *t;
        return wrong();
    }
    return wrong();
}

void failOption(std::string_view name, std::string_view where, std::string_view message) {
    if (where.empty()) fail(name, ": ", message);
    fail(where, ": ", name, ": ", message);
}

} // namespace detail

} // namespace voxfx
