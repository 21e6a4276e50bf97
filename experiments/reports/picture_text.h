// Text, legends and banners on RGB pictures (bev.png, model pictures): glyphs rasterised by
// stb_truetype (libstb) from Debian's DejaVu Sans (fonts-dejavu-core), read at run time like the
// page's three.js. Without the font file the swatches, boxes and bars are still drawn, the words
// are not (the picture says less but stays correct).
#pragma once

#include "experiments/reports/model_picture.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// Where the pictures' font is read from (fonts-dejavu-core).
inline constexpr const char* kPictureFontFile = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// An RGB colour, 0..255 per channel.
using PictureColor = std::array<std::uint8_t, 3>;

/// A rectangle of pixels, corners included.
struct PictureBox {
  int x0 = 0;  ///< left column
  int y0 = 0;  ///< top row
  int x1 = 0;  ///< right column
  int y1 = 0;  ///< bottom row
};

/// One line of a legend: a swatch of `color` (a cross instead when `cross`) and its label.
struct LegendEntry {
  PictureColor color{0, 0, 0};  ///< swatch colour
  std::string label;            ///< what the colour shows
  bool cross = false;           ///< draw a "+" (a marked position) instead of a filled square
};

/// Whether the font could be read (text is drawn only then).
bool picture_font_available();

/// Width in pixels of `text` at `pixel_height` (0 without the font).
int picture_text_width(const std::string& text, double pixel_height);

/// Draws `text` (ASCII; other bytes drawn as '?') with its top-left at (x, y), `pixel_height` high,
/// blended onto the image by glyph coverage; returns the x after the text.
int draw_picture_text(RgbImage& image, int x, int y, const std::string& text, double pixel_height, PictureColor color);

/// Fills a rectangle (clipped to the image).
void fill_picture_box(RgbImage& image, const PictureBox& box, PictureColor color);

/// Draws a "+" of half length `arm` and thickness `width` centred at (x, y).
void draw_picture_cross(RgbImage& image, int x, int y, int arm, int width, PictureColor color);

/// A legend in a white box with a dark frame, its top-left corner at (x, y): optional `title` line
/// then one row per entry (swatch or cross, then label). Returns the box drawn.
PictureBox draw_picture_legend(RgbImage& image, int x, int y, const std::string& title,
                               const std::vector<LegendEntry>& entries, double pixel_height);

/// A banner along the top of the picture: `text` on `background`, full width. Returns its box.
PictureBox draw_picture_banner(RgbImage& image, const std::string& text, PictureColor background, double pixel_height);

}  // namespace quadrix
