// voxfx_exr — the OpenEXR module: half-float RGB images (see io/module_api.hpp, io/image.cpp).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <vector>

#include <OpenEXR/ImfRgbaFile.h>

#include "io/module_api.hpp"

namespace voxfx::detail {

namespace {

bool writeRgb(const char* path, int width, int height, const float* rgb, std::string* error) {
    try {
        // Half floats: the largest finite value is 65504; clamp finite values so that they stay finite.
        auto toHalf = [](float v) { return half(std::isfinite(v) ? std::clamp(v, -65504.0f, 65504.0f) : v); };
        const size_t n = size_t(width) * size_t(height);
        std::vector<Imf::Rgba> pixels(n);
        for (size_t i = 0; i < n; ++i)
            pixels[i] =
                Imf::Rgba(toHalf(rgb[3 * i]), toHalf(rgb[3 * i + 1]), toHalf(rgb[3 * i + 2]), half(1.0f));
        Imf::RgbaOutputFile out(path, width, height, Imf::WRITE_RGB, 1.0f, Imath::V2f(0, 0), 1.0f,
                                Imf::INCREASING_Y, Imf::ZIP_COMPRESSION, 1);
        // Row 0 is the top row in both Image and OpenEXR's default data window.
        out.setFrameBuffer(pixels.data(), 1, size_t(width));
        out.writePixels(height);
        return true;
    } catch (const std::exception& e) { *error = e.what(); } catch (...) {
        *error = "unknown error in the OpenEXR module";
    }
    return false;
}

bool readRgb(const char* path, int* width, int* height, std::vector<float>* rgb, std::string* error) {
    try {
        // RgbaInputFile converts whatever the file holds (RGB, RGBA, luminance/chroma, Y only).
        Imf::RgbaInputFile in(path);
        const Imath::Box2i dw = in.dataWindow();
        const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
        if (w <= 0 || h <= 0) {
            *error = "empty data window";
            return false;
        }
        std::vector<Imf::Rgba> pixels(size_t(w) * size_t(h));
        // The frame buffer is addressed with the data window's origin.
        in.setFrameBuffer(pixels.data() - dw.min.x - ptrdiff_t(dw.min.y) * w, 1, size_t(w));
        in.readPixels(dw.min.y, dw.max.y);
        rgb->resize(3 * pixels.size());
        for (size_t i = 0; i < pixels.size(); ++i) {
            (*rgb)[3 * i] = float(pixels[i].r);
            (*rgb)[3 * i + 1] = float(pixels[i].g);
            (*rgb)[3 * i + 2] = float(pixels[i].b);
        }
        *width = w;
        *height = h;
        return true;
    } catch (const std::exception& e) { *error = e.what(); } catch (...) {
        *error = "unknown error in the OpenEXR module";
    }
    return false;
}

constexpr ExrModule kTable{kModuleAbi, sizeof(ExrModule), writeRgb, readRgb};

} // namespace
} // namespace voxfx::detail

extern "C" const void* voxfx_module_exr(uint32_t abi) {
    return abi == voxfx::detail::kModuleAbi ? &voxfx::detail::kTable : nullptr;
}
