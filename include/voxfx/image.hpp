// voxfx — images: a linear float RGB image, the value every renderer writes into, and the sRGB
// curve. Its files (PNG, PFM, OpenEXR, Radiance HDR) are read and written by voxfx/image_io.hpp.
// Thread-safety: an Image is a value: concurrent reads are fine, a write needs exclusive access.
#pragma once

#include <cstdint>
#include <vector>

#include "voxfx/math.hpp"

namespace voxfx {

/// Linear-light RGB pixels, row-major with row 0 at the top (image convention).
struct Image {
    int64_t width = 0, height = 0;
    std::vector<Vec3f> pixels;

    Image() = default;
    Image(int64_t w, int64_t h, Vec3f fill = {0, 0, 0}) : width(w), height(h), pixels(size_t(w * h), fill) {}
    Vec3f& at(int64_t x, int64_t y) { return pixels[size_t(y * width + x)]; }
    const Vec3f& at(int64_t x, int64_t y) const { return pixels[size_t(y * width + x)]; }
};

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1] (clamped).
float linearToSrgb(float v);
float srgbToLinear(float v);

/// The image as 8-bit sRGB, three bytes (R, G, B) per pixel in row order: each channel
/// lround(linearToSrgb(v) * 255), what writePng stores and what a viewer shows.
std::vector<uint8_t> toSrgb8(const Image& image);

} // namespace voxfx
