// The names users give modes, fills, operations, formats and light types (voxfx/enum_names.hpp):
// every enumerator the compiler knows has exactly one name in its enum's table, no name is given
// twice, every name parses back to its value in any case, and unknown names list the choices.
//
// The oracle for "every enumerator" is the compiler, not the table: enumeratorsOf<T>() asks it,
// for each value of T's underlying type, whether that value is a named enumerator (GCC and Clang
// spell a named value `V = voxfx::Fill::Gwn` and an unnamed one `V = (voxfx::Fill)5` in
// __PRETTY_FUNCTION__), so a value added to an enum without a name fails here.
#include <algorithm>
#include <cstdint>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include "io/scene_gltf.hpp"
#include "voxfx/attribute_io.hpp"
#include "voxfx/batch.hpp"
#include "voxfx/contains.hpp"
#include "voxfx/csg.hpp"
#include "voxfx/distance.hpp"
#include "voxfx/dsm.hpp"
#include "voxfx/glass.hpp"
#include "voxfx/grid_io.hpp"
#include "voxfx/morphology.hpp"
#include "voxfx/raster.hpp"
#include "voxfx/render.hpp"
#include "voxfx/scene.hpp"
#include "voxfx/sdf_io.hpp"
#include "voxfx/shadow.hpp"
#include "voxfx/surface_mesh.hpp"
#include "voxfx/volume_io.hpp"
#include "voxfx/volume_scene.hpp"
#include "voxfx/voxelize.hpp"

namespace voxfx {
namespace {

template <auto V> std::string_view prettyFunctionOf() { return __PRETTY_FUNCTION__; }

// Whether V is a named enumerator of its type (see the top of the file).
template <auto V> bool isNamedEnumerator() {
    const std::string_view s = prettyFunctionOf<V>();
    const std::size_t at = s.find("V = ");
    return at != std::string_view::npos && at + 4 < s.size() && s[at + 4] != '(' && s[at + 4] != '-' &&
           (s[at + 4] < '0' || s[at + 4] > '9');
}

template <class T, std::size_t... I> std::vector<T> namedValuesAmong(std::index_sequence<I...>) {
    std::vector<T> values;
    ((isNamedEnumerator<T(I)>() ? values.push_back(T(I)) : void()), ...);
    return values;
}

// Every enumerator of T, from the compiler (all these enums have an 8-bit unsigned underlying type).
template <class T> std::vector<T> enumeratorsOf() {
    static_assert(std::is_same_v<std::underlying_type_t<T>, uint8_t>);
    return namedValuesAmong<T>(std::make_index_sequence<256>());
}

std::string upperCase(std::string s) {
    for (char& c : s) c = c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c;
    return s;
}

// The table of T against the compiler's enumerators; `parse` is how users turn a name into a value.
template <class T, class Parse> void expectOneNamePerValue(std::span<const EnumName<T>> names, Parse parse) {
    const std::vector<T> values = enumeratorsOf<T>();
    ASSERT_FALSE(values.empty()) << "the enumerator probe found nothing: " << prettyFunctionOf<T(0)>();
    for (const T v : values) {
        int canonical = 0;
        for (const EnumName<T>& n : names) canonical += n.value == v && !n.alias;
        EXPECT_EQ(canonical, 1) << "value " << int(v) << " of " << prettyFunctionOf<T(0)>()
                                << " needs exactly one name that is not an alias";
        EXPECT_STREQ(toString(v), enumName(v, names));
    }
    std::set<std::string> seen;
    for (const EnumName<T>& n : names) {
        EXPECT_TRUE(seen.insert(upperCase(n.name)).second) << "name '" << n.name << "' is given twice";
        EXPECT_NE(std::find(values.begin(), values.end(), n.value), values.end())
            << "name '" << n.name << "' is for a value that is no enumerator";
        EXPECT_EQ(parse(n.name), n.value) << n.name;
        EXPECT_EQ(parse(upperCase(n.name)), n.value) << upperCase(n.name);
        if (!n.alias) { EXPECT_STREQ(toString(n.value), n.name); }
    }
}

// For enums without a parse function of their own: the table's parse.
template <class T> void expectOneNamePerValue(std::span<const EnumName<T>> names) {
    expectOneNamePerValue<T>(names, [&](const std::string& s) { return parseEnum<T>(s, "value", names); });
}

TEST(EnumNamesTest, EveryEnumeratorHasOneNameThatParsesBackInAnyCase) {
    expectOneNamePerValue<VoxelizeMode>(kVoxelizeModeNames, parseVoxelizeMode);
    expectOneNamePerValue<Fill>(kFillNames, parseFill);
    expectOneNamePerValue<Axis>(kAxisNames, parseAxis);
    expectOneNamePerValue<Slicing>(kSlicingNames, parseSlicing);
    expectOneNamePerValue<Device>(kDeviceNames, parseDevice);
    expectOneNamePerValue<Coverage>(kCoverageNames, parseCoverage);
    expectOneNamePerValue<DsmStorage>(kDsmStorageNames, parseDsmStorage);
    expectOneNamePerValue<DsmFilter>(kDsmFilterNames, parseDsmFilter);
    expectOneNamePerValue<MorphOp>(kMorphOpNames, parseMorphOp);
    expectOneNamePerValue<MorphBorder>(kMorphBorderNames, parseMorphBorder);
    expectOneNamePerValue<CsgOp>(kCsgOpNames, parseCsgOp);
    expectOneNamePerValue<ContainsMethod>(kContainsMethodNames, parseContainsMethod);
    expectOneNamePerValue<SignMethod>(kSignMethodNames, parseSignMethod);
    expectOneNamePerValue<SurfaceSource>(kSurfaceSourceNames, parseSurfaceSource);
    expectOneNamePerValue<LightType>(
        kLightTypeNames, [](const std::string& n) { return detail::parseLightType(n, "scene.json"); });
    expectOneNamePerValue<GridFormat>(kGridFormatNames);
    expectOneNamePerValue<SdfFormat>(kSdfFormatNames);
    expectOneNamePerValue<AttributeChannel>(kAttributeChannelNames);
    expectOneNamePerValue<AntiAliasing>(kAntiAliasingNames);
    expectOneNamePerValue<ToneMap>(kToneMapNames);
    expectOneNamePerValue<SkyKind>(kSkyKindNames);
    expectOneNamePerValue<VolumeShading>(kVolumeShadingNames);
    expectOneNamePerValue<Occlusion>(kOcclusionNames);
    expectOneNamePerValue<VolumeFormat>(kVolumeFormatNames);
    expectOneNamePerValue<ScalarType>(kScalarTypeNames);
    expectOneNamePerValue<BatchStatus>(kBatchStatusNames);
    expectOneNamePerValue<ShapeOp>(kShapeOpNames);
    expectOneNamePerValue<ObjectKind>(kObjectKindNames);
}

// The probe itself: it must tell named values from the others, or the test above proves nothing.
enum class ProbeEnum : uint8_t { A, B, C = 7 };
TEST(EnumNamesTest, TheEnumeratorProbeFindsExactlyTheNamedValues) {
    EXPECT_EQ(enumeratorsOf<ProbeEnum>(), (std::vector<ProbeEnum>{ProbeEnum::A, ProbeEnum::B, ProbeEnum::C}));
}

// And the check must fail on each kind of broken table: a value without a name, a name given
// twice, a name that does not parse back.
enum class MissingName : uint8_t { A, B, C };
constexpr EnumName<MissingName> kMissingNames[] = {{"a", MissingName::A}, {"b", MissingName::B}};
const char* toString(MissingName v) { return enumName(v, kMissingNames); }
enum class TwiceNamed : uint8_t { A, B };
constexpr EnumName<TwiceNamed> kTwiceNames[] = {
    {"a", TwiceNamed::A}, {"b", TwiceNamed::B}, {"A", TwiceNamed::B, true}};
const char* toString(TwiceNamed v) { return enumName(v, kTwiceNames); }
enum class NotParsedBack : uint8_t { A, B };
constexpr EnumName<NotParsedBack> kNotParsedNames[] = {{"a", NotParsedBack::A}, {"b", NotParsedBack::B}};
const char* toString(NotParsedBack v) { return enumName(v, kNotParsedNames); }

// The failures `check` reports, caught instead of failing this test.
template <class Check> std::string failuresOf(Check check) {
    ::testing::TestPartResultArray results;
    {
        ::testing::ScopedFakeTestPartResultReporter reporter(
            ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
        check();
    }
    std::string messages;
    for (int i = 0; i < results.size(); ++i)
        messages += results.GetTestPartResult(i).message() + std::string("\n");
    return messages;
}

TEST(EnumNamesTest, TheCheckFailsOnABrokenTable) {
    EXPECT_NE(failuresOf([] { expectOneNamePerValue<MissingName>(kMissingNames); }).find("value 2 of"),
              std::string::npos);
    EXPECT_NE(
        failuresOf([] { expectOneNamePerValue<TwiceNamed>(kTwiceNames); }).find("name 'A' is given twice"),
        std::string::npos);
    EXPECT_NE(failuresOf([] {
                  expectOneNamePerValue<NotParsedBack>(kNotParsedNames,
                                                       [](const std::string&) { return NotParsedBack::A; });
              }).find("parse(n.name)"),
              std::string::npos);
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
        EXPECT_STREQ(e.what(), "unknown fill '' (allowed: auto, parity, flood, vote, winding, gwn)");
    }
    try {
        glassOptionsNamed("opal");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "unknown glass method 'opal' (allowed: none, exact, multi, two-surface, frosted)");
    }
}

} // namespace
} // namespace voxfx
