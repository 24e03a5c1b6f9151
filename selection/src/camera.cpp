// Pixel size R from Low & Tan 1997 §4 ("LOD determination").
#include "scenelod/selection/camera.h"

#include <algorithm>
#include <cmath>

namespace scenelod::selection {

float pixelSize(const Camera& c, float distance) {
  const float h = static_cast<float>(std::max<uint32_t>(c.viewport_height_px, 1));
  if (c.projection == Projection::kOrthographic) return c.ortho_height / h;
  const float d = std::max(distance, c.near_plane);
  return 2.0f * d * std::tan(c.fov_y_rad * 0.5f) / h;
}

}  // namespace scenelod::selection
