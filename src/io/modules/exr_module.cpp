// voxfx_exr — the OpenEXR module: half-float RGB images (see io/module_api.hpp, io/image.cpp).
#include <algorithm>
#include <cmath>
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

constexpr ExrModule kTable{kModuleAbi, sizeof(ExrModule), writeRgb};

} // namespace
} // namespace voxfx::detail

extern "C" const void* voxfx_module_exr(uint32_t abi) {
    return abi == voxfx::detail::kModuleAbi ? &voxfx::detail::kTable : nullptr;
}
