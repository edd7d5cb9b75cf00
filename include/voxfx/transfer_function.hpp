// voxfx — 1D transfer function: scalar value -> colour (linear RGB) and opacity.
//
// Two piecewise-linear curves over the scalar value, each given by control points sorted by
// value: colour points (value, r, g, b) and opacity points (value, alpha). Below the first point
// a curve keeps the first point's value, above the last the last one's. Two points at the same
// value make a step: the value itself takes the right-hand point.
//
// JSON (either form, in a file read by loadTransferFunction (voxfx/volume_io.hpp) or text given
// to parseTransferFunction):
//   {"points": [{"value": 0, "color": [0, 0, 0], "opacity": 0},
//               {"value": 80, "color": [1, 0.9, 0.8], "opacity": 0.6}]}
//   {"color": [[0, 0, 0, 0], [80, 1, 0.9, 0.8]], "opacity": [[0, 0], [40, 0.1], [80, 0.6]]}
// Control points must be finite, sorted by value, with opacity in [0, 1] and colour >= 0 (linear
// RGB may exceed 1); anything else throws voxfx::Error naming the source and the point.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "voxfx/math.hpp"

namespace voxfx {

struct Rgba {
    float r = 0, g = 0, b = 0, a = 0;
    bool operator==(const Rgba&) const = default;
};

struct ColorPoint {
    double value = 0;
    Vec3d color;
};

struct OpacityPoint {
    double value = 0;
    double opacity = 0;
};

class TransferFunction {
public:
    TransferFunction() = default;
    /// Throws voxfx::Error (message starting with `source`) for empty, unsorted or non-finite
    /// points, opacity outside [0, 1] or negative colour.
    TransferFunction(std::vector<ColorPoint> color, std::vector<OpacityPoint> opacity,
                     const std::string& source = "transfer function");

    const std::vector<ColorPoint>& colorPoints() const { return color_; }
    const std::vector<OpacityPoint>& opacityPoints() const { return opacity_; }

    Vec3d color(double value) const;
    double opacity(double value) const;
    /// Colour and opacity at `value`. A NaN value, or a default-constructed function, gives
    /// transparent black (colour 0, opacity 0).
    Rgba operator()(double value) const;

    /// An upper bound of the opacity over the values [lo, hi], exact for this piecewise-linear
    /// curve: the larger end, or a control point between them (0 for a default-constructed
    /// function). Empty-space skipping reads it: a region whose values span [lo, hi] is invisible
    /// when it is 0.
    double maxOpacity(double lo, double hi) const;

    /// Range of values spanned by the control points (first to last of both curves).
    double minValue() const;
    double maxValue() const;

private:
    std::vector<ColorPoint> color_;
    std::vector<OpacityPoint> opacity_;
};

/// A transfer function sampled at n evenly spaced values over [lo, hi] (entry i at
/// lo + i * (hi - lo) / (n - 1)), looked up with linear interpolation between entries: what a
/// renderer indexes per sample instead of searching the control points.
class TransferTable {
public:
    /// Throws voxfx::Error for n < 2 or a range that is not finite with lo < hi.
    TransferTable(const TransferFunction& tf, double lo, double hi, int n);
    Rgba operator()(double value) const;
    const std::vector<Rgba>& entries() const { return table_; }
    double lo() const { return lo_; }
    double hi() const { return hi_; }

private:
    std::vector<Rgba> table_;
    double lo_ = 0, hi_ = 1, scale_ = 1;
};

/// A transfer function pre-integrated over ray intervals (Engel, Kraus and Ertl 2001, in the
/// length-independent form of the extinction): along an interval over which the sampled value runs
/// linearly from a to b, the mean extinction
///   sigma(a, b) = 1 / (b - a) * integral over [a, b] of -ln(1 - alpha(s)) / opacityLength ds
/// (alpha clamped to 1 - 1e-7), integrated exactly over the piecewise-linear opacity, so an
/// interval of length d passes exp(-sigma(a, b) * d) whatever features of the curve lie between its
/// samples (a sharp opacity peak no longer depends on where the samples fall: no slab rings).
/// sigma(a, a) is the extinction at a; an interval whose values all have opacity 0 gets exactly 0.
/// The colour is the extinction-weighted mean of the colour curve over [a, b] (from a table of 1024
/// cells over the control points' range; the colour at the middle value where the interval spans
/// under two cells or has no extinction). Thread-safety: a value; concurrent reads are fine.
class PreintegratedTransfer {
public:
    PreintegratedTransfer() = default; ///< transparent everywhere
    /// Throws voxfx::Error for a non-positive or non-finite opacityLength.
    PreintegratedTransfer(const TransferFunction& tf, double opacityLength);
    /// Mean extinction (per world unit) over values running linearly from a to b (either order).
    double extinction(double a, double b) const;
    /// The integral of -ln(1 - alpha) from the first opacity point to v (negative below it): a
    /// walk that reuses each sample as the next interval's start keeps it with the value.
    double cumulative(double v) const;
    /// extinction(a, b) given ca = cumulative(a) and cb = cumulative(b).
    double extinction(double a, double ca, double b, double cb) const;
    /// The smaller of the extinctions at values a and b, min(extinction(a, a), extinction(b, b)),
    /// with one logarithm: the extinction grows with the opacity.
    double smallerPointExtinction(double a, double b) const;
    /// Extinction-weighted mean colour over the same interval.
    Vec3d color(double a, double b) const;
    const TransferFunction& transfer() const { return tf_; }

private:
    double pointExtinction(double v) const;
    double pieceFrom(std::size_t i, double a1, double dv) const;
    TransferFunction tf_;
    double opacityLength_ = 1;
    std::vector<double> prefix_; ///< integral up to each opacity point
    /// Per opacity point: the antiderivative of -ln(1 - alpha) at its opacity, and -ln(1 - alpha)
    /// there (alpha clamped): cumulative's integral from the point takes one logarithm, not three.
    std::vector<double> antiAt_, depthAt_;
    double lo_ = 0, cell_ = 1;   ///< colour table: cell i spans lo + [i, i + 1] * cell
    std::vector<double> tableS_; ///< integral of sigma at cell boundaries
    std::vector<Vec3d> tableE_;  ///< integral of sigma * colour at cell boundaries
};

/// Parses the JSON text of a transfer function; `source` (a file name) starts every message.
TransferFunction parseTransferFunction(std::string_view json,
                                       const std::string& source = "transfer function");

} // namespace voxfx
