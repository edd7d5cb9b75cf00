// Tests of src/io/image.cpp: PNG round trips with the sRGB curve, PFM layout, errors.
#include <fstream>

#include <gtest/gtest.h>

#include "test_util.hpp"
#include "voxfx/image.hpp"

namespace voxfx {
namespace {

TEST(ImageTest, SrgbCurveMatchesTheStandardAtKnownPoints) {
    // IEC 61966-2-1: linear 0.5 encodes to 0.7354, 0.0031308 is the linear-segment knee.
    EXPECT_NEAR(linearToSrgb(0.5f), 0.7354f, 1e-4f);
    EXPECT_NEAR(linearToSrgb(0.0031308f), 0.0404500f, 1e-6f);
    EXPECT_FLOAT_EQ(linearToSrgb(2.0f), 1.0f);
    for (float v = 0; v <= 1.0f; v += 0.01f) EXPECT_NEAR(srgbToLinear(linearToSrgb(v)), v, 1e-5f);
}

TEST(ImageTest, PngRoundTripKeepsEveryPixelWithinOneCodeValue) {
    test::TempDir dir;
    Image img(37, 23);
    for (int64_t y = 0; y < img.height; ++y)
        for (int64_t x = 0; x < img.width; ++x) img.at(x, y) = {float(x) / 36.0f, float(y) / 22.0f, 0.25f};
    writePng(img, dir.file("a.png"));
    const Image back = readPng(dir.file("a.png"));
    ASSERT_EQ(back.width, 37);
    ASSERT_EQ(back.height, 23);
    for (int64_t y = 0; y < img.height; ++y)
        for (int64_t x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(linearToSrgb(back.at(x, y)[c]), linearToSrgb(img.at(x, y)[c]),
                            0.5f / 255.0f + 1e-6f);
}

TEST(ImageTest, PfmStoresRowsBottomUpAsLittleEndianFloats) {
    test::TempDir dir;
    Image img(2, 2);
    img.at(0, 0) = {1, 2, 3}; // top-left
    img.at(1, 1) = {7, 8, 9}; // bottom-right
    writePfm(img, dir.file("a.pfm"));
    std::ifstream in(dir.file("a.pfm"), std::ios::binary);
    std::string magic, scale;
    int w = 0, h = 0;
    in >> magic >> w >> h >> scale;
    in.get();
    float px[12];
    in.read(reinterpret_cast<char*>(px), sizeof px);
    EXPECT_EQ(magic, "PF");
    EXPECT_EQ(scale, "-1.0");
    // First stored row is the bottom one: (0,1) then (1,1).
    EXPECT_EQ(px[3], 7.0f);
    EXPECT_EQ(px[5], 9.0f);
    EXPECT_EQ(px[6], 1.0f); // second stored row starts with the top-left pixel
}

TEST(ImageTest, BadFilesRaiseErrorsNamingThePath) {
    test::TempDir dir;
    EXPECT_THROW(readPng(dir.file("missing.png")), Error);
    test::writeFile(dir.file("fake.png"), "definitely not a png");
    try {
        readPng(dir.file("fake.png"));
        FAIL();
    } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("fake.png"), std::string::npos); }
    EXPECT_THROW(writePng(Image(2, 2), dir.file("no/such/dir/x.png")), Error);
}

} // namespace
} // namespace voxfx
