// voxfx — PNG (libpng), PFM, Radiance HDR and OpenEXR image files (OpenEXR through the voxfx_exr
// module).
#include "voxfx/image_io.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <memory>

#include <png.h>

#include "core/atomic_file.hpp"
#include "io/module_api.hpp"
#include "voxfx/error.hpp"
#include "voxfx/file_name.hpp"

namespace voxfx {

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
    std::vector<uint8_t> rgb = toSrgb8(image);
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

Image readExr(const std::string& path) {
    const detail::ExrModule& exr = detail::exrModule();
    int w = 0, h = 0;
    std::vector<float> rgb;
    std::string error;
    if (!exr.readRgb(path.c_str(), &w, &h, &rgb, &error)) fail("cannot read '", path, "': ", error);
    Image image(w, h);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        image.pixels[i] = {rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]};
    return image;
}

namespace {
// One whitespace-delimited token of a PFM header.
std::string imagePfmToken(std::istream& in) {
    std::string t;
    in >> t;
    return t;
}
} // namespace

Image readPfm(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail("cannot open image '", path, "'");
    const std::string magic = imagePfmToken(in);
    if (magic != "PF" && magic != "Pf") fail("'", path, "' is not a PFM file");
    const int channels = magic == "PF" ? 3 : 1;
    int64_t w = 0, h = 0;
    double scale = 0;
    try {
        w = std::stoll(imagePfmToken(in));
        h = std::stoll(imagePfmToken(in));
        scale = std::stod(imagePfmToken(in));
    } catch (const std::exception&) { fail("'", path, "': malformed PFM header"); }
    if (w <= 0 || h <= 0 || w > (1 << 20) || h > (1 << 20) || scale == 0)
        fail("'", path, "': malformed PFM header");
    in.get(); // the single whitespace byte after the scale
    const bool little = scale < 0;
    std::vector<float> data(size_t(w * h * channels));
    in.read(reinterpret_cast<char*>(data.data()), std::streamsize(data.size() * sizeof(float)));
    if (!in) fail("'", path, "': truncated PFM data");
    const bool hostLittle = std::endian::native == std::endian::little;
    if (little != hostLittle)
        for (float& f : data) {
            uint32_t u;
            std::memcpy(&u, &f, 4);
            u = __builtin_bswap32(u);
            std::memcpy(&f, &u, 4);
        }
    Image image(w, h);
    for (int64_t y = 0; y < h; ++y) // PFM rows run bottom to top
        for (int64_t x = 0; x < w; ++x) {
            const float* p = data.data() + ((h - 1 - y) * w + x) * channels;
            image.at(x, y) = channels == 3 ? Vec3f{p[0], p[1], p[2]} : Vec3f{p[0], p[0], p[0]};
        }
    return image;
}

Vec3f decodeRgbe(uint8_t r, uint8_t g, uint8_t b, uint8_t e) {
    if (e == 0) return {0, 0, 0};
    const float f = std::ldexp(1.0f, int(e) - (128 + 8));
    return {(float(r) + 0.5f) * f, (float(g) + 0.5f) * f, (float(b) + 0.5f) * f};
}

Image readHdr(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail("cannot open image '", path, "'");
    std::string line;
    std::getline(in, line);
    if (line.rfind("#?", 0) != 0) fail("'", path, "' is not a Radiance HDR file");
    bool rgbe = true;
    while (std::getline(in, line) && !line.empty())
        if (line.rfind("FORMAT=", 0) == 0) rgbe = line == "FORMAT=32-bit_rle_rgbe";
    if (!rgbe) fail("'", path, "': only FORMAT=32-bit_rle_rgbe is supported");
    std::getline(in, line);
    char ya[3] = {}, xa[3] = {};
    long long h = 0, w = 0;
    if (std::sscanf(line.c_str(), "%2s %lld %2s %lld", ya, &h, xa, &w) != 4 || std::string(ya) != "-Y" ||
        std::string(xa) != "+X" || w <= 0 || h <= 0 || w > (1 << 20) || h > (1 << 20))
        fail("'", path, "': unsupported resolution line '", line, "' (expected -Y H +X W)");
    Image image(w, h);
    std::vector<uint8_t> scan(size_t(w) * 4);
    auto truncated = [&] { fail("'", path, "': truncated HDR data"); };
    for (int64_t y = 0; y < h; ++y) {
        uint8_t head[4];
        if (!in.read(reinterpret_cast<char*>(head), 4)) truncated();
        const bool rle = w >= 8 && w < 32768 && head[0] == 2 && head[1] == 2 && (head[2] & 0x80) == 0;
        if (rle) {
            if ((int64_t(head[2]) << 8 | head[3]) != w) fail("'", path, "': scanline width mismatch");
            for (int c = 0; c < 4; ++c)
                for (int64_t x = 0; x < w;) {
                    const int n0 = in.get();
                    if (n0 == EOF) truncated();
                    if (n0 > 128) { // a run
                        const int64_t n = n0 - 128;
                        const int v = in.get();
                        if (v == EOF || x + n > w) truncated();
                        for (int64_t k = 0; k < n; ++k) scan[size_t((x + k) * 4 + c)] = uint8_t(v);
                        x += n;
                    } else { // literal bytes
                        const int64_t n = n0;
                        if (n == 0 || x + n > w) fail("'", path, "': bad run length");
                        for (int64_t k = 0; k < n; ++k) {
                            const int v = in.get();
                            if (v == EOF) truncated();
                            scan[size_t((x + k) * 4 + c)] = uint8_t(v);
                        }
                        x += n;
                    }
                }
        } else { // flat pixels
            std::memcpy(scan.data(), head, 4);
            if (w > 1 && !in.read(reinterpret_cast<char*>(scan.data() + 4), std::streamsize((w - 1) * 4)))
                truncated();
        }
        for (int64_t x = 0; x < w; ++x) {
            const uint8_t* p = scan.data() + x * 4;
            image.at(x, y) = decodeRgbe(p[0], p[1], p[2], p[3]);
        }
    }
    return image;
}

Image readImage(const std::string& path) {
    const std::string ext = fileExtension(path);
    if (ext == ".png") return readPng(path);
    if (ext == ".pfm") return readPfm(path);
    if (ext == ".hdr") return readHdr(path);
    if (ext == ".exr") return readExr(path);
    fail(path, ": unknown image extension (allowed: .png, .pfm, .hdr, .exr)");
}

} // namespace voxfx
