// Pixel size R from Low & Tan 1997 §4 ("LOD determination"), and plane-based frustum culling of
// bounding spheres.
#include "scenelod/selection/camera.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace scenelod::selection {

namespace {
bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

glm::vec4 plane(const glm::vec3& normal, const glm::vec3& point) {
  const glm::vec3 n = glm::normalize(normal);
  return glm::vec4(n, -glm::dot(n, point));
}
}  // namespace

float pixelSize(const Camera& c, float distance) {
  const float h = static_cast<float>(std::max<uint32_t>(c.viewport_height_px, 1));
  if (c.projection == Projection::kOrthographic) return c.ortho_height / h;
  return std::max(distance, c.near_plane) * pixelSizeFactor(c);
}

float pixelSizeFactor(const Camera& c) {
  if (c.projection == Projection::kOrthographic) return 0.0f;
  const float h = static_cast<float>(std::max<uint32_t>(c.viewport_height_px, 1));
  return 2.0f * std::tan(c.fov_y_rad * 0.5f) / h;
}

bool cameraValid(const Camera& c) {
  if (!finite3(c.eye) || !finite3(c.target) || !finite3(c.up)) return false;
  const glm::vec3 f = c.target - c.eye;
  const float fl = glm::length(f);
  if (!(fl > 0.0f) || !std::isfinite(fl)) return false;
  const float ul = glm::length(c.up);
  if (!(ul > 0.0f)) return false;
  if (glm::length(glm::cross(f / fl, c.up / ul)) < 1e-6f) return false;
  if (!(c.near_plane > 0.0f) || !(c.far_plane > c.near_plane) || !std::isfinite(c.far_plane)) return false;
  if (c.viewport_width_px < 1 || c.viewport_height_px < 1) return false;
  if (c.projection == Projection::kPerspective)
    return c.fov_y_rad > 0.0f && c.fov_y_rad < 3.14159f;
  return c.ortho_height > 0.0f && std::isfinite(c.ortho_height);
}

Frustum computeFrustum(const Camera& c) {
  Frustum fr;
  const glm::vec3 f = glm::normalize(c.target - c.eye);
  const glm::vec3 r = glm::normalize(glm::cross(f, c.up));
  const glm::vec3 u = glm::cross(r, f);
  fr.eye = c.eye;
  fr.forward = f;
  const float aspect = static_cast<float>(c.viewport_width_px) / static_cast<float>(c.viewport_height_px);
  fr.planes[0] = plane(f, c.eye + f * c.near_plane);
  fr.planes[1] = plane(-f, c.eye + f * c.far_plane);
  if (c.projection == Projection::kPerspective) {
    const float ty = std::tan(c.fov_y_rad * 0.5f), tx = ty * aspect;
    fr.planes[2] = plane(r + f * tx, c.eye);
    fr.planes[3] = plane(-r + f * tx, c.eye);
    fr.planes[4] = plane(u + f * ty, c.eye);
    fr.planes[5] = plane(-u + f * ty, c.eye);
  } else {
    const float hy = c.ortho_height * 0.5f, hx = hy * aspect;
    fr.planes[2] = plane(r, c.eye - r * hx);
    fr.planes[3] = plane(-r, c.eye + r * hx);
    fr.planes[4] = plane(u, c.eye - u * hy);
    fr.planes[5] = plane(-u, c.eye + u * hy);
  }
  return fr;
}

}  // namespace scenelod::selection
