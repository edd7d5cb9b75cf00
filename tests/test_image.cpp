// Tests of src/io/image.cpp: PNG written and read against plain libpng with the sRGB curve, PFM
// layout, EXR read back with plain OpenEXR, errors.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>
#include <png.h>

#include "test_util.hpp"
#include "voxfx/image_io.hpp"

namespace voxfx {
namespace {

TEST(ImageTest, SrgbCurveMatchesTheStandardAtKnownPoints) {
    // IEC 61966-2-1: linear 0.5 encodes to 0.7354, 0.0031308 is the linear-segment knee.
    EXPECT_NEAR(linearToSrgb(0.5f), 0.7354f, 1e-4f);
    EXPECT_NEAR(linearToSrgb(0.0031308f), 0.0404500f, 1e-6f);
    EXPECT_FLOAT_EQ(linearToSrgb(2.0f), 1.0f);
    for (float v = 0; v <= 1.0f; v += 0.01f) EXPECT_NEAR(srgbToLinear(linearToSrgb(v)), v, 1e-5f);
}

// The sRGB curve of IEC 61966-2-1, written out here (not voxfx's linearToSrgb / srgbToLinear).
double srgbEncode(double v) {
    v = std::clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}
double srgbDecode(double e) { return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4); }

TEST(ImageTest, PngReadsBackWithPlainLibpngAsSrgbCodeValues) {
    test::TempDir dir;
    Image img(37, 23);
    for (int64_t y = 0; y < img.height; ++y)
        for (int64_t x = 0; x < img.width; ++x) img.at(x, y) = {float(x) / 36.0f, float(y) / 22.0f, 0.25f};
    img.at(0, 0) = {-1.0f, 2.0f, 0.001f}; // clamped, clamped, on the linear segment
    writePng(img, dir.file("a.png"));
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    ASSERT_NE(png_image_begin_read_from_file(&png, dir.file("a.png").c_str()), 0) << png.message;
    EXPECT_EQ(png.width, 37u);
    EXPECT_EQ(png.height, 23u);
    EXPECT_EQ(png.flags & PNG_IMAGE_FLAG_COLORSPACE_NOT_sRGB, 0u) << "the file must say it is sRGB";
    png.format = PNG_FORMAT_RGB;
    std::vector<uint8_t> codes(PNG_IMAGE_SIZE(png));
    ASSERT_NE(png_image_finish_read(&png, nullptr, codes.data(), 0, nullptr), 0) << png.message;
    ASSERT_EQ(codes.size(), size_t(37 * 23 * 3));
    int64_t wrong = 0;
    for (int64_t y = 0; y < img.height; ++y)
        for (int64_t x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const double want = 255 * srgbEncode(img.at(x, y)[c]);
                const double got = codes[size_t((y * 37 + x) * 3 + c)];
                wrong += std::abs(got - want) > 0.5 + 1e-3; // rounded to the nearest code value
            }
    EXPECT_EQ(wrong, 0);
}

TEST(ImageTest, ReadPngDecodesAPlainLibpngFileToLinearValues) {
    test::TempDir dir;
    const int w = 16, h = 9;
    std::vector<uint8_t> codes(size_t(w * h * 3));
    for (size_t i = 0; i < codes.size(); ++i) codes[i] = uint8_t((i * 37) % 256);
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    png.width = w;
    png.height = h;
    png.format = PNG_FORMAT_RGB;
    const std::string path = dir.file("libpng.png");
    ASSERT_NE(png_image_write_to_file(&png, path.c_str(), 0, codes.data(), 0, nullptr), 0) << png.message;
    const Image back = readPng(path);
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    int64_t wrong = 0;
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                wrong += std::abs(back.at(x, y)[c] - srgbDecode(codes[size_t((y * w + x) * 3 + c)] / 255.0)) >
                         1e-6;
    EXPECT_EQ(wrong, 0);
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

// Reads R, G, B of an EXR file as 32-bit floats with OpenEXR's general InputFile interface (not
// the Rgba interface the writer uses), row 0 at the top of the data window.
Image readExrWithOpenExr(const std::string& path, Imf::PixelType* storedType) {
    Imf::InputFile in(path.c_str());
    const Imath::Box2i dw = in.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    const Imf::ChannelList& channels = in.header().channels();
    for (const char* name : {"R", "G", "B"}) {
        const Imf::Channel* c = channels.findChannel(name);
        EXPECT_NE(c, nullptr) << name;
        if (c && storedType) *storedType = c->type;
    }
    EXPECT_EQ(channels.findChannel("A"), nullptr);
    Image img(w, h);
    std::vector<float> plane[3];
    Imf::FrameBuffer fb;
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        plane[c].resize(size_t(w) * size_t(h));
        // Base pointer shifted so that the data window's (min.x, min.y) lands on element 0.
        char* base = reinterpret_cast<char*>(plane[c].data() - dw.min.x - ptrdiff_t(dw.min.y) * w);
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * size_t(w)));
    }
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = {plane[0][i], plane[1][i], plane[2][i]};
    return img;
}

TEST(ImageTest, ExrKeepsHdrValuesWithinHalfPrecision) {
    test::TempDir dir;
    Image img(19, 11);
    // Values well above 1 (what PNG would clip), tiny ones, zero, and distinct per pixel and channel
    // so that a flipped or transposed image fails.
    for (int64_t y = 0; y < img.height; ++y)
        for (int64_t x = 0; x < img.width; ++x)
            img.at(x, y) = {0.001f * float(x + 1), 3.5f * float(y) + 0.25f, float(x * y) * 17.0f + 1e-3f};
    img.at(0, 0) = {1000.0f, 0.0f, 42.125f};
    img.at(18, 10) = {1e6f, -2.0f, 0.5f}; // beyond the half range: clamped to 65504
    writeExr(img, dir.file("hdr.exr"));
    Imf::PixelType stored = Imf::FLOAT;
    const Image back = readExrWithOpenExr(dir.file("hdr.exr"), &stored);
    EXPECT_EQ(stored, Imf::HALF);
    ASSERT_EQ(back.width, img.width);
    ASSERT_EQ(back.height, img.height);
    float maxSeen = 0;
    for (int64_t y = 0; y < img.height; ++y)
        for (int64_t x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const float want = std::min(img.at(x, y)[c], 65504.0f), got = back.at(x, y)[c];
                maxSeen = std::max(maxSeen, got);
                // Half floats: 11 significant bits (relative error <= 2^-11), subnormals below 2^-14.
                EXPECT_NEAR(got, want, std::abs(want) * std::ldexp(1.0f, -11) + std::ldexp(1.0f, -24))
                    << x << ", " << y << " channel " << c;
            }
    EXPECT_GT(maxSeen, 1.0f); // the file really holds HDR values
    EXPECT_EQ(back.at(18, 10).x, 65504.0f);
}

TEST(ImageTest, ExrToABadPathThrowsNamingItAndLeavesNoFile) {
    test::TempDir dir;
    const std::string bad = dir.file("no/such/dir/x.exr");
    try {
        writeExr(Image(2, 2, {2, 2, 2}), bad);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("x.exr"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(bad));
    EXPECT_THROW(writeExr(Image(), dir.file("empty.exr")), Error);
    // A directory in the way: error, and nothing (not even a temporary) left behind.
    std::filesystem::create_directory(dir.file("taken.exr"));
    EXPECT_THROW(writeExr(Image(2, 2), dir.file("taken.exr")), Error);
    int entries = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.file(""))) {
        ++entries;
        EXPECT_EQ(e.path().filename(), "taken.exr");
    }
    EXPECT_EQ(entries, 1);
}

} // namespace
} // namespace voxfx
