#include "scenelod/eval/image.h"

#include <algorithm>

#include <stb_image_write.h>

namespace scenelod::eval {

Error writePng(const std::string& path, const Image& img) {
  if (img.width <= 0 || img.height <= 0 || img.rgb.size() != static_cast<size_t>(img.width) * img.height * 3)
    return {Status::kInvalidArgument, path + ": image is empty or its pixel buffer does not match " +
                                          std::to_string(img.width) + "x" + std::to_string(img.height)};
  if (!stbi_write_png(path.c_str(), img.width, img.height, 3, img.rgb.data(), img.width * 3))
    return {Status::kIoError, path + ": cannot write PNG (does the folder exist and is it writable?)"};
  return {};
}

void blit(Image& dst, const Image& src, int x, int y) {
  for (int sy = 0; sy < src.height; ++sy) {
    const int dy = y + sy;
    if (dy < 0 || dy >= dst.height) continue;
    for (int sx = 0; sx < src.width; ++sx) {
      const int dx = x + sx;
      if (dx < 0 || dx >= dst.width) continue;
      std::copy_n(src.pixel(sx, sy), 3, dst.pixel(dx, dy));
    }
  }
}

}  // namespace scenelod::eval
