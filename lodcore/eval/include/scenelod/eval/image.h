#pragma once
// RGB8 images and PNG output (stb_image_write, Debian libstb).
#include <cstdint>
#include <string>
#include <vector>

#include "scenelod/lodcore/status.h"

namespace scenelod::eval {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  // width * height * 3 bytes, rows top to bottom

  Image() = default;
  Image(int w, int h, uint8_t fill = 255) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, fill) {}
  uint8_t* pixel(int x, int y) { return rgb.data() + (static_cast<size_t>(y) * width + x) * 3; }
  const uint8_t* pixel(int x, int y) const { return rgb.data() + (static_cast<size_t>(y) * width + x) * 3; }
};

// Writes the image as an 8-bit RGB PNG. Returns an error naming the path when it cannot be written
// or the image is empty or inconsistent.
Error writePng(const std::string& path, const Image& image);

// Copies `src` into `dst` with its top-left corner at (x, y), clipped to dst.
void blit(Image& dst, const Image& src, int x, int y);

}  // namespace scenelod::eval
