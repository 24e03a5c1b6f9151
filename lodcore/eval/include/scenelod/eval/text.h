#pragma once
// Text in images with a tiny built-in 5x7 bitmap font (labels for plots and picture grids).
// Covers digits, letters (lower case drawn as small capitals), space and common punctuation;
// other characters draw as a box.
#include <cstdint>
#include <string>

#include "scenelod/eval/image.h"

namespace scenelod::eval {

struct Rgb8 {
  uint8_t r = 0, g = 0, b = 0;
};

// Draws `text` with its top-left corner at (x, y), each font pixel `scale` x `scale` image pixels;
// vertical = true writes bottom to top (rotated 90 degrees counter-clockwise). Clipped to the image.
void drawText(Image& img, int x, int y, const std::string& text, Rgb8 color, int scale = 1, bool vertical = false);

// Width in pixels of `text` drawn at `scale` (6 pixels per character including spacing, minus 1).
int textWidth(const std::string& text, int scale = 1);
constexpr int kTextHeight = 7;  // font pixels

}  // namespace scenelod::eval
