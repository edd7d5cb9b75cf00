// voxfx — image files: PNG (libpng, sRGB-encoded 8 bit), PFM and OpenEXR (linear HDR; OpenEXR
// through the voxfx_exr module) and Radiance HDR, read and written as voxfx::Image.
// Thread-safety: functions on different paths may run concurrently; none uses threads.
#pragma once

#include <cstdint>
#include <string>

#include "voxfx/image.hpp"
#include "voxfx/math.hpp"

namespace voxfx {

/// Writes an 8-bit sRGB PNG (gamma-correct: linear values are encoded with the sRGB curve and
/// the file carries an sRGB chunk). Atomic: temporary file, then rename. Throws voxfx::Error.
void writePng(const Image& image, const std::string& path);
/// Reads an 8/16-bit PNG (gray, RGB, RGBA; alpha ignored) into linear RGB. The stored values are
/// taken as sRGB-encoded (what writePng writes); gAMA and iCCP chunks are not applied.
Image readPng(const std::string& path);
/// Writes a little-endian PFM (portable float map): linear HDR values, opens in most HDR tools.
void writePfm(const Image& image, const std::string& path);
/// Writes an OpenEXR file: linear HDR values as half-float R, G, B channels (no alpha), ZIP
/// compression, no sRGB curve. Finite values beyond the half range (|v| > 65504) are clamped to
/// it; NaN and infinities are kept. Atomic: temporary file, then rename. Throws voxfx::Error
/// naming the path.
void writeExr(const Image& image, const std::string& path);

/// Reads a PFM (colour "PF" or grey "Pf", either byte order; rows bottom to top in the file).
Image readPfm(const std::string& path);
/// Reads a Radiance .hdr (RGBE, "FORMAT=32-bit_rle_rgbe", orientation "-Y H +X W"), flat or with
/// the new run-length encoding per scanline. XYZE files and other orientations are refused.
Image readHdr(const std::string& path);
/// Reads an OpenEXR file's R, G, B channels (missing ones read as 0; Y-only files as grey) as
/// linear floats, through the exr module.
Image readExr(const std::string& path);
/// Reads .png, .pfm, .hdr or .exr by extension; throws voxfx::Error listing them otherwise.
Image readImage(const std::string& path);
/// One Radiance RGBE pixel as linear RGB, the way Radiance's colr_color decodes it:
/// e == 0 gives black, otherwise channel c = (byte_c + 0.5) * 2^(e - 136).
Vec3f decodeRgbe(uint8_t r, uint8_t g, uint8_t b, uint8_t e);

} // namespace voxfx
