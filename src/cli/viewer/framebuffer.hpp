// voxfx view — the software framebuffer the window shows (internal to cli/): 32-bit pixels
// 0xAARRGGBB (SDL's ARGB8888), the rendered frame scaled into it, and text over it in a built-in
// 5x8 bitmap font (no font library needed).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace voxfx::cli::viewer {

/// A glyph cell at scale 1: 5 pixels and a gap across, 8 pixels (a descender's row included) and a
/// gap of 2 down.
inline constexpr int kGlyphAdvance = 6;
inline constexpr int kLineHeight = 10;

struct Framebuffer {
    int width = 0, height = 0;
    std::vector<uint32_t> pixels; ///< row-major, row 0 on top, 0xAARRGGBB
    Framebuffer() = default;
    Framebuffer(int w, int h);
};

struct Rect {
    int x = 0, y = 0, w = 0, h = 0;
};

/// The 8-bit RGB image (w x h, row 0 on top) scaled to the whole framebuffer by nearest pixel: the
/// same pixels when the sizes agree, blocks of pixels for a preview of lower resolution.
void blitRgb(Framebuffer& fb, const uint8_t* rgb, int w, int h);
/// Multiplies the pixels of the rectangle (clipped) by `keep` (a translucent dark panel).
void darkenRect(Framebuffer& fb, int x, int y, int w, int h, float keep);
/// Pixels `text` takes across at `scale`.
int textWidth(std::string_view text, int scale);
/// Draws `text` (printable ASCII; anything else as '?') with its top-left corner at (x, y), clipped.
void drawText(Framebuffer& fb, int x, int y, std::string_view text, uint32_t rgb, int scale);
/// `text` broken into lines of at most `maxChars` characters after a `separator` (", " keeps a
/// "name value" pair together); an item longer than a line is broken at spaces, a word longer than
/// a line stays whole.
std::vector<std::string> wrapWords(const std::string& text, int maxChars,
                                   const std::string& separator = ", ");
/// White lines of text on a darkened box whose top-left corner is (x, y); returns the box.
Rect drawPanel(Framebuffer& fb, int x, int y, const std::vector<std::string>& lines, int scale);

} // namespace voxfx::cli::viewer
