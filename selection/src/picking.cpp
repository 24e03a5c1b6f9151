// Picking against the level drawn this frame, and the focus factor of Funkhouser & Séquin 1993
// (benefit grows for objects near where the user looks; here near a picked or user-set world point).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "ray_scene_impl.h"

namespace scenelod::selection {

Ray pixelRay(const Camera& c, glm::vec2 pixel_px) {
  const float w = static_cast<float>(std::max<uint32_t>(c.viewport_width_px, 1));
  const float h = static_cast<float>(std::max<uint32_t>(c.viewport_height_px, 1));
  const glm::vec3 forward = glm::normalize(c.target - c.eye);
  const glm::vec3 right = glm::normalize(glm::cross(forward, c.up));
  const glm::vec3 up = glm::cross(right, forward);
  const float x = 2.0f * pixel_px.x / w - 1.0f;   // -1 left .. 1 right
  const float y = 1.0f - 2.0f * pixel_px.y / h;   // -1 bottom .. 1 top
  const float aspect = w / h;
  Ray r;
  if (c.projection == Projection::kOrthographic) {
    const float half_h = 0.5f * c.ortho_height;
    r.origin = c.eye + right * (x * half_h * aspect) + up * (y * half_h);
    r.direction = forward;
  } else {
    const float t = std::tan(0.5f * c.fov_y_rad);
    r.origin = c.eye;
    r.direction = glm::normalize(forward + right * (x * t * aspect) + up * (y * t));
  }
  return r;
}

PickHit RayScene::intersect(const Ray& ray, float t_near, float t_far) const {
  const Impl& m = *impl_;
  PickHit out;
  if (!m.device) return out;
  int64_t best = -1;
  traverse(m.bvh, m.box_lo, m.box_hi, ray.origin, ray.direction, t_near, t_far,
           [&](uint32_t id, float, float, float& t_max) {
             const int32_t level = m.drawn_level[id];
             if (!m.live[id] || level < 0) return false;
             RTCScene proto = m.chains[m.chain[id]].levels[static_cast<size_t>(level)];
             if (proto && intersectObject(m, id, proto, ray.origin, ray.direction, t_near, t_max)) best = id;
             return false;
           });
  if (best < 0) return out;
  const uint32_t id = static_cast<uint32_t>(best);
  out.object = static_cast<int32_t>(id);
  out.level = m.drawn_level[id];
  out.distance = t_far * glm::length(ray.direction);
  out.point = ray.origin + t_far * ray.direction;
  return out;
}

PickHit RayScene::pick(const Camera& camera, glm::vec2 pixel_px) const {
  const Ray r = pixelRay(camera, pixel_px);
  const float t_near = camera.projection == Projection::kPerspective ? camera.near_plane : 0.0f;
  return intersect(r, t_near, camera.far_plane);
}

FocusParams focusFromPick(const RayScene& scene, const PickHit& hit, float radius_scale, float gain) {
  FocusParams f;
  if (hit.object < 0 || !scene.isLive(static_cast<uint32_t>(hit.object))) return f;
  f.enabled = true;
  f.point = hit.point;
  f.radius = std::max(radius_scale * scene.worldSpheres()[static_cast<size_t>(hit.object)].w, 1e-6f);
  f.gain = gain;
  return f;
}

void computeFocusFactors(Span<const glm::vec4> spheres, const FocusParams& p, Span<float> focus) {
  const size_t n = spheres.count;
  if (!p.enabled || !(p.radius > 0.0f)) {
    std::fill(focus.data, focus.data + n, 1.0f);
    return;
  }
  const float inv_r = 1.0f / p.radius;
  for (size_t i = 0; i < n; ++i) {
    const glm::vec4 s = spheres[i];
    const float d = std::max(0.0f, glm::length(glm::vec3(s) - p.point) - s.w) * inv_r;
    const float k = d < 1.0f ? (1.0f - d * d) : 0.0f;
    focus[i] = 1.0f + p.gain * k * k;
  }
}

}  // namespace scenelod::selection
