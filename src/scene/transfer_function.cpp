// voxfx — 1D transfer function: validation, piecewise-linear lookup, table, JSON parsing.
#include "voxfx/transfer_function.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

namespace voxfx {

namespace {

template <class Point, class Get> auto lookup(const std::vector<Point>& pts, double x, Get get) {
    if (x < pts.front().value) return get(pts.front());
    if (x >= pts.back().value) return get(pts.back());
    // First point with value > x: x lies in [prev.value, next.value) (a step takes the right side).
    const auto next =
        std::upper_bound(pts.begin(), pts.end(), x, [](double v, const Point& p) { return v < p.value; });
    const auto prev = next - 1;
    const double t = (x - prev->value) / (next->value - prev->value);
    return get(*prev) + (get(*next) - get(*prev)) * t;
}

} // namespace

TransferFunction::TransferFunction(std::vector<ColorPoint> color, std::vector<OpacityPoint> opacity,
                                   const std::string& source)
    : color_(std::move(color)), opacity_(std::move(opacity)) {
    if (color_.empty()) fail(source, ": the transfer function has no colour control points");
    if (opacity_.empty()) fail(source, ": the transfer function has no opacity control points");
    for (std::size_t i = 0; i < color_.size(); ++i) {
        const ColorPoint& p = color_[i];
        if (!std::isfinite(p.value)) fail(source, ": colour point ", i, " has a value that is not finite");
        if (!isFinite(p.color))
            fail(source, ": colour point ", i, " (value ", p.value, ") has a non-finite colour");
        if (p.color.x < 0 || p.color.y < 0 || p.color.z < 0)
            fail(source, ": colour point ", i, " (value ", p.value, ") has a negative colour component");
        if (i > 0 && p.value < color_[i - 1].value)
            fail(source, ": colour points are not sorted by value: point ", i, " (", p.value,
                 ") comes after point ", i - 1, " (", color_[i - 1].value, ")");
    }
    for (std::size_t i = 0; i < opacity_.size(); ++i) {
        const OpacityPoint& p = opacity_[i];
        if (!std::isfinite(p.value)) fail(source, ": opacity point ", i, " has a value that is not finite");
        if (!(p.opacity >= 0 && p.opacity <= 1))
            fail(source, ": opacity point ", i, " (value ", p.value, ") has opacity ", p.opacity,
                 ", outside [0, 1]");
        if (i > 0 && p.value < opacity_[i - 1].value)
            fail(source, ": opacity points are not sorted by value: point ", i, " (", p.value,
                 ") comes after point ", i - 1, " (", opacity_[i - 1].value, ")");
    }
}

Vec3d TransferFunction::color(double value) const {
    if (color_.empty() || std::isnan(value)) return {}; // default-constructed or NaN: black
    return lookup(color_, value, [](const ColorPoint& p) { return p.color; });
}

double TransferFunction::opacity(double value) const {
    if (opacity_.empty() || std::isnan(value)) return 0;
    return lookup(opacity_, value, [](const OpacityPoint& p) { return p.opacity; });
}

Rgba TransferFunction::operator()(double value) const {
    if (std::isnan(value) || color_.empty()) return {};
    const Vec3d c = color(value);
    return {float(c.x), float(c.y), float(c.z), float(opacity(value))};
}

double TransferFunction::maxOpacity(double lo, double hi) const {
    if (opacity_.empty()) return 0;
    double m = std::max(opacity(lo), opacity(hi));
    for (const OpacityPoint& p : opacity_)
        if (p.value >= lo && p.value <= hi) m = std::max(m, p.opacity);
    return m;
}

double TransferFunction::minValue() const {
    if (color_.empty()) return 0;
    return std::min(color_.front().value, opacity_.front().value);
}

double TransferFunction::maxValue() const {
    if (color_.empty()) return 0;
    return std::max(color_.back().value, opacity_.back().value);
}

namespace {

constexpr double kMaxPreintegratedOpacity = 1.0 - 1e-7;

// ln(1 - alpha) by std::log, not std::log1p (half its cost on glibc 2.36, a volume sample's largest
// arithmetic): 1 - alpha loses only alpha's bits below 2^-53, an absolute error of about 1e-16 in
// the logarithm, the size of the rounding the antiderivative's differences have anyway (its values
// lie near -1), and an opacity of 0 still gives exactly 0.
double preintegratedLog(double alpha) { return std::log(1 - alpha); }

double preintegratedOpticalDepth(double alpha) {
    return -preintegratedLog(std::min(alpha, kMaxPreintegratedOpacity));
}

// The antiderivative of -ln(1 - alpha) in alpha: (1 - alpha) ln(1 - alpha) - (1 - alpha).
double preintegratedAnti(double a) { return (1 - a) * preintegratedLog(a) - (1 - a); }

// The integral of -ln(1 - alpha) over dv along which alpha runs linearly from a0 to a1 (clamped to
// kMaxPreintegratedOpacity).
double preintegratedPiece(double a0, double a1, double dv) {
    if (!(dv > 0)) return 0;
    const double m = kMaxPreintegratedOpacity;
    if (std::abs(a1 - a0) < 1e-9) return preintegratedOpticalDepth(0.5 * (a0 + a1)) * dv;
    if ((a0 - m) * (a1 - m) < 0) { // split where the clamp starts
        const double t = (m - a0) / (a1 - a0);
        return preintegratedPiece(a0, m, t * dv) + preintegratedPiece(m, a1, (1 - t) * dv);
    }
    if (a0 >= m && a1 >= m) return preintegratedOpticalDepth(m) * dv;
    return (preintegratedAnti(a1) - preintegratedAnti(a0)) / (a1 - a0) * dv;
}

} // namespace

PreintegratedTransfer::PreintegratedTransfer(const TransferFunction& tf, double opacityLength)
    : tf_(tf), opacityLength_(opacityLength) {
    if (!(opacityLength > 0) || !std::isfinite(opacityLength))
        fail("pre-integrated transfer function: opacityLength must be positive, got ", opacityLength);
    const std::vector<OpacityPoint>& op = tf_.opacityPoints();
    if (op.empty()) return;
    prefix_.assign(op.size(), 0.0);
    for (const OpacityPoint& p : op) {
        antiAt_.push_back(preintegratedAnti(p.opacity));
        depthAt_.push_back(preintegratedOpticalDepth(p.opacity));
    }
    for (std::size_t i = 1; i < op.size(); ++i)
        prefix_[i] = prefix_[i - 1] +
                     preintegratedPiece(op[i - 1].opacity, op[i].opacity, op[i].value - op[i - 1].value);
    // The colour table: Simpson's rule over 4 sub-steps per cell.
    const int cells = 1024;
    lo_ = tf_.minValue();
    const double hi = tf_.maxValue();
    cell_ = hi > lo_ ? (hi - lo_) / cells : 1.0;
    tableS_.assign(cells + 1, 0.0);
    tableE_.assign(cells + 1, Vec3d{0, 0, 0});
    for (int i = 0; i < cells; ++i) {
        double s = 0;
        Vec3d e{0, 0, 0};
        for (int k = 0; k <= 8; ++k) {
            const double w = (k == 0 || k == 8) ? 1 : (k % 2 ? 4 : 2);
            const double v = lo_ + cell_ * (double(i) + double(k) / 8.0);
            const double sg = pointExtinction(v);
            s += w * sg;
            e += tf_.color(v) * (w * sg);
        }
        tableS_[std::size_t(i) + 1] = tableS_[std::size_t(i)] + s * cell_ / 24.0;
        tableE_[std::size_t(i) + 1] = tableE_[std::size_t(i)] + e * (cell_ / 24.0);
    }
}

double PreintegratedTransfer::pointExtinction(double v) const {
    return preintegratedOpticalDepth(tf_.opacity(v)) / opacityLength_;
}

double PreintegratedTransfer::cumulative(double v) const {
    if (tf_.opacityPoints().empty() || std::isnan(v)) return 0;
    const std::vector<OpacityPoint>& op = tf_.opacityPoints();
    // Beyond the points the opacity is constant: its optical depth kept per point (no logarithm).
    if (v <= op.front().value) return depthAt_.front() * (v - op.front().value);
    if (v >= op.back().value) return prefix_.back() + depthAt_.back() * (v - op.back().value);
    // The piece [op[i].value, op[i + 1].value) holding v (the last of equal values: steps).
    const auto it = std::upper_bound(op.begin(), op.end(), v,
                                     [](double x, const OpacityPoint& p) { return x < p.value; });
    const std::size_t i = std::size_t(it - op.begin()) - 1;
    const double t = (v - op[i].value) / (op[i + 1].value - op[i].value);
    const double a = op[i].opacity + t * (op[i + 1].opacity - op[i].opacity);
    return prefix_[i] + pieceFrom(i, a, v - op[i].value);
}

// preintegratedPiece(op[i].opacity, a1, dv), the same bits, with the point's antiderivative and
// optical depth kept: one logarithm where the piece is below the clamp, none where it is flat.
double PreintegratedTransfer::pieceFrom(std::size_t i, double a1, double dv) const {
    const double a0 = tf_.opacityPoints()[i].opacity, m = kMaxPreintegratedOpacity;
    if (!(dv > 0)) return 0;
    if (a1 == a0) return depthAt_[i] * dv; // 0.5 * (a0 + a1) is a0
    if (a0 < m && a1 < m && !(std::abs(a1 - a0) < 1e-9))
        return (preintegratedAnti(a1) - antiAt_[i]) / (a1 - a0) * dv;
    return preintegratedPiece(a0, a1, dv); // near the point, or at the clamp
}

double PreintegratedTransfer::extinction(double a, double b) const {
    return extinction(a, cumulative(a), b, cumulative(b));
}

double PreintegratedTransfer::extinction(double a, double ca, double b, double cb) const {
    if (tf_.opacityPoints().empty() || std::isnan(a) || std::isnan(b)) return 0;
    if (std::abs(b - a) <= 1e-6 * std::max({1.0, std::abs(a), std::abs(b)})) {
        // pointExtinction, without the search and the logarithm beyond the points (the same bits).
        const std::vector<OpacityPoint>& op = tf_.opacityPoints();
        const double v = 0.5 * (a + b);
        if (v < op.front().value) return depthAt_.front() / opacityLength_;
        if (v >= op.back().value) return depthAt_.back() / opacityLength_;
        return pointExtinction(v);
    }
    return std::max(0.0, (cb - ca) / (b - a)) / opacityLength_;
}

double PreintegratedTransfer::smallerPointExtinction(double a, double b) const {
    if (tf_.opacityPoints().empty() || std::isnan(a) || std::isnan(b)) return 0;
    return preintegratedOpticalDepth(std::min(tf_.opacity(a), tf_.opacity(b))) / opacityLength_;
}

Vec3d PreintegratedTransfer::color(double a, double b) const {
    if (tf_.colorPoints().empty() || std::isnan(a) || std::isnan(b)) return {};
    if (a > b) std::swap(a, b);
    if (b - a < 2 * cell_ || tableS_.empty()) return tf_.color(0.5 * (a + b));
    const auto at = [&](double v, double& s, Vec3d& e) {
        const double n = double(tableS_.size() - 1), u = (v - lo_) / cell_;
        if (u <= 0 || u >= n) { // beyond the table the curves are constant
            const std::size_t i = u <= 0 ? 0 : tableS_.size() - 1;
            const double edge = u <= 0 ? lo_ : lo_ + n * cell_, sg = pointExtinction(edge);
            s = tableS_[i] + sg * (v - edge);
            e = tableE_[i] + tf_.color(edge) * (sg * (v - edge));
            return;
        }
        const auto i = std::min(std::size_t(u), tableS_.size() - 2);
        const double f = u - double(i);
        s = tableS_[i] + f * (tableS_[i + 1] - tableS_[i]);
        e = tableE_[i] + (tableE_[i + 1] - tableE_[i]) * f;
    };
    double sa = 0, sb = 0;
    Vec3d ea, eb;
    at(a, sa, ea);
    at(b, sb, eb);
    if (!(sb - sa > 1e-12 * std::max(1.0, std::abs(sb)))) return tf_.color(0.5 * (a + b));
    return (eb - ea) / (sb - sa);
}

TransferTable::TransferTable(const TransferFunction& tf, double lo, double hi, int n) : lo_(lo), hi_(hi) {
    if (n < 2) fail("a transfer table needs at least 2 entries, got ", n);
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi))
        fail("a transfer table needs a finite range lo < hi, got [", lo, ", ", hi, "]");
    scale_ = double(n - 1) / (hi - lo);
    table_.resize(std::size_t(n));
    for (int i = 0; i < n; ++i) table_[std::size_t(i)] = tf(lo + double(i) * (hi - lo) / double(n - 1));
}

Rgba TransferTable::operator()(double value) const {
    if (std::isnan(value)) return {};
    const double u = std::clamp((value - lo_) * scale_, 0.0, double(table_.size() - 1));
    const auto i = std::min(std::size_t(u), table_.size() - 2);
    const float t = float(u - double(i));
    const Rgba& a = table_[i];
    const Rgba& b = table_[i + 1];
    return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t, a.a + (b.a - a.a) * t};
}

namespace {

using nlohmann::json;

double number(const json& j, const std::string& source, const std::string& what) {
    if (!j.is_number()) fail(source, ": ", what, " must be a number");
    return j.get<double>();
}

Vec3d rgb(const json& j, const std::string& source, const std::string& what) {
    if (!j.is_array() || j.size() != 3) fail(source, ": ", what, " must be an array [r, g, b]");
    return {number(j[0], source, what), number(j[1], source, what), number(j[2], source, what)};
}

} // namespace

TransferFunction parseTransferFunction(std::string_view text, const std::string& source) {
    json j;
    try {
        // NaN is not JSON; a file that spells it fails here with the parser's position.
        j = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) { fail(source, ": not valid JSON: ", e.what()); }
    if (!j.is_object()) fail(source, ": a transfer function must be a JSON object");
    for (const auto& item : j.items())
        if (item.key() != "points" && item.key() != "color" && item.key() != "opacity")
            fail(source, ": unknown key \"", item.key(),
                 "\" in a transfer function (known: points, color, opacity)");
    std::vector<ColorPoint> color;
    std::vector<OpacityPoint> opacity;
    if (j.contains("points")) {
        if (j.contains("color") || j.contains("opacity"))
            fail(source, ": give either \"points\" or \"color\" and \"opacity\", not both");
        const json& pts = j["points"];
        if (!pts.is_array()) fail(source, ": \"points\" must be an array");
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const json& p = pts[i];
            const std::string what = "point " + std::to_string(i);
            if (!p.is_object() || !p.contains("value") || !p.contains("color") || !p.contains("opacity"))
                fail(source, ": ", what, " must be an object with \"value\", \"color\" and \"opacity\"");
            const double v = number(p["value"], source, what + " \"value\"");
            color.push_back({v, rgb(p["color"], source, what + " \"color\"")});
            opacity.push_back({v, number(p["opacity"], source, what + " \"opacity\"")});
        }
    } else {
        if (!j.contains("color") || !j.contains("opacity"))
            fail(source, ": a transfer function needs \"points\", or both \"color\" and \"opacity\"");
        const json& c = j["color"];
        const json& o = j["opacity"];
        if (!c.is_array() || !o.is_array()) fail(source, ": \"color\" and \"opacity\" must be arrays");
        for (std::size_t i = 0; i < c.size(); ++i) {
            const std::string what = "colour point " + std::to_string(i);
            if (!c[i].is_array() || c[i].size() != 4) fail(source, ": ", what, " must be [value, r, g, b]");
            color.push_back({number(c[i][0], source, what),
                             {number(c[i][1], source, what), number(c[i][2], source, what),
                              number(c[i][3], source, what)}});
        }
        for (std::size_t i = 0; i < o.size(); ++i) {
            const std::string what = "opacity point " + std::to_string(i);
            if (!o[i].is_array() || o[i].size() != 2) fail(source, ": ", what, " must be [value, opacity]");
            opacity.push_back({number(o[i][0], source, what), number(o[i][1], source, what)});
        }
    }
    return TransferFunction(std::move(color), std::move(opacity), source);
}

} // namespace voxfx
