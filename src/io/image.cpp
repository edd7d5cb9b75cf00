// voxfx — PNG (libpng), PFM and OpenEXR image files (OpenEXR through the voxfx_exr module).
#include "voxfx/image.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>

#include <png.h>

#include "core/atomic_file.hpp"
#include "io/module_api.hpp"
#include "voxfx/error.hpp"

namespace voxfx {

float linearToSrgb(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

float srgbToLinear(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

namespace {
void pngWrite(png_structp png, png_bytep data, png_size_t length) {
    auto* out = static_cast<std::ostream*>(png_get_io_ptr(png));
    out->write(reinterpret_cast<const char*>(data), std::streamsize(length));
}
void pngFlush(png_structp) {}
[[noreturn]] void pngError(png_structp png, png_const_charp message) {
    // libpng requires the error callback not to return: unwind through the C frames via longjmp.
    auto* text = static_cast<std::string*>(png_get_error_ptr(png));
    *text = message;
    png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}
} // namespace

void writePng(const Image& image, const std::string& path) {
    if (image.width <= 0 || image.height <= 0) fail("cannot write an empty image to '", path, "'");
    std::vector<unsigned char> rgb(size_t(image.width * image.height * 3));
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            rgb[3 * i + size_t(c)] =
                static_cast<unsigned char>(std::lround(linearToSrgb(image.pixels[i][c]) * 255.0f));
    detail::AtomicFile file(path);
    std::ostream& out = file.stream();
    std::string error;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, pngError, pngWarning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) fail("cannot write '", path, "': libpng could not start");
    std::vector<png_bytep> rows(size_t(image.height));
    for (int64_t y = 0; y < image.height; ++y) rows[size_t(y)] = rgb.data() + y * image.width * 3;
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        fail("cannot write '", path, "': ", error);
    }
    png_set_write_fn(png, &out, pngWrite, pngFlush);
    png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    png_write_image(png, rows.data());
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    file.commit();
}

Image readPng(const std::string& path) {
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
    if (!f) fail("cannot open image '", path, "'");
    unsigned char sig[8] = {};
    if (std::fread(sig, 1, 8, f.get()) != 8 || png_sig_cmp(sig, 0, 8)) fail("'", path, "' is not a PNG file");
    std::string error;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, pngError, pngWarning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) fail("cannot read '", path, "': libpng could not start");
    Image image;
    std::vector<unsigned char> data;
    std::vector<png_bytep> rows;
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        fail("cannot read '", path, "': ", error);
    }
    png_init_io(png, f.get());
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    png_set_strip_16(png);
    png_set_strip_alpha(png);
    png_set_palette_to_rgb(png);
    png_set_gray_to_rgb(png);
    png_set_expand_gray_1_2_4_to_8(png);
    png_read_update_info(png, info);
    const auto w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    data.resize(size_t(w) * h * 3);
    rows.resize(h);
    for (png_uint_32 y = 0; y < h; ++y) rows[y] = data.data() + size_t(y) * w * 3;
    png_read_image(png, rows.data());
    png_destroy_read_struct(&png, &info, nullptr);
    image = Image(w, h);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            image.pixels[i][c] = srgbToLinear(float(data[3 * i + size_t(c)]) / 255.0f);
    return image;
}

void writePfm(const Image& image, const std::string& path) {
    if (image.width <= 0 || image.height <= 0) fail("cannot write an empty image to '", path, "'");
    detail::AtomicFile file(path);
    std::ostream& out = file.stream();
    out << "PF\n" << image.width << " " << image.height << "\n-1.0\n";
    // PFM rows run bottom to top.
    for (int64_t y = image.height - 1; y >= 0; --y)
        out.write(reinterpret_cast<const char*>(&image.pixels[size_t(y * image.width)]),
                  std::streamsize(image.width * 3 * sizeof(float)));
    file.commit();
}

void writeExr(const Image& image, const std::string& path) {
    if (image.width <= 0 || image.height <= 0) fail("cannot write an empty image to '", path, "'");
    if (image.width > std::numeric_limits<int>::max() || image.height > std::numeric_limits<int>::max())
        fail("cannot write '", path, "': ", image.width, " x ", image.height, " is too large for OpenEXR");
    const detail::ExrModule& exr = detail::exrModule();
    std::vector<float> rgb(3 * image.pixels.size());
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) rgb[3 * i + size_t(c)] = image.pixels[i][c];
    // OpenEXR opens files by name and seeks back to write its offset table: write the temporary
    // file by name, then let AtomicFile rename it.
    detail::AtomicFile file(path);
    std::string error;
    if (!exr.writeRgb(file.tempPath().c_str(), int(image.width), int(image.height), rgb.data(), &error))
        fail("cannot write '", path, "': ", error);
    file.commit();
}

} // namespace voxfx
