// The names users give modes, fills, operations and light types (src/core/enum_names.hpp): every
// toString() name parses back to its value, in any case, and unknown names list the choices.
#include <string>

#include <gtest/gtest.h>

#include "io/scene_gltf.hpp"
#include "voxfx/voxfx.hpp"

namespace voxfx {
namespace {

std::string upper(std::string s) {
    for (char& c : s) c = c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c;
    return s;
}

// Every value of an enum with `count` values (0 .. count-1) survives toString -> parse, also upper-cased.
template <class T, class Parse> void expectRoundTrip(int count, Parse parse) {
    for (int i = 0; i < count; ++i) {
        const T v = T(i);
        const std::string name = toString(v);
        EXPECT_EQ(parse(name), v) << name;
        EXPECT_EQ(parse(upper(name)), v) << upper(name);
    }
}

TEST(EnumNamesTest, EveryNameParsesBackToItsValueInAnyCase) {
    expectRoundTrip<VoxelizeMode>(5, parseVoxelizeMode);
    expectRoundTrip<Fill>(4, parseFill);
    expectRoundTrip<Axis>(3, parseAxis);
    expectRoundTrip<Slicing>(2, parseSlicing);
    expectRoundTrip<Device>(3, parseDevice);
    expectRoundTrip<MorphOp>(4, parseMorphOp);
    expectRoundTrip<MorphBorder>(3, parseMorphBorder);
    expectRoundTrip<CsgOp>(4, parseCsgOp);
    expectRoundTrip<SurfaceSource>(2, parseSurfaceSource);
    expectRoundTrip<LightType>(3,
                               [](const std::string& n) { return detail::parseLightType(n, "scene.json"); });
}

TEST(EnumNamesTest, AliasesAreAcceptedButNotListed) {
    EXPECT_EQ(parseMorphOp("Closing"), MorphOp::Close);
    EXPECT_EQ(parseCsgOp("minus"), CsgOp::Difference);
    try {
        parseCsgOp("glue");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "unknown CSG operation 'glue' (allowed: union, intersection, difference, xor)");
    }
}

TEST(EnumNamesTest, UnknownNamesSayWhereWhatAndTheChoices) {
    try {
        detail::parseLightType("area", "scene.json: lights[2]");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "scene.json: lights[2]: unknown light type 'area' (allowed: directional, spot, point)");
    }
    try {
        parseFill("");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "unknown fill '' (allowed: parity, flood, vote, winding, gwn)");
    }
}

} // namespace
} // namespace voxfx
