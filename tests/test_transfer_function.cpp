// Tests of the 1D transfer function: lookups against values worked out by hand, the table, and
// every kind of bad control points.
#include <cmath>
#include <functional>

#include "test_util.hpp"
#include "voxfx/transfer_function.hpp"
#include "voxfx/volume_io.hpp"

namespace voxfx {
namespace {

using test::TempDir;
using test::writeFile;

void expectErrorWith(const std::function<void()>& f, const std::string& a, const std::string& b) {
    try {
        f();
        ADD_FAILURE() << "no error; expected one mentioning '" << b << "'";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(a), std::string::npos) << msg;
        EXPECT_NE(msg.find(b), std::string::npos) << msg;
    }
}

TEST(TransferFunction, PointsFormLooksUpHandComputedValues) {
    const TransferFunction tf = parseTransferFunction(R"({"points": [
        {"value": 0,   "color": [0, 0, 0],   "opacity": 0},
        {"value": 100, "color": [1, 0.5, 0], "opacity": 0.2},
        {"value": 200, "color": [1, 1, 1],   "opacity": 1}]})");
    // value 50: halfway between the first two points.
    Rgba c = tf(50);
    EXPECT_FLOAT_EQ(c.r, 0.5f);
    EXPECT_FLOAT_EQ(c.g, 0.25f);
    EXPECT_FLOAT_EQ(c.b, 0.0f);
    EXPECT_FLOAT_EQ(c.a, 0.1f);
    // value 175: three quarters from 100 to 200.
    c = tf(175);
    EXPECT_FLOAT_EQ(c.r, 1.0f);
    EXPECT_FLOAT_EQ(c.g, 0.875f);
    EXPECT_FLOAT_EQ(c.b, 0.75f);
    EXPECT_FLOAT_EQ(c.a, 0.8f);
    // At and beyond the ends: the end points.
    EXPECT_EQ(tf(100), (Rgba{1, 0.5f, 0, 0.2f}));
    EXPECT_EQ(tf(-5), (Rgba{0, 0, 0, 0}));
    EXPECT_EQ(tf(1e9), (Rgba{1, 1, 1, 1}));
    EXPECT_EQ(tf(std::nan("")), (Rgba{0, 0, 0, 0}));
    EXPECT_EQ(tf.minValue(), 0);
    EXPECT_EQ(tf.maxValue(), 200);
}

TEST(TransferFunction, SeparateCurvesAndSteps) {
    const TransferFunction tf = parseTransferFunction(R"({
        "color": [[10, 1, 0, 0], [20, 0, 0, 1]],
        "opacity": [[0, 0], [50, 0], [50, 0.5], [90, 0.9]]})");
    EXPECT_NEAR(tf.color(12.5).x, 0.75, 1e-12);
    EXPECT_NEAR(tf.color(12.5).z, 0.25, 1e-12);
    EXPECT_EQ(tf.color(0).x, 1.0);
    // Two opacity points at 50 make a step; 50 itself takes the right-hand point.
    EXPECT_EQ(tf.opacity(49.999), 0.0);
    EXPECT_EQ(tf.opacity(50), 0.5);
    EXPECT_NEAR(tf.opacity(70), 0.7, 1e-12);
    EXPECT_EQ(tf.minValue(), 0);
    EXPECT_EQ(tf.maxValue(), 90);
}

TEST(TransferFunction, TableAgreesWithTheFunctionAtItsEntriesAndOnLinearStretches) {
    const TransferFunction tf({{0, {0, 0, 0}}, {64, {1, 2, 3}}}, {{0, 0}, {32, 1}, {64, 0.5}});
    const TransferTable table(tf, 0, 64, 65); // one entry per unit, control points on entries
    for (int i = 0; i <= 64; ++i) EXPECT_EQ(table.entries()[std::size_t(i)], tf(double(i)));
    for (double x = -3; x < 70; x += 0.37) {
        const Rgba a = table(x), b = tf(x);
        EXPECT_NEAR(a.r, b.r, 1e-5);
        EXPECT_NEAR(a.g, b.g, 1e-5);
        EXPECT_NEAR(a.b, b.b, 1e-5);
        EXPECT_NEAR(a.a, b.a, 1e-5);
    }
    EXPECT_THROW(TransferTable(tf, 0, 64, 1), Error);
    EXPECT_THROW(TransferTable(tf, 5, 5, 16), Error);
}

// The oracle: the extinction and extinction-weighted colour over a linear value ramp by a dense
// midpoint sum of the curve itself.
TEST(TransferFunction, PreintegratedIntervalsAreTheMeanOverTheValueRamp) {
    const TransferFunction tf({{0, {0, 0, 1}}, {0.5, {1, 0, 0}}, {1, {1, 1, 1}}},
                              {{0.2, 0}, {0.45, 0}, {0.5, 0.9}, {0.55, 0}, {0.7, 0.3}, {0.7, 1}, {0.9, 0.2}});
    const double len = 0.25;
    const PreintegratedTransfer pre(tf, len);
    const auto dense = [&](double a, double b, Vec3d& color) {
        const int n = 200000;
        double s = 0;
        Vec3d e{0, 0, 0};
        for (int i = 0; i < n; ++i) {
            const double v = a + (b - a) * (i + 0.5) / n;
            const double sg = -std::log(1 - std::min(tf.opacity(v), 1 - 1e-7)) / len;
            s += sg / n;
            e += tf.color(v) * (sg / n);
        }
        color = s > 0 ? e / s : tf.color(0.5 * (a + b));
        return s;
    };
    const double ramps[][2] = {{0.3, 0.6},  {0.6, 0.3},   {0.4, 0.52}, {0.68, 0.72}, {-1, 2},
                               {0.1, 0.44}, {0.46, 0.47}, {0.95, 3},   {0.8, 0.8}};
    for (const auto& r : ramps) {
        Vec3d c;
        const double want = dense(r[0], r[1], c);
        EXPECT_NEAR(pre.extinction(r[0], r[1]), want, 1e-4 * std::max(1.0, want)) << r[0] << " " << r[1];
        const Vec3d got = pre.color(r[0], r[1]);
        EXPECT_NEAR(got.x, c.x, 0.01) << r[0] << " " << r[1];
        EXPECT_NEAR(got.y, c.y, 0.01) << r[0] << " " << r[1];
        EXPECT_NEAR(got.z, c.z, 0.01) << r[0] << " " << r[1];
    }
    // Where the curve is transparent over the whole ramp: exactly 0 (empty-space skipping relies on it).
    EXPECT_EQ(pre.extinction(0.0, 0.44), 0.0);
    // A thin peak between two samples that both read opacity 0 counts.
    EXPECT_EQ(tf.opacity(0.42), 0.0);
    EXPECT_EQ(tf.opacity(0.55), 0.0);
    EXPECT_GT(pre.extinction(0.42, 0.55), 1.0);
}

TEST(TransferFunction, NanValueAndEmptyFunctionGiveTransparentBlack) {
    const TransferFunction tf({{0, {1, 1, 1}}, {1, {1, 1, 1}}}, {{0, 1}, {1, 1}});
    EXPECT_EQ(tf.opacity(std::nan("")), 0.0);
    EXPECT_EQ(tf.color(std::nan("")), Vec3d(0, 0, 0));
    const TransferFunction none;
    EXPECT_EQ(none(0.5), (Rgba{0, 0, 0, 0}));
    EXPECT_EQ(none.opacity(0.5), 0.0);
    EXPECT_EQ(none.color(0.5), Vec3d(0, 0, 0));
}

TEST(TransferFunction, BadControlPointsGiveAClearError) {
    const double nan = std::nan("");
    const std::string src = "tf.json";
    expectErrorWith([&] { TransferFunction({}, {{0, 1}}, src); }, src, "no colour control points");
    expectErrorWith([&] { TransferFunction({{0, {1, 1, 1}}}, {}, src); }, src, "no opacity control points");
    expectErrorWith(
        [&] {
            TransferFunction({{0, {1, 1, 1}}, {nan, {1, 1, 1}}}, {{0, 1}}, src);
        },
        src, "colour point 1 has a value that is not finite");
    expectErrorWith([&] { TransferFunction({{0, {1, nan, 1}}}, {{0, 1}}, src); }, src, "non-finite colour");
    expectErrorWith([&] { TransferFunction({{0, {1, 1, 1}}}, {{0, nan}}, src); }, src, "opacity point 0");
    expectErrorWith([&] { TransferFunction({{0, {1, 1, 1}}}, {{0, 1.5}}, src); }, src, "outside [0, 1]");
    expectErrorWith([&] { TransferFunction({{0, {-1, 1, 1}}}, {{0, 1}}, src); }, src, "negative colour");
    expectErrorWith(
        [&] {
            TransferFunction({{5, {1, 1, 1}}, {4, {1, 1, 1}}}, {{0, 1}}, src);
        },
        src, "colour points are not sorted by value: point 1");
    expectErrorWith(
        [&] {
            TransferFunction({{0, {1, 1, 1}}}, {{0, 1}, {2, 1}, {1, 1}}, src);
        },
        src, "opacity points are not sorted by value: point 2");

    const auto parse = [&](const std::string& json) {
        return [json, src] { parseTransferFunction(json, src); };
    };
    expectErrorWith(parse(R"({"points": []})"), src, "no colour control points");
    expectErrorWith(parse(R"({"points": [{"value": NaN, "color": [0,0,0], "opacity": 0}]})"), src,
                    "not valid JSON");
    expectErrorWith(parse(R"({"points": [{"value": 1, "color": [0,0], "opacity": 0}]})"), src, "[r, g, b]");
    expectErrorWith(parse(R"({"points": [{"value": "a", "color": [0,0,0], "opacity": 0}]})"), src,
                    "must be a number");
    expectErrorWith(parse(R"({"points": [{"value": 2, "color": [0,0,0], "opacity": 0},
                                         {"value": 1, "color": [0,0,0], "opacity": 0}]})"),
                    src, "not sorted");
    expectErrorWith(parse(R"({"colour": [[0, 1, 1, 1]]})"), src, "unknown key \"colour\"");
    expectErrorWith(parse(R"({"color": [[0, 1, 1, 1]]})"), src, "both \"color\" and \"opacity\"");
    expectErrorWith(parse(R"({"color": [[0, 1, 1]], "opacity": [[0, 1]]})"), src, "[value, r, g, b]");
    expectErrorWith(parse("[1, 2]"), src, "JSON object");
}

TEST(TransferFunction, LoadsFromAFileAndNamesItInErrors) {
    TempDir dir;
    const std::string good =
        writeFile(dir.file("tf.json"), R"({"color": [[0, 1, 1, 1]], "opacity": [[0, 0.5]]})");
    EXPECT_EQ(loadTransferFunction(good)(3), (Rgba{1, 1, 1, 0.5f}));
    const std::string bad =
        writeFile(dir.file("bad.json"), R"({"color": [[0, 1, 1, 1]], "opacity": [[0, 2]]})");
    expectErrorWith([&] { loadTransferFunction(bad); }, bad, "outside [0, 1]");
    const std::string gone = dir.file("gone.json");
    expectErrorWith([&] { loadTransferFunction(gone); }, gone, "cannot open");
}

} // namespace
} // namespace voxfx
