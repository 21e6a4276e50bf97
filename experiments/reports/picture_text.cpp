// Text, legends and banners on RGB pictures (see picture_text.h).
#include "experiments/reports/picture_text.h"

// The one translation unit holding stb's TrueType rasteriser.
#define STB_TRUETYPE_IMPLEMENTATION
#include <stb/stb_truetype.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <mutex>

namespace quadrix {
namespace {

// The font file and its stb handle, loaded once (empty when the file is missing or unreadable).
struct PictureFont {
  std::vector<unsigned char> bytes;
  stbtt_fontinfo info{};
  bool loaded = false;
};

const PictureFont& picture_font() {
  static PictureFont font;
  static std::once_flag once;
  std::call_once(once, [] {
    std::ifstream in(kPictureFontFile, std::ios::binary);
    if (!in) return;
    font.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    font.loaded = !font.bytes.empty() &&
                  stbtt_InitFont(&font.info, font.bytes.data(), stbtt_GetFontOffsetForIndex(font.bytes.data(), 0)) != 0;
  });
  return font;
}

int glyph_of(char c) { return (c >= 32 && c < 127) ? c : '?'; }

void blend(RgbImage& image, int x, int y, PictureColor color, double coverage) {
  if (x < 0 || y < 0 || x >= image.width || y >= image.height || coverage <= 0.0) return;
  std::uint8_t* pixel = &image.pixels[3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) + static_cast<std::size_t>(x))];
  for (int k = 0; k < 3; ++k)
    pixel[k] = static_cast<std::uint8_t>(std::lround(pixel[k] + std::min(1.0, coverage) * (color[static_cast<std::size_t>(k)] - pixel[k])));
}

}  // namespace

bool picture_font_available() { return picture_font().loaded; }

int picture_text_width(const std::string& text, double pixel_height) {
  const PictureFont& font = picture_font();
  if (!font.loaded) return 0;
  const float scale = stbtt_ScaleForPixelHeight(&font.info, static_cast<float>(pixel_height));
  double width = 0.0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    int advance = 0, bearing = 0;
    stbtt_GetCodepointHMetrics(&font.info, glyph_of(text[i]), &advance, &bearing);
    width += advance * scale;
    if (i + 1 < text.size()) width += scale * stbtt_GetCodepointKernAdvance(&font.info, glyph_of(text[i]), glyph_of(text[i + 1]));
  }
  return static_cast<int>(std::ceil(width));
}

int draw_picture_text(RgbImage& image, int x, int y, const std::string& text, double pixel_height, PictureColor color) {
  const PictureFont& font = picture_font();
  if (!font.loaded) return x;
  const float scale = stbtt_ScaleForPixelHeight(&font.info, static_cast<float>(pixel_height));
  int ascent = 0, descent = 0, gap = 0;
  stbtt_GetFontVMetrics(&font.info, &ascent, &descent, &gap);
  const int baseline = y + static_cast<int>(std::lround(ascent * scale));
  double pen = x;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const int codepoint = glyph_of(text[i]);
    int width = 0, height = 0, offset_x = 0, offset_y = 0;
    unsigned char* bitmap = stbtt_GetCodepointBitmap(&font.info, scale, scale, codepoint, &width, &height, &offset_x, &offset_y);
    const int left = static_cast<int>(std::lround(pen)) + offset_x;
    for (int row = 0; row < height; ++row)
      for (int column = 0; column < width; ++column)
        blend(image, left + column, baseline + offset_y + row, color, bitmap[row * width + column] / 255.0);
    stbtt_FreeBitmap(bitmap, nullptr);
    int advance = 0, bearing = 0;
    stbtt_GetCodepointHMetrics(&font.info, codepoint, &advance, &bearing);
    pen += advance * scale;
    if (i + 1 < text.size()) pen += scale * stbtt_GetCodepointKernAdvance(&font.info, codepoint, glyph_of(text[i + 1]));
  }
  return static_cast<int>(std::ceil(pen));
}

void fill_picture_box(RgbImage& image, const PictureBox& box, PictureColor color) {
  for (int y = std::max(0, box.y0); y <= std::min(image.height - 1, box.y1); ++y)
    for (int x = std::max(0, box.x0); x <= std::min(image.width - 1, box.x1); ++x) blend(image, x, y, color, 1.0);
}

void draw_picture_cross(RgbImage& image, int x, int y, int arm, int width, PictureColor color) {
  const int half = width / 2;
  fill_picture_box(image, {x - arm, y - half, x + arm, y - half + width - 1}, color);
  fill_picture_box(image, {x - half, y - arm, x - half + width - 1, y + arm}, color);
}

PictureBox draw_picture_legend(RgbImage& image, int x, int y, const std::string& title,
                               const std::vector<LegendEntry>& entries, double pixel_height) {
  const int line = static_cast<int>(std::lround(1.45 * pixel_height));
  const int pad = static_cast<int>(std::lround(0.6 * pixel_height));
  const int swatch = static_cast<int>(std::lround(0.9 * pixel_height));
  int text_width = picture_text_width(title, pixel_height);
  for (const LegendEntry& entry : entries)
    text_width = std::max(text_width, swatch + pad + picture_text_width(entry.label, pixel_height));
  text_width = std::max(text_width, swatch);
  const int rows = static_cast<int>(entries.size()) + (title.empty() ? 0 : 1);
  const PictureBox box{x, y, x + 2 * pad + text_width, y + 2 * pad + rows * line - (line - static_cast<int>(pixel_height))};
  fill_picture_box(image, box, {40, 40, 40});
  fill_picture_box(image, {box.x0 + 2, box.y0 + 2, box.x1 - 2, box.y1 - 2}, {255, 255, 255});
  int row_y = y + pad;
  if (!title.empty()) {
    draw_picture_text(image, x + pad, row_y, title, pixel_height, {0, 0, 0});
    row_y += line;
  }
  for (const LegendEntry& entry : entries) {
    const int top = row_y + static_cast<int>(std::lround(0.1 * pixel_height));
    if (entry.cross)
      draw_picture_cross(image, x + pad + swatch / 2, top + swatch / 2, swatch / 2, std::max(2, swatch / 5), entry.color);
    else
      fill_picture_box(image, {x + pad, top, x + pad + swatch - 1, top + swatch - 1}, entry.color);
    draw_picture_text(image, x + pad + swatch + pad, row_y, entry.label, pixel_height, {0, 0, 0});
    row_y += line;
  }
  return box;
}

PictureBox draw_picture_banner(RgbImage& image, const std::string& text, PictureColor background, double pixel_height) {
  const int pad = static_cast<int>(std::lround(0.4 * pixel_height));
  const PictureBox box{0, 0, image.width - 1, static_cast<int>(std::lround(pixel_height)) + 2 * pad};
  fill_picture_box(image, box, background);
  draw_picture_text(image, pad, pad, text, pixel_height, {0, 0, 0});
  return box;
}

}  // namespace quadrix
