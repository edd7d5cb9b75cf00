// voxfx — the sRGB curve of images (IEC 61966-2-1).
#include "voxfx/image.hpp"

#include <algorithm>
#include <cmath>

namespace voxfx {

float linearToSrgb(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

std::vector<uint8_t> toSrgb8(const Image& image) {
    std::vector<uint8_t> out(image.pixels.size() * 3);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            out[3 * i + size_t(c)] =
                static_cast<uint8_t>(std::lround(linearToSrgb(image.pixels[i][c]) * 255.0f));
    return out;
}

float srgbToLinear(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

} // namespace voxfx
