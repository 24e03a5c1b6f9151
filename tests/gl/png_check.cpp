// Checks a screenshot of `scenelod view`: the PNG decodes, has the expected size, and more than
// MIN_PERCENT % of its pixels differ from the background colour (the top-left pixel) by more than a
// few levels, so something was really drawn. Usage: png_check FILE.png WIDTH HEIGHT MIN_PERCENT
#include <cstdio>
#include <cstdlib>

#include <stb_image.h>

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: png_check FILE.png WIDTH HEIGHT MIN_PERCENT\n");
    return 2;
  }
  int w = 0, h = 0, channels = 0;
  unsigned char* px = stbi_load(argv[1], &w, &h, &channels, 3);
  if (!px) {
    std::fprintf(stderr, "png_check: %s: cannot read the PNG (%s)\n", argv[1], stbi_failure_reason());
    return 1;
  }
  const int want_w = std::atoi(argv[2]), want_h = std::atoi(argv[3]);
  const double min_percent = std::atof(argv[4]);
  if (w != want_w || h != want_h) {
    std::fprintf(stderr, "png_check: %s: %dx%d, expected %dx%d\n", argv[1], w, h, want_w, want_h);
    stbi_image_free(px);
    return 1;
  }
  long drawn = 0;
  for (long i = 0; i < static_cast<long>(w) * h; ++i) {
    int diff = 0;
    for (int c = 0; c < 3; ++c) diff += std::abs(static_cast<int>(px[i * 3 + c]) - static_cast<int>(px[c]));
    if (diff > 6) ++drawn;
  }
  stbi_image_free(px);
  const double percent = 100.0 * static_cast<double>(drawn) / (static_cast<double>(w) * h);
  std::printf("png_check: %s: %dx%d, %.2f %% of pixels differ from the background (need > %.2f %%)\n", argv[1], w, h,
              percent, min_percent);
  return percent > min_percent ? 0 : 1;
}
